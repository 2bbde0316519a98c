//! Decisions with a stated false-alarm probability (math.md §7.3).
//!
//! R i.i.d. runs give X_r ∈ [0, b]; H₀ is the theorem, E X ≤ B. A violation is flagged only when a
//! *lower confidence bound* on E X exceeds B, so P_{H₀}(flag) ≤ α:
//! * Hoeffding: `LCB = X̄ − b √(ln(1/α)/(2R))`;
//! * empirical Bernstein (Maurer & Pontil 2009, Thm 4): `LCB = X̄ − √(2V ln(2/α)/R) − 7b ln(2/α)/(3(R−1))`;
//! * betting (Waudby-Smith & Ramdas 2024, *Estimating means of bounded random variables by
//!   betting*, JRSS-B): for a candidate mean m the capital `K_t(m) = Π_{i≤t} (1 + λ_i(m)(X_i − m))`,
//!   with a predictable bet `λ_i(m) = min(λ̂_i, c/m) ≥ 0`, is a non-negative supermartingale when
//!   E X ≤ m, so by Ville's inequality `P(max_t K_t(m) ≥ 1/α) ≤ α`. Every factor is non-increasing
//!   in m (for X ≥ 0), so the rejected m form an interval [0, LCB) and LCB is found by bisection.
//!   Its width is ≈ √(2V ln(1/α)/R): unlike Bernstein it pays no range term of order b/R, which
//!   matters when X̄ ≪ b (the bounds here are loose, so X̄ is 1–5 % of b).
//!
//! The kit uses the largest of the three at level α/3 each (a union bound keeps the level α).
//! A row flags every claimed bound B < LCB, that is every B exceeded by the measured mean by more
//! than the interval's width `w = X̄ − LCB`.
//!
//! **Minimum detectable effect** (one definition for every statistical row of the table,
//! [`min_detectable`]): the smallest violation (a true mean above B, or a bias of a mean claimed
//! to be 0) that the row flags with probability at least [`POWER`] = 0.8, in the normal
//! approximation `X̄ ≈ N(μ, SE²)` with the width w held fixed: `w + z_{0.8}·SE`, z_{0.8} =
//! Φ⁻¹(0.8) = 0.8416, SE the standard error of X̄. (`w` alone is detected only half the time.)
//! For a z-test at critical value z_crit (the real-environment rows) w = z_crit·SE, so it is
//! `(z_crit + z_{0.8})·SE`.
//!
//! A row whose LCB is ≤ 0, or whose B is at least the largest value the statistic can take, could
//! flag no bound it states: it is *uninformative* ([`assess`]). Suites split α by Bonferroni.

use crate::record::check::{Measured, Verdict};
use serde::{Deserialize, Serialize};

/// The power at which the table states every statistical row's minimum detectable effect.
pub const POWER: f64 = 0.8;

/// Φ⁻¹([`POWER`]): the standard normal quantile at the stated power.
pub const POWER_Z: f64 = 0.841_621_233_572_914_3;

/// The minimum detectable effect at power [`POWER`] (module docs): a row that flags every
/// effect above `width` (X̄ − LCB, or the larger half of a two-sided interval) flags, with
/// probability ≥ 0.8 in the normal approximation, every true effect of at least
/// `width + z_{0.8}·se`, `se` the standard error of the mean.
pub fn min_detectable(width: f64, se: f64) -> f64 {
    width + POWER_Z * se
}

/// The standard error `s/√n` of the mean of `xs` (0 for fewer than two values).
pub fn standard_error(xs: &[f64]) -> f64 {
    let n = xs.len();
    if n < 2 {
        return 0.0;
    }
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (var / n as f64).sqrt()
}

/// Summary of R runs of a per-run statistic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// R.
    pub runs: usize,
    /// X̄.
    pub mean: f64,
    /// Unbiased sample variance.
    pub variance: f64,
    /// The a-priori range bound b (X ∈ [0, b]).
    pub range: f64,
    /// The runs in the order they were drawn (the betting bound is sequential).
    #[serde(skip)]
    pub values: Vec<f64>,
}

impl Sample {
    /// Summarise `xs` (each in [0, b]).
    ///
    /// # Panics
    /// If fewer than two runs are given (a programming error of the caller).
    pub fn new(xs: &[f64], range: f64) -> Self {
        assert!(xs.len() >= 2, "need at least two runs");
        let r = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / r;
        let variance = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r - 1.0);
        Self {
            runs: xs.len(),
            mean,
            variance,
            range,
            values: xs.to_vec(),
        }
    }

    /// Hoeffding lower confidence bound at level α.
    pub fn hoeffding_lcb(&self, alpha: f64) -> f64 {
        self.mean - self.range * ((1.0 / alpha).ln() / (2.0 * self.runs as f64)).sqrt()
    }

    /// Empirical-Bernstein lower confidence bound at level α (Maurer & Pontil 2009, Thm 4).
    pub fn bernstein_lcb(&self, alpha: f64) -> f64 {
        let r = self.runs as f64;
        let l = (2.0 / alpha).ln();
        self.mean - (2.0 * self.variance * l / r).sqrt() - 7.0 * self.range * l / (3.0 * (r - 1.0))
    }

    /// Whether the betting test rejects "E X ≤ m" at level α: `max_t K_t(m) ≥ 1/α` (see the
    /// module docs). The bet is `λ_t = min(λ̂_t, c/m)` with c = 1/2 and the predictable plug-in
    /// `λ̂_t = √(2 ln(1/α) / (R σ̂²_{t−1}))`, σ̂²_{t−1} the running variance of the first t − 1 runs
    /// (with a small prior, 10⁻⁶b², so the first bets are finite). The threshold carries a relative
    /// margin of 10⁻⁹ for the rounding of the product (≤ R ulps).
    pub fn betting_rejects(&self, m: f64, alpha: f64) -> bool {
        self.rejects_with(m, alpha, &self.plug_in_bets(alpha))
    }

    /// The predictable plug-in bets `λ̂_t = √(2 ln(1/α) / (R σ̂²_{t−1}))` of
    /// [`Sample::betting_rejects`], one per run; they do not depend on the candidate m.
    fn plug_in_bets(&self, alpha: f64) -> Vec<f64> {
        let r = self.values.len() as f64;
        let log_term = 2.0 * (1.0 / alpha).ln();
        let prior = 1e-6 * self.range * self.range;
        let (mut sum, mut sq, mut t) = (0.0f64, prior, 0.0f64);
        let mut bets = Vec::with_capacity(self.values.len());
        for &x in &self.values {
            let x = x.max(0.0);
            let var = sq / (t + 1.0);
            bets.push((log_term / (r * var)).sqrt());
            // Running mean before this run, then the squared deviation from it (predictable).
            let mean_before = if t > 0.0 { sum / t } else { x };
            sq += (x - mean_before).powi(2);
            sum += x;
            t += 1.0;
        }
        bets
    }

    /// The betting test for candidate `m` with the plug-in `bets` of [`Sample::plug_in_bets`].
    fn rejects_with(&self, m: f64, alpha: f64, bets: &[f64]) -> bool {
        if m <= 0.0 {
            // Every X ≥ 0, so "E X ≤ 0" is refuted by any positive run only in the limit; a
            // non-positive bound is handled by the caller (the statistic's lower end is ≥ 0).
            return false;
        }
        let threshold = (1.0 / alpha) * (1.0 + 1e-9);
        let cap = 0.5 / m;
        let mut capital = 1.0f64;
        for (&x, &bet) in self.values.iter().zip(bets) {
            // X ≥ 0 is what makes every factor positive; a value rounded below 0 counts as 0
            // (which only lowers the capital).
            let x = x.max(0.0);
            capital *= 1.0 + bet.min(cap) * (x - m);
            if capital >= threshold {
                return true;
            }
        }
        false
    }

    /// Betting lower confidence bound at level α: the supremum of the rejected m (bisection,
    /// 100 steps, returning a rejected m, so every B ≤ it is rejected too). 0 if none is rejected.
    pub fn betting_lcb(&self, alpha: f64) -> f64 {
        let bets = self.plug_in_bets(alpha);
        let (mut lo, mut hi) = (0.0f64, self.range.max(self.mean));
        if self.rejects_with(hi, alpha, &bets) {
            return hi;
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.rejects_with(mid, alpha, &bets) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The decision rule's LCB: the largest of Hoeffding, empirical Bernstein and betting at
    /// α/3 each.
    pub fn lcb(&self, alpha: f64) -> f64 {
        let a = alpha / 3.0;
        self.hoeffding_lcb(a)
            .max(self.bernstein_lcb(a))
            .max(self.betting_lcb(a))
    }

    /// A lower confidence bound at level α that stays valid when the values are bounded
    /// martingale differences around their conditional means (each E[X_t | X_1..X_{t−1}] ≥ the
    /// bound): the larger of Azuma–Hoeffding (the Hoeffding formula) and betting (Ville's
    /// inequality), at α/2 each.
    pub fn martingale_lcb(&self, alpha: f64) -> f64 {
        let a = alpha / 2.0;
        self.hoeffding_lcb(a).max(self.betting_lcb(a))
    }

    /// The matching upper bound: [`Sample::martingale_lcb`] applied to b − X.
    pub fn martingale_ucb(&self, alpha: f64) -> f64 {
        let mirrored: Vec<f64> = self.values.iter().map(|x| self.range - x).collect();
        self.range - Sample::new(&mirrored, self.range).martingale_lcb(alpha)
    }

    /// The standard error of the mean, `√(V/R)`.
    pub fn se(&self) -> f64 {
        (self.variance / self.runs as f64).sqrt()
    }

    /// The minimum detectable violation at power [`POWER`]: `(X̄ − LCB) + z_{0.8}·SE`
    /// ([`min_detectable`]). The row flags a claimed bound B exactly when the measured mean
    /// exceeds B by more than X̄ − LCB; a true mean above B by this much is flagged with
    /// probability ≥ 0.8.
    pub fn min_detectable_violation(&self, alpha: f64) -> f64 {
        min_detectable(self.mean - self.lcb(alpha), self.se())
    }

    /// The matching upper confidence bound at level α: the three bounds applied to b − X (each
    /// at α/3), the smallest taken.
    pub fn ucb(&self, alpha: f64) -> f64 {
        let mirrored: Vec<f64> = self.values.iter().map(|x| self.range - x).collect();
        self.range - Sample::new(&mirrored, self.range).lcb(alpha)
    }
}

impl Measured {
    /// The mean of `sample` with the decision rule's confidence bounds at level `alpha`
    /// ([`Sample::lcb`], [`Sample::ucb`]), its standard error, the number of runs and α.
    pub fn from_sample(sample: &Sample, alpha: f64) -> Self {
        Measured::statistic(sample.mean)
            .with_interval(sample.lcb(alpha), sample.ucb(alpha))
            .with_se(sample.se())
            .with_runs(sample.runs)
            .with_alpha(alpha)
    }
}

/// Outcome of testing H₀: E X ≤ B.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decision {
    /// LCB ≤ B: no evidence against the bound.
    Consistent,
    /// LCB > B: the bound is violated with confidence 1 − α.
    Violated,
}

/// Test H₀: E X ≤ `bound` at level α.
pub fn decide(sample: &Sample, bound: f64, alpha: f64) -> Decision {
    if sample.lcb(alpha) > bound {
        Decision::Violated
    } else {
        Decision::Consistent
    }
}

/// The verdict of a statistical row on H₀: E X ≤ `bound`, where X can take no value above
/// `statistic_max` (a certified supremum, e.g. G_F² for a mean of ‖∇F‖²):
/// * [`Verdict::Fails`] if LCB > `bound` (violated with confidence 1 − α);
/// * [`Verdict::Uninformative`] otherwise, if LCB ≤ 0 (the row could flag no non-negative bound)
///   or `bound ≥ statistic_max` (no distribution of X could violate it);
/// * [`Verdict::Holds`] otherwise: the row could have flagged any B < LCB and did not flag B.
pub fn assess(sample: &Sample, bound: f64, statistic_max: f64, alpha: f64) -> Verdict {
    let lcb = sample.lcb(alpha);
    if lcb > bound {
        Verdict::Fails
    } else if lcb <= 0.0 || bound >= statistic_max {
        Verdict::Uninformative
    } else {
        Verdict::Holds
    }
}

/// A two-sided confidence interval for E X, where every run's X lies in [−c, c] (a certified
/// range), for testing H₀: E X = 0 (the tracking rows, [`crate::checks::tracking`]).
///
/// The bounds valid for bounded martingale differences ([`Sample::martingale_lcb`]: Azuma–Hoeffding
/// and betting; not empirical Bernstein, which needs independence) are applied to
/// Y = X + c ∈ [0, 2c] at α/2 per side, so P_{H₀}(0 ∉ [LCB, UCB]) ≤ α whether the values are
/// i.i.d. runs or the steps of runs whose conditional means are 0. Each value is known as an enclosure
/// [lower, upper] (exact gradients in interval arithmetic); the LCB uses the lower ends and the
/// UCB the upper ends, so rounding can never exclude 0 spuriously.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZeroMeanTest {
    /// R.
    pub runs: usize,
    /// X̄ (midpoints of the enclosures).
    pub mean: f64,
    /// Lower confidence bound on E X at level α/2.
    pub lcb: f64,
    /// Upper confidence bound on E X at level α/2.
    pub ucb: f64,
    /// The certified range c (|X| ≤ c).
    pub range: f64,
    /// α (both sides together).
    pub alpha: f64,
    /// The standard error of X̄ (the midpoints' s/√R).
    pub se: f64,
}

impl ZeroMeanTest {
    /// The interval from the runs' enclosures `lows[r] ≤ X_r ≤ highs[r]`, each in [−c, c].
    ///
    /// # Panics
    /// If fewer than two runs are given or the two lists differ in length.
    pub fn new(lows: &[f64], highs: &[f64], c: f64, alpha: f64) -> Self {
        assert_eq!(lows.len(), highs.len(), "one enclosure per run");
        let shift =
            |xs: &[f64]| -> Vec<f64> { xs.iter().map(|x| (x + c).clamp(0.0, 2.0 * c)).collect() };
        let lo = Sample::new(&shift(lows), 2.0 * c);
        let hi = Sample::new(&shift(highs), 2.0 * c);
        let mids: Vec<f64> = lows.iter().zip(highs).map(|(a, b)| 0.5 * (a + b)).collect();
        let mean = mids.iter().sum::<f64>() / mids.len() as f64;
        Self {
            runs: lows.len(),
            mean,
            lcb: lo.martingale_lcb(alpha / 2.0) - c,
            ucb: hi.martingale_ucb(alpha / 2.0) - c,
            range: c,
            alpha,
            se: standard_error(&mids),
        }
    }

    /// The larger distance from X̄ to an end of the interval: a mean shifted by more than this
    /// (either way) moves the interval off 0.
    pub fn half_width(&self) -> f64 {
        (self.mean - self.lcb).max(self.ucb - self.mean)
    }

    /// The minimum detectable bias at power [`POWER`]: [`ZeroMeanTest::half_width`] +
    /// z_{0.8}·SE ([`min_detectable`]).
    pub fn min_detectable_bias(&self) -> f64 {
        min_detectable(self.half_width(), self.se)
    }

    /// The verdict on H₀: E X = 0:
    /// * [`Verdict::Fails`] if 0 ∉ [LCB, UCB] (the mean is non-zero with confidence 1 − α);
    /// * [`Verdict::Uninformative`] otherwise, if the half-width is ≥ c (no mean the statistic
    ///   can have could be flagged);
    /// * [`Verdict::Holds`] otherwise.
    pub fn verdict(&self) -> Verdict {
        if self.lcb > 0.0 || self.ucb < 0.0 {
            Verdict::Fails
        } else if self.half_width() >= self.range {
            Verdict::Uninformative
        } else {
            Verdict::Holds
        }
    }
}

/// Bonferroni: the per-check level for m checks at family level α.
pub fn bonferroni(alpha: f64, m: usize) -> f64 {
    alpha / m.max(1) as f64
}

/// The standard normal upper quantile Φ⁻¹(1 − p) = −Φ⁻¹(p) for 0 < p < 1/2 (statrs' inverse
/// CDF, taken at p so that small p keeps its precision).
pub fn normal_upper_quantile(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    -Normal::standard().inverse_cdf(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_a_clear_violation_and_not_a_clear_compliance() {
        let xs: Vec<f64> = (0..400)
            .map(|i| 0.5 + 0.1 * ((i % 7) as f64 / 7.0))
            .collect();
        let s = Sample::new(&xs, 1.0);
        assert_eq!(decide(&s, 0.3, 1e-3), Decision::Violated);
        assert_eq!(decide(&s, 0.6, 1e-3), Decision::Consistent);
        assert!(s.lcb(1e-3) < s.mean && s.mean < s.ucb(1e-3));
    }

    /// The false-alarm rate under H₀ (E X = B exactly) stays below α (simulated, seeded).
    #[test]
    fn false_alarm_rate_is_below_alpha() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let (alpha, trials) = (0.05, 2000);
        let mut alarms = 0;
        for _ in 0..trials {
            // Bernoulli(0.3) has mean 0.3 = B.
            let xs: Vec<f64> = (0..50)
                .map(|_| f64::from(u8::from(rng.random::<f64>() < 0.3)))
                .collect();
            if decide(&Sample::new(&xs, 1.0), 0.3, alpha) == Decision::Violated {
                alarms += 1;
            }
        }
        assert!(f64::from(alarms) / f64::from(trials) <= alpha, "{alarms}");
    }

    /// The betting test's false-alarm rate at the boundary E X = B stays below α, for a
    /// low-variance statistic far below its range (the regime of the bound checks) and for a
    /// Bernoulli one.
    #[test]
    fn betting_false_alarm_rate_is_below_alpha() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let (alpha, trials) = (0.05, 2000);
        let mut alarms = [0u32; 2];
        for _ in 0..trials {
            // Uniform on [0.008, 0.012]: mean 0.01, range b = 1.
            let xs: Vec<f64> = (0..100)
                .map(|_| 0.008 + 0.004 * rng.random::<f64>())
                .collect();
            alarms[0] += u32::from(Sample::new(&xs, 1.0).betting_rejects(0.01, alpha));
            let ys: Vec<f64> = (0..100)
                .map(|_| f64::from(u8::from(rng.random::<f64>() < 0.3)))
                .collect();
            alarms[1] += u32::from(Sample::new(&ys, 1.0).betting_rejects(0.3, alpha));
        }
        for a in alarms {
            assert!(f64::from(a) / f64::from(trials) <= alpha, "{alarms:?}");
        }
    }

    /// Where X̄ ≪ b the betting bound is far sharper than Bernstein's (whose range term
    /// 7b ln(2/α)/(3(R − 1)) exceeds X̄ here), and the rejected bounds are exactly those below it.
    #[test]
    fn betting_bound_is_sharp_for_small_means_and_consistent() {
        let xs: Vec<f64> = (0..100)
            .map(|i| 0.01 + 0.002 * ((i % 5) as f64 - 2.0))
            .collect();
        let s = Sample::new(&xs, 1.0);
        assert!(s.bernstein_lcb(1e-3) < 0.0);
        let b = s.betting_lcb(1e-3);
        assert!(b > 0.008 && b < 0.01, "{b}");
        assert!(s.betting_rejects(b, 1e-3) && !s.betting_rejects(b * 1.001, 1e-3));
        assert_eq!(assess(&s, 0.5 * b, 1.0, 1e-3), Verdict::Fails);
        assert_eq!(assess(&s, 0.02, 1.0, 1e-3), Verdict::Holds);
        // A bound at or above the statistic's maximum cannot be refuted: uninformative.
        assert_eq!(assess(&s, 1.0, 1.0, 1e-3), Verdict::Uninformative);
        // Too few runs for a positive LCB: uninformative.
        let few = Sample::new(&[0.0, 0.01], 1.0);
        assert!(few.lcb(1e-3) <= 0.0);
        assert_eq!(assess(&few, 0.02, 1.0, 1e-3), Verdict::Uninformative);
    }

    /// The minimum detectable violation is detected with probability ≈ [`POWER`]: samples whose
    /// true mean exceeds B by it are flagged in about 80 % of trials (simulated, seeded; the
    /// width X̄ − LCB varies a little between samples, hence the tolerance), and X̄ − LCB alone,
    /// the old definition, in only about half.
    #[test]
    fn the_minimum_detectable_violation_is_flagged_with_the_stated_power() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let (alpha, runs, trials, bound) = (1e-2, 400, 300, 0.3);
        let draw = |rng: &mut rand::rngs::StdRng, mean: f64| -> Vec<f64> {
            (0..runs)
                .map(|_| (mean + 0.2 * (rng.random::<f64>() - 0.5)).clamp(0.0, 1.0))
                .collect()
        };
        let pilot = Sample::new(&draw(&mut rng, bound), 1.0);
        let mdv = pilot.min_detectable_violation(alpha);
        let width = pilot.mean - pilot.lcb(alpha);
        assert!((mdv - width - POWER_Z * pilot.se()).abs() < 1e-12);
        let rate = |rng: &mut rand::rngs::StdRng, shift: f64| {
            (0..trials)
                .filter(|_| {
                    decide(&Sample::new(&draw(rng, bound + shift), 1.0), bound, alpha)
                        == Decision::Violated
                })
                .count() as f64
                / trials as f64
        };
        let at_mdv = rate(&mut rng, mdv);
        let at_width = rate(&mut rng, width);
        assert!((0.7..=0.9).contains(&at_mdv), "{at_mdv}");
        assert!((0.35..=0.65).contains(&at_width), "{at_width}");
    }

    /// A two-sided test's minimum detectable bias is its half-width plus z₀.₈ standard errors.
    #[test]
    fn the_minimum_detectable_bias_adds_the_power_quantile() {
        let lows: Vec<f64> = (0..200)
            .map(|i| if i % 2 == 0 { -0.5 } else { 0.5 })
            .collect();
        let t = ZeroMeanTest::new(&lows, &lows, 1.0, 1e-2);
        assert!((t.se - standard_error(&lows)).abs() < 1e-15);
        assert!((t.min_detectable_bias() - t.half_width() - POWER_Z * t.se).abs() < 1e-15);
        assert!((POWER_Z - 0.841_621_233_572_914_3).abs() < 1e-15);
    }
}
