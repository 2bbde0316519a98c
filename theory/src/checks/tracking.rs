//! Rows 2e and 3d: the property the STORM and O2NC proofs rest on, tested along each
//! algorithm's own iterates (math.md §§3.2, 4, 5), at the Monte-Carlo sizes of rows 2c and 3b.
//!
//! **STORM (Theorem S, step 1).** With ε_k = d_k − ∇F(θ_k) the recursion of every STORM variant
//! reads ε_{k+1} = (1 − a_{k+1}) ε_k + u_{k+1}, and the proof needs the increment
//! `u_{k+1} = a W + (1 − a) Z` to have conditional mean zero given the past F_k (W = g(θ_{k+1}, τ_{k+1})
//! − ∇F(θ_{k+1}), Z = g(θ_{k+1}, τ_{k+1}) − g̃_k − ∇F(θ_{k+1}) + ∇F(θ_k)); that is what makes
//! E ε_k = 0 for every k. It holds for IS-STORM (identity I3); without the weight the old-point term
//! has bias b(θ_k, θ_{k+1}) = O(η_k‖d_k‖) along the step (E10); the printed Algorithm 4 (E9) adds
//! (1 − a)(2∇F(θ_k) − d_k) to it. The row tests H₀: E[h_k u_{k+1} | F_k] = 0 with the predictable
//! sign h_k = sign(d_k) (the old-point bias points along the step θ_{k+1} − θ_k = −η_k d_k).
//!
//! **O2NC (Theorem 3.7).** The proof needs E[g_n | Δ_n, F_{n−1}] = ∇F(w_n); it holds when
//! τ_n ∼ p(·; w_n) and not for the printed τ_n ∼ p(·; θ_n) (E11), whose bias is
//! O(‖θ_n − w_n‖) = O((1 − s_n)‖Δ_n‖) along Δ_n. The row tests H₀: E[h_n (g_n − ∇F(w_n)) | Δ_n, F_{n−1}] = 0
//! with h_n = sign(θ_n − θ_{n−1}) = sign(Δ_n).
//!
//! **Decision.** Each step's value is normalised by a bound c on |u| (resp. |g_n − ∇F(w_n)|) that
//! follows from the algorithm's update and the global constants alone (see [`StormRange`]), so
//! z = h u / c ∈ [−1, 1]. Under H₀ the z of all runs, concatenated in the order they were drawn, are
//! martingale differences, so Azuma–Hoeffding and the betting bound of [`crate::stats`] (both valid
//! for bounded martingale differences; empirical Bernstein is not used) give a two-sided interval
//! ([`ZeroMeanTest`]). Testing the R·K increments sequentially rather than one average per run is
//! what gives the rows power: a run's average has the range of a single step but a spread √K
//! smaller, and a range-limited test of R = 100 averages cannot resolve a mean below ≈ 0.17 of the
//! range. Exact ∇F at the iterates is enclosed in intervals (forward DP); the lower ends of the
//! enclosures give the LCB and the upper ends the UCB. The decision "0 is outside the interval" is
//! what carries the level α; when the conditional means vary along the runs (as under the
//! alternative), the betting bound reflects the stretches where the capital grew and the interval
//! need not contain z̄.

use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::stats::ZeroMeanTest;
use ilopt::scalar::{Interval, Scalar};

/// The largest probability ratio of the tied rational softmax P2' on M1 (rounded up): every
/// probability lies in [(3 − √3)/6, (3 + √3)/6], so a one-factor prefix weight (T = 3) is at most
/// (3 + √3)/(3 − √3) = 2 + √3.
pub const M1_WEIGHT_MAX: f64 = 3.732_050_807_568_878;

/// The per-step values of a tracking row: enclosures (`lows[i]`, `highs[i]`) of z = h u / c, in the
/// order they were drawn (runs concatenated).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tracking {
    /// Lower ends.
    pub lows: Vec<f64>,
    /// Upper ends.
    pub highs: Vec<f64>,
    /// Runs recorded.
    pub runs: usize,
}

impl Tracking {
    /// Record one step's enclosure of h·x / c, clamped to [−1, 1] (a no-op under H₀, where
    /// |x| ≤ c).
    fn push(&mut self, h: f64, x: Interval, c: f64) {
        if h == 0.0 {
            self.lows.push(0.0);
            self.highs.push(0.0);
            return;
        }
        let z = x.product(&Interval::try_from((h, h)).unwrap_or(Interval::ENTIRE))
            / Interval::try_from((c, c)).unwrap_or(Interval::ENTIRE);
        self.lows.push(z.inf().clamp(-1.0, 1.0));
        self.highs.push(z.sup().clamp(-1.0, 1.0));
    }
}

/// The momentum a_{k+1} = (7/(k+7))^{2/3} of schedule (3.43) for the step k → k + 1, computed as
/// the kit's `f64` STORM computes it (`r = ∛(7/(k+7))`, `a = r²`), and 1 − a.
pub fn one_minus_a(k: u64) -> f64 {
    let r = (7.0 / (k as f64 + 7.0)).cbrt();
    1.0 - r * r
}

/// A bound on |u_{k+1}| from the update rule alone (the algorithm's own, since each row tests its
/// algorithm), with G_∞ ≥ sup |g|, G_F ≥ sup |∇F|:
/// * STORM recursion d_{k+1} = g_new + (1 − a)(d_k − g̃_k) with |g̃_k| ≤ W:
///   u_{k+1} = W_{k+1} + (1 − a)(∇F(θ_k) − g̃_k), so |u_{k+1}| ≤ G_∞ + G_F + (1 − a)(G_F + W);
/// * printed Algorithm 4, d_{k+1} = g_new + (1 − a) g(θ_k, τ_{k+1}), |d_k| ≤ 2G_∞:
///   u_{k+1} = g_new − ∇F(θ_{k+1}) + (1 − a)(g_old − ε_k), so
///   |u_{k+1}| ≤ G_∞ + G_F + (1 − a)(3G_∞ + G_F).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StormRange {
    /// The STORM recursion with an old-point term bounded by `w` (G_∞ unweighted, w_max·G_∞ with
    /// the trajectory weight, w_max·G_closed per decision).
    Recursion {
        /// W ≥ sup |g̃|.
        w: f64,
    },
    /// The printed Algorithm 4 update (E9).
    Printed,
}

/// The momenta a_{k+1} of the runs a tracker follows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Momentum {
    /// Schedule (3.43), as [`one_minus_a`].
    Thesis,
    /// A constant a ∈ [0, 1] (the kit's `constant` schedule).
    Constant(f64),
}

impl Momentum {
    /// 1 − a_{k+1} for the step k → k + 1.
    pub fn one_minus_a(self, k: u64) -> f64 {
        match self {
            Momentum::Thesis => one_minus_a(k),
            Momentum::Constant(a) => 1.0 - a,
        }
    }
}

impl StormRange {
    /// The bound on |u_{k+1}| for the step k → k + 1 of schedule (3.43) (rounded up).
    pub fn bound(self, k: u64, g_inf: f64, g_f: f64) -> f64 {
        self.bound_with(one_minus_a(k), g_inf, g_f)
    }

    /// The bound on |u_{k+1}| for a step with momentum 1 − a = `oma` (rounded up).
    pub fn bound_with(self, oma: f64, g_inf: f64, g_f: f64) -> f64 {
        let oma = oma.clamp(0.0, 1.0);
        let c = match self {
            StormRange::Recursion { w } => g_inf + g_f + oma * (g_f + w),
            StormRange::Printed => g_inf + g_f + oma * (3.0 * g_inf + g_f),
        };
        c * (1.0 + 1e-12)
    }
}

/// Accumulates the STORM tracking values of one algorithm over runs.
#[derive(Debug, Clone)]
pub struct StormTracker {
    range: StormRange,
    momentum: Momentum,
    g_inf: f64,
    g_f: f64,
    /// (k, d_k, enclosure of ε_k) of the last observed iterate.
    prev: Option<(u64, f64, Interval)>,
    /// The values recorded so far.
    pub tracking: Tracking,
}

impl StormTracker {
    /// A tracker for an algorithm with schedule (3.43) whose |u| is bounded by `range` with these
    /// constants.
    pub fn new(range: StormRange, g_inf: f64, g_f: f64) -> Self {
        Self::with_momentum(range, Momentum::Thesis, g_inf, g_f)
    }

    /// As [`StormTracker::new`] for runs with the given momenta.
    pub fn with_momentum(range: StormRange, momentum: Momentum, g_inf: f64, g_f: f64) -> Self {
        Self {
            range,
            momentum,
            g_inf,
            g_f,
            prev: None,
            tracking: Tracking::default(),
        }
    }

    /// Start a new run.
    pub fn start_run(&mut self) {
        self.prev = None;
        self.tracking.runs += 1;
    }

    /// The iterate θ_k with direction d_k and ∇F(θ_k) ∈ `grad` (k ≥ 1 in the algorithm's
    /// numbering; the runner reports θ_{k+1}, d_{k+1} after step k). Records z for the pair
    /// (k − 1, k) when the previous iterate was observed.
    pub fn observe(&mut self, k: u64, d: f64, grad: Interval) {
        let eps = Interval::try_from((d, d)).unwrap_or(Interval::ENTIRE) - grad;
        if let Some((j, d_prev, eps_prev)) = self.prev
            && j + 1 == k
        {
            let oma = self.momentum.one_minus_a(j);
            let u = eps
                - Interval::try_from((oma, oma))
                    .unwrap_or(Interval::ENTIRE)
                    .product(&eps_prev);
            let c = self.range.bound_with(oma, self.g_inf, self.g_f);
            self.tracking.push(sign(d_prev), u, c);
        }
        self.prev = Some((k, d, eps));
    }
}

/// Accumulates the O2NC tracking values over runs.
#[derive(Debug, Clone)]
pub struct O2ncTracker {
    /// c = G_∞ + G_F ≥ |g_n − ∇F(w_n)| (rounded up).
    c: f64,
    /// θ_{n−1}.
    prev_theta: Option<f64>,
    /// The values recorded so far.
    pub tracking: Tracking,
}

impl O2ncTracker {
    /// A tracker with |g| ≤ `g_inf`, |∇F| ≤ `g_f`.
    pub fn new(g_inf: f64, g_f: f64) -> Self {
        Self {
            c: (g_inf + g_f) * (1.0 + 1e-12),
            prev_theta: None,
            tracking: Tracking::default(),
        }
    }

    /// Start a new run from θ₀.
    pub fn start_run(&mut self, theta0: f64) {
        self.prev_theta = Some(theta0);
        self.tracking.runs += 1;
    }

    /// Step n: θ_n, the evaluation point w_n, g_n = g(w_n, τ_n) and ∇F(w_n) ∈ `grad`.
    pub fn observe(&mut self, theta: f64, g: f64, grad: Interval) {
        let h = self.prev_theta.map_or(0.0, |p| sign(theta - p));
        let e = Interval::try_from((g, g)).unwrap_or(Interval::ENTIRE) - grad;
        self.tracking.push(h, e, self.c);
        self.prev_theta = Some(theta);
    }

    /// The range c.
    pub fn range(&self) -> f64 {
        self.c
    }
}

fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// What a tracking row states about its algorithm.
#[derive(Debug, Clone)]
pub struct TrackingSpec {
    /// Row id.
    pub id: String,
    /// The thesis result.
    pub result: String,
    /// The claim (H₀).
    pub claim: String,
    /// Assumptions, the range's derivation first.
    pub assumptions: Vec<String>,
    /// Role in the table.
    pub role: Role,
    /// Erratum.
    pub erratum: String,
    /// Free text prepended to the numbers.
    pub context: String,
}

/// The row of a tracking test from its recorded values at level `alpha` (two-sided): fails if 0 is
/// outside the interval, uninformative if the interval's half-width is the whole range.
pub fn row(spec: TrackingSpec, tracking: &Result<Tracking, String>, alpha: f64) -> Check {
    let header = Check::builder(spec.id, spec.result, spec.claim, spec.role)
        .assumptions(spec.assumptions)
        .erratum(spec.erratum);
    let t = match tracking {
        Ok(t) if t.lows.len() >= 2 => t,
        Ok(_) => {
            return header
                .details("fewer than two recorded steps")
                .decided(Method::Statistical, Verdict::Inconclusive);
        }
        Err(e) => {
            return header
                .details(e.clone())
                .decided(Method::Statistical, Verdict::Inconclusive);
        }
    };
    let test = ZeroMeanTest::new(&t.lows, &t.highs, 1.0, alpha);
    let verdict = test.verdict();
    let mdb = test.min_detectable_bias();
    header
        .measured(
            Measured::statistic(test.mean)
                .with_interval(test.lcb, test.ucb)
                .with_se(test.se)
                .with_runs(t.runs)
                .with_alpha(alpha),
        )
        .details(format!(
            "{}; {} runs, {} steps; z̄ = {:.3e}, two-sided {:.2}% interval [{:.3e}, {:.3e}]{} (Azuma–Hoeffding ∨ betting at α/4 each per side, valid for martingale differences; α = {:.1e}), range [−1, 1] (z = h·x/c); minimum detectable bias {:.3e} (in units of c; at power 0.8: half-width + 0.84·SE, SE = {:.2e}) → {}",
            spec.context,
            t.runs,
            t.lows.len(),
            test.mean,
            100.0 * (1.0 - alpha),
            test.lcb,
            test.ucb,
            if test.lcb > test.ucb {
                ", whose one-sided bounds cross (the lower above the upper: no constant mean fits the runs)"
            } else {
                ""
            },
            alpha,
            mdb,
            test.se,
            match (verdict, test.lcb > test.mean || test.ucb < test.mean) {
                (Verdict::Fails, true) =>
                    "mean ≠ 0: the property fails along these iterates (the conditional means vary along the runs, so the betting interval need not contain z̄; the decision, 0 outside it, is what carries α)",
                (Verdict::Fails, false) => "mean ≠ 0: the property fails along these iterates",
                (Verdict::Holds, _) => "no evidence against mean 0",
                (Verdict::Uninformative, _) => "the interval spans the range (no power)",
                (Verdict::Inconclusive, _) => "inconclusive",
            }
        ))
        .decided(Method::Statistical, verdict)
}

/// Whether tracking row `row` resolves, at its size, the error `erratum` of a wrong algorithm
/// run through the same check (`wrong`: its probe or control, same sizes and level). The bias the
/// wrong algorithm shows through the check is its measured |z̄| (the right algorithm's mean is
/// 0), in the check's own normalisation on that algorithm; the check resolves it when that bias
/// is at least the minimum detectable bias of the check there (half-width + z_{0.8}·SE,
/// [`crate::stats::min_detectable`]), and is *uninformative for* the erratum otherwise. The
/// label is appended to the row's claim and details and recorded for the power list
/// ([`Measured::resolution`]); the verdict on the row's own claim is unchanged.
pub fn label_resolution(row: &mut Check, wrong: &Check, erratum: &str) {
    let seen = wrong.measured.as_ref().and_then(|m| {
        let (lcb, ucb, se) = (m.lcb?, m.ucb?, m.se?);
        let half = (m.value - lcb).max(ucb - m.value);
        Some((m.value.abs(), crate::stats::min_detectable(half, se)))
    });
    let label = match seen {
        Some((bias, mdb)) if bias >= mdb => format!(
            "resolves {erratum} at this size: the bias through this check of {} is |z̄| = {bias:.2e} ≥ its minimum detectable bias {mdb:.2e}",
            wrong.id
        ),
        Some((bias, mdb)) => format!(
            "uninformative for {erratum} at this size: the bias through this check of {} is |z̄| = {bias:.2e} < its minimum detectable bias {mdb:.2e}",
            wrong.id
        ),
        None => format!(
            "resolution of {erratum} unknown: row {} has no interval",
            wrong.id
        ),
    };
    row.claim = format!("{} ({label})", row.claim);
    row.details = format!("{}; {label}", row.details);
    if let Some(m) = row.measured.as_mut() {
        m.resolution = Some(label);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measured(id: &str, mean: f64, half: f64, se: f64, role: Role) -> Check {
        Check::builder(id, "r", "c", role)
            .measured(
                Measured::statistic(mean)
                    .with_interval(mean - half, mean + half)
                    .with_se(se),
            )
            .decided(Method::Statistical, Verdict::Holds)
    }

    /// A row whose wrong algorithm's bias is below the check's minimum detectable bias is
    /// labelled uninformative for the erratum, one above it resolves it; the verdict is kept.
    #[test]
    fn a_tracking_row_is_labelled_by_what_it_resolves() {
        let mut row = measured("2e", 2e-6, 1e-5, 3e-6, Role::Corrected);
        label_resolution(
            &mut row,
            &measured("2e.unweighted", 4.6e-6, 1.2e-5, 3e-6, Role::Probe),
            "E10",
        );
        assert!(
            row.claim.contains("uninformative for E10 at this size"),
            "{}",
            row.claim
        );
        assert!(row.claim.contains("2e.unweighted"), "{}", row.claim);
        assert_eq!(row.verdict, Verdict::Holds);
        let m = row.measured.as_ref().expect("measured");
        assert!(
            m.resolution
                .as_deref()
                .is_some_and(|r| r.starts_with("uninformative for E10"))
        );
        let mut wide = measured("2e.c", -6e-5, 3.6e-4, 1e-5, Role::Corrected);
        label_resolution(
            &mut wide,
            &measured(
                "2e.c.unweighted",
                1.1e-3,
                5.3e-4,
                1e-5,
                Role::NegativeControl,
            ),
            "E10",
        );
        assert!(
            wide.details.contains("resolves E10 at this size"),
            "{}",
            wide.details
        );
        let mut none = measured("3d", 0.0, 1e-3, 1e-4, Role::Corrected);
        let bare = Check::builder("3d.printed5", "r", "c", Role::Probe)
            .decided(Method::Statistical, Verdict::Inconclusive);
        label_resolution(&mut none, &bare, "E11");
        assert!(
            none.claim.contains("resolution of E11 unknown"),
            "{}",
            none.claim
        );
    }
}
