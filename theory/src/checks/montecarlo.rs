//! Checks 1 and 3: the SGD bound (3.27) and the online-to-non-convex bounds (§3.4, eq. 3.71) by
//! Monte Carlo over seeded runs of the kit's own algorithms on M1 (P2'), with **exact ∇F at the
//! iterates** (forward DP in interval arithmetic; the *lower* end of each per-run statistic is
//! used for the decision so rounding can never raise a false alarm — math.md §7.2) and the
//! decision rule of [`crate::stats`] at a stated false-alarm probability.
//!
//! Every check takes a `claim_scale`: 1 checks the theorem; a small value checks a deliberately
//! wrong (understated) bound, which the check must flag.

use crate::bounds::{O2ncParams, o2nc_theorem, sgd_constant, sgd_step_admissible, upper};
use crate::check::{Check, Measured, Method, Role, Verdict};
use crate::checks::constants::ToyConstants;
use crate::checks::tracking::{O2ncTracker, Tracking};
use crate::stats::{Sample, assess};
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::o2nc::O2ncConfig;
use ilopt::algo::sgd::{SgdConfig, SgdStep};
use ilopt::algo::{ConfigNumber, IterationMetrics, Runner, StoppingRule, Termination};
use ilopt::exact::forward::forward;
use ilopt::problem::EstimatorForm;
use ilopt::scalar::{BigRational, Interval, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use std::cell::RefCell;

/// Monte-Carlo sizes and level.
#[derive(Debug, Clone, Copy)]
pub struct McSettings {
    /// Independent seeded runs R.
    pub runs: usize,
    /// False-alarm probability of this check (after Bonferroni).
    pub alpha: f64,
}

/// Enclosure of ∇F(θ) at a point θ (f64 coordinates, exactly).
fn grad_enclosure(p: &ToyProblem<Interval>, theta: &[f64]) -> Result<Vec<Interval>, String> {
    let th: Vec<Interval> = theta
        .iter()
        .map(|x| Interval::try_from((*x, *x)).map_err(|e| format!("θ = {x}: {e:?}")))
        .collect::<Result<_, _>>()?;
    forward(p, &th)
        .map(|f| f.gradient)
        .map_err(|e| e.to_string())
}

/// (lower, midpoint) of ‖v‖² for an interval vector.
fn norm_sq_bounds(v: &[Interval]) -> (f64, f64) {
    let lo: f64 = v.iter().map(|x| x.mig() * x.mig()).sum();
    let mid: f64 = v.iter().map(|x| x.mid() * x.mid()).sum();
    (lo, mid)
}

fn inconclusive(id: &str, result: &str, claim: String, details: String) -> Check {
    Check {
        id: id.into(),
        result: result.into(),
        claim,
        assumptions: vec![],
        constants: vec![],
        bound: None,
        measured: None,
        tightness: None,
        method: Method::Statistical,
        verdict: Verdict::Inconclusive,
        erratum: None,
        role: Role::Thesis,
        details,
    }
}

/// Per-run statistics of R runs: (rigorous lower ends, midpoints), in seed order.
pub type Runs = (Vec<f64>, Vec<f64>);

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
    let pi = ToyProblem::<Interval>::new(mdp);
    let pf = ToyProblem::<f64>::new(mdp);
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
            match grad_enclosure(&pi, m.theta.as_slice()) {
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
                .run_config(&cfg(r as u64), &pf)
        });
        let (lo, mid, err) = acc.into_inner();
        match rec {
            Ok(rec) if !matches!(rec.termination, Termination::Failed(_)) && err.is_none() => {
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

/// The claim prefix of a scaled (control) bound.
fn scale_prefix(claim_scale: f64) -> String {
    if claim_scale == 1.0 {
        String::new()
    } else {
        format!("{claim_scale}·")
    }
}

/// The measured value of a statistical row and its verdict ([`assess`]): the LCB of the lower
/// ends against `upper(bound)`, the statistic's certified maximum `statistic_max`.
fn measure(
    lows: &[f64],
    mids: &[f64],
    range: f64,
    bound: f64,
    statistic_max: f64,
    mc: McSettings,
) -> (Measured, Verdict, String) {
    let sample = Sample::new(lows, range);
    let mean_mid = mids.iter().sum::<f64>() / mids.len() as f64;
    let lcb = sample.lcb(mc.alpha);
    let verdict = assess(&sample, upper(bound), statistic_max, mc.alpha);
    let text = format!(
        "R = {}; X̄ = {mean_mid:.5}, LCB = {lcb:.5} (max of Hoeffding, empirical Bernstein, betting at α/3 each; α = {:.1e}, range [0, {range:.4}]), B = {bound:.5}; flags any B < {lcb:.5}, minimum detectable violation X̄ − LCB = {:.5}; the statistic cannot exceed {statistic_max:.4}",
        mc.runs,
        mc.alpha,
        mean_mid - lcb,
    );
    (
        Measured {
            value: mean_mid,
            lcb: Some(lcb),
            ucb: Some(sample.ucb(mc.alpha)),
            runs: Some(mc.runs),
            alpha: Some(mc.alpha),
        },
        verdict,
        text,
    )
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
/// verdict by [`assess`], with the statistic's maximum G_F²).
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
    Check {
        id: "1".into(),
        result: result.into(),
        claim,
        assumptions: vec![
            "(S1) F L-smooth on a box holding every iterate a.s.".into(),
            "(S2) E g = ∇F, E‖g‖² ≤ σ² + ‖∇F‖² (c = 1)".into(),
            "(S3) fresh τ_k ∼ p(·; θ_k), η ≤ 1/(Lc)".into(),
        ],
        constants: k_consts.all(),
        bound: Some(bound),
        tightness: Some(measured.value / bound),
        measured: Some(measured),
        method: Method::Statistical,
        verdict,
        erratum: None,
        role: if claim_scale == 1.0 {
            Role::Thesis
        } else {
            Role::NegativeControl
        },
        details: format!(
            "{} runs of the kit's SGD from θ₁ = {theta1}; {text}; η ≤ 1/(Lc) holds (Lη = {:.3})",
            mc.runs,
            l * eta_f
        ),
    }
}

/// Which Algorithm 5 a run of check 3 uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum O2ncVariant {
    /// IL-correct: τ_n ∼ p(·; w_n) (math.md §5).
    IlCorrect,
    /// As printed (E11): τ_n ∼ p(·; θ_n), the kit's `printed_algorithm_5` — a negative control.
    Printed,
}

/// Check 3: online-to-non-convex (IL-correct sampling at w_n), budget N, radius δ:
/// (a) ‖w̄ᵏ − wᵏ_t‖ ≤ δ on every block of every run (deterministic);
/// (b) E[(1/K) Σ_k ‖(1/T) Σ_t ∇F(wᵏ_t)‖] ≤ Δ₀/(DM) + G/√T + σ/√T (theorem level).
pub fn o2nc(
    mdp: &ToyMdp,
    k_consts: &ToyConstants,
    theta0: f64,
    n: u64,
    delta: (i64, i64),
    mc: McSettings,
    claim_scale: f64,
) -> Vec<Check> {
    o2nc_variant(
        mdp,
        k_consts,
        theta0,
        n,
        delta,
        mc,
        &[claim_scale],
        O2ncVariant::IlCorrect,
    )
}

/// Check 3 for one Algorithm 5 variant: row 3a (IL-correct only) and one row 3b per entry of
/// `claim_scales`, all from **one** sample (same N, δ, R, α and verdict code). A scale ≠ 1, or
/// the printed variant, is a negative control that the row must flag.
#[allow(clippy::too_many_arguments)]
pub fn o2nc_variant(
    mdp: &ToyMdp,
    k_consts: &ToyConstants,
    theta0: f64,
    n: u64,
    delta: (i64, i64),
    mc: McSettings,
    claim_scales: &[f64],
    variant: O2ncVariant,
) -> Vec<Check> {
    let sample = o2nc_sample(mdp, k_consts, theta0, n, delta, mc.runs, variant);
    o2nc_rows(k_consts, n, delta, mc, &sample, claim_scales, variant)
}

/// What R runs of check 3 recorded.
#[derive(Debug, Clone)]
pub struct O2ncSample {
    /// Per run, X = (1/K) Σ_k ‖(1/T) Σ_t ∇F(wᵏ_t)‖ (lower ends, midpoints).
    pub runs: Runs,
    /// max over runs, blocks and t of |w̄ᵏ − wᵏ_t|.
    pub worst_spread: f64,
    /// The per-step values of the tracking row 3d ([`crate::checks::tracking`]):
    /// sign(Δ_n)(g_n − ∇F(w_n))/(G_∞ + G_F).
    pub tracking: Tracking,
}

/// The O2NC configuration of check 3 and its parameters T, K, M.
fn o2nc_config(
    k_consts: &ToyConstants,
    n: u64,
    delta: (i64, i64),
) -> Result<(O2ncConfig, ilopt::algo::o2nc::O2ncParameters), String> {
    let config = O2ncConfig {
        budget: n,
        delta: ConfigNumber::ratio(delta.0, delta.1),
        g: ConfigNumber::Float(k_consts.g2.value.sqrt().next_up()),
        delta0: ConfigNumber::Exact(BigRational::from_float(k_consts.b_f.value).expect("finite")),
        form: EstimatorForm::Causal,
    };
    let params = config.parameters().map_err(|e| e.to_string())?;
    Ok((config, params))
}

/// R seeded runs of Algorithm 5 (`variant`) with budget N and radius δ from θ₀, recording the
/// statistic of check 3b (exact ∇F at every w_n, enclosed in intervals) and the spread of 3a.
///
/// # Errors
/// A message naming the run if a run fails or ∇F cannot be enclosed.
pub fn o2nc_sample(
    mdp: &ToyMdp,
    k_consts: &ToyConstants,
    theta0: f64,
    n: u64,
    delta: (i64, i64),
    runs: usize,
    variant: O2ncVariant,
) -> Result<O2ncSample, String> {
    o2nc_sample_tracked(
        mdp,
        k_consts,
        theta0,
        n,
        delta,
        runs,
        variant,
        (k_consts.g_inf.value, k_consts.g_f.value),
    )
}

/// As [`o2nc_sample`], with the tracking values normalised by G_∞ + G_F for the given
/// `(G_∞, G_F)` (bounds of sup |g| and sup |∇F| valid wherever the iterates go).
///
/// # Errors
/// As [`o2nc_sample`].
#[allow(clippy::too_many_arguments)]
pub fn o2nc_sample_tracked(
    mdp: &ToyMdp,
    k_consts: &ToyConstants,
    theta0: f64,
    n: u64,
    delta: (i64, i64),
    runs: usize,
    variant: O2ncVariant,
    (g_inf, g_f): (f64, f64),
) -> Result<O2ncSample, String> {
    let mut tracker = O2ncTracker::new(g_inf, g_f);
    let (config, params) = o2nc_config(k_consts, n, delta)?;
    let algorithm = match variant {
        O2ncVariant::IlCorrect => AlgorithmConfig::O2nc(config),
        O2ncVariant::Printed => AlgorithmConfig::PrintedAlgorithm5(config),
    };
    let (t, kb) = (params.t as usize, params.k as usize);
    let pi = ToyProblem::<Interval>::new(mdp);
    let pf = ToyProblem::<f64>::new(mdp);
    let (mut lows, mut mids) = (vec![], vec![]);
    let mut worst_spread = 0.0f64;
    for r in 0..runs {
        let cfg = RunConfig {
            algorithm: algorithm.clone(),
            theta0: vec![ConfigNumber::Float(theta0)],
            seed: r as u64,
            stop: StoppingRule::iterations(params.m + 1),
        };
        // (θ_n, w_n, g_n) per step.
        let ws = RefCell::new(Vec::<(f64, f64, f64)>::with_capacity(params.m as usize));
        let observer = |m: &IterationMetrics<f64>| {
            if let (Some(w), Some(g)) = (&m.evaluated_at, &m.estimate) {
                ws.borrow_mut().push((m.theta[0], w[0], g[0]));
            }
        };
        let rec = Runner::new(cfg.stop.clone()).and_then(|runner| {
            runner
                .keep_history(false)
                .with_observer(observer)
                .run_config(&cfg, &pf)
        });
        match rec {
            Err(e) => return Err(format!("run {r}: {e}")),
            Ok(rec) if matches!(rec.termination, Termination::Failed(_)) => {
                return Err(format!("run {r}: {}", rec.termination));
            }
            Ok(_) => {}
        }
        let steps = ws.into_inner();
        if steps.len() < t * kb {
            return Err(format!(
                "run {r}: {} evaluation points, expected {}",
                steps.len(),
                t * kb
            ));
        }
        let ws: Vec<f64> = steps.iter().map(|s| s.1).collect();
        let grads = ws
            .iter()
            .map(|w| grad_enclosure(&pi, &[*w]).map(|g| g[0]))
            .collect::<Result<Vec<Interval>, String>>()?;
        tracker.start_run(theta0);
        for ((theta, _, g), grad) in steps.iter().zip(&grads) {
            tracker.observe(*theta, *g, *grad);
        }
        let (mut lo_sum, mut mid_sum) = (0.0, 0.0);
        for (block, block_grads) in ws.chunks(t).zip(grads.chunks(t)).take(kb) {
            let mean = block.iter().sum::<f64>() / t as f64;
            worst_spread = block
                .iter()
                .fold(worst_spread, |m, w| m.max((w - mean).abs()));
            let mut acc = Interval::zero();
            for g in block_grads {
                acc += *g;
            }
            let avg = acc / Interval::from_i64(t as i64);
            lo_sum += avg.mig();
            mid_sum += avg.mid().abs();
        }
        // The outer average's rounding is absorbed by the factor.
        lows.push(lo_sum / kb as f64 * (1.0 - 1e-9));
        mids.push(mid_sum / kb as f64);
    }
    Ok(O2ncSample {
        runs: (lows, mids),
        worst_spread,
        tracking: tracker.tracking,
    })
}

/// Rows 3a (IL-correct only) and one row 3b per entry of `claim_scales` from a sample of
/// [`o2nc_sample`] (the verdict by [`assess`], with the statistic's maximum G_F).
pub fn o2nc_rows(
    k_consts: &ToyConstants,
    n: u64,
    delta: (i64, i64),
    mc: McSettings,
    sample: &Result<O2ncSample, String>,
    claim_scales: &[f64],
    variant: O2ncVariant,
) -> Vec<Check> {
    let result = match variant {
        O2ncVariant::IlCorrect => "Online-to-non-convex (Alg. 5, IL-correct), Thm 3.8",
        O2ncVariant::Printed => {
            "Online-to-non-convex, Algorithm 5 as printed (τ_n ∼ θ_n), against Thm 3.8's bound"
        }
    };
    let claim = |claim_scale: f64| {
        format!(
            "E[(1/K) Σ_k ‖(1/T) Σ_t ∇F(wᵏ_t)‖] ≤ {}(Δ₀/(DM) + (G + σ)/√T), N = {n}, δ = {}/{}{}",
            scale_prefix(claim_scale),
            delta.0,
            delta.1,
            if variant == O2ncVariant::Printed {
                ", run by the printed Algorithm 5"
            } else {
                ""
            }
        )
    };
    let (params, sample) = match (o2nc_config(k_consts, n, delta), sample) {
        (Ok((_, p)), Ok(s)) => (p, s),
        (Err(e), _) => return vec![inconclusive("3", result, claim(1.0), e)],
        (_, Err(e)) => return vec![inconclusive("3", result, claim(1.0), e.clone())],
    };
    let (t, kb) = (params.t as usize, params.k as usize);
    let (lows, mids) = &sample.runs;
    let worst_spread = sample.worst_spread;
    let delta_f = delta.0 as f64 / delta.1 as f64;
    let (g, sigma, delta0) = (
        k_consts.g2.value.sqrt().next_up(),
        k_consts.sigma2.value.sqrt().next_up(),
        k_consts.b_f.value,
    );
    let bound1 = o2nc_theorem(
        delta0,
        delta_f,
        g,
        sigma,
        O2ncParams {
            t: params.t,
            k: params.k,
            m: params.m,
        },
    );
    // X ≤ sup ‖∇F‖ ≤ G_F.
    let b = k_consts.g_f.value;
    let mut rows = vec![];
    if variant == O2ncVariant::IlCorrect {
        rows.push(Check {
            id: "3a".into(),
            result: result.into(),
            claim: format!("‖w̄ᵏ − wᵏ_t‖ ≤ δ = {delta_f} for every block and run"),
            assumptions: vec!["‖Δ_n‖ ≤ D = δ/T, restart Δ = 0 per block (E14)".into()],
            constants: vec![],
            bound: Some(delta_f),
            measured: Some(Measured::exact(worst_spread)),
            tightness: Some(worst_spread / delta_f),
            method: Method::Exact,
            verdict: Verdict::from_bool(worst_spread <= delta_f * (1.0 + 1e-12)),
            erratum: Some("E14".into()),
            role: Role::Thesis,
            details: format!(
                "max over {} runs × {kb} blocks of max_t |w̄ᵏ − wᵏ_t| = {worst_spread:.6}",
                mc.runs
            ),
        });
    }
    for &claim_scale in claim_scales {
        let bound = bound1 * claim_scale;
        let (measured, verdict, text) = measure(lows, mids, b, bound, b, mc);
        let control = claim_scale != 1.0 || variant == O2ncVariant::Printed;
        rows.push(Check {
            id: match (variant, claim_scale == 1.0) {
                (O2ncVariant::IlCorrect, true) => "3b".into(),
                (O2ncVariant::IlCorrect, false) => "3b.ctl".into(),
                (O2ncVariant::Printed, _) => "3b.printed5".into(),
            },
            result: result.into(),
            claim: claim(claim_scale),
            assumptions: vec![
                match variant {
                    O2ncVariant::IlCorrect => "τ_n ∼ p(·; w_n) (E11)".into(),
                    O2ncVariant::Printed => {
                        "violated on purpose: τ_n ∼ p(·; θ_n) (E11), the kit's printed_algorithm_5"
                            .into()
                    }
                },
                "G² ≥ sup E‖g‖², σ² ≥ sup Var, Δ₀ ≥ F(θ₀) − F*".into(),
            ],
            constants: k_consts.all(),
            bound: Some(bound),
            tightness: Some(measured.value / bound),
            measured: Some(measured),
            method: Method::Statistical,
            verdict,
            erratum: Some("E11, E12, E13".into()),
            role: if variant == O2ncVariant::Printed {
                Role::Probe
            } else if control {
                Role::NegativeControl
            } else {
                Role::Thesis
            },
            details: format!("T = {t}, K = {kb}, M = {}, D = δ/T; {text}", params.m),
        });
    }
    rows
}
