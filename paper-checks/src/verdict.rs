//! Verdicts that respect uncertainty: every claim of chapter 4 is judged by confidence intervals,
//! never by point estimates, and failed runs count as failures.
//!
//! Three outcomes ([`Verdict`]): *reproduced* when the claim holds at the confidence level,
//! *not reproduced* when its negation does (or the event it needs never happened), *inconclusive*
//! when the intervals overlap.
//!
//! * Calls (or time) to converge are compared by **medians with distribution-free intervals**
//!   ([`MedianCi`]: order statistics of the binomial law, exact coverage ≥ 95 %). A run that never
//!   converged within its budget, or diverged, enters as +∞: a method whose median is +∞ did not
//!   converge in most runs, and no claim that it is faster can be reproduced.
//! * Levels ("≈ 70 % success") and extremes ("BC has the most crashes") use the means' Student-t
//!   intervals ([`crate::stats::Summary`]).
//! * A claim in favour of a method with **diverged** runs is never *reproduced*: the best it can
//!   be is *inconclusive*, and the evidence names the failures ([`cap_for_failures`]).

use crate::stats::Summary;
use serde::Serialize;
use statrs::distribution::{Binomial, DiscreteCDF};

/// A claim's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// The claim holds at the confidence level.
    Reproduced,
    /// The intervals overlap: the data decide neither way.
    Inconclusive,
    /// The claim's negation holds at the confidence level, or what it needs never happened.
    NotReproduced,
}

impl Verdict {
    /// `reproduced` / `inconclusive` / `not reproduced`.
    pub fn text(self) -> &'static str {
        match self {
            Verdict::Reproduced => "reproduced",
            Verdict::Inconclusive => "inconclusive",
            Verdict::NotReproduced => "not reproduced",
        }
    }

    /// The verdict of a claim made of parts that must all hold: reproduced if every part is,
    /// not reproduced if some part is not, inconclusive otherwise (and for no parts).
    pub fn all(parts: &[Verdict]) -> Verdict {
        if parts.contains(&Verdict::NotReproduced) {
            Verdict::NotReproduced
        } else if !parts.is_empty() && parts.iter().all(|v| *v == Verdict::Reproduced) {
            Verdict::Reproduced
        } else {
            Verdict::Inconclusive
        }
    }
}

/// How one run ended, for the comparisons of this module.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Outcome {
    /// Sustained convergence reached at this cost (gradient calls or seconds).
    Converged(f64),
    /// Ran its whole budget without converging.
    NotConverged,
    /// Left the stated parameter bound or produced a non-finite value.
    Diverged,
}

impl Outcome {
    /// The cost, +∞ for a run that did not converge.
    pub fn cost(self) -> f64 {
        match self {
            Outcome::Converged(c) => c,
            Outcome::NotConverged | Outcome::Diverged => f64::INFINITY,
        }
    }
}

/// Counts of a method's run outcomes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Tally {
    /// Runs that converged.
    pub converged: usize,
    /// Runs that used their budget without converging.
    pub not_converged: usize,
    /// Runs that diverged.
    pub diverged: usize,
}

impl Tally {
    /// Count `runs`.
    pub fn of(runs: &[Outcome]) -> Self {
        let mut t = Tally::default();
        for r in runs {
            match r {
                Outcome::Converged(_) => t.converged += 1,
                Outcome::NotConverged => t.not_converged += 1,
                Outcome::Diverged => t.diverged += 1,
            }
        }
        t
    }

    /// All runs.
    pub fn runs(&self) -> usize {
        self.converged + self.not_converged + self.diverged
    }

    /// `converged k/n` with the failures, e.g. `converged 7/10, 2 never, 1 diverged`.
    pub fn text(&self) -> String {
        let mut s = format!("converged {}/{}", self.converged, self.runs());
        if self.not_converged > 0 {
            s += &format!(", {} never", self.not_converged);
        }
        if self.diverged > 0 {
            s += &format!(", {} diverged", self.diverged);
        }
        s
    }
}

/// A median with a distribution-free confidence interval `[x_(k), x_(n−k+1)]` (order statistics;
/// `k` the largest index with `P(Bin(n, ½) < k) ≤ (1 − level)/2`, so the coverage is at least
/// `level` for any continuous law). Values may be +∞ (runs that never converged): the interval
/// then reaches +∞ when too many runs did not converge.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MedianCi {
    /// Sample size.
    pub n: usize,
    /// The sample median (the mean of the two middle values for even n; +∞ if one of them is).
    pub median: f64,
    /// Lower end (NaN if the sample is too small for the level).
    pub lo: f64,
    /// Upper end (NaN if the sample is too small for the level).
    pub hi: f64,
    /// The exact coverage `1 − 2 P(Bin(n, ½) < k)` of the interval.
    pub coverage: f64,
}

impl MedianCi {
    /// The median of `xs` with an interval of coverage ≥ `level` (`0 < level < 1`).
    pub fn of(xs: &[f64], level: f64) -> Self {
        let n = xs.len();
        let mut v = xs.to_vec();
        v.sort_by(f64::total_cmp);
        let median = match n {
            0 => f64::NAN,
            _ if n % 2 == 1 => v[n / 2],
            _ => {
                // Sorted: a ≤ b, so an infinite middle value makes b infinite.
                let (a, b) = (v[n / 2 - 1], v[n / 2]);
                if b.is_infinite() {
                    f64::INFINITY
                } else {
                    0.5 * (a + b)
                }
            }
        };
        let alpha = (1.0 - level) / 2.0;
        // P(Bin(n, ½) ≤ k − 1) ≤ α for the largest k ≥ 1.
        let mut k = 0;
        if n > 0 {
            let b = Binomial::new(0.5, n as u64).expect("p = 1/2 and n ≥ 1 are valid");
            while k < n / 2 && b.cdf(k as u64) <= alpha {
                k += 1;
            }
        }
        if k == 0 {
            return MedianCi {
                n,
                median,
                lo: f64::NAN,
                hi: f64::NAN,
                coverage: f64::NAN,
            };
        }
        let b = Binomial::new(0.5, n as u64).expect("valid");
        MedianCi {
            n,
            median,
            lo: v[k - 1],
            hi: v[n - k],
            coverage: 1.0 - 2.0 * b.cdf(k as u64 - 1),
        }
    }

    /// `median [lo, hi]` with ∞ written as `∞`.
    pub fn text(&self, num: impl Fn(f64) -> String) -> String {
        let f = |x: f64| {
            if x.is_infinite() {
                "∞".to_string()
            } else {
                num(x)
            }
        };
        if self.lo.is_nan() {
            format!(
                "{} (n = {}, too few for an interval)",
                f(self.median),
                self.n
            )
        } else {
            format!(
                "{} [{}, {}] (n = {})",
                f(self.median),
                f(self.lo),
                f(self.hi),
                self.n
            )
        }
    }
}

impl MedianCi {
    /// The estimate for a table whose other column gives n: `median [lo, hi]`, or `∞` alone when
    /// the median and both ends are +∞ (most runs never converged).
    pub fn cell(&self, num: impl Fn(f64) -> String) -> String {
        let all_infinite = [self.median, self.lo, self.hi]
            .iter()
            .all(|x| x.is_infinite() && *x > 0.0);
        let f = |x: f64| {
            if x.is_infinite() {
                "∞".to_string()
            } else {
                num(x)
            }
        };
        if all_infinite {
            "∞".to_string()
        } else if self.lo.is_nan() {
            format!("{} (too few for an interval)", f(self.median))
        } else {
            format!("{} [{}, {}]", f(self.median), f(self.lo), f(self.hi))
        }
    }
}

/// "`a` needs less than `b`" for costs with median intervals: reproduced if `a`'s interval lies
/// wholly below `b`'s, not reproduced if `b`'s lies wholly below `a`'s or `a` did not converge
/// in most runs (median +∞), inconclusive otherwise (overlap, or an interval too small to exist).
pub fn less(a: &MedianCi, b: &MedianCi) -> Verdict {
    if a.median.is_infinite() || a.median.is_nan() {
        return Verdict::NotReproduced;
    }
    if a.lo.is_nan() || b.lo.is_nan() {
        return Verdict::Inconclusive;
    }
    if a.hi < b.lo {
        Verdict::Reproduced
    } else if b.hi < a.lo {
        Verdict::NotReproduced
    } else {
        Verdict::Inconclusive
    }
}

/// "`target` needs the least of all": [`less`] against each other method, combined by
/// [`Verdict::all`].
pub fn least(target: &MedianCi, others: &[&MedianCi]) -> Verdict {
    Verdict::all(&others.iter().map(|o| less(target, o)).collect::<Vec<_>>())
}

/// "`target` needs the most of all": reproduced if its interval lies wholly above every other
/// method's (an other that never converged in most runs has median +∞ and cannot be exceeded),
/// not reproduced if some other's lies wholly above its own, or `target` never converged in most
/// runs (the ordering of calls to converge needs it to converge).
pub fn most(target: &MedianCi, others: &[&MedianCi]) -> Verdict {
    if target.median.is_infinite() || target.median.is_nan() {
        return Verdict::NotReproduced;
    }
    Verdict::all(
        &others
            .iter()
            .map(|o| {
                if o.median.is_infinite() {
                    Verdict::NotReproduced
                } else {
                    less(o, target)
                }
            })
            .collect::<Vec<_>>(),
    )
}

/// "the mean lies in `[lo, hi]`": reproduced if the mean's interval lies inside the band, not
/// reproduced if it is disjoint from it, inconclusive if it straddles an edge (or has no width:
/// fewer than 2 values).
pub fn within(s: &Summary, lo: f64, hi: f64) -> Verdict {
    if !(s.mean.is_finite() && s.half_width.is_finite()) {
        return Verdict::Inconclusive;
    }
    if s.lo() >= lo && s.hi() <= hi {
        Verdict::Reproduced
    } else if s.hi() < lo || s.lo() > hi {
        Verdict::NotReproduced
    } else {
        Verdict::Inconclusive
    }
}

/// "`target`'s mean is the largest" (`largest = true`) or the smallest: reproduced if its
/// interval is disjoint from and beyond every other's, not reproduced if some other's interval is
/// disjoint from and beyond its own, inconclusive otherwise.
pub fn extreme(target: &Summary, others: &[&Summary], largest: bool) -> Verdict {
    let above = |a: &Summary, b: &Summary| {
        if largest {
            a.lo() > b.hi()
        } else {
            a.hi() < b.lo()
        }
    };
    if !(target.mean.is_finite() && target.half_width.is_finite()) {
        return Verdict::Inconclusive;
    }
    Verdict::all(
        &others
            .iter()
            .map(|o| {
                if !(o.mean.is_finite() && o.half_width.is_finite()) {
                    Verdict::Inconclusive
                } else if above(target, o) {
                    Verdict::Reproduced
                } else if above(o, target) {
                    Verdict::NotReproduced
                } else {
                    Verdict::Inconclusive
                }
            })
            .collect::<Vec<_>>(),
    )
}

/// A claim in favour of methods with diverged runs is never reproduced: `Reproduced` becomes
/// `Inconclusive` when any of `favoured` diverged.
pub fn cap_for_failures(v: Verdict, favoured: &[Tally]) -> Verdict {
    if v == Verdict::Reproduced && favoured.iter().any(|t| t.diverged > 0) {
        Verdict::Inconclusive
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_drops_n_and_prints_a_wholly_infinite_estimate_as_infinity() {
        let num = |x: f64| format!("{x}");
        let never = MedianCi::of(&[f64::INFINITY; 10], 0.95);
        assert_eq!(never.cell(num), "∞");
        assert!(never.text(num).contains("n = 10"));
        let some = MedianCi::of(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0], 0.95);
        let cell = some.cell(num);
        assert!(cell.starts_with("5.5 [") && !cell.contains("n ="), "{cell}");
        let inf = f64::INFINITY;
        let half = MedianCi::of(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, inf, inf, inf, inf], 0.95);
        assert!(half.cell(num).ends_with(", ∞]"), "{}", half.cell(num));
    }

    fn ci(xs: &[f64]) -> MedianCi {
        MedianCi::of(xs, 0.95)
    }

    #[test]
    fn the_median_interval_uses_the_binomial_order_statistics() {
        // n = 10: P(Bin(10, ½) ≤ 1) = 11/1024 ≤ 0.025 < P(≤ 2) = 56/1024, so k = 2:
        // [x_(2), x_(9)] with coverage 1 − 22/1024.
        let xs: Vec<f64> = (1..=10).map(f64::from).rev().collect();
        let c = ci(&xs);
        assert_eq!((c.lo, c.median, c.hi), (2.0, 5.5, 9.0));
        assert!((c.coverage - (1.0 - 22.0 / 1024.0)).abs() < 1e-12);
        // n = 20: k = 6 (P(≤ 5) = 21700/2²⁰ ≈ 0.0207).
        let xs: Vec<f64> = (1..=20).map(f64::from).collect();
        let c = ci(&xs);
        assert_eq!((c.lo, c.hi), (6.0, 15.0));
        // n = 5: P(≤ 0) = 1/32 > 0.025: no 95 % interval exists.
        assert!(ci(&[1.0, 2.0, 3.0, 4.0, 5.0]).lo.is_nan());
        // Runs that never converged are +∞ and push the interval up.
        let mut xs: Vec<f64> = (1..=10).map(f64::from).collect();
        xs[9] = f64::INFINITY;
        xs[8] = f64::INFINITY;
        assert_eq!(ci(&xs).hi, f64::INFINITY);
    }

    #[test]
    fn overlapping_intervals_are_inconclusive_and_disjoint_ones_decide() {
        let fast: Vec<f64> = (1..=10).map(f64::from).collect();
        let slow: Vec<f64> = (20..30).map(f64::from).collect();
        let mid: Vec<f64> = (5..15).map(f64::from).collect();
        assert_eq!(less(&ci(&fast), &ci(&slow)), Verdict::Reproduced);
        assert_eq!(less(&ci(&slow), &ci(&fast)), Verdict::NotReproduced);
        assert_eq!(less(&ci(&fast), &ci(&mid)), Verdict::Inconclusive);
        assert_eq!(
            least(&ci(&fast), &[&ci(&slow), &ci(&mid)]),
            Verdict::Inconclusive
        );
        assert_eq!(
            most(&ci(&slow), &[&ci(&fast), &ci(&mid)]),
            Verdict::Reproduced
        );
        let a = Summary::of(&[0.70, 0.71, 0.69, 0.70]);
        let b = Summary::of(&[0.5, 0.9, 0.6, 0.8]);
        assert_eq!(within(&a, 0.6, 0.8), Verdict::Reproduced);
        assert_eq!(within(&a, 0.8, 0.9), Verdict::NotReproduced);
        assert_eq!(within(&b, 0.6, 0.8), Verdict::Inconclusive);
        assert_eq!(extreme(&a, &[&b], true), Verdict::Inconclusive);
        let low = Summary::of(&[0.1, 0.11, 0.12]);
        assert_eq!(extreme(&a, &[&low], true), Verdict::Reproduced);
        assert_eq!(extreme(&low, &[&a], true), Verdict::NotReproduced);
        assert_eq!(extreme(&low, &[&a], false), Verdict::Reproduced);
    }

    #[test]
    fn runs_that_never_converge_count_as_such_and_decide_against_their_method() {
        let runs = [
            Outcome::Converged(5.0),
            Outcome::NotConverged,
            Outcome::Diverged,
            Outcome::NotConverged,
        ];
        let t = Tally::of(&runs);
        assert_eq!((t.converged, t.not_converged, t.diverged), (1, 2, 1));
        assert_eq!(t.text(), "converged 1/4, 2 never, 1 diverged");
        let never: Vec<f64> = [Outcome::NotConverged; 10]
            .iter()
            .map(|o| o.cost())
            .collect();
        let slow: Vec<f64> = (20..30).map(f64::from).collect();
        // A method that never converged is not faster than anything, and one that did is not
        // "the slowest" against it.
        assert_eq!(less(&ci(&never), &ci(&slow)), Verdict::NotReproduced);
        assert_eq!(most(&ci(&slow), &[&ci(&never)]), Verdict::NotReproduced);
        assert_eq!(most(&ci(&never), &[&ci(&slow)]), Verdict::NotReproduced);
    }

    #[test]
    fn diverged_runs_never_give_a_reproduced_claim_in_their_favour() {
        let mut fast: Vec<Outcome> = (1..=10).map(|x| Outcome::Converged(f64::from(x))).collect();
        fast[9] = Outcome::Diverged;
        let slow: Vec<f64> = (20..30).map(f64::from).collect();
        let costs: Vec<f64> = fast.iter().map(|o| o.cost()).collect();
        let v = less(&ci(&costs), &ci(&slow));
        assert_eq!(v, Verdict::Reproduced);
        assert_eq!(
            cap_for_failures(v, &[Tally::of(&fast)]),
            Verdict::Inconclusive
        );
        let clean: Vec<Outcome> = (1..=10).map(|x| Outcome::Converged(f64::from(x))).collect();
        assert_eq!(
            cap_for_failures(v, &[Tally::of(&clean)]),
            Verdict::Reproduced
        );
        assert_eq!(
            cap_for_failures(Verdict::NotReproduced, &[Tally::of(&fast)]),
            Verdict::NotReproduced
        );
    }

    #[test]
    fn parts_combine_conservatively() {
        use Verdict::*;
        assert_eq!(Verdict::all(&[Reproduced, Reproduced]), Reproduced);
        assert_eq!(Verdict::all(&[Reproduced, Inconclusive]), Inconclusive);
        assert_eq!(Verdict::all(&[Inconclusive, NotReproduced]), NotReproduced);
        assert_eq!(Verdict::all(&[]), Inconclusive);
    }
}
