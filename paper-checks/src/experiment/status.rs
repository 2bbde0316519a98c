//! How a run ended ([`RunStatus`]) and sustained convergence ([`sustained`], [`status_of`]).

use super::{Checkpoint, Evaluated};
use serde::{Deserialize, Serialize};

/// How a run ended (serialised with a `status` tag: `converged`, `not-converged`, `diverged`).
///
/// Wall times are kept out of it (they live in [`SeedTiming`](super::SeedTiming), so that the results files are
/// byte-identical across reruns): the time to convergence is [`SeedTiming::converge_seconds`](super::SeedTiming::converge_seconds).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "kebab-case")]
pub enum RunStatus {
    /// Sustained convergence: the score held the threshold at `sustain` consecutive checkpoints
    /// from `checkpoint` on, and the run never diverged.
    Converged {
        /// Index of the first checkpoint of the window.
        checkpoint: usize,
        /// Gradient calls at that checkpoint.
        gradient_evaluations: u64,
    },
    /// Ran to its budget (or, when tuning, ended) without sustained convergence.
    NotConverged,
    /// ‖θ‖ left the norm bound, θ became non-finite, or a step failed: never converged.
    Diverged {
        /// What happened (e.g. `‖θ‖ = 3.2e5 > 1e4`, `non-finite θ`, the step's error).
        reason: String,
        /// Gradient calls when it happened.
        gradient_evaluations: u64,
    },
}

impl RunStatus {
    /// Whether the run converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, RunStatus::Converged { .. })
    }
    /// Whether the run diverged.
    pub fn is_diverged(&self) -> bool {
        matches!(self, RunStatus::Diverged { .. })
    }
    /// The convergence checkpoint, if converged.
    pub fn checkpoint(&self) -> Option<usize> {
        match self {
            RunStatus::Converged { checkpoint, .. } => Some(*checkpoint),
            _ => None,
        }
    }
}

/// The first index i with `scores[i..i + sustain]` all ≥ `threshold` (the window must be complete).
pub fn sustained(scores: &[f64], threshold: f64, sustain: usize) -> Option<usize> {
    let k = sustain.max(1);
    if scores.len() < k {
        return None;
    }
    (0..=scores.len() - k).find(|&i| scores[i..i + k].iter().all(|&s| s >= threshold))
}

/// The status of a run from its checkpoints and its divergence, if any: a diverged run is never
/// converged.
pub fn status_of(
    checkpoints: &[Checkpoint],
    threshold: f64,
    sustain: usize,
    diverged: Option<(String, u64)>,
) -> RunStatus {
    if let Some((reason, gradient_evaluations)) = diverged {
        return RunStatus::Diverged {
            reason,
            gradient_evaluations,
        };
    }
    let scores: Vec<f64> = checkpoints.iter().map(|c| c.score()).collect();
    match sustained(&scores, threshold, sustain) {
        Some(i) => RunStatus::Converged {
            checkpoint: i,
            gradient_evaluations: checkpoints[i].gradient_evaluations,
        },
        None => RunStatus::NotConverged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp(score: f64, calls: u64) -> Checkpoint {
        Checkpoint::new(
            calls,
            0,
            &ilopt::problem::Cost {
                gradient_evaluations: calls,
                ..Default::default()
            },
            None,
            None,
            &ilopt::evaluate::Evaluation {
                score: Some(score),
                ..Default::default()
            },
        )
    }

    #[test]
    fn sustained_convergence_needs_three_consecutive_checkpoints() {
        let t = 0.8;
        // Two above, a dip, then three above: converged at index 3, not 0.
        let s = [0.9, 0.9, 0.5, 0.85, 0.8, 1.0];
        assert_eq!(sustained(&s, t, 3), Some(3));
        // Above at the last two checkpoints only: an incomplete window is not convergence.
        assert_eq!(sustained(&[0.1, 0.9, 0.9], t, 3), None);
        assert_eq!(sustained(&[0.9, 0.9], t, 3), None);
        // Alternating never holds.
        assert_eq!(sustained(&[0.9, 0.1, 0.9, 0.1, 0.9], t, 3), None);
        let cps: Vec<Checkpoint> = s
            .iter()
            .enumerate()
            .map(|(i, &x)| cp(x, 100 * i as u64))
            .collect();
        assert_eq!(
            status_of(&cps, t, 3, None),
            RunStatus::Converged {
                checkpoint: 3,
                gradient_evaluations: 300
            }
        );
        assert_eq!(status_of(&cps[..3], t, 3, None), RunStatus::NotConverged);
    }

    #[test]
    fn diverged_runs_are_never_counted_converged() {
        // Converged by its scores, then ‖θ‖ left the bound: diverged, not converged.
        let cps: Vec<Checkpoint> = (0..5).map(|i| cp(1.0, 100 * i)).collect();
        let s = status_of(&cps, 0.8, 3, Some(("‖θ‖ = 2e34 > 1e4".into(), 450)));
        assert!(s.is_diverged());
        assert!(!s.is_converged());
        assert_eq!(s.checkpoint(), None);
        // The serialised status names itself (the verdict code reads it).
        let json = serde_json::to_string(&s).unwrap();
        assert!(json.contains(r#""status":"diverged""#), "{json}");
    }
}
