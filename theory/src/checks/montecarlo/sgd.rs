//! Check 1: the SGD bound (3.27) over seeded runs of the kit's SGD, and its scaled negative
//! control from the same sample.

use super::{GradientCells, McSettings, Runs, inconclusive, measure, norm_sq_bounds, scale_prefix};
use crate::bounds::{sgd_constant, sgd_step_admissible};
use crate::certify::box_constants::ToyConstants;
use crate::record::check::{Check, Method, Role};
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::sgd::{SgdConfig, SgdStep};
use ilopt::algo::{ConfigNumber, IterationMetrics, Runner, StoppingRule, Termination};
use ilopt::problem::{EstimatorForm, IlProblem};
use ilopt::toy::{ToyMdp, ToyProblem};
use std::cell::RefCell;

/// The per-run statistic of check 1, `X = (1/K) Σ_{k=1}^K ‖∇F(θ_k)‖²`, over R seeded runs of the
/// kit's SGD with constant η from θ₁: (lower ends, midpoints) of each run's X (exact ∇F enclosed
/// in intervals, so the lower end is a rigorous lower bound on X).
///
/// # Errors
/// A message naming the run if a run fails or ∇F cannot be enclosed.
pub fn sgd_sample(
    mdp: &ToyMdp,
    theta1: f64,
    eta: (i64, i64),
    k: u64,
    runs: usize,
) -> Result<Runs, String> {
    sgd_sample_on(mdp, &mut ToyProblem::<f64>::new(mdp), theta1, eta, k, runs)
}

/// [`sgd_sample`] with the kit's SGD run on `oracle`, a gradient oracle for F of `mdp` (the plain
/// toy problem, or one with a baseline): ∇F at the iterates is `mdp`'s.
///
/// # Errors
/// As [`sgd_sample`].
pub fn sgd_sample_on<P: IlProblem<f64>>(
    mdp: &ToyMdp,
    oracle: &mut P,
    theta1: f64,
    eta: (i64, i64),
    k: u64,
    runs: usize,
) -> Result<Runs, String> {
    let cells = RefCell::new(GradientCells::new(mdp));
    let pf = oracle;
    let cfg = |seed: u64| RunConfig {
        algorithm: AlgorithmConfig::Sgd(SgdConfig {
            step: SgdStep::constant(ConfigNumber::ratio(eta.0, eta.1)),
            form: EstimatorForm::Causal,
        }),
        theta0: vec![ConfigNumber::Float(theta1)],
        seed,
        stop: StoppingRule::iterations(k - 1),
    };
    let (mut lows, mut mids) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
    for r in 0..runs {
        let acc = RefCell::new((0.0f64, 0.0f64, None::<String>));
        let observer = |m: &IterationMetrics<f64>| {
            let mut a = acc.borrow_mut();
            match cells.borrow_mut().enclose(m.theta.as_slice()) {
                Ok(g) => {
                    let (lo, mid) = norm_sq_bounds(&g);
                    a.0 += lo;
                    a.1 += mid;
                }
                Err(e) => a.2 = Some(e),
            }
        };
        let rec = Runner::new(cfg(r as u64).stop.clone()).and_then(|runner| {
            runner
                .keep_history(false)
                .with_observer(observer)
                .run_config(&cfg(r as u64), pf)
        });
        let (lo, mid, err) = acc.into_inner();
        match rec {
            Ok(rec) if !matches!(rec.termination, Termination::Diverged(_)) && err.is_none() => {
                // The sum's own rounding (relative ≤ K·2⁻⁵³) is absorbed by the factor.
                lows.push(lo / k as f64 * (1.0 - 1e-9));
                mids.push(mid / k as f64);
            }
            Ok(rec) => return Err(format!("run {r}: {:?} {err:?}", rec.termination)),
            Err(e) => return Err(format!("run {r}: {e}")),
        }
    }
    Ok((lows, mids))
}

/// Check 1: SGD with constant η on `mdp` from θ₁, K iterates, eq. 3.27 (averaged form):
/// E[(1/K) Σ_{k=1}^K ‖∇F(θ_k)‖²] ≤ Lησ² + 2B_F/(ηK), with c = 1 (σ² = sup Var).
/// `claim_scale` ≠ 1 states a deliberately wrong (scaled) bound — a negative control.
pub fn sgd(
    mdp: &ToyMdp,
    k_consts: &ToyConstants,
    theta1: f64,
    eta: (i64, i64),
    k: u64,
    mc: McSettings,
    claim_scale: f64,
) -> Check {
    let eta_f = eta.0 as f64 / eta.1 as f64;
    if !sgd_step_admissible(k_consts.l_f.value, 1.0, eta_f) {
        return sgd_row(
            k_consts,
            theta1,
            eta,
            k,
            mc,
            claim_scale,
            &Err(String::new()),
        );
    }
    let sims = sgd_sample(mdp, theta1, eta, k, mc.runs);
    sgd_row(k_consts, theta1, eta, k, mc, claim_scale, &sims)
}

/// Check 1 and its negative control from **one** sample (same K, R, α and verdict code): the
/// theorem's bound, and the same bound multiplied by `control_scale` (< 1), which the row must
/// flag.
pub fn sgd_with_control(
    mdp: &ToyMdp,
    k_consts: &ToyConstants,
    theta1: f64,
    eta: (i64, i64),
    k: u64,
    mc: McSettings,
    control_scale: f64,
) -> Vec<Check> {
    let eta_f = eta.0 as f64 / eta.1 as f64;
    let sims = if sgd_step_admissible(k_consts.l_f.value, 1.0, eta_f) {
        sgd_sample(mdp, theta1, eta, k, mc.runs)
    } else {
        Err(String::new())
    };
    let mut control = sgd_row(k_consts, theta1, eta, k, mc, control_scale, &sims);
    control.id = "1.ctl".into();
    vec![sgd_row(k_consts, theta1, eta, k, mc, 1.0, &sims), control]
}

/// The row of check 1 for a bound scaled by `claim_scale`, from a sample of [`sgd_sample`] (the
/// verdict by [`crate::stats::assess`], with the statistic's maximum G_F²).
pub fn sgd_row(
    k_consts: &ToyConstants,
    theta1: f64,
    eta: (i64, i64),
    k: u64,
    mc: McSettings,
    claim_scale: f64,
    sims: &Result<Runs, String>,
) -> Check {
    let (l, s2, bf, gf) = (
        k_consts.l_f.value,
        k_consts.sigma2.value,
        k_consts.b_f.value,
        k_consts.g_f.value,
    );
    let eta_f = eta.0 as f64 / eta.1 as f64;
    let claim = format!(
        "(1/K) Σ E‖∇F(θ_k)‖² ≤ {}(Lησ² + 2B_F/(ηK)), η = {}/{}, K = {k}",
        scale_prefix(claim_scale),
        eta.0,
        eta.1
    );
    let result = "SGD, eq. 3.27";
    // Side condition η ≤ 1/(Lc), c = 1, with the rigorous L (an upper bound: if it holds for the
    // bound it holds for the true constant).
    if !sgd_step_admissible(l, 1.0, eta_f) {
        return inconclusive(
            "1",
            result,
            claim,
            format!("side condition η ≤ 1/(Lc) fails: η = {eta_f}, L = {l}"),
        );
    }
    let bound = sgd_constant(l, eta_f, s2, bf, k) * claim_scale;
    let (lows, mids) = match sims {
        Ok(x) => x,
        Err(e) => return inconclusive("1", result, claim, e.clone()),
    };
    // X ≤ sup ‖∇F‖² ≤ G_F² (the rounding factor keeps it an upper bound).
    let b = gf * gf * (1.0 + 1e-12);
    let (measured, verdict, text) = measure(lows, mids, b, bound, b, mc);
    let role = if claim_scale == 1.0 {
        Role::Thesis
    } else {
        Role::NegativeControl
    };
    Check::builder("1", result, claim, role)
        .assumptions([
            "(S1) F L-smooth on a box holding every iterate a.s.",
            "(S2) E g = ∇F, E‖g‖² ≤ σ² + ‖∇F‖² (c = 1)",
            "(S3) fresh τ_k ∼ p(·; θ_k), η ≤ 1/(Lc)",
        ])
        .constants(k_consts.all())
        .bound(bound)
        .tightness(measured.value / bound)
        .measured(measured)
        .details(format!(
            "{} runs of the kit's SGD from θ₁ = {theta1}; {text}; η ≤ 1/(Lc) holds (Lη = {:.3})",
            mc.runs,
            l * eta_f
        ))
        .decided(Method::Statistical, verdict)
}
