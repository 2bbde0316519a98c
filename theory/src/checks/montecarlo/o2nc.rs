//! Check 3: the online-to-non-convex bounds (§3.4, Theorem 3.7 and eq. 3.71) over seeded runs of
//! the kit's Algorithm 5 (IL-correct, and the printed one as a probe), with the per-step values
//! the tracking row 3d tests.

use super::{GradientCells, McSettings, Runs, inconclusive, measure, scale_prefix};
use crate::bounds::{O2ncParams, o2nc_theorem};
use crate::certify::box_constants::ToyConstants;
use crate::checks::tracking::{O2ncTracker, Tracking};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::o2nc::O2ncConfig;
use ilopt::algo::{ConfigNumber, IterationMetrics, Runner, StoppingRule, Termination};
use ilopt::problem::EstimatorForm;
use ilopt::scalar::{BigRational, Interval, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use std::cell::RefCell;

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
    let mut cells = GradientCells::new(mdp);
    let mut pf = ToyProblem::<f64>::new(mdp);
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
                .run_config(&cfg, &mut pf)
        });
        match rec {
            Err(e) => return Err(format!("run {r}: {e}")),
            Ok(rec) if matches!(rec.termination, Termination::Diverged(_)) => {
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
            .map(|w| cells.enclose(&[*w]).map(|g| g[0]))
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
/// [`o2nc_sample`] (the verdict by [`crate::stats::assess`], with the statistic's maximum G_F).
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
        rows.push(
            Check::builder(
                "3a",
                result,
                format!(
                    "‖w̄ᵏ − wᵏ_t‖ ≤ δ = {delta_f} for every block and run (holds by construction: the projection ‖Δ_n‖ ≤ D = δ/T keeps a block's T iterates within δ; sampled over the runs, not a test)"
                ),
                Role::Thesis,
            )
            .assumptions(["‖Δ_n‖ ≤ D = δ/T, restart Δ = 0 per block (E14)"])
            .bound(delta_f)
            .measured(Measured::exact(worst_spread))
            .tightness(worst_spread / delta_f)
            .erratum("E14")
            .details(format!(
                "max over {} runs × {kb} blocks of max_t |w̄ᵏ − wᵏ_t| = {worst_spread:.6}",
                mc.runs
            ))
            .decided(
                Method::Sampled,
                Verdict::from_bool(worst_spread <= delta_f * (1.0 + 1e-12)),
            ),
        );
    }
    for &claim_scale in claim_scales {
        let bound = bound1 * claim_scale;
        let (measured, verdict, text) = measure(lows, mids, b, bound, b, mc);
        let control = claim_scale != 1.0 || variant == O2ncVariant::Printed;
        let id = match (variant, claim_scale == 1.0) {
            (O2ncVariant::IlCorrect, true) => "3b",
            (O2ncVariant::IlCorrect, false) => "3b.ctl",
            (O2ncVariant::Printed, _) => "3b.printed5",
        };
        let role = if variant == O2ncVariant::Printed {
            Role::Probe
        } else if control {
            Role::NegativeControl
        } else {
            Role::Thesis
        };
        let sampling = match variant {
            O2ncVariant::IlCorrect => "τ_n ∼ p(·; w_n) (E11)",
            O2ncVariant::Printed => {
                "violated on purpose: τ_n ∼ p(·; θ_n) (E11), the kit's printed_algorithm_5"
            }
        };
        rows.push(
            Check::builder(id, result, claim(claim_scale), role)
                .assumptions([sampling, "G² ≥ sup E‖g‖², σ² ≥ sup Var, Δ₀ ≥ F(θ₀) − F*"])
                .constants(k_consts.all())
                .bound(bound)
                .tightness(measured.value / bound)
                .measured(measured)
                .erratum("E11, E12, E13")
                .details(format!(
                    "T = {t}, K = {kb}, M = {}, D = δ/T; {text}",
                    params.m
                ))
                .decided(Method::Statistical, verdict),
        );
    }
    rows
}
