//! Why a run ended ([`Termination`]) and how it diverged ([`Divergence`]). The `Display` strings
//! are the ones written in `ilopt run`'s `seed-*.csv`/`summary.json` and in paper-checks' stored
//! results (`gradient-budget`, `finished`, `diverged: non-finite θ`, …).

use super::AlgoError;
use super::records::RecordedTermination;

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
