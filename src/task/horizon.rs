//! How long one trajectory of a task is: the objective the eq. 3.15 estimators target.

use serde::{Deserialize, Serialize};

/// What a trajectory of a [`super::TaskProblem`] is (see the module docs of [`super`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Horizon {
    /// One episode, ending when the task says so (termination or the task's own time limit):
    /// F(θ) = E Σ_{t=1}^{n} l(s_t, θ) with the episode's random length n.
    Episodic,
    /// A stream of exactly `steps` decisions (the thesis's F with T − 1 = `steps` losses,
    /// eqs. 3.1–3.16); `after_end` says what follows an episode that ends before.
    Fixed {
        /// Decisions per trajectory (≥ 1).
        steps: usize,
        /// Reset or absorb.
        after_end: AfterEnd,
    },
}

/// What a [`Horizon::Fixed`] stream does when an episode ends before its last decision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AfterEnd {
    /// A new episode starts from the task's reset law and the stream goes on (the thesis's
    /// protocol for CartPole): the augmented kernel replaces each terminal transition by a reset.
    Reset,
    /// The stream absorbs: each remaining step costs [`super::Task::absorbing_loss`] of the end
    /// state and takes no decision.
    Absorb,
}

impl Horizon {
    /// The thesis's objective with `steps` decisions and `after_end`.
    pub fn fixed(steps: usize, after_end: AfterEnd) -> Self {
        Self::Fixed { steps, after_end }
    }

    /// The number of decisions a stream has, if fixed.
    pub fn steps(&self) -> Option<usize> {
        match self {
            Self::Episodic => None,
            Self::Fixed { steps, .. } => Some(*steps),
        }
    }

    /// A short label for tables and provenance: `episodic`, `fixed-500-reset`, `fixed-200-absorb`.
    pub fn label(&self) -> String {
        match self {
            Self::Episodic => "episodic".into(),
            Self::Fixed { steps, after_end } => format!(
                "fixed-{steps}-{}",
                match after_end {
                    AfterEnd::Reset => "reset",
                    AfterEnd::Absorb => "absorb",
                }
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_and_json_name_the_choice() {
        let h = Horizon::fixed(500, AfterEnd::Reset);
        assert_eq!(h.label(), "fixed-500-reset");
        assert_eq!(Horizon::Episodic.label(), "episodic");
        let json = serde_json::to_string(&h).unwrap();
        assert_eq!(json, r#"{"kind":"fixed","steps":500,"after_end":"reset"}"#);
        assert_eq!(serde_json::from_str::<Horizon>(&json).unwrap(), h);
        assert_eq!(h.steps(), Some(500));
        assert_eq!(Horizon::Episodic.steps(), None);
    }
}
