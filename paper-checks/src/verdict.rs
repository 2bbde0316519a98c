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
//!   converge in most runs: no claim that it is faster can be reproduced, and against methods
//!   that certainly converged it needs the most ([`most`]).
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
                // Sorted: a ≤ b, so a middle value of +∞ makes b = +∞.
                let (a, b) = (v[n / 2 - 1], v[n / 2]);
                if b == f64::INFINITY {
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
/// wholly below `b`'s (`a.hi < b.lo`), not reproduced if `b`'s lies wholly below `a`'s
/// (`b.hi < a.lo`) or `a` did not converge in most runs (median +∞) or has no runs (median NaN),
/// inconclusive otherwise (intervals that overlap or touch, or an interval too small to exist:
/// an end that is NaN).
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

/// "`target` needs the most of all", judged against each other method and combined by
/// [`Verdict::all`]: reproduced against `o` if `target.lo > o.hi` with `o.hi` finite (a lower end
/// of +∞ counts: a target that did not converge in most runs needs more than a method that
/// certainly converged); not reproduced if `target.hi < o.lo` (the target certainly needs less);
/// inconclusive otherwise: overlapping or touching intervals (as in [`less`]), both reaching +∞ (neither converged, nothing
/// tells them apart), or an end that does not exist (NaN: too few runs; every comparison with it
/// is false, so it decides nothing).
pub fn most(target: &MedianCi, others: &[&MedianCi]) -> Verdict {
    Verdict::all(
        &others
            .iter()
            .map(|o| {
                if o.hi < f64::INFINITY && target.lo > o.hi {
                    Verdict::Reproduced
                } else if target.hi < o.lo {
                    Verdict::NotReproduced
                } else {
                    Verdict::Inconclusive
                }
            })
            .collect::<Vec<_>>(),
    )
}

/// "the mean lies in `[lo, hi]`" (a closed band): reproduced if the mean's interval lies inside
/// the band (its ends may meet the band's), not reproduced if it is disjoint from it (wholly below
/// `lo` or wholly above `hi`), inconclusive if it straddles or touches an edge from outside, or
/// is not a finite interval (no width: fewer than 2 values; or an infinite mean or width).
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
/// disjoint from and beyond its own, inconclusive otherwise (intervals that overlap or touch, no
/// others, or an interval that is not finite: fewer than 2 values, or an infinite mean or width,
/// which decides nothing against that method).
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
        // A method that never converged is not faster than anything, one that did is not "the
        // slowest" against it, and it needs more than one that certainly converged.
        assert_eq!(less(&ci(&never), &ci(&slow)), Verdict::NotReproduced);
        assert_eq!(most(&ci(&slow), &[&ci(&never)]), Verdict::NotReproduced);
        assert_eq!(most(&ci(&never), &[&ci(&slow)]), Verdict::Reproduced);
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

    const INF: f64 = f64::INFINITY;

    /// A median interval given by its ends (n = 10, as [`MedianCi::of`] would give at 95 %).
    fn iv(lo: f64, median: f64, hi: f64) -> MedianCi {
        MedianCi {
            n: 10,
            median,
            lo,
            hi,
            coverage: 1.0 - 22.0 / 1024.0,
        }
    }

    /// A mean's interval `mean ± half_width` (binary fractions, so its ends are exact).
    fn sm(mean: f64, half_width: f64) -> Summary {
        Summary {
            n: 4,
            mean,
            half_width,
        }
    }

    #[test]
    fn verdicts_read_as_their_names() {
        assert_eq!(Verdict::Reproduced.text(), "reproduced");
        assert_eq!(Verdict::Inconclusive.text(), "inconclusive");
        assert_eq!(Verdict::NotReproduced.text(), "not reproduced");
    }

    #[test]
    fn a_conjunction_needs_every_part_and_fails_with_any() {
        use Verdict::*;
        assert_eq!(Verdict::all(&[Reproduced]), Reproduced);
        assert_eq!(Verdict::all(&[Inconclusive]), Inconclusive);
        assert_eq!(Verdict::all(&[NotReproduced]), NotReproduced);
        assert_eq!(Verdict::all(&[Reproduced, NotReproduced]), NotReproduced);
        assert_eq!(Verdict::all(&[NotReproduced, Reproduced]), NotReproduced);
        assert_eq!(Verdict::all(&[Inconclusive, Reproduced]), Inconclusive);
    }

    #[test]
    fn outcomes_cost_their_calls_or_infinity_and_tally_by_kind() {
        assert_eq!(Outcome::Converged(3.5).cost(), 3.5);
        assert_eq!(Outcome::Converged(0.0).cost(), 0.0);
        assert_eq!(Outcome::NotConverged.cost(), INF);
        assert_eq!(Outcome::Diverged.cost(), INF);
        let runs = [
            Outcome::Converged(1.0),
            Outcome::Diverged,
            Outcome::NotConverged,
            Outcome::Converged(2.0),
            Outcome::NotConverged,
            Outcome::Converged(3.0),
        ];
        let t = Tally::of(&runs);
        assert_eq!((t.converged, t.not_converged, t.diverged), (3, 2, 1));
        assert_eq!(t.runs(), 6);
        assert_eq!(t.text(), "converged 3/6, 2 never, 1 diverged");
        let clean = Tally::of(&runs[3..4]);
        assert_eq!(clean.runs(), 1);
        assert_eq!(clean.text(), "converged 1/1");
        let never = Tally::of(&[Outcome::NotConverged]);
        assert_eq!(never.text(), "converged 0/1, 1 never");
        let failed = Tally::of(&[Outcome::Diverged, Outcome::Diverged]);
        assert_eq!(failed.text(), "converged 0/2, 2 diverged");
        assert_eq!(Tally::of(&[]), Tally::default());
        assert_eq!(Tally::default().runs(), 0);
        assert_eq!(Tally::default().text(), "converged 0/0");
    }

    #[test]
    fn the_median_is_the_middle_value_or_the_mean_of_the_two_middle_values() {
        assert_eq!(ci(&[3.0, 1.0, 2.0]).median, 2.0);
        assert_eq!(ci(&[7.0]).median, 7.0);
        assert_eq!(ci(&[4.0, 1.0, 3.0, 2.0]).median, 2.5);
        assert_eq!(ci(&[10.0, 20.0]).median, 15.0);
        // +∞ as one of the two middle values makes the median +∞ (most runs did not converge).
        assert_eq!(ci(&[1.0, INF]).median, INF);
        assert_eq!(ci(&[-INF, INF]).median, INF);
        assert_eq!(ci(&[1.0, 2.0, INF, INF]).median, INF);
        // Two middle values of −∞ have the median −∞, not +∞.
        assert_eq!(ci(&[-INF, -INF]).median, -INF);
        let empty = ci(&[]);
        assert_eq!(empty.n, 0);
        assert!(empty.median.is_nan() && empty.lo.is_nan() && empty.hi.is_nan());
        assert!(empty.coverage.is_nan());
        let one = ci(&[7.0]);
        assert_eq!(one.n, 1);
        assert!(one.lo.is_nan() && one.hi.is_nan() && one.coverage.is_nan());
    }

    #[test]
    fn the_interval_takes_the_largest_k_whose_tail_fits_the_level() {
        let xs: Vec<f64> = (1..=10).map(f64::from).collect();
        // n = 8 at 95 %: P(Bin(8, ½) ≤ 0) = 1/256 ≤ 0.025 < P(≤ 1) = 9/256, so k = 1.
        let c = ci(&xs[..8]);
        assert_eq!((c.lo, c.hi), (1.0, 8.0));
        assert!((c.coverage - (1.0 - 2.0 / 256.0)).abs() < 1e-12);
        // n = 10 at 80 %: P(≤ 2) = 56/1024 ≤ 0.1 < P(≤ 3) = 176/1024, so k = 3.
        let c = MedianCi::of(&xs, 0.8);
        assert_eq!((c.lo, c.hi), (3.0, 8.0));
        assert!((c.coverage - (1.0 - 112.0 / 1024.0)).abs() < 1e-12);
        // The threshold between k = 2 and k = 1 is the level whose α is P(≤ 1) itself: a level
        // a hair below it gives k = 2 (coverage 1 − 2 P(≤ 1), just above the level), a hair
        // above it only k = 1.
        let p1 = Binomial::new(0.5, 10).unwrap().cdf(1);
        assert!((p1 - 11.0 / 1024.0).abs() < 1e-15);
        let c = MedianCi::of(&xs, 1.0 - 2.0 * p1 - 1e-12);
        assert_eq!((c.lo, c.hi), (2.0, 9.0));
        assert!(c.coverage >= 1.0 - 2.0 * p1 - 1e-12);
        let c = MedianCi::of(&xs, 1.0 - 2.0 * p1 + 1e-12);
        assert_eq!((c.lo, c.hi), (1.0, 10.0));
        // Every interval covers at least its level.
        for n in 6..=40 {
            let ys: Vec<f64> = (0..n).map(f64::from).collect();
            let c = ci(&ys);
            assert!(c.coverage >= 0.95 && c.coverage < 1.0, "n = {n}: {c:?}");
            assert!(c.lo <= c.median && c.median <= c.hi, "n = {n}: {c:?}");
        }
    }

    #[test]
    fn text_and_cell_write_the_median_its_ends_and_infinity() {
        let num = |x: f64| format!("{x}");
        let xs: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(ci(&xs).text(num), "5.5 [2, 9] (n = 10)");
        assert_eq!(ci(&xs).cell(num), "5.5 [2, 9]");
        let few = ci(&[1.0, 3.0, 5.0]);
        assert_eq!(few.text(num), "3 (n = 3, too few for an interval)");
        assert_eq!(few.cell(num), "3 (too few for an interval)");
        let never = ci(&[INF; 10]);
        assert_eq!(never.text(num), "∞ [∞, ∞] (n = 10)");
        let mut half = xs.clone();
        half[5..].fill(INF);
        assert_eq!(ci(&half).cell(num), "∞ [2, ∞]");
        assert_eq!(ci(&[INF]).cell(num), "∞ (too few for an interval)");
    }

    #[test]
    fn less_needs_disjoint_intervals_and_a_finite_median() {
        let a = iv(1.0, 2.0, 3.0);
        // Touching intervals overlap at a point: inconclusive either way.
        assert_eq!(less(&a, &iv(3.0, 4.0, 5.0)), Verdict::Inconclusive);
        assert_eq!(less(&iv(3.0, 4.0, 5.0), &a), Verdict::Inconclusive);
        assert_eq!(less(&a, &iv(3.5, 4.0, 5.0)), Verdict::Reproduced);
        assert_eq!(less(&iv(3.5, 4.0, 5.0), &a), Verdict::NotReproduced);
        assert_eq!(less(&a, &iv(2.5, 4.0, 5.0)), Verdict::Inconclusive);
        // A median of +∞ (most runs did not converge) or NaN (no runs) is never faster, even
        // when its interval overlaps the other's.
        assert_eq!(less(&iv(2.0, INF, INF), &a), Verdict::NotReproduced);
        assert_eq!(less(&ci(&[]), &a), Verdict::NotReproduced);
        assert_eq!(less(&ci(&[]), &ci(&[])), Verdict::NotReproduced);
        // An interval that does not exist decides nothing, whatever the other end says.
        assert_eq!(less(&ci(&[1.0]), &iv(5.0, 6.0, 7.0)), Verdict::Inconclusive);
        assert_eq!(
            less(&iv(f64::NAN, 1.5, 2.0), &iv(5.0, 6.0, 7.0)),
            Verdict::Inconclusive
        );
        assert_eq!(
            less(&iv(5.0, 6.0, 7.0), &iv(f64::NAN, 1.5, 2.0)),
            Verdict::Inconclusive
        );
        assert_eq!(less(&a, &ci(&[9.0])), Verdict::Inconclusive);
        // Against a method that never converged, a finite interval is faster.
        assert_eq!(less(&a, &iv(INF, INF, INF)), Verdict::Reproduced);
    }

    #[test]
    fn least_is_less_than_every_other() {
        let a = iv(1.0, 2.0, 3.0);
        let (above, overlap, below) = (iv(4.0, 5.0, 6.0), iv(2.0, 5.0, 6.0), iv(0.0, 0.5, 0.9));
        assert_eq!(
            least(&a, &[&above, &iv(8.0, 9.0, INF)]),
            Verdict::Reproduced
        );
        assert_eq!(least(&a, &[&above, &overlap]), Verdict::Inconclusive);
        assert_eq!(least(&a, &[&above, &below]), Verdict::NotReproduced);
        assert_eq!(least(&a, &[]), Verdict::Inconclusive);
    }

    #[test]
    fn most_needs_the_target_above_every_finite_upper_end() {
        let t = iv(20.0, 25.0, 30.0);
        // Lower end above the other's upper end: reproduced; equal to it (touching) or a hair
        // below: inconclusive.
        assert_eq!(most(&t, &[&iv(5.0, 10.0, 19.5)]), Verdict::Reproduced);
        assert_eq!(most(&t, &[&iv(5.0, 10.0, 20.0)]), Verdict::Inconclusive);
        assert_eq!(most(&t, &[&iv(5.0, 10.0, 20.5)]), Verdict::Inconclusive);
        assert_eq!(most(&t, &[&iv(1.0, 5.0, 10.0)]), Verdict::Reproduced);
        // Upper end below the other's lower end: not reproduced; equal to it: inconclusive.
        assert_eq!(most(&t, &[&iv(30.5, 40.0, 50.0)]), Verdict::NotReproduced);
        assert_eq!(most(&t, &[&iv(30.0, 40.0, 50.0)]), Verdict::Inconclusive);
        // Every other is judged: one overlap or one above decides.
        let below = iv(1.0, 5.0, 10.0);
        assert_eq!(most(&t, &[&below, &iv(2.0, 3.0, 4.0)]), Verdict::Reproduced);
        assert_eq!(
            most(&t, &[&below, &iv(5.0, 22.0, 25.0)]),
            Verdict::Inconclusive
        );
        assert_eq!(
            most(&t, &[&below, &iv(31.0, 40.0, 50.0)]),
            Verdict::NotReproduced
        );
        assert_eq!(most(&t, &[]), Verdict::Inconclusive);
    }

    #[test]
    fn a_target_that_did_not_converge_needs_the_most_against_methods_that_did() {
        let never = iv(INF, INF, INF);
        let finite = iv(1.0, 5.0, 10.0);
        assert_eq!(most(&never, &[&finite]), Verdict::Reproduced);
        assert_eq!(
            most(&never, &[&finite, &iv(2.0, 3.0, 4.0)]),
            Verdict::Reproduced
        );
        // Its median +∞ with a finite lower end: only what lies wholly below that end.
        let mostly = iv(12.0, INF, INF);
        assert_eq!(most(&mostly, &[&finite]), Verdict::Reproduced);
        assert_eq!(most(&mostly, &[&iv(1.0, 5.0, 13.0)]), Verdict::Inconclusive);
        // Another that may not converge either: nothing tells them apart.
        assert_eq!(most(&never, &[&never]), Verdict::Inconclusive);
        assert_eq!(most(&never, &[&iv(3.0, 7.0, INF)]), Verdict::Inconclusive);
        assert_eq!(most(&never, &[&finite, &never]), Verdict::Inconclusive);
        // A target that certainly converged against one that never did needs less.
        assert_eq!(most(&finite, &[&never]), Verdict::NotReproduced);
        assert_eq!(most(&finite, &[&iv(3.0, INF, INF)]), Verdict::Inconclusive);
    }

    #[test]
    fn most_without_an_interval_decides_nothing() {
        let t = iv(20.0, 25.0, 30.0);
        assert_eq!(
            most(&ci(&[25.0]), &[&iv(1.0, 2.0, 3.0)]),
            Verdict::Inconclusive
        );
        assert_eq!(most(&ci(&[]), &[&iv(1.0, 2.0, 3.0)]), Verdict::Inconclusive);
        assert_eq!(most(&t, &[&ci(&[1.0])]), Verdict::Inconclusive);
        assert_eq!(most(&t, &[&ci(&[])]), Verdict::Inconclusive);
        assert_eq!(most(&ci(&[INF]), &[&ci(&[1.0])]), Verdict::Inconclusive);
    }

    #[test]
    fn within_is_inside_the_closed_band_or_disjoint_from_it() {
        // The interval [0.625, 0.875].
        let s = sm(0.75, 0.125);
        assert_eq!((s.lo(), s.hi()), (0.625, 0.875));
        assert_eq!(within(&s, 0.625, 0.875), Verdict::Reproduced);
        assert_eq!(within(&s, 0.5, 1.0), Verdict::Reproduced);
        assert_eq!(within(&s, 0.6875, 1.0), Verdict::Inconclusive);
        assert_eq!(within(&s, 0.5, 0.8125), Verdict::Inconclusive);
        assert_eq!(within(&s, 0.6875, 0.8125), Verdict::Inconclusive);
        // Touching the band from outside is not disjoint from it.
        assert_eq!(within(&s, 0.875, 1.0), Verdict::Inconclusive);
        assert_eq!(within(&s, 0.0, 0.625), Verdict::Inconclusive);
        // Wholly below the band, or wholly above it.
        assert_eq!(within(&s, 0.9, 1.0), Verdict::NotReproduced);
        assert_eq!(within(&s, 0.0, 0.5), Verdict::NotReproduced);
        assert_eq!(within(&s, -INF, 0.5), Verdict::NotReproduced);
        assert_eq!(within(&s, 0.0, INF), Verdict::Reproduced);
    }

    #[test]
    fn within_an_interval_that_is_not_finite_is_inconclusive() {
        assert_eq!(
            within(&Summary::of(&[0.7]), 0.0, 1.0),
            Verdict::Inconclusive
        );
        assert_eq!(
            within(&Summary::of(&[0.7]), 0.8, 1.0),
            Verdict::Inconclusive
        );
        assert_eq!(within(&Summary::of(&[]), 0.0, 1.0), Verdict::Inconclusive);
        assert_eq!(within(&sm(INF, 1.0), 0.0, INF), Verdict::Inconclusive);
        assert_eq!(within(&sm(INF, 1.0), 0.0, 1.0), Verdict::Inconclusive);
        assert_eq!(within(&sm(-INF, 1.0), 0.0, 1.0), Verdict::Inconclusive);
        assert_eq!(within(&sm(0.5, INF), -INF, INF), Verdict::Inconclusive);
        assert_eq!(within(&sm(f64::NAN, 1.0), 0.0, 1.0), Verdict::Inconclusive);
    }

    #[test]
    fn extreme_needs_disjoint_intervals_beyond_every_other() {
        let t = sm(0.75, 0.125); // [0.625, 0.875]
        let touching = sm(0.4375, 0.1875); // [0.25, 0.625]
        let below = sm(0.375, 0.125); // [0.25, 0.5]
        let above = sm(1.0, 0.0625); // [0.9375, 1.0625]
        assert_eq!((touching.hi(), below.hi()), (0.625, 0.5));
        for largest in [true, false] {
            assert_eq!(extreme(&t, &[&touching], largest), Verdict::Inconclusive);
            assert_eq!(extreme(&touching, &[&t], largest), Verdict::Inconclusive);
            assert_eq!(extreme(&t, &[], largest), Verdict::Inconclusive);
        }
        assert_eq!(extreme(&t, &[&below], true), Verdict::Reproduced);
        assert_eq!(extreme(&t, &[&below], false), Verdict::NotReproduced);
        assert_eq!(extreme(&below, &[&t], false), Verdict::Reproduced);
        assert_eq!(extreme(&below, &[&t], true), Verdict::NotReproduced);
        assert_eq!(
            extreme(&t, &[&below, &touching], true),
            Verdict::Inconclusive
        );
        assert_eq!(extreme(&t, &[&below, &above], true), Verdict::NotReproduced);
        assert_eq!(extreme(&above, &[&below, &t], true), Verdict::Reproduced);
        assert_eq!(extreme(&below, &[&above, &t], false), Verdict::Reproduced);
    }

    #[test]
    fn extreme_against_an_interval_that_is_not_finite_is_inconclusive() {
        let t = sm(0.75, 0.125);
        let one = Summary::of(&[0.1]);
        for largest in [true, false] {
            for bad in [
                sm(INF, 1.0),
                sm(-INF, 1.0),
                sm(0.5, INF),
                sm(f64::NAN, 0.1),
                one,
            ] {
                assert_eq!(
                    extreme(&bad, &[&t], largest),
                    Verdict::Inconclusive,
                    "{bad:?}"
                );
                assert_eq!(
                    extreme(&t, &[&bad], largest),
                    Verdict::Inconclusive,
                    "{bad:?}"
                );
            }
        }
    }

    #[test]
    fn a_cap_applies_only_to_a_reproduced_claim_with_a_diverged_favoured_run() {
        use Verdict::*;
        let clean = Tally {
            converged: 5,
            not_converged: 5,
            diverged: 0,
        };
        let failed = Tally {
            converged: 9,
            not_converged: 0,
            diverged: 1,
        };
        assert_eq!(cap_for_failures(Reproduced, &[]), Reproduced);
        assert_eq!(cap_for_failures(Reproduced, &[clean]), Reproduced);
        assert_eq!(cap_for_failures(Reproduced, &[failed]), Inconclusive);
        assert_eq!(cap_for_failures(Reproduced, &[clean, failed]), Inconclusive);
        assert_eq!(cap_for_failures(Inconclusive, &[failed]), Inconclusive);
        assert_eq!(cap_for_failures(NotReproduced, &[failed]), NotReproduced);
        assert_eq!(cap_for_failures(NotReproduced, &[clean]), NotReproduced);
    }
}
