//! What a run records: the library's record family ([`ilopt::algo::records`]: [`Checkpoint`],
//! [`SeedTiming`], and [`SeedRun`] with the appendix's verdict, [`RunStatus`]), which
//! `ilopt run` shares, and how the appendix reads a checkpoint ([`Evaluated`]) and a run
//! ([`AppendixRun`]).

use super::RunStatus;
pub use ilopt::algo::RecordedTermination;
pub use ilopt::algo::records::{Checkpoint, SeedTiming};

/// One seeded run of the appendix: its seed index, status and hyper-parameters are set.
pub type SeedRun = ilopt::algo::records::SeedRun<RunStatus>;

/// A checkpoint's evaluation as the appendix reads it: every appendix checkpoint comes from
/// evaluation episodes, so its score, reward, loss and outcome counts are present (a missing
/// score, reward or loss reads as NaN, which the report's range checks flag; a missing count as
/// 0, as CartPole's time-outs do).
pub trait Evaluated {
    /// The score (obstacle: success rate; CartPole: mean reward / 500).
    fn score(&self) -> f64;
    /// The mean episode reward.
    fn reward(&self) -> f64;
    /// The mean per-decision supervised loss on the evaluation states.
    fn loss(&self) -> f64;
    /// Successful episodes.
    fn successes(&self) -> u32;
    /// Crashed episodes.
    fn crashes(&self) -> u32;
    /// Timed-out episodes (0 for CartPole).
    fn timeouts(&self) -> u32;
}

impl Evaluated for Checkpoint {
    fn score(&self) -> f64 {
        self.score.unwrap_or(f64::NAN)
    }
    fn reward(&self) -> f64 {
        self.reward.unwrap_or(f64::NAN)
    }
    fn loss(&self) -> f64 {
        self.eval_loss.unwrap_or(f64::NAN)
    }
    fn successes(&self) -> u32 {
        self.successes.unwrap_or(0)
    }
    fn crashes(&self) -> u32 {
        self.crashes.unwrap_or(0)
    }
    fn timeouts(&self) -> u32 {
        self.timeouts.unwrap_or(0)
    }
}

/// A run as the appendix reads it: [`run_spec`](super::run_spec) sets its seed index and status.
pub trait AppendixRun {
    /// The seed's index (0 if unset).
    fn seed_index(&self) -> u32;
    /// How the run ended ([`RunStatus::NotConverged`] if unset).
    fn status(&self) -> &RunStatus;
    /// Index of the sustained-convergence checkpoint, if the run converged.
    fn converged(&self) -> Option<usize> {
        self.status().checkpoint()
    }
}

/// The status of a run that records none.
const UNSET: RunStatus = RunStatus::NotConverged;

impl AppendixRun for SeedRun {
    fn seed_index(&self) -> u32 {
        self.seed_index.unwrap_or(0)
    }
    fn status(&self) -> &RunStatus {
        self.status.as_ref().unwrap_or(&UNSET)
    }
}
