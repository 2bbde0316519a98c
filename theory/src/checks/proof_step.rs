//! One inequality of a proof, checked at many points: its slack (right side − left side) at each,
//! the smallest slack and where it was reached, and the row that reports it.
//!
//! A proof-step row states one inequality of a derivation (for example the descent step
//! (3.21)–(3.23) of the SGD proof) and evaluates both sides exactly (in ℚ) or as enclosures
//! (intervals, where roots enter) at every point it is given — typically the iterates of real
//! runs. The step holds when every slack is ≥ 0 (for an enclosure: its lower end is ≥ 0); it fails,
//! exactly or rigorously, when some slack is < 0 (for an enclosure: its upper end is < 0); an
//! enclosure that straddles 0 leaves the row inconclusive.

use crate::record::check::{Check, Measured, Method, Role, Verdict};
use ilopt::scalar::{BigRational, Interval, Scalar};
use std::cmp::Ordering;

/// The slacks of one inequality over the points it was checked at.
#[derive(Debug, Clone, PartialEq)]
pub struct StepSlack {
    /// Number of points checked.
    pub points: usize,
    /// Points where the inequality is certainly violated (slack < 0).
    pub violated: usize,
    /// Points where an enclosure of the slack contains 0 (never for exact slacks).
    pub undecided: usize,
    /// The smallest slack seen (for enclosures: the smallest lower end), as `f64` for the report.
    pub min_slack: f64,
    /// The index (in the order given) of the point with the smallest slack.
    pub argmin: usize,
    /// The largest right-hand side seen, as a scale for the slack (|rhs|, `f64`).
    pub scale: f64,
}

impl Default for StepSlack {
    fn default() -> Self {
        Self::new()
    }
}

impl StepSlack {
    /// No point checked yet.
    pub fn new() -> Self {
        StepSlack {
            points: 0,
            violated: 0,
            undecided: 0,
            min_slack: f64::INFINITY,
            argmin: 0,
            scale: 0.0,
        }
    }

    /// Record `lhs ≤ rhs` at the next point, exactly.
    pub fn exact(&mut self, lhs: &BigRational, rhs: &BigRational) {
        let slack = rhs - lhs;
        let violated = slack < BigRational::from_ratio(0, 1);
        self.record(slack.to_f64(), violated, false, rhs.to_f64().abs());
    }

    /// Record `lhs ≤ rhs` at the next point for enclosures of both sides: certainly violated if
    /// `sup lhs < inf rhs` fails the other way (`inf lhs > sup rhs`), undecided if they overlap.
    pub fn enclosed(&mut self, lhs: Interval, rhs: Interval) {
        let slack = rhs - lhs;
        let (violated, undecided) = match slack.certain_cmp(&Interval::zero()) {
            Some(Ordering::Less) => (true, false),
            Some(_) => (false, false),
            None => (false, slack.sup() > 0.0 || slack.inf() < 0.0),
        };
        self.record(slack.inf(), violated, undecided, rhs.sup().abs());
    }

    fn record(&mut self, slack: f64, violated: bool, undecided: bool, scale: f64) {
        if slack < self.min_slack || self.points == 0 {
            self.min_slack = slack;
            self.argmin = self.points;
        }
        self.points += 1;
        self.violated += usize::from(violated);
        self.undecided += usize::from(undecided);
        self.scale = self.scale.max(scale);
    }

    /// Holds if no point violated it and none was undecided; fails if some point violated it;
    /// inconclusive otherwise (and when no point was checked).
    pub fn verdict(&self) -> Verdict {
        if self.points == 0 {
            Verdict::Inconclusive
        } else if self.violated > 0 {
            Verdict::Fails
        } else if self.undecided > 0 {
            Verdict::Inconclusive
        } else {
            Verdict::Holds
        }
    }

    /// The numbers behind the verdict, for a row's details.
    pub fn summary(&self) -> String {
        format!(
            "{} points; min slack {:.4e} at point {} (largest |rhs| {:.4e}); {} violated, {} undecided",
            self.points, self.min_slack, self.argmin, self.scale, self.violated, self.undecided
        )
    }

    /// The row for this step, undecided: measured value = the smallest slack, details =
    /// [`StepSlack::summary`] (add constants or an erratum, then decide it).
    pub fn row(
        &self,
        id: impl Into<String>,
        result: impl Into<String>,
        claim: impl Into<String>,
        role: Role,
    ) -> crate::record::check::CheckBuilder {
        Check::builder(id, result, claim, role)
            .measured(Measured::exact(self.min_slack))
            .details(self.summary())
    }

    /// [`StepSlack::row`] decided by [`StepSlack::verdict`].
    pub fn decided_row(
        &self,
        id: impl Into<String>,
        result: impl Into<String>,
        claim: impl Into<String>,
        role: Role,
        method: Method,
    ) -> Check {
        self.row(id, result, claim, role)
            .decided(method, self.verdict())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ilopt::scalar::parse_exact;

    fn q(s: &str) -> BigRational {
        parse_exact(s).unwrap()
    }

    #[test]
    fn exact_slacks_decide_holds_and_fails() {
        let mut s = StepSlack::new();
        s.exact(&q("1"), &q("2"));
        s.exact(&q("1/3"), &q("1/3"));
        assert_eq!(s.verdict(), Verdict::Holds);
        assert_eq!((s.min_slack, s.argmin), (0.0, 1));
        s.exact(&q("2"), &q("1"));
        assert_eq!(s.verdict(), Verdict::Fails);
        assert_eq!((s.violated, s.argmin), (1, 2));
        assert_eq!(StepSlack::new().verdict(), Verdict::Inconclusive);
    }

    #[test]
    fn enclosed_slacks_are_undecided_when_they_straddle_zero() {
        let iv = |a: f64, b: f64| Interval::try_from((a, b)).unwrap();
        let mut s = StepSlack::new();
        s.enclosed(iv(0.0, 1.0), iv(2.0, 3.0));
        assert_eq!(s.verdict(), Verdict::Holds);
        s.enclosed(iv(0.0, 2.5), iv(2.0, 3.0));
        assert_eq!(s.verdict(), Verdict::Inconclusive);
        s.enclosed(iv(4.0, 5.0), iv(2.0, 3.0));
        assert_eq!(s.verdict(), Verdict::Fails);
        let row = s.decided_row("x", "r", "c", Role::Corrected, Method::Rigorous);
        assert_eq!(row.verdict, Verdict::Fails);
        assert_eq!(row.method, Method::Rigorous);
    }
}
