//! Means with 95% confidence intervals over seeds — the Student-t interval ([`Summary`], from
//! `ilopt-plot`, which shades the same bands) and the range-respecting [`Interval`] the appendix
//! prints (a seeded percentile bootstrap for quantities bounded on both sides, a Student-t
//! interval clamped to 0 for non-negative ones) — and the seed derivation.

use ilopt::seeding::splitmix64;
use serde::Serialize;

pub use ilopt::seeding::fnv1a;
pub use ilopt_plot::band::{Summary, t975};

/// The range a quantity can take, which decides its interval ([`Interval::of`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Range {
    /// Bounded on both sides, `[lo, hi]` (a success rate, crashes out of E episodes, a reward
    /// capped by the horizon): percentile bootstrap over seeds, whose ends stay inside the
    /// range of the data and so inside the quantity's range.
    Bounded {
        /// Least possible value.
        lo: f64,
        /// Greatest possible value.
        hi: f64,
    },
    /// At least 0 with no upper bound (gradient calls, seconds, a loss): the Student-t interval
    /// with its lower end clamped to 0 (and flagged as clamped).
    NonNegative,
    /// Any real value: the Student-t interval as it is.
    Real,
}

/// How an [`Interval`] was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Percentile bootstrap of the mean over seeds ([`BOOTSTRAP_RESAMPLES`] resamples).
    Bootstrap,
    /// Student-t, `mean ± t(0.975, n−1)·s/√n`, its lower end clamped to the quantity's least
    /// value (0 for a non-negative quantity, none for a real one).
    StudentTClamped,
}

/// Resamples of every bootstrap interval.
pub const BOOTSTRAP_RESAMPLES: usize = 10_000;

/// A mean over seeds with a 95% interval that respects the quantity's range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Interval {
    /// Sample size (seeds).
    pub n: usize,
    /// Mean (NaN for n = 0).
    pub mean: f64,
    /// Lower end (NaN for n < 2).
    pub lo: f64,
    /// Upper end (NaN for n < 2).
    pub hi: f64,
    /// How the ends were computed.
    pub method: Method,
    /// Whether the lower end was raised to the range's lower bound.
    pub clamped_lo: bool,
}

impl Interval {
    /// The interval of `xs` for a quantity of `range`. A bootstrap draws its resamples from a
    /// generator seeded by `key` (name the quantity and the configuration), so the same data
    /// and key always give the same interval, whatever the thread count.
    pub fn of(xs: &[f64], range: Range, key: &str) -> Self {
        match range {
            Range::Bounded { lo, hi } => {
                let mut i = bootstrap_mean(xs, BOOTSTRAP_RESAMPLES, derive_seed(key, 0));
                // The ends are means of data already in the range; clamp only against
                // rounding.
                if i.lo.is_finite() {
                    i.lo = i.lo.clamp(lo, hi);
                    i.hi = i.hi.clamp(lo, hi);
                }
                i
            }
            Range::NonNegative => t_clamped(xs, 0.0),
            Range::Real => t_clamped(xs, f64::NEG_INFINITY),
        }
    }

    /// The interval with every value multiplied by `k > 0` (a fraction in percent).
    #[must_use]
    pub fn scaled(self, k: f64) -> Self {
        Interval {
            mean: k * self.mean,
            lo: k * self.lo,
            hi: k * self.hi,
            ..self
        }
    }

    /// Whether the interval has finite ends (n ≥ 2).
    pub fn has_ends(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }
}

/// The Student-t interval of `xs` with its lower end raised to `floor` where it falls below.
pub fn t_clamped(xs: &[f64], floor: f64) -> Interval {
    let s = Summary::of(xs);
    let raw_lo = s.lo();
    let clamped_lo = raw_lo < floor;
    Interval {
        n: s.n,
        mean: s.mean,
        lo: if clamped_lo { floor } else { raw_lo },
        hi: s.hi(),
        method: Method::StudentTClamped,
        clamped_lo,
    }
}

/// SplitMix64 as a stream ([`splitmix64`] of the states seed, seed + γ, …): the generator of
/// the bootstrap's resamples.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        let out = splitmix64(self.0);
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        out
    }

    /// A uniform index below `n` (Lemire's multiply-shift on the high 32 bits; the bias,
    /// below n/2³², is immaterial for a few dozen seeds).
    fn below(&mut self, n: usize) -> usize {
        (((self.next() >> 32) * n as u64) >> 32) as usize
    }
}

/// The 95% percentile bootstrap interval of the mean of `xs`: `resamples` resamples of size n
/// drawn with replacement (generator seeded by `seed`), their means sorted, the ends the order
/// statistics at ⌈0.025·B⌉ and ⌈0.975·B⌉ (1-based). NaN ends for n < 2.
pub fn bootstrap_mean(xs: &[f64], resamples: usize, seed: u64) -> Interval {
    let n = xs.len();
    let mean = if n == 0 {
        f64::NAN
    } else {
        xs.iter().sum::<f64>() / n as f64
    };
    let (mut lo, mut hi) = (f64::NAN, f64::NAN);
    if n >= 2 && resamples > 0 {
        let mut rng = SplitMix(seed);
        let mut means: Vec<f64> = (0..resamples)
            .map(|_| (0..n).map(|_| xs[rng.below(n)]).sum::<f64>() / n as f64)
            .collect();
        means.sort_by(f64::total_cmp);
        let at = |p: f64| means[((p * resamples as f64).ceil() as usize).clamp(1, resamples) - 1];
        (lo, hi) = (at(0.025), at(0.975));
    }
    Interval {
        n,
        mean,
        lo,
        hi,
        method: Method::Bootstrap,
        clamped_lo: false,
    }
}

/// A seed derived only from a key (the configuration's identity) and an index.
pub fn derive_seed(key: &str, index: u64) -> u64 {
    splitmix64(fnv1a(key) ^ splitmix64(index))
}

#[cfg(test)]
mod tests {
    use super::*;
    /// n = 2: the resample mean is a, (a+b)/2 or b with probabilities ¼, ½, ¼, so the 2.5% and
    /// 97.5% percentiles are exactly a and b.
    #[test]
    fn bootstrap_of_two_values_spans_them() {
        let i = bootstrap_mean(&[2.0, 6.0], BOOTSTRAP_RESAMPLES, 7);
        assert_eq!((i.mean, i.lo, i.hi), (4.0, 2.0, 6.0));
        assert!(bootstrap_mean(&[1.0], 100, 7).lo.is_nan());
        assert!(bootstrap_mean(&[], 100, 7).mean.is_nan());
    }

    /// Against the exact bootstrap distribution, enumerated over all 4⁴ equally likely
    /// resamples of a sample of four, at quantiles away from the distribution's atoms.
    #[test]
    fn bootstrap_percentiles_match_the_enumerated_distribution() {
        let xs = [0.0, 1.0, 3.0, 10.0];
        let mut all = Vec::new();
        for a in 0..4 {
            for b in 0..4 {
                for c in 0..4 {
                    for d in 0..4 {
                        all.push((xs[a] + xs[b] + xs[c] + xs[d]) / 4.0);
                    }
                }
            }
        }
        all.sort_by(f64::total_cmp);
        // Exact type-1 quantiles of the 256 equally likely means.
        let exact = |p: f64| all[((p * 256.0).ceil() as usize) - 1];
        let i = bootstrap_mean(&xs, 20_000, 11);
        // The Monte-Carlo percentile lies within a neighbouring atom of the exact one.
        let near = |got: f64, p: f64| {
            let (a, b) = (exact(p - 0.01), exact(p + 0.01));
            got >= a && got <= b
        };
        assert!(near(i.lo, 0.025), "lo {} vs {}", i.lo, exact(0.025));
        assert!(near(i.hi, 0.975), "hi {} vs {}", i.hi, exact(0.975));
    }

    /// For a large sample the percentile bootstrap of the mean approaches the normal interval
    /// mean ± 1.96·s/√n (the bootstrap's s uses n, not n − 1).
    #[test]
    fn bootstrap_of_a_large_sample_approaches_the_normal_interval() {
        let xs: Vec<f64> = (0..400).map(|k| ((k * 37) % 101) as f64).collect();
        let n = xs.len() as f64;
        let m = xs.iter().sum::<f64>() / n;
        let sd = (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt();
        let half = 1.959_964 * sd / n.sqrt();
        let i = bootstrap_mean(&xs, 20_000, 3);
        assert!(
            ((m - i.lo) / half - 1.0).abs() < 0.05,
            "{} {}",
            m - i.lo,
            half
        );
        assert!(
            ((i.hi - m) / half - 1.0).abs() < 0.05,
            "{} {}",
            i.hi - m,
            half
        );
    }

    /// The same data and key give the same interval; the ends never leave the data's range.
    #[test]
    fn bounded_intervals_are_deterministic_and_inside_the_range() {
        let xs = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let r = Range::Bounded { lo: 0.0, hi: 1.0 };
        let a = Interval::of(&xs, r, "SGD/success");
        assert_eq!(a, Interval::of(&xs, r, "SGD/success"));
        assert_eq!(a.method, Method::Bootstrap);
        assert_eq!(a.mean, 0.125);
        assert!(
            a.lo >= 0.0 && a.hi <= 1.0 && a.lo <= a.mean && a.mean <= a.hi,
            "{a:?}"
        );
        // The t interval of the same data runs below zero.
        assert!(Summary::of(&xs).lo() < 0.0);
    }

    /// The clamped t interval: the t interval's upper end, its lower end raised to 0 (and
    /// flagged) only where it fell below.
    #[test]
    fn non_negative_intervals_are_clamped_t_intervals() {
        let xs = [1_000.0, 2_000.0, 250_000.0];
        let s = Summary::of(&xs);
        let i = Interval::of(&xs, Range::NonNegative, "k");
        assert_eq!(i.method, Method::StudentTClamped);
        assert!(s.lo() < 0.0 && i.lo == 0.0 && i.clamped_lo && i.hi == s.hi());
        let xs = [10.0, 11.0, 12.0];
        let i = Interval::of(&xs, Range::NonNegative, "k");
        assert!(!i.clamped_lo && (i.lo - Summary::of(&xs).lo()).abs() < 1e-12);
        assert!(Interval::of(&[3.0], Range::NonNegative, "k").lo.is_nan());
    }
}
