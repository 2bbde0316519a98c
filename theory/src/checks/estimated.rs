//! Check 7: the SGD bound (3.27) on the real tasks, with **estimated** constants.
//!
//! On CartPole and the obstacle task the constants cannot be bounded rigorously, so they are
//! estimated — and labelled as estimates, never as certificates:
//! * B̂_F = F̂(θ₁), the Monte-Carlo mean trajectory loss at θ₁ (F ≥ 0 makes F(θ₁) an upper bound on
//!   F(θ₁) − F*, but its estimate is only an estimate);
//! * σ̂² = max over probe points of tr Var̂(g) (the c = 1 form of (S2));
//! * L̂_F = max over probe pairs (θ, θ + ρu) of ‖ḡ(θ + ρu) − ḡ(θ)‖/ρ with common random numbers.
//!
//! Then R seeded SGD runs with η = min(η₀, 1/L̂) give X = (1/K) Σ_k ‖∇F(θ_k)‖², with ‖∇F(θ_k)‖²
//! estimated without bias as ‖ḡ_M‖² − tr Var̂/M at every `stride`-th iterate. The row reports
//! X̄, B̂ = L̂ησ̂² + 2B̂_F/(ηK) and the tightness X̄/B̂, so a reader sees whether the theory's rate
//! describes the task; the verdict compares point estimates and is labelled an estimate. The row
//! is "inconclusive (uninformative)" when X̄ is within two standard errors (over the R runs) of 0:
//! the per-iterate ‖∇F‖² estimates are then dominated by their variance correction and the
//! comparison with B̂ carries no information. On the real tasks it runs under the objective the
//! chapter-4 experiments use (the fixed horizon, see `suite::real_environments`).

use crate::bounds::sgd_constant;
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::record::constant::Constant;
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::sgd::{SgdConfig, SgdStep};
use ilopt::algo::{ConfigNumber, IterationMetrics, Runner, StoppingRule, Termination};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use nalgebra::DVector;
use rand::SeedableRng;
use std::cell::RefCell;

/// Sizes of the estimate.
#[derive(Debug, Clone, Copy)]
pub struct EstimateSizes {
    /// Oracle samples per gradient estimate M.
    pub m: usize,
    /// Probe points for σ̂² and L̂.
    pub probes: usize,
    /// Probe radius ρ.
    pub rho: f64,
    /// Probe points are θ₁ + spread·U[−1, 1]ᵈ (the first is θ₁ itself).
    pub spread: f64,
    /// SGD runs R.
    pub runs: usize,
    /// SGD iterations K.
    pub k: u64,
    /// Evaluate ∇F at every `stride`-th iterate.
    pub stride: u64,
    /// Largest step size η₀.
    pub eta0: f64,
}

/// (ḡ_M, tr Var̂) at θ from M trajectories with seeds seed0..seed0+M.
fn mean_and_trace<P: IlProblem<f64>>(
    p: &mut P,
    theta: &DVector<f64>,
    m: usize,
    seed0: u64,
) -> Result<(DVector<f64>, f64), String> {
    let mut c = Cost::default();
    let mut sum = DVector::zeros(theta.len());
    let mut sq = 0.0;
    let mut samples = Vec::with_capacity(m);
    for i in 0..m {
        let mut rng = KitRng::seed_from_u64(seed0 + i as u64);
        let t = p
            .rollout(&Behaviour::Learner(theta), &mut rng, &mut c)
            .map_err(|e| e.to_string())?;
        let g = p
            .estimate(theta, &t, EstimatorForm::Causal, &mut c)
            .map_err(|e| e.to_string())?;
        sum += &g;
        samples.push(g);
    }
    let mean = sum / m as f64;
    for g in &samples {
        sq += (g - &mean).norm_squared();
    }
    Ok((mean, sq / (m as f64 - 1.0)))
}

/// The row `id` for one task. `theta1` is the SGD start; probe points are θ₁ plus seeded
/// perturbations.
pub fn sgd_row<P: IlProblem<f64>>(
    id: &str,
    name: &str,
    p: &mut P,
    theta1: &DVector<f64>,
    s: EstimateSizes,
) -> Check {
    let result = "SGD, eq. 3.27 (real task, estimated constants)";
    let fail = |d: String| {
        Check::builder(
            id,
            result,
            format!("{name}: (1/K) Σ E‖∇F(θ_k)‖² ≤ Lησ² + 2B_F/(ηK)"),
            Role::Thesis,
        )
        .details(d)
        .decided(Method::Estimate, Verdict::Inconclusive)
    };
    // B̂_F.
    let mut c = Cost::default();
    let mut f = 0.0;
    for i in 0..s.m {
        let mut rng = KitRng::seed_from_u64(5_000_000 + i as u64);
        match p
            .rollout(&Behaviour::Learner(theta1), &mut rng, &mut c)
            .and_then(|t| p.trajectory_loss(theta1, &t))
        {
            Ok(l) => f += l,
            Err(e) => return fail(e.to_string()),
        }
    }
    let b_f = f / s.m as f64;
    // σ̂², L̂ on probes.
    let mut dir_rng = KitRng::seed_from_u64(7);
    let (mut sigma2, mut l) = (0.0f64, 0.0f64);
    for j in 0..s.probes {
        let scale = if j == 0 { 0.0 } else { s.spread };
        let theta = theta1
            + DVector::from_fn(theta1.len(), |_, _| {
                scale * rand::Rng::random_range(&mut dir_rng, -1.0..1.0)
            });
        let u = DVector::from_fn(theta1.len(), |_, _| {
            rand::Rng::random_range(&mut dir_rng, -1.0..1.0)
        })
        .normalize();
        let seed0 = 10_000_000 * (j as u64 + 1);
        let (g0, tr) = match mean_and_trace(p, &theta, s.m, seed0) {
            Ok(x) => x,
            Err(e) => return fail(e),
        };
        let (g1, _) = match mean_and_trace(p, &(&theta + &u * s.rho), s.m, seed0) {
            Ok(x) => x,
            Err(e) => return fail(e),
        };
        sigma2 = sigma2.max(tr);
        l = l.max((g1 - g0).norm() / s.rho);
    }
    let eta = s.eta0.min(1.0 / l);
    let bound = sgd_constant(l, eta, sigma2, b_f, s.k);
    // SGD runs.
    let mut xs = vec![];
    for r in 0..s.runs {
        let cfg = RunConfig {
            algorithm: AlgorithmConfig::Sgd(SgdConfig {
                step: SgdStep::Constant {
                    eta: ConfigNumber::Float(eta),
                },
                form: EstimatorForm::Causal,
            }),
            theta0: theta1.iter().map(|x| ConfigNumber::Float(*x)).collect(),
            seed: 100 + r as u64,
            stop: StoppingRule::iterations(s.k - 1),
        };
        let iterates = RefCell::new(vec![]);
        let obs = |m: &IterationMetrics<f64>| {
            if m.iteration.is_multiple_of(s.stride) {
                iterates.borrow_mut().push(m.theta.clone());
            }
        };
        match Runner::new(cfg.stop.clone()).and_then(|run| {
            run.keep_history(false)
                .with_observer(obs)
                .run_config(&cfg, p)
        }) {
            Ok(rec) if !matches!(rec.termination, Termination::Diverged(_)) => {}
            Ok(rec) => return fail(format!("run {r}: {}", rec.termination)),
            Err(e) => return fail(e.to_string()),
        }
        let its = iterates.into_inner();
        let mut acc = 0.0;
        for (i, th) in its.iter().enumerate() {
            match mean_and_trace(p, th, s.m, 900_000_000 + (r * 10_000 + i) as u64) {
                Ok((g, tr)) => acc += g.norm_squared() - tr / s.m as f64,
                Err(e) => return fail(e),
            }
        }
        xs.push(acc / its.len() as f64);
    }
    let mean = xs.iter().sum::<f64>() / xs.len() as f64;
    // The spread of X over the runs: X̄ within 2 standard errors of 0 says nothing about the
    // bound (the per-iterate ‖∇F‖² estimates are then dominated by their variance correction).
    let se = if xs.len() > 1 {
        (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / ((xs.len() - 1) * xs.len()) as f64)
            .sqrt()
    } else {
        f64::INFINITY
    };
    let informative = mean - 2.0 * se > 0.0;
    let verdict = if informative {
        Verdict::from_bool(mean <= bound)
    } else {
        Verdict::Uninformative
    };
    Check::builder(
        id,
        result,
        format!("{name}: (1/K) Σ E‖∇F(θ_k)‖² ≤ L̂ησ̂² + 2B̂_F/(ηK), K = {}, η = {eta:.4e}", s.k),
        Role::Thesis,
    )
    .assumptions(["constants are Monte-Carlo ESTIMATES (not certificates); L̂ is a local, sampled smoothness"])
    .constants(vec![
        Constant::estimate("B_F", b_f, format!("F̂(θ₁) from {} roll-outs", s.m)),
        Constant::estimate("σ²", sigma2, format!("max tr Var̂(g) over {} probe points (θ₁ ± {}), M = {}", s.probes, s.spread, s.m)),
        Constant::estimate("L_F", l, format!("max ‖ḡ(θ+ρu) − ḡ(θ)‖/ρ over {} probes, ρ = {}, common random numbers", s.probes, s.rho)),
    ])
    .bound(bound)
    .measured(Measured::statistic(mean).with_interval(mean - 2.0 * se, mean + 2.0 * se).with_se(se).with_runs(s.runs))
    .tightness(mean / bound)
    .erratum("E2")
    .details(format!(
            "ESTIMATES: B̂_F = {b_f:.4e}, σ̂² = {sigma2:.4e}, L̂ = {l:.4e}; η = min({}, 1/L̂) = {eta:.4e}; X̄ = {mean:.4e} ± {se:.2e} (s.e. over {} runs; ‖∇F‖² at every {}-th iterate, unbiased from M = {} trajectories), B̂ = {bound:.4e}, X̄/B̂ = {:.3e}{}{}",
            s.eta0,
            s.runs,
            s.stride,
            s.m,
            mean / bound,
            if mean > 1e6 * bound { " — SGD diverged: the local estimates do not describe the task" } else { "" },
            if informative { "; point estimates against estimated constants: not a certificate" } else { "; UNINFORMATIVE: X̄ is within 2 s.e. of 0: the per-iterate ‖∇F‖² estimates are dominated by their variance correction, the measurement is noise" }
    ))
    .decided(Method::Estimate, verdict)
}
