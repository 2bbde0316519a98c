//! What a run of the appendix produces: every configuration's per-seed results and wall times,
//! the baselines, the tuning, the Fig. 4.2 study and the theorem-check table.

use crate::config::AlgorithmEntry;
use crate::experiment::{Checkpoint, ReferencePolicy, SeedRun, SeedTiming, TaskKind};
pub use crate::gradient_error::GradientErrorResult;
use crate::protocol::TuningResult;
use ilopt_theory::check::Check;
use serde::{Deserialize, Serialize};

/// All results of one algorithm on one task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConfigResult {
    /// The task.
    pub task: TaskKind,
    /// The algorithm's label.
    pub label: String,
    /// Hash of everything that determines the results (reuse key).
    pub key_hash: String,
    /// The algorithm entry as configured.
    pub entry: AlgorithmEntry,
    /// Per-seed results, in seed order.
    pub runs: Vec<SeedRun>,
}

/// A configuration of the obstacle task labelled STORM with the given runs (its entry an Adam
/// configuration; the report's tests read only the runs).
#[cfg(test)]
pub(crate) fn storm_config_for_tests(runs: Vec<SeedRun>) -> ConfigResult {
    ConfigResult {
        task: TaskKind::Obstacle,
        label: "STORM".into(),
        key_hash: String::new(),
        entry: serde_json::from_value(serde_json::json!({
            "label": "STORM",
            "config": {"algorithm": "adam", "form": "causal", "alpha": 0.005,
                       "beta1": 0.9, "beta2": 0.999, "epsilon": 1e-8}
        }))
        .expect("an entry"),
        runs,
    }
}

/// Wall times of one configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConfigTiming {
    /// The task.
    pub task: TaskKind,
    /// The algorithm's label.
    pub label: String,
    /// Per-seed timings, in seed order.
    pub runs: Vec<SeedTiming>,
    /// Wall time of the whole configuration (all seeds, evaluation included).
    pub wall_seconds: f64,
}

/// A configuration's results with its timings (absent when reused without a timing file).
pub type ConfigWithTiming = (ConfigResult, Option<ConfigTiming>);

/// A baseline policy's evaluation on every seed's evaluation episodes (the episodes the learners'
/// checkpoints of that seed meet).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BaselineResult {
    /// The task.
    pub task: TaskKind,
    /// Which baseline.
    pub baseline: ReferencePolicy,
    /// Its label in tables and figures.
    pub label: String,
    /// One evaluation per seed, in seed order (iteration 0, zero cost).
    pub runs: Vec<Checkpoint>,
}

/// Everything the reports need.
#[derive(Debug, Clone)]
pub struct Results {
    /// Fig. 4.2.
    pub gradient_error: GradientErrorResult,
    /// Obstacle configurations in table order.
    pub obstacle: Vec<ConfigWithTiming>,
    /// CartPole configurations in table order.
    pub cartpole: Vec<ConfigWithTiming>,
    /// The baselines of both tasks (obstacle first, table order).
    pub baselines: Vec<BaselineResult>,
    /// The tuning of every row (both tasks, table order; rows without a grid have one point and
    /// no tuning runs).
    pub tuning: Vec<TuningResult>,
    /// The theorem-check table.
    pub theory: TheoryTable,
    /// Configurations computed in this run (the others were reused).
    pub computed: Vec<String>,
    /// Files removed from `runs/` and `timings/` because no row of this profile produces them.
    pub removed_stale: Vec<String>,
}

/// The theorem-check table of a run: the checks, or the note that the profile ran none.
#[derive(Debug, Clone, PartialEq)]
pub enum TheoryTable {
    /// The profile sets `theory_profile = "none"`.
    NotRun,
    /// Every check of the table, in table order.
    Checks(Vec<Check>),
}

impl TheoryTable {
    /// The checks (none when not run).
    pub fn checks(&self) -> &[Check] {
        match self {
            TheoryTable::NotRun => &[],
            TheoryTable::Checks(c) => c,
        }
    }
}
