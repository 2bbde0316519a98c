//! Why a run ended ([`Termination`]) and how it diverged ([`Divergence`]). The `Display` strings
//! are the ones written in `ilopt run`'s `seed-*.csv`/`summary.json` and in paper-checks' stored
//! results (`gradient-budget`, `finished`, `diverged: non-finite θ`, …).

use super::AlgoError;
use serde::{Deserialize, Serialize};

/// Why a run ended.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Termination {
    /// `max_iterations` reached.
    MaxIterations,
    /// The gradient-evaluation budget is used up.
    GradientBudget,
    /// The target loss was reached.
    TargetLoss,
    /// The time limit passed.
    TimeOut,
    /// The algorithm completed its own schedule (O2NC, forward training).
    Finished,
    /// The run diverged: a step failed, θ is not finite, ‖θ‖ left its bound, or the steps stopped
    /// costing gradient calls. The record keeps everything up to that point.
    Diverged(Divergence),
    /// A checkpoint observer's criterion was met (paper-checks' `sustained-convergence`); the
    /// string is the reason as written in the results.
    Stopped(&'static str),
}

impl std::fmt::Display for Termination {
    /// The text the records store ([`RecordedTermination`]'s, which reads it back).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        RecordedTermination::from(self).fmt(f)
    }
}

impl Termination {
    /// The divergence, if the run diverged.
    pub fn divergence(&self) -> Option<&Divergence> {
        match self {
            Termination::Diverged(d) => Some(d),
            _ => None,
        }
    }
}

/// How a run diverged (every caller judges divergence through these).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Divergence {
    /// [`Algorithm::step`](super::Algorithm::step) returned an error (an oracle error, an
    /// undecidable interval branch, a non-finite update).
    StepFailed(AlgoError),
    /// An entry of θ is NaN or infinite.
    NonFiniteTheta,
    /// ‖θ‖₂ exceeds the bound ([`NormBound`](super::observer::NormBound)).
    NormBound {
        /// ‖θ‖₂ ([`norm_of`](super::observer::norm_of)).
        norm: f64,
        /// The bound.
        bound: f64,
    },
    /// This many steps in a row cost no gradient call
    /// ([`StoppingRule::max_free_steps`](super::StoppingRule::max_free_steps)): a budget in
    /// gradient calls would never be used up.
    NoGradientCall {
        /// The steps.
        steps: u64,
    },
}

impl std::fmt::Display for Divergence {
    /// The reason without the `diverged: ` of [`Termination`]'s text (paper-checks' run status
    /// stores it so).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Divergence::StepFailed(e) => write!(f, "step failed: {e}"),
            Divergence::NonFiniteTheta => write!(f, "non-finite θ"),
            Divergence::NormBound { norm, bound } => write!(f, "‖θ‖ = {norm:.3e} > {bound:e}"),
            Divergence::NoGradientCall { steps } => {
                write!(f, "{steps} steps in a row without a gradient call")
            }
        }
    }
}

/// Why a run ended, as it is stored: [`Termination`]'s kinds with the divergence's and the
/// observer's reasons as text, written as [`Termination`]'s `Display` string
/// (`gradient-budget`, `finished`, `diverged: non-finite θ`, `sustained-convergence`, …) and
/// read back from it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "String", from = "String")]
pub enum RecordedTermination {
    /// `max-iterations`.
    MaxIterations,
    /// `gradient-budget`: the budget of gradient calls is used up.
    GradientBudget,
    /// `target-loss`.
    TargetLoss,
    /// `time-out`.
    TimeOut,
    /// `finished`: the algorithm completed its own schedule.
    Finished,
    /// `diverged: <reason>` ([`Divergence`]'s text).
    Diverged(String),
    /// A checkpoint observer's reason (e.g. paper-checks' `sustained-convergence`), or any other
    /// text read back.
    Stopped(String),
}

impl RecordedTermination {
    /// Whether the run diverged.
    pub fn is_diverged(&self) -> bool {
        matches!(self, RecordedTermination::Diverged(_))
    }
}

impl From<&Termination> for RecordedTermination {
    fn from(t: &Termination) -> Self {
        match t {
            Termination::MaxIterations => RecordedTermination::MaxIterations,
            Termination::GradientBudget => RecordedTermination::GradientBudget,
            Termination::TargetLoss => RecordedTermination::TargetLoss,
            Termination::TimeOut => RecordedTermination::TimeOut,
            Termination::Finished => RecordedTermination::Finished,
            Termination::Diverged(d) => RecordedTermination::Diverged(d.to_string()),
            Termination::Stopped(reason) => RecordedTermination::Stopped((*reason).to_string()),
        }
    }
}

impl std::fmt::Display for RecordedTermination {
    /// The text of every file that records a run (also [`Termination`]'s `Display`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RecordedTermination::MaxIterations => write!(f, "max-iterations"),
            RecordedTermination::GradientBudget => write!(f, "gradient-budget"),
            RecordedTermination::TargetLoss => write!(f, "target-loss"),
            RecordedTermination::TimeOut => write!(f, "time-out"),
            RecordedTermination::Finished => write!(f, "finished"),
            RecordedTermination::Diverged(d) => write!(f, "diverged: {d}"),
            RecordedTermination::Stopped(reason) => write!(f, "{reason}"),
        }
    }
}

impl From<RecordedTermination> for String {
    fn from(t: RecordedTermination) -> String {
        t.to_string()
    }
}

impl From<String> for RecordedTermination {
    /// The inverse of the `Display` text; a text that names no other kind is
    /// [`RecordedTermination::Stopped`] with it.
    fn from(s: String) -> Self {
        match s.as_str() {
            "max-iterations" => RecordedTermination::MaxIterations,
            "gradient-budget" => RecordedTermination::GradientBudget,
            "target-loss" => RecordedTermination::TargetLoss,
            "time-out" => RecordedTermination::TimeOut,
            "finished" => RecordedTermination::Finished,
            _ => match s.strip_prefix("diverged: ") {
                Some(reason) => RecordedTermination::Diverged(reason.to_string()),
                None => RecordedTermination::Stopped(s),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kind's text, as the files hold it, read back to the same kind.
    #[test]
    fn a_recorded_termination_reads_back_its_own_text() {
        let all = [
            (Termination::MaxIterations, "max-iterations"),
            (Termination::GradientBudget, "gradient-budget"),
            (Termination::TargetLoss, "target-loss"),
            (Termination::TimeOut, "time-out"),
            (Termination::Finished, "finished"),
            (
                Termination::Diverged(Divergence::NonFiniteTheta),
                "diverged: non-finite θ",
            ),
            (
                Termination::Diverged(Divergence::NormBound {
                    norm: 3.2e5,
                    bound: 1e4,
                }),
                "diverged: ‖θ‖ = 3.200e5 > 1e4",
            ),
            (
                Termination::Stopped("sustained-convergence"),
                "sustained-convergence",
            ),
        ];
        for (t, text) in &all {
            assert_eq!(t.to_string(), *text);
            let r = RecordedTermination::from(t);
            let json = serde_json::to_string(&r).unwrap();
            assert_eq!(json, serde_json::to_string(text).unwrap());
            assert_eq!(
                serde_json::from_str::<RecordedTermination>(&json).unwrap(),
                r
            );
            assert_eq!(RecordedTermination::from(text.to_string()), r);
        }
        assert!(RecordedTermination::from(&all[5].0).is_diverged());
        assert!(!RecordedTermination::from(&all[7].0).is_diverged());
    }
}
