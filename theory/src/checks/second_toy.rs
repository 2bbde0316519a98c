//! A second toy, so that no bound check rests on M1 alone: M(1/2, 1/4, 1/2, 4) of math.md §6 with
//! the tied softmax P2' (c = 1/2) and **one parameter per state** (`examples/toy/m2-tied-two-groups.json`):
//! two states, two parameters θ = (θ_A, θ_B), horizon 4 (32 prefixes).
//!
//! * Row 8c: its constants B_F (exact) and L_F ≥ sup ‖∇²F‖₂ (via ‖mag H‖_F), σ², G², G_F, G_∞ over
//!   the stated box `[−R, R]²`, by 2-D interval branch-and-bound, each certificate re-checked box by
//!   box by the second route ([`crate::certify::recheck`]) and tiled exactly.
//! * Row 1b: the SGD bound (3.27) on it, by Monte Carlo over seeded runs of the kit's SGD with the
//!   exact ∇F at every iterate (enclosed in intervals by the mean-value form on cells,
//!   [`GradientCells`]; the lower end of each run's statistic) and
//!   the decision rule of [`crate::stats`]. The constants hold on the box only, so every iterate of
//!   every run is checked to lie in it; if one leaves, the row says so and is inconclusive.

use crate::bounds::{sgd_constant, sgd_step_admissible, upper};
use crate::certify::box_constants::{ToyConstants, compute};
use crate::certify::recheck::Coverage;
use crate::checks::constants::toy_row;
use crate::checks::montecarlo::GradientCells;
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::stats::{Sample, assess};
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::sgd::{SgdConfig, SgdStep};
use ilopt::algo::{ConfigNumber, IterationMetrics, Runner, StoppingRule, Termination};
use ilopt::problem::EstimatorForm;
use ilopt::scalar::BigRational;
use ilopt::toy::{ToyMdp, ToyProblem};
use std::cell::RefCell;

/// The second toy (see the module docs), read from its toy-MDP file.
///
/// # Panics
/// Never: the file is part of the repository and is valid (a test reads it).
pub fn m2_two_groups() -> ToyMdp {
    ToyMdp::from_json_str(include_str!(
        "../../../examples/toy/m2-tied-two-groups.json"
    ))
    .expect("valid toy file")
}

/// Half-width R of the box `[−R, R]²` the constants of the second toy are bounded on.
pub const BOX_RADIUS: f64 = 8.0;

/// The box `[−R, R]²`.
pub fn domain() -> Vec<[f64; 2]> {
    vec![[-BOX_RADIUS, BOX_RADIUS]; 2]
}

/// Sizes of row 1b.
#[derive(Debug, Clone, Copy)]
pub struct SgdSizes {
    /// Runs R.
    pub runs: usize,
    /// Iterations K.
    pub k: u64,
    /// Step η as a ratio.
    pub eta: (i64, i64),
    /// False-alarm probability.
    pub alpha: f64,
}

/// What R runs of row 1b recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct SgdSample {
    /// Per run, the rigorous lower end of X = (1/K) Σ_k ‖∇F(θ_k)‖².
    pub lows: Vec<f64>,
    /// Per run, the midpoint of X.
    pub mids: Vec<f64>,
    /// Runs with an iterate outside the box.
    pub left: usize,
    /// The largest |θ_i| over all iterates.
    pub farthest: f64,
}

/// R seeded runs of the kit's SGD with constant η from θ₁ on `mdp` (sizes `s`), each reporting
/// X = (1/K) Σ_k ‖∇F(θ_k)‖² (exact ∇F enclosed in intervals) and whether it left `domain`.
///
/// # Errors
/// A message naming the run if a run fails or ∇F cannot be enclosed.
pub fn sgd_sample(
    mdp: &ToyMdp,
    domain: &[[f64; 2]],
    theta1: &[f64],
    s: SgdSizes,
) -> Result<SgdSample, String> {
    let cells = RefCell::new(GradientCells::new(mdp));
    let mut pf = ToyProblem::<f64>::new(mdp);
    let cfg = |seed: u64| RunConfig {
        algorithm: AlgorithmConfig::Sgd(SgdConfig {
            step: SgdStep::constant(ConfigNumber::ratio(s.eta.0, s.eta.1)),
            form: EstimatorForm::Causal,
        }),
        theta0: theta1.iter().map(|t| ConfigNumber::Float(*t)).collect(),
        seed,
        stop: StoppingRule::iterations(s.k - 1),
    };
    let inside = |th: &[f64]| th.iter().zip(domain).all(|(t, [a, b])| a <= t && t <= b);
    let mut out = SgdSample {
        lows: vec![],
        mids: vec![],
        left: 0,
        farthest: 0.0,
    };
    for r in 0..s.runs {
        // (Σ lower ends, Σ midpoints, iterates seen, an iterate outside the box, an error,
        // largest |θ_i|).
        let acc = RefCell::new((0.0f64, 0.0f64, 0u64, false, None::<String>, 0.0f64));
        let observer = |m: &IterationMetrics<f64>| {
            let mut a = acc.borrow_mut();
            let th = m.theta.as_slice();
            a.2 += 1;
            a.5 = th.iter().fold(a.5, |x, t| x.max(t.abs()));
            if !inside(th) {
                a.3 = true;
            }
            match cells.borrow_mut().enclose(th) {
                Ok(g) => {
                    a.0 += g.iter().map(|g| g.mig() * g.mig()).sum::<f64>();
                    a.1 += g.iter().map(|g| g.mid() * g.mid()).sum::<f64>();
                }
                Err(e) => a.4 = Some(e),
            }
        };
        let rec = Runner::new(cfg(r as u64).stop.clone()).and_then(|runner| {
            runner
                .keep_history(false)
                .with_observer(observer)
                .run_config(&cfg(r as u64), &mut pf)
        });
        let (lo, mid, seen, left, err, far) = acc.into_inner();
        out.farthest = out.farthest.max(far);
        match rec {
            Ok(rec) if !matches!(rec.termination, Termination::Diverged(_)) && err.is_none() => {
                if seen != s.k {
                    return Err(format!(
                        "run {r}: {seen} iterates observed, expected {}",
                        s.k
                    ));
                }
                out.left += usize::from(left);
                // The sum's own rounding (relative ≤ K·2⁻⁵³) is absorbed by the factor.
                out.lows.push(lo / s.k as f64 * (1.0 - 1e-9));
                out.mids.push(mid / s.k as f64);
            }
            Ok(rec) => return Err(format!("run {r}: {:?} {err:?}", rec.termination)),
            Err(e) => return Err(format!("run {r}: {e}")),
        }
    }
    Ok(out)
}

/// Row 1b: SGD with constant η from θ₁ on `mdp`, eq. 3.27 in its averaged form
/// `(1/K) Σ_k E‖∇F(θ_k)‖² ≤ Lησ² + 2B_F/(ηK)` (c = 1, σ² = sup Var), with the box constants `k`
/// on `domain`; `claim_scale` < 1 states a deliberately understated bound (a negative control).
pub fn sgd(
    mdp: &ToyMdp,
    name: &str,
    k: &ToyConstants,
    domain: &[[f64; 2]],
    theta1: &[f64],
    s: SgdSizes,
    claim_scale: f64,
) -> Check {
    let sample = sgd_sample(mdp, domain, theta1, s);
    sgd_row(name, k, domain, theta1, s, claim_scale, &sample)
}

/// Row 1b from a sample of [`sgd_sample`], for the bound scaled by `claim_scale`: the verdict by
/// [`assess`] with the statistic's maximum G_F² (so a row whose LCB is ≤ 0 is *uninformative*),
/// inconclusive if an iterate left the box.
pub fn sgd_row(
    name: &str,
    k: &ToyConstants,
    domain: &[[f64; 2]],
    theta1: &[f64],
    s: SgdSizes,
    claim_scale: f64,
    sample: &Result<SgdSample, String>,
) -> Check {
    let (l, s2, bf, gf) = (k.l_f.value, k.sigma2.value, k.b_f.value, k.g_f.value);
    let eta = s.eta.0 as f64 / s.eta.1 as f64;
    let result = "SGD, eq. 3.27 (second toy)";
    let claim = format!(
        "{name}: (1/K) Σ E‖∇F(θ_k)‖² ≤ {}(Lησ² + 2B_F/(ηK)), η = {}/{}, K = {}, θ₁ = {theta1:?}",
        if claim_scale == 1.0 {
            String::new()
        } else {
            format!("{claim_scale}·")
        },
        s.eta.0,
        s.eta.1,
        s.k
    );
    let role = if claim_scale == 1.0 {
        Role::Thesis
    } else {
        Role::NegativeControl
    };
    let id = if claim_scale == 1.0 { "1b" } else { "1b.ctl" };
    let mut row = Check::builder(id, result, claim, role)
        .assumptions([
            format!("(S1) F L-smooth on the box {domain:?}; every iterate is checked to lie in it"),
            "(S2) E g = ∇F, E‖g‖² ≤ σ² + ‖∇F‖² (c = 1)".into(),
            "(S3) fresh τ_k ∼ p(·; θ_k), η ≤ 1/(Lc)".into(),
        ])
        .constants(k.all())
        .decided(Method::Statistical, Verdict::Inconclusive);
    if !sgd_step_admissible(l, 1.0, eta) {
        row.details = format!("side condition η ≤ 1/(Lc) fails: η = {eta}, L = {l}");
        return row;
    }
    let bound = sgd_constant(l, eta, s2, bf, s.k) * claim_scale;
    row.bound = Some(bound);
    let sample = match sample {
        Ok(x) => x,
        Err(e) => {
            row.details = e.clone();
            return row;
        }
    };
    let b = gf * gf * (1.0 + 1e-12);
    let stats = Sample::new(&sample.lows, b);
    let mean_mid = sample.mids.iter().sum::<f64>() / sample.mids.len() as f64;
    let (lcb, ucb) = (stats.lcb(s.alpha), stats.ucb(s.alpha));
    row.measured = Some(
        Measured::statistic(mean_mid)
            .with_interval(lcb, ucb)
            .with_se(stats.se())
            .with_runs(s.runs)
            .with_alpha(s.alpha),
    );
    row.tightness = Some(mean_mid / bound);
    row.verdict = if sample.left > 0 {
        Verdict::Inconclusive
    } else {
        assess(&stats, upper(bound), b, s.alpha)
    };
    // The rule flags exactly the bounds below the LCB; with LCB ≤ 0 it could flag none.
    let power = if lcb > 0.0 {
        format!(
            "it would flag any B < {lcb:.5}, minimum detectable violation (power 0.8) X̄ − LCB + 0.84·SE = {:.5}",
            crate::stats::min_detectable(mean_mid - lcb, stats.se())
        )
    } else {
        "LCB ≤ 0: at this R it could flag no B ≥ 0 (uninformative; the range G_F² dominates)".into()
    };
    row.details = format!(
        "R = {} runs of the kit's SGD; X̄ = {mean_mid:.5}, LCB = {lcb:.5} (max of Hoeffding, empirical Bernstein, betting at α/3 each; α = {:.1e}, range G_F² = {b:.4}), B = {bound:.5}; {power}; Lη = {:.3} ≤ 1; largest |θ_i| over all iterates {:.3}, runs leaving the box {}{}",
        s.runs,
        s.alpha,
        l * eta,
        sample.farthest,
        sample.left,
        if sample.left > 0 {
            " (the box constants do not cover them: inconclusive)"
        } else {
            " (the box constants apply)"
        }
    );
    row
}

/// Sizes of the second toy's rows per profile: branch-and-bound tolerance, which certificate
/// boxes the second route re-checks, and the SGD runs.
#[derive(Debug, Clone, Copy)]
pub struct SecondToySizes {
    /// Branch-and-bound tolerance of the box constants.
    pub tol: f64,
    /// Box budget of each constant's branch-and-bound.
    pub max_boxes: usize,
    /// Boxes re-checked by the second route.
    pub coverage: Coverage,
    /// Row 1b.
    pub sgd: SgdSizes,
}

/// The sizes of a profile. Quick: tolerance 0.1 and 5,000 boxes per constant, a seeded sample of
/// boxes re-checked, R = 200 runs (the range G_F² ≈ 14 puts Hoeffding's and Bernstein's LCB
/// below 0, the betting LCB is ≈ 0.057 at X̄ ≈ 0.062, so the row flags any B below it); full:
/// tolerance 0.02 and 50,000 boxes, every box re-checked, R = 10,000 runs. Both: η = 1/100, K = 2,000 (so B < G_F², the largest value the statistic can
/// take), α = [`crate::protocol::family_level`] (the suite's family-wise level split over its
/// statistical claims, this one included: [`crate::protocol::FAMILY_CLAIMS`]).
pub fn sizes(full: bool) -> SecondToySizes {
    SecondToySizes {
        tol: if full { 0.02 } else { 0.1 },
        max_boxes: if full { 50_000 } else { 5_000 },
        coverage: crate::certify::recheck::coverage_for(full),
        sgd: SgdSizes {
            runs: if full { 10_000 } else { 200 },
            k: 2_000,
            eta: (1, 100),
            alpha: crate::protocol::family_level(),
        },
    }
}

/// Rows 8c (constants on the box, certificates re-checked) and 1b (SGD, eq. 3.27) for the second
/// toy from θ₁ = (0, 0).
///
/// # Errors
/// A message if a constant cannot be enclosed.
pub fn rows(s: SecondToySizes) -> Result<Vec<Check>, String> {
    let m2 = m2_two_groups();
    let dom = domain();
    let zero = BigRational::from_integer(0.into());
    let k = compute(&m2, &[zero.clone(), zero], None, &dom, s.tol, s.max_boxes)
        .map_err(|e| e.to_string())?;
    let name = "M(1/2, 1/4, 1/2, 4), P2' per state (c = 1/2)";
    Ok(vec![
        toy_row(&k, name, &dom, s.coverage, "8c"),
        sgd(&m2, name, &k, &dom, &[0.0, 0.0], s.sgd, 1.0),
    ])
}
