//! The profile's benches (one per task and objective its rows use) and the baselines'
//! evaluation on them.

use crate::config::Profile;
use crate::error::Error;
use crate::experiment::{ReferencePolicy, TaskKind, TaskLearner, baseline_seed, task_learner};
use crate::results::BaselineResult;
use ilopt::task::Horizon;
use rayon::prelude::*;

/// The benches of a profile: one per (task, objective) used by its rows.
pub(super) struct TaskLearners(Vec<(TaskKind, Horizon, TaskLearner)>);

impl TaskLearners {
    pub(super) fn new(profile: &Profile) -> Result<Self, Error> {
        let mut v: Vec<(TaskKind, Horizon, TaskLearner)> = Vec::new();
        for (kind, t) in [
            (TaskKind::Obstacle, &profile.obstacle),
            (TaskKind::Cartpole, &profile.cartpole),
        ] {
            for e in &t.algorithms {
                let h = e.horizon(t, kind);
                if !v.iter().any(|(k, hh, _)| *k == kind && *hh == h) {
                    v.push((kind, h, task_learner(kind, t, h)?));
                }
            }
        }
        Ok(TaskLearners(v))
    }
    pub(super) fn get(&self, kind: TaskKind, h: Horizon) -> &TaskLearner {
        self.0
            .iter()
            .find(|(k, hh, _)| *k == kind && *hh == h)
            .map(|x| &x.2)
            .expect("a bench for every row's objective")
    }
    /// The task's bench under its default objective (baselines: no training).
    pub(super) fn of_task(&self, kind: TaskKind) -> &TaskLearner {
        self.0
            .iter()
            .find(|(k, _, _)| *k == kind)
            .map(|x| &x.2)
            .expect("every task has a row")
    }
}

/// Evaluate every task's baselines on every seed's evaluation episodes (cheap: no training, so
/// never cached).
pub(super) fn baselines_job(
    profile: &Profile,
    benches: &TaskLearners,
    seeds: &[u32],
) -> Result<Vec<BaselineResult>, Error> {
    let mut out = Vec::new();
    for (kind, t) in [
        (TaskKind::Obstacle, &profile.obstacle),
        (TaskKind::Cartpole, &profile.cartpole),
    ] {
        let bench = benches.of_task(kind);
        for &b in ReferencePolicy::of(kind) {
            let runs = seeds
                .par_iter()
                .map(|&s| baseline_seed(bench, kind, t, b, s))
                .collect::<Result<Vec<_>, Error>>()?;
            out.push(BaselineResult {
                task: kind,
                baseline: b,
                label: b.label(kind, t),
                runs,
            });
        }
    }
    Ok(out)
}
