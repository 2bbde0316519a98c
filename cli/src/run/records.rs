//! What a run records: its checkpoints ([`Checkpoint`]), its deterministic result ([`SeedRun`]),
//! its wall times ([`SeedTiming`], kept apart so that every other file is byte-identical across
//! reruns) — the library's record types, which paper-checks shares — and its final θ
//! ([`SavedTheta`], what `ilopt eval` loads).

pub use ilopt::algo::RecordedTermination;
pub use ilopt::algo::records::{Checkpoint, SeedRun, SeedTiming};
use serde::{Deserialize, Serialize};

/// A saved policy parameter: `theta-seed-<n>.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedTheta {
    /// The task (`cartpole`, `obstacle`, `toy`).
    pub task: String,
    /// The policy (`softmax`, `logistic`, `linear-gaussian`, `toy`).
    pub policy: String,
    /// The seed of the run that produced it.
    pub seed: u64,
    /// θ.
    pub theta: Vec<f64>,
}
