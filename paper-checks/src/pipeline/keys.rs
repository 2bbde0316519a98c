//! The cache keys: a hash of everything that determines a stored result (the row, its task's
//! section and expert, the seeds, the size profile, and the code version).

use crate::config::{AlgorithmEntry, Profile, TaskExperiment};
use crate::experiment::{TaskKind, run_key};
use crate::stats::fnv1a;

/// What determines a task's runs apart from the algorithm rows: the section without its rows,
/// and the expert's identity.
pub(super) fn section_key(kind: TaskKind, t: &TaskExperiment) -> String {
    let expert = (kind == TaskKind::Cartpole)
        .then(|| crate::config::expert_identity(t.expert.unwrap_or_default()));
    let mut bare = t.clone();
    bare.algorithms.clear();
    format!(
        "{}|{}",
        serde_json::to_string(&bare).unwrap_or_default(),
        expert.unwrap_or_default()
    )
}

/// The cache key of a row's report runs: the row at its selected hyper-parameters, its task's
/// section and expert, the number of seeds, and the code version.
pub(super) fn task_key(
    profile: &Profile,
    kind: TaskKind,
    t: &TaskExperiment,
    e: &AlgorithmEntry,
    version: &str,
) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!(
            "{}|{}|{}|{}|code={version}",
            run_key(kind, t, e),
            section_key(kind, t),
            serde_json::to_string(e).unwrap_or_default(),
            profile.seeds
        ))
    )
}

/// The cache key of a row's tuning: the row with its grid, its task's section and expert, the
/// number of tuning seeds, the protocol's rungs and extensions, and the code version.
pub(super) fn tuning_key(
    profile: &Profile,
    kind: TaskKind,
    t: &TaskExperiment,
    e: &AlgorithmEntry,
    version: &str,
) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!(
            "tuning|{}|{}|{}|{}|{}|code={version}",
            kind.name(),
            section_key(kind, t),
            serde_json::to_string(e).unwrap_or_default(),
            profile.tuning_seeds,
            serde_json::to_string(&profile.tuning).unwrap_or_default()
        ))
    )
}

/// The cache key of the Fig. 4.2 study: its settings and the code version.
pub(super) fn gradient_key(profile: &Profile, version: &str) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!(
            "gradient-error|{}|code={version}",
            profile.gradient_error.key_hash()
        ))
    )
}

/// The cache key of the theorem table: its size profile and the code version.
pub(super) fn theory_key(profile: &Profile, version: &str) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!("theory|{}|code={version}", profile.theory_profile))
    )
}
