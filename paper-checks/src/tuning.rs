//! The pre-registered hyper-parameter protocol.
//!
//! **Grid.** Each algorithm row of a profile may carry a `grid`: dimensions, each a dotted path
//! into the row's [`AlgorithmConfig`](ilopt::algo::AlgorithmConfig) (its JSON form) or `"m"` (trajectories per gradient through
//! [`ilopt::batched::Batched`]), with the values tried. The grid is their Cartesian product, the
//! first dimension varying slowest ([`crate::grid::points`]); the grid order is the profile's order.
//!
//! **Tuning seeds.** Every grid point is run on `tuning_seeds` seeds whose RNG seeds are derived
//! from the key `"tuning|<run key>"` ([`tuning_seed`]) and whose evaluation episodes come from
//! the key `"<task>-tuning-eval"`; the report runs use `"<run key>"` and `"<task>-eval"`. The
//! pipeline checks that no tuning seed equals a report seed before it runs anything.
//!
//! **Selection rule** ([`selection_score`], [`select`]): the median over the tuning seeds of the
//! gradient calls at the sustained-convergence checkpoint, a run that did not converge or diverged
//! counting `2 × budget`; the smallest median wins, ties go to the first point in grid order. A
//! tuning run stops at sustained convergence or divergence (the rule needs nothing later). The
//! thesis's numbers never enter: the rule reads only the tuning runs.
//!
//! Every point's result is kept ([`TuningResult`]) and published as the appendix's sensitivity
//! table; the selected point is recorded in the provenance.

use crate::experiment::{RunStatus, TaskKind};
use crate::grid::GridPoint;
use crate::stats::derive_seed;
use serde::{Deserialize, Serialize};

/// The RNG seed of tuning seed `index` of a run key: the key namespace `"tuning|…"`, disjoint
/// in construction from the report seeds' `"<run key>"` (and checked by the pipeline).
pub fn tuning_seed(run_key: &str, index: u32) -> u64 {
    derive_seed(&format!("tuning|{run_key}"), u64::from(index))
}

/// The key of the tuning runs' evaluation episodes (the report runs use `"<task>-eval"`).
pub fn tuning_eval_key(kind: TaskKind, seed_index: u32) -> String {
    format!("{}-tuning-eval|{seed_index}", kind.name())
}

/// The selection statistic of one grid point: the median over its runs of the gradient calls at
/// sustained convergence, `2 × budget` for a run that did not converge or diverged.
pub fn selection_score(statuses: &[RunStatus], budget: u64) -> f64 {
    let mut xs: Vec<f64> = statuses
        .iter()
        .map(|s| match s {
            RunStatus::Converged {
                gradient_evaluations,
                ..
            } => *gradient_evaluations as f64,
            _ => 2.0 * budget as f64,
        })
        .collect();
    if xs.is_empty() {
        return f64::INFINITY;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// The selected point: the smallest score, ties to the first in grid order.
pub fn select(scores: &[f64]) -> usize {
    let mut best = 0;
    for (i, s) in scores.iter().enumerate() {
        if s.total_cmp(&scores[best]).is_lt() {
            best = i;
        }
    }
    best
}

/// One tuning run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuningRun {
    /// Tuning seed index.
    pub seed_index: u32,
    /// Its RNG seed.
    pub seed: u64,
    /// How it ended.
    pub status: RunStatus,
    /// Gradient calls when it stopped.
    pub gradient_evaluations: u64,
    /// Score of its last checkpoint.
    pub last_score: Option<f64>,
}

/// One grid point's tuning runs and statistic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// The point.
    pub point: GridPoint,
    /// Its runs, in seed order.
    pub runs: Vec<TuningRun>,
    /// [`selection_score`] of the runs.
    pub score: f64,
}

/// A row's whole tuning: every grid point and the one selected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuningResult {
    /// The task.
    pub task: TaskKind,
    /// The row's label.
    pub label: String,
    /// Reuse key.
    pub key_hash: String,
    /// The grid's dimensions (paths) in order.
    pub dims: Vec<String>,
    /// Every point, in grid order.
    pub points: Vec<PointResult>,
    /// Index of the selected point.
    pub selected: usize,
    /// The budget the statistic is relative to.
    pub budget: u64,
}

impl TuningResult {
    /// The selected point.
    pub fn chosen(&self) -> &GridPoint {
        &self.points[self.selected].point
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::GridDim;

    fn entry(grid: Vec<GridDim>) -> crate::config::AlgorithmEntry {
        crate::config::AlgorithmEntry {
            label: "Adam".into(),
            role: Default::default(),
            note: None,
            horizon: None,
            m: None,
            baseline: None,
            config: serde_json::from_str(
                r#"{"algorithm":"adam","form":"causal","alpha":0.005,"beta1":0.9,"beta2":0.999,"epsilon":1e-8}"#,
            )
            .unwrap(),
            grid,
            hyper_parameters_of: None,
        }
    }

    #[test]
    fn grid_is_the_product_in_order() {
        let e = entry(vec![
            GridDim {
                path: "alpha".into(),
                values: vec![0.001.into(), 0.01.into()],
            },
            GridDim {
                path: "m".into(),
                values: vec![1.into(), 16.into()],
            },
        ]);
        let pts = e.grid_points().unwrap();
        assert_eq!(pts.len(), 4);
        assert_eq!(pts[1].m, 16);
        assert_eq!(pts[1].describe(), "alpha=0.001, m=16");
        assert_eq!(pts[2].describe(), "alpha=0.01, m=1");
        let bad = entry(vec![GridDim {
            path: "alhpa".into(),
            values: vec![0.1.into()],
        }]);
        assert!(bad.grid_points().unwrap_err().contains("alhpa"));
    }

    #[test]
    fn a_baseline_grid_dimension_sets_the_points_baseline_and_keys_name_it() {
        use ilopt::baseline::Baseline;
        let mut e = entry(vec![GridDim {
            path: "baseline".into(),
            values: vec![
                serde_json::json!({"kind": "none"}),
                serde_json::json!({"kind": "leave-one-out"}),
            ],
        }]);
        e.m = Some(16);
        let pts = e.grid_points().unwrap();
        assert_eq!(pts[0].baseline, Baseline::None);
        assert_eq!(pts[1].baseline, Baseline::LeaveOneOut);
        assert_eq!(pts[1].describe(), "baseline={kind=leave-one-out}");
        let key = |b: &Baseline| {
            crate::experiment::run_key_of(
                crate::experiment::TaskKind::Cartpole,
                "Adam",
                &pts[0].config,
                16,
                ilopt::task::Horizon::Episodic,
                b,
            )
        };
        // Without a baseline the key is the one rows had before the option existed.
        assert!(!key(&Baseline::None).contains("baseline"));
        assert!(key(&Baseline::LeaveOneOut).ends_with(r#"|baseline={"kind":"leave-one-out"}"#));
        // A baseline fixed outside the grid is named in the point's description.
        e.grid = vec![GridDim {
            path: "alpha".into(),
            values: vec![0.01.into()],
        }];
        e.baseline = Some(Baseline::LeaveOneOut);
        assert_eq!(
            e.grid_points().unwrap()[0].describe(),
            "alpha=0.01, baseline={kind=leave-one-out}"
        );
    }

    #[test]
    fn selection_takes_the_median_with_failures_at_twice_the_budget() {
        let c = |g| RunStatus::Converged {
            checkpoint: 1,
            gradient_evaluations: g,
        };
        let d = RunStatus::Diverged {
            reason: "x".into(),
            gradient_evaluations: 5,
        };
        assert_eq!(selection_score(&[c(10), c(30), c(20)], 100), 20.0);
        // A diverged run is never counted converged: it counts 2 × budget.
        assert_eq!(selection_score(&[c(10), d.clone(), d], 100), 200.0);
        assert_eq!(
            selection_score(&[c(10), RunStatus::NotConverged], 100),
            105.0
        );
        assert_eq!(select(&[200.0, 50.0, 50.0]), 1);
        assert_eq!(select(&[200.0, 200.0]), 0);
    }
}

#[cfg(test)]
mod profile_tests {
    use super::*;
    use crate::config::Profile;
    use crate::experiment::run_key_of;

    /// Every tuning seed of the committed profiles (every grid point of every row) differs from
    /// every report seed the rows could use (every grid point, as the selection is not known
    /// before tuning).
    #[test]
    fn tuning_seeds_never_overlap_report_seeds() {
        for name in ["quick.toml", "full.toml"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("configs")
                .join(name);
            let p = Profile::load(&path).unwrap();
            let mut report = std::collections::BTreeSet::new();
            let mut tuning = std::collections::BTreeSet::new();
            for (kind, t) in [
                (TaskKind::Obstacle, &p.obstacle),
                (TaskKind::Cartpole, &p.cartpole),
            ] {
                for e in &t.algorithms {
                    let h = e.horizon(t, kind.name());
                    for pt in e.grid_points().unwrap() {
                        let rk = run_key_of(kind, &e.label, &pt.config, pt.m, h, &pt.baseline);
                        for s in 0..p.seeds {
                            report.insert(derive_seed(&rk, u64::from(s)));
                        }
                        for s in 0..p.tuning_seeds {
                            tuning.insert(tuning_seed(&rk, s));
                        }
                    }
                }
            }
            assert!(!report.is_empty() && !tuning.is_empty());
            assert!(
                report.is_disjoint(&tuning),
                "{name}: a tuning seed equals a report seed"
            );
            // The evaluation episodes' keys differ as well.
            assert_ne!(
                tuning_eval_key(TaskKind::Cartpole, 0),
                crate::experiment::eval_key(TaskKind::Cartpole, 0)
            );
        }
    }
}
