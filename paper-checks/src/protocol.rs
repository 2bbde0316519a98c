//! The pre-registered hyper-parameter protocol.
//!
//! **Grid.** Each algorithm row of a profile may carry a `grid` (one product of dimensions) or
//! `grids` (several products tried together): dimensions are dotted paths into the row's
//! [`AlgorithmConfig`](ilopt::algo::AlgorithmConfig) (its JSON form), `"m"` (trajectories per
//! gradient through [`ilopt::batched::Batched`]) or `"baseline"`, each with a list of values or
//! a log range over the half-decade series ([`crate::grid::GridDim`]).
//!
//! **Tuning seeds.** Every grid point is run on `tuning_seeds` seeds whose RNG seeds are derived
//! from the key `"tuning|<run key>"` ([`tuning_seed`]) and whose evaluation episodes come from
//! the key `"<task>-tuning-eval"`; the report runs use `"<run key>"` and `"<task>-eval"`. The
//! pipeline checks that no tuning seed equals a report seed before it runs anything.
//!
//! **Score** ([`Score`], lexicographic, [`Score::cmp_better`]): first the median over the tuning
//! seeds of the gradient calls to sustained convergence (+∞ for a run that did not converge or
//! diverged); then, among points tied there (including "nothing converged"), the larger mean over
//! the seeds of the area under the learning curve ([`area_under_curve`]: the mean score over the
//! checkpoints, a diverged run scoring 0 from the point it diverged); then the smaller step (the
//! point's first log dimension); then the fewer trajectories per gradient. A tie that survives
//! all four is broken by the point's text and *reported* as a tie ([`TuningResult::tied_with`]).
//! There is no first-in-grid tie-break.
//!
//! **Successive halving** (Jamieson & Talwalkar 2016; the rung schedule of Hyperband, Li et al.
//! 2018; [`TuningProtocol`]): every point runs to the first rung's budget, the best
//! ⌈n / `halving`⌉ by the score at that budget go on to the next rung — with every point tied
//! with the last of them on the two run-reading keys, so that a rung that cannot tell points
//! apart eliminates none — and so on; the last rung is the whole budget. A run is deterministic in its key, so a run to a larger budget repeats
//! the shorter one and extends it; a run that converged or diverged at a lower rung is not run
//! again (its result at any larger budget is the same).
//!
//! **Edge extension**: when the pick lies on an end of one of its log dimensions, that dimension
//! grows by the next value of the series beyond the end and the selection is made again over
//! the grown grid, up to `extensions` times. Every round is recorded ([`Round`]); a pick still
//! on an edge after the last round, or one whose tuning runs never converged, is reported as
//! such and caps the verdicts of the claims its row enters ([`TuningResult::weakness`]).
//!
//! Tuning runs stop at sustained convergence or divergence (the score needs nothing later: the
//! curve of a converged run is carried at its last score). The thesis's numbers never enter: the
//! rule reads only the tuning runs.

pub use crate::config::TuningProtocol;
use crate::experiment::{RunStatus, TaskKind};
use crate::grid::GridPoint;
use crate::stats::derive_seed;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;

/// The RNG seed of tuning seed `index` of a run key: the key namespace `"tuning|…"`, disjoint
/// in construction from the report seeds' `"<run key>"` (and checked by the pipeline).
pub fn tuning_seed(run_key: &str, index: u32) -> u64 {
    derive_seed(&format!("tuning|{run_key}"), u64::from(index))
}

/// The key of the tuning runs' evaluation episodes (the report runs use `"<task>-eval"`).
pub fn tuning_eval_key(kind: TaskKind, seed_index: u32) -> String {
    format!("{}-tuning-eval|{seed_index}", kind.name())
}

impl TuningProtocol {
    /// Check the schedule.
    ///
    /// # Errors
    /// `(field, reason)` for empty or non-increasing rungs, a rung outside (0, 1], a last rung
    /// other than 1, or `halving` below 2.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, r: &str| Err((f.to_string(), r.to_string()));
        if self.rungs.is_empty() {
            return bad("rungs", "must list at least one fraction (the last 1)");
        }
        if self
            .rungs
            .iter()
            .any(|f| !(f.is_finite() && *f > 0.0 && *f <= 1.0))
        {
            return bad("rungs", "every fraction must lie in (0, 1]");
        }
        if self.rungs.windows(2).any(|w| w[0] >= w[1]) {
            return bad("rungs", "the fractions must increase");
        }
        if *self.rungs.last().unwrap_or(&0.0) != 1.0 {
            return bad("rungs", "the last rung must be 1 (the whole budget)");
        }
        if self.halving < 2 {
            return bad("halving", "must be at least 2");
        }
        Ok(())
    }

    /// The rungs' budgets in gradient calls for a task with this budget and checkpoint
    /// interval: each fraction of the budget rounded up to a multiple of `every` (so that a
    /// rung's checkpoints are the first of the whole run's), at most the budget, repeats
    /// dropped.
    pub fn rung_budgets(&self, budget: u64, every: u64) -> Vec<u64> {
        let mut out: Vec<u64> = Vec::new();
        for f in &self.rungs {
            let raw = (f * budget as f64).ceil() as u64;
            let b = raw
                .div_ceil(every.max(1))
                .saturating_mul(every.max(1))
                .min(budget);
            if out.last() != Some(&b) {
                out.push(b);
            }
        }
        out
    }

    /// The rung budgets for a grid of `points` points: [`TuningProtocol::rung_budgets`], or the
    /// whole budget alone for a grid smaller than `exhaustive_below`.
    pub fn rungs_for(&self, points: usize, budget: u64, every: u64) -> Vec<u64> {
        if points < self.exhaustive_below as usize {
            vec![budget]
        } else {
            self.rung_budgets(budget, every)
        }
    }

    /// How many points go on from a rung of `n` points: ⌈n / halving⌉.
    pub fn kept(&self, n: usize) -> usize {
        n.div_ceil(self.halving.max(2) as usize)
    }
}

/// One tuning run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuningRun {
    /// Tuning seed index.
    pub seed_index: u32,
    /// Its RNG seed.
    pub seed: u64,
    /// The budget it was run to (a rung's).
    pub budget: u64,
    /// How it ended.
    pub status: RunStatus,
    /// Gradient calls when it stopped.
    pub gradient_evaluations: u64,
    /// The score at each checkpoint reached, in order (calls 0, `every`, 2·`every`, …).
    pub scores: Vec<f64>,
    /// The gradient calls actually spent at each of those checkpoints (a step may overshoot).
    pub calls: Vec<u64>,
}

impl TuningRun {
    /// Score of its last checkpoint.
    pub fn last_score(&self) -> Option<f64> {
        self.scores.last().copied()
    }

    /// Whether the run's result at a larger budget is this one: it converged or diverged.
    pub fn is_final(&self) -> bool {
        !matches!(self.status, RunStatus::NotConverged)
    }

    /// This run as the same seed's run to `budget` would have been (runs are deterministic in
    /// their key, and a run to a smaller budget is the first part of a run to a larger one):
    /// itself when it converged or diverged by then; its first checkpoints, not converged,
    /// when it ran past `budget`; `None` when it stopped short of `budget` without converging
    /// or diverging (it must be run again).
    pub fn at_budget(&self, budget: u64, every: u64) -> Option<TuningRun> {
        let n = checkpoint_count(budget, every);
        if self.is_final() && self.scores.len() <= n {
            return Some(TuningRun {
                budget,
                ..self.clone()
            });
        }
        // Not converged nor diverged, and stopped before `budget`'s last checkpoint.
        if self.scores.len() < n {
            return None;
        }
        Some(TuningRun {
            budget,
            status: RunStatus::NotConverged,
            gradient_evaluations: self.calls.get(n - 1).copied().unwrap_or(0),
            scores: self.scores[..n].to_vec(),
            calls: self.calls[..n.min(self.calls.len())].to_vec(),
            ..self.clone()
        })
    }
}

/// The number of checkpoints of a run to `budget` with checkpoints every `every` calls: the
/// call counts 0, `every`, 2·`every`, … below the budget, and the budget.
pub fn checkpoint_count(budget: u64, every: u64) -> usize {
    (budget.div_ceil(every.max(1)) + 1) as usize
}

/// The area under a run's learning curve up to `budget`: the mean of its scores over the
/// [`checkpoint_count`] checkpoints, where the checkpoints after a divergence score 0 and those
/// after sustained convergence (where a tuning run stops) keep the last score.
pub fn area_under_curve(run: &TuningRun, budget: u64, every: u64) -> f64 {
    let n = checkpoint_count(budget, every);
    if n == 0 {
        return 0.0;
    }
    let fill = match run.status {
        RunStatus::Diverged { .. } => 0.0,
        _ => run.last_score().unwrap_or(0.0),
    };
    let sum: f64 = (0..n)
        .map(|i| run.scores.get(i).copied().unwrap_or(fill))
        .sum();
    sum / n as f64
}

/// The median of `xs` (+∞ entries allowed; NaN for none).
fn median(mut xs: Vec<f64>) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// A grid point's lexicographic tuning score at one budget (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Score {
    /// The budget the runs were scored at.
    pub budget: u64,
    /// Median over the seeds of the calls to sustained convergence (+∞: not converged or
    /// diverged; serialised as `null`).
    #[serde(with = "infinite_as_null")]
    pub median_calls: f64,
    /// Mean over the seeds of [`area_under_curve`].
    pub auc: f64,
    /// The point's step: its first log dimension's value (+∞ when it has none).
    #[serde(with = "infinite_as_null")]
    pub step: f64,
    /// Trajectories per gradient.
    pub m: usize,
    /// Runs converged / diverged (of the seeds).
    pub converged: usize,
    /// Runs that diverged.
    pub diverged: usize,
}

mod infinite_as_null {
    use serde::{Deserialize, Deserializer, Serializer};
    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        if x.is_finite() {
            s.serialize_f64(*x)
        } else {
            s.serialize_none()
        }
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}

impl Score {
    /// The score of `point`'s runs at `budget` (checkpoints every `every` calls).
    pub fn of(point: &GridPoint, runs: &[TuningRun], budget: u64, every: u64) -> Self {
        let calls: Vec<f64> = runs
            .iter()
            .map(|r| match r.status {
                RunStatus::Converged {
                    gradient_evaluations,
                    ..
                } if gradient_evaluations <= budget => gradient_evaluations as f64,
                _ => f64::INFINITY,
            })
            .collect();
        let converged = calls.iter().filter(|c| c.is_finite()).count();
        let auc = if runs.is_empty() {
            0.0
        } else {
            runs.iter()
                .map(|r| area_under_curve(r, budget, every))
                .sum::<f64>()
                / runs.len() as f64
        };
        Score {
            budget,
            median_calls: median(calls),
            auc,
            step: point_step(point),
            m: point.m,
            converged,
            diverged: runs.iter().filter(|r| r.status.is_diverged()).count(),
        }
    }

    /// `Less` when `self` is the better score: fewer median calls, then the larger area, then
    /// the smaller step, then the fewer trajectories per gradient.
    pub fn cmp_better(&self, other: &Score) -> Ordering {
        self.median_calls
            .total_cmp(&other.median_calls)
            .then(other.auc.total_cmp(&self.auc))
            .then(self.step.total_cmp(&other.step))
            .then(self.m.cmp(&other.m))
    }

    /// Whether the two scores tie on the two keys that read the runs (median calls and area).
    pub fn ties_on_runs(&self, other: &Score) -> bool {
        self.median_calls.total_cmp(&other.median_calls).is_eq()
            && self.auc.total_cmp(&other.auc).is_eq()
    }
}

/// A point's step: the value of its first log dimension ([`crate::grid::GridDim::is_log`]),
/// recorded in the point's values; +∞ when it has none.
fn point_step(point: &GridPoint) -> f64 {
    point
        .log_dims
        .first()
        .and_then(|path| point.values.iter().find(|(p, _)| p == path))
        .and_then(|(_, v)| v.as_f64())
        .unwrap_or(f64::INFINITY)
}

/// The order of `scored` (index, score, text) from best to worst: [`Score::cmp_better`], then
/// the point's text (a deterministic last resort, reported as a tie).
pub fn ranking(scored: &[(usize, &Score, String)]) -> Vec<usize> {
    let mut order: Vec<&(usize, &Score, String)> = scored.iter().collect();
    order.sort_by(|a, b| a.1.cmp_better(b.1).then_with(|| a.2.cmp(&b.2)));
    order.into_iter().map(|x| x.0).collect()
}

/// How many points a rung of successive halving promotes: the first `k` of `order` (the rung's
/// [`ranking`], best first) and every point after them that ties with the k-th on the keys that
/// read the runs ([`Score::ties_on_runs`]), so that a rung which cannot tell points apart
/// eliminates none of them (the step and m break ties for the final pick, not for promotion).
/// `scored` holds every ranked point's score by index.
///
/// # Panics
/// If `k` is 0 or exceeds `order`, or a ranked index has no score in `scored`.
pub fn promoted(order: &[usize], k: usize, scored: &[(usize, Score)]) -> usize {
    let score_of = |i: usize| {
        &scored
            .iter()
            .find(|x| x.0 == i)
            .expect("a ranked point's score")
            .1
    };
    let cutoff = score_of(order[k - 1]);
    k + order[k..]
        .iter()
        .take_while(|&&i| score_of(i).ties_on_runs(cutoff))
        .count()
}

/// The points other than the pick (grid index `pick`) that reached the pick's final budget with
/// a score tied with its own on the keys that read the runs: the ties the step and m broke.
pub fn tied_with(reached: &[PointResult], pick: usize, pick_score: &Score) -> Vec<String> {
    reached
        .iter()
        .filter(|p| p.point.index != pick)
        .filter(|p| {
            p.score
                .as_ref()
                .is_some_and(|s| s.budget == pick_score.budget && s.ties_on_runs(pick_score))
        })
        .map(|p| p.point.describe())
        .collect()
}

/// One grid point's tuning runs and score at the highest rung it reached.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// The point.
    pub point: GridPoint,
    /// Its runs at that rung, in seed order.
    pub runs: Vec<TuningRun>,
    /// Its score there (absent for a row without a grid).
    pub score: Option<Score>,
    /// The highest rung it reached (0-based).
    pub rung: usize,
}

/// One rung of one round of successive halving.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RungRecord {
    /// Its budget in gradient calls.
    pub budget: u64,
    /// How many points ran at it.
    pub points: usize,
    /// How many went on to the next rung (the pick, at the last).
    pub kept: usize,
}

/// One round of selection: successive halving over the grid as it stood, and the extension
/// the pick asked for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Round {
    /// The grid's size in points.
    pub points: usize,
    /// The rungs.
    pub rungs: Vec<RungRecord>,
    /// The pick (its text).
    pub pick: String,
    /// The dimensions extended after this round (`path: from … to` as grown).
    pub extended: Vec<String>,
}

/// A row's whole tuning: every grid point tried and the one selected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuningResult {
    /// The task.
    pub task: TaskKind,
    /// The row's label.
    pub label: String,
    /// Reuse key.
    pub key_hash: String,
    /// The grid's dimensions (paths) in order, over every sub-grid.
    pub dims: Vec<String>,
    /// Every point tried, in grid order of the final grid.
    pub points: Vec<PointResult>,
    /// Index of the selected point.
    pub selected: usize,
    /// The task's budget (the last rung's).
    pub budget: u64,
    /// The rounds of selection (empty for a row without a grid).
    #[serde(default)]
    pub rounds: Vec<Round>,
    /// The log dimensions on whose end the pick still lies after the last round.
    #[serde(default)]
    pub on_edge: Vec<String>,
    /// The points the pick tied with on both run-reading keys (median calls and area).
    #[serde(default)]
    pub tied_with: Vec<String>,
    /// How many tuning seeds each point ran.
    #[serde(default)]
    pub tuning_seeds: u32,
}

impl TuningResult {
    /// The selected point.
    pub fn chosen(&self) -> &GridPoint {
        &self.points[self.selected].point
    }

    /// Whether this row was tuned (it has a grid of its own).
    pub fn is_tuned(&self) -> bool {
        !self.rounds.is_empty()
    }

    /// Why the pick cannot carry a "not reproduced": no tuning run of the pick converged, the
    /// pick lies on an edge of its grid after extension, or fewer than 3 tuning seeds; `None`
    /// when none applies or the row was not tuned.
    pub fn weakness(&self) -> Option<String> {
        if !self.is_tuned() {
            return None;
        }
        let mut why = Vec::new();
        let chosen = &self.points[self.selected];
        if chosen.score.as_ref().is_some_and(|s| s.converged == 0) {
            why.push("no tuning run of its pick converged".to_string());
        }
        if !self.on_edge.is_empty() {
            why.push(format!(
                "its pick lies on an edge of {} after extension",
                self.on_edge.join(", ")
            ));
        }
        if self.tuning_seeds < 3 {
            why.push(format!(
                "{} tuning seed(s), fewer than 3",
                self.tuning_seeds
            ));
        }
        (!why.is_empty()).then(|| why.join("; "))
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
            grids: Vec::new(),
            hyper_parameters_of: None,
        }
    }

    #[test]
    fn grid_is_the_product_in_order() {
        let e = entry(vec![
            GridDim::list("alpha", vec![0.001.into(), 0.01.into()]),
            GridDim::list("m", vec![1.into(), 16.into()]),
        ]);
        let pts = e.grid_points().unwrap();
        assert_eq!(pts.len(), 4);
        assert_eq!(pts[1].m, 16);
        assert_eq!(pts[1].describe(), "alpha=0.001, m=16");
        assert_eq!(pts[2].describe(), "alpha=0.01, m=1");
        let bad = entry(vec![GridDim::list("alhpa", vec![0.1.into()])]);
        assert!(bad.grid_points().unwrap_err().contains("alhpa"));
    }

    #[test]
    fn a_baseline_grid_dimension_sets_the_points_baseline_and_keys_name_it() {
        use ilopt::baseline::Baseline;
        let mut e = entry(vec![GridDim::list(
            "baseline",
            vec![
                serde_json::json!({"kind": "none"}),
                serde_json::json!({"kind": "leave-one-out"}),
            ],
        )]);
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
        e.grid = vec![GridDim::list("alpha", vec![0.01.into()])];
        e.baseline = Some(Baseline::LeaveOneOut);
        assert_eq!(
            e.grid_points().unwrap()[0].describe(),
            "alpha=0.01, baseline={kind=leave-one-out}"
        );
    }

    fn run(status: RunStatus, scores: &[f64]) -> TuningRun {
        TuningRun {
            seed_index: 0,
            seed: 0,
            budget: 400,
            gradient_evaluations: 0,
            scores: scores.to_vec(),
            calls: (0..scores.len() as u64).map(|i| 100 * i + 3).collect(),
            status,
        }
    }

    #[test]
    fn a_run_at_a_smaller_budget_is_the_first_part_of_a_longer_one() {
        // Run to 400 (checkpoints at 0..=400 every 100), not converged.
        let long = run(RunStatus::NotConverged, &[0.1, 0.2, 0.3, 0.4, 0.5]);
        let short = long.at_budget(200, 100).unwrap();
        assert_eq!(short.scores, vec![0.1, 0.2, 0.3]);
        assert_eq!((short.budget, short.gradient_evaluations), (200, 203));
        assert_eq!(short.status, RunStatus::NotConverged);
        assert_eq!(short.calls, vec![3, 103, 203]);
        // A run to exactly that budget is itself.
        let mut exact = run(RunStatus::NotConverged, &[0.1, 0.2, 0.3]);
        exact.budget = 200;
        assert_eq!(exact.at_budget(200, 100).unwrap().scores, exact.scores);
        // A longer budget than it ran needs a new run, unless it had ended.
        assert!(long.at_budget(800, 100).is_none());
        let mut d = run(div(), &[0.5, 1.0]);
        d.budget = 200;
        let later = d.at_budget(800, 100).unwrap();
        assert_eq!((later.status, later.budget), (div(), 800));
        // Converged at the third checkpoint (the window ended at 200): converged at 200 and
        // later, not converged at 100 (its window had not ended).
        let mut c = run(conv(0), &[0.9, 0.9, 0.9]);
        c.budget = 400;
        assert!(c.at_budget(200, 100).unwrap().status.is_converged());
        assert!(c.at_budget(800, 100).unwrap().status.is_converged());
        let early = c.at_budget(100, 100).unwrap();
        assert_eq!(early.status, RunStatus::NotConverged);
        assert_eq!(early.scores, vec![0.9, 0.9]);
    }

    fn conv(calls: u64) -> RunStatus {
        RunStatus::Converged {
            checkpoint: 1,
            gradient_evaluations: calls,
        }
    }

    fn div() -> RunStatus {
        RunStatus::Diverged {
            reason: "x".into(),
            gradient_evaluations: 150,
        }
    }

    fn point(eta: f64, m: usize) -> GridPoint {
        let e = entry(vec![
            GridDim::log("alpha", eta, eta),
            GridDim::list("m", vec![m.into()]),
        ]);
        e.grid_points().unwrap().remove(0)
    }

    #[test]
    fn tuning_seeds_and_episodes_have_keys_of_their_own() {
        let rk = "obstacle|SGD|{}|m=1|fixed";
        let seeds: Vec<u64> = (0..4).map(|i| tuning_seed(rk, i)).collect();
        for (i, s) in seeds.iter().enumerate() {
            assert_eq!(*s, derive_seed(&format!("tuning|{rk}"), i as u64));
            assert_ne!(*s, derive_seed(rk, i as u64));
        }
        assert_eq!(
            seeds
                .iter()
                .collect::<std::collections::BTreeSet<_>>()
                .len(),
            4
        );
        assert_eq!(
            tuning_eval_key(TaskKind::Cartpole, 2),
            "cartpole-tuning-eval|2"
        );
        assert_ne!(
            tuning_eval_key(TaskKind::Obstacle, 0),
            tuning_eval_key(TaskKind::Obstacle, 1)
        );
    }

    #[test]
    fn the_area_fills_diverged_runs_with_zero_and_converged_ones_with_their_last_score() {
        // Budget 400, every 100: checkpoints at 0, 100, 200, 300, 400.
        assert_eq!(checkpoint_count(400, 100), 5);
        assert_eq!(checkpoint_count(450, 100), 6);
        let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        let d = run(div(), &[0.5, 1.0]);
        close(area_under_curve(&d, 400, 100), 1.5 / 5.0);
        let c = run(conv(100), &[0.0, 1.0, 0.5]);
        close(
            area_under_curve(&c, 400, 100),
            (0.0 + 1.0 + 0.5 * 3.0) / 5.0,
        );
        let n = run(RunStatus::NotConverged, &[0.1, 0.2, 0.3, 0.4, 0.5]);
        close(area_under_curve(&n, 400, 100), 0.3);
        // At a lower rung only the first checkpoints count.
        close(area_under_curve(&n, 200, 100), 0.2);
    }

    #[test]
    fn the_scores_area_is_the_mean_of_its_runs_areas() {
        let p = point(1e-3, 1);
        // Areas over checkpoints 0, 100, …, 400: 0.2 and 0.6 (not-converged runs to the budget).
        let low = run(RunStatus::NotConverged, &[0.2; 5]);
        let high = run(RunStatus::NotConverged, &[0.6; 5]);
        let s = Score::of(&p, &[low, high], 400, 100);
        assert!((s.auc - 0.4).abs() < 1e-12, "{}", s.auc);
        assert_eq!(Score::of(&p, &[], 400, 100).auc, 0.0);
    }

    #[test]
    fn a_score_survives_json_with_its_infinite_entries_as_null() {
        let s = Score {
            budget: 400,
            median_calls: f64::INFINITY,
            auc: 0.25,
            step: 1e-3,
            m: 16,
            converged: 0,
            diverged: 1,
        };
        let text = serde_json::to_string(&s).unwrap();
        assert!(text.contains(r#""median_calls":null"#), "{text}");
        assert_eq!(serde_json::from_str::<Score>(&text).unwrap(), s);
        let finite = Score {
            median_calls: 300.0,
            step: f64::INFINITY,
            ..s
        };
        let text = serde_json::to_string(&finite).unwrap();
        assert!(text.contains(r#""step":null"#), "{text}");
        assert_eq!(serde_json::from_str::<Score>(&text).unwrap(), finite);
    }

    #[test]
    fn the_median_takes_the_middle_value_or_the_mean_of_the_middle_two() {
        assert!(median(vec![]).is_nan());
        assert_eq!(median(vec![7.0]), 7.0);
        // Unsorted input, odd and even counts.
        assert_eq!(median(vec![5.0, 1.0, 3.0]), 3.0);
        assert_eq!(median(vec![8.0, 2.0, 4.0, 6.0]), 5.0);
        assert_eq!(median(vec![10.0, 1.0, 4.0, 2.0, 30.0, 6.0]), 5.0);
        // +∞ entries (runs that did not converge) sort last.
        assert_eq!(median(vec![f64::INFINITY, 100.0, 300.0]), 300.0);
        assert_eq!(median(vec![f64::INFINITY, 100.0, 300.0, 200.0]), 250.0);
        assert!(median(vec![f64::INFINITY, 100.0, f64::INFINITY, 200.0]).is_infinite());
    }

    #[test]
    fn the_score_is_lexicographic_median_then_area_then_step_then_m() {
        let p = point(1e-3, 1);
        // Median calls over three seeds; a diverged or unconverged run counts +∞.
        let s = Score::of(
            &p,
            &[run(conv(300), &[]), run(conv(100), &[]), run(div(), &[])],
            400,
            100,
        );
        assert_eq!((s.median_calls, s.converged, s.diverged), (300.0, 2, 1));
        let s = Score::of(
            &p,
            &[
                run(conv(100), &[]),
                run(div(), &[]),
                run(RunStatus::NotConverged, &[]),
            ],
            400,
            100,
        );
        assert!(s.median_calls.is_infinite());
        // Convergence after the scored budget does not count at a lower rung.
        let late = Score::of(&p, &[run(conv(300), &[])], 200, 100);
        assert!(late.median_calls.is_infinite());
        assert_eq!(s.step, 1e-3);
        let base = Score {
            budget: 400,
            median_calls: f64::INFINITY,
            auc: 0.5,
            step: 1e-3,
            m: 16,
            converged: 0,
            diverged: 0,
        };
        let with = |f: &dyn Fn(&mut Score)| {
            let mut x = base.clone();
            f(&mut x);
            x
        };
        let faster = with(&|x| x.median_calls = 300.0);
        let higher = with(&|x| x.auc = 0.6);
        let smaller = with(&|x| x.step = 1e-4);
        let fewer = with(&|x| x.m = 1);
        assert_eq!(faster.cmp_better(&higher), Ordering::Less);
        assert_eq!(higher.cmp_better(&smaller), Ordering::Less);
        assert_eq!(smaller.cmp_better(&fewer), Ordering::Less);
        assert_eq!(fewer.cmp_better(&base), Ordering::Less);
        assert_eq!(base.cmp_better(&base.clone()), Ordering::Equal);
        assert!(base.ties_on_runs(&smaller) && !base.ties_on_runs(&higher));
        // The ranking never depends on the grid order: only on the scores and the texts.
        let a = (0, &base, "b".to_string());
        let b = (1, &higher, "a".to_string());
        let c = (2, &base, "a".to_string());
        assert_eq!(ranking(&[a.clone(), b.clone(), c.clone()]), vec![1, 2, 0]);
        assert_eq!(ranking(&[c, a, b]), vec![1, 2, 0]);
    }

    fn scored_at(budget: u64, median_calls: f64, auc: f64, step: f64) -> Score {
        Score {
            budget,
            median_calls,
            auc,
            step,
            m: 1,
            converged: 0,
            diverged: 0,
        }
    }

    /// A rung promotes its best k and every point tied with the k-th on the run-reading keys,
    /// whatever their steps; a point that differs from the k-th is cut, even where it ties with
    /// a point behind it.
    #[test]
    fn a_rung_promotes_its_best_k_and_the_points_tied_with_the_kth() {
        let inf = f64::INFINITY;
        // Scored in grid order; point 4 ties with point 1 on the runs, with a larger step.
        let scored = vec![
            (0, scored_at(400, 200.0, 0.5, 1e-3)),
            (1, scored_at(400, 300.0, 0.4, 1e-3)),
            (2, scored_at(400, inf, 0.1, 1e-3)),
            (3, scored_at(400, 100.0, 0.9, 1e-3)),
            (4, scored_at(400, 300.0, 0.4, 1e-2)),
        ];
        let ranked: Vec<(usize, &Score, String)> =
            scored.iter().map(|(i, s)| (*i, s, i.to_string())).collect();
        let order = ranking(&ranked);
        assert_eq!(order, vec![3, 0, 1, 4, 2]);
        let kept: Vec<usize> = (1..=5).map(|k| promoted(&order, k, &scored)).collect();
        assert_eq!(kept, vec![1, 2, 4, 4, 5]);
    }

    /// The ties a pick names are the other points scored at its final budget that tie with it on
    /// the run-reading keys: not a point with the same keys cut at an earlier rung, not one at the
    /// final budget with another area, not one without a score.
    #[test]
    fn the_ties_named_are_the_points_at_the_picks_budget_that_tie_on_the_runs() {
        let inf = f64::INFINITY;
        let at = |i: usize, eta: f64, budget: u64, auc: f64| {
            let mut p = point(eta, 1);
            p.index = i;
            PointResult {
                point: p,
                runs: vec![],
                score: Some(scored_at(budget, inf, auc, eta)),
                rung: 0,
            }
        };
        let reached = vec![
            at(0, 1e-4, 800, 0.3),
            at(1, 1e-3, 800, 0.3),
            at(2, 1e-2, 400, 0.3),
            at(3, 1e-5, 800, 0.2),
            PointResult {
                score: None,
                ..at(4, 1e-6, 800, 0.3)
            },
        ];
        let pick = reached[0].score.clone().unwrap();
        assert_eq!(
            tied_with(&reached, 0, &pick),
            vec![reached[1].point.describe()]
        );
        assert_eq!(
            tied_with(&reached, 1, &reached[1].score.clone().unwrap()),
            vec![reached[0].point.describe()]
        );
    }

    #[test]
    fn a_pick_is_weak_without_convergence_on_an_edge_or_with_few_seeds() {
        let p = point(1e-3, 1);
        let converged = Score::of(&p, &[run(conv(100), &[])], 400, 100);
        let never = Score::of(&p, &[run(RunStatus::NotConverged, &[])], 400, 100);
        let result = |score: Score, on_edge: Vec<String>, seeds: u32| TuningResult {
            task: TaskKind::Obstacle,
            label: "SGD".into(),
            key_hash: String::new(),
            dims: vec!["alpha".into()],
            points: vec![PointResult {
                point: p.clone(),
                runs: vec![],
                score: Some(score),
                rung: 0,
            }],
            selected: 0,
            budget: 400,
            rounds: vec![Round {
                points: 1,
                rungs: vec![],
                pick: String::new(),
                extended: vec![],
            }],
            on_edge,
            tied_with: vec![],
            tuning_seeds: seeds,
        };
        assert_eq!(result(converged.clone(), vec![], 3).weakness(), None);
        let w = result(never, vec![], 3).weakness().unwrap();
        assert!(w.contains("no tuning run"), "{w}");
        let w = result(converged.clone(), vec!["alpha (upper end)".into()], 3)
            .weakness()
            .unwrap();
        assert!(w.contains("edge of alpha (upper end)"), "{w}");
        let w = result(converged.clone(), vec![], 2).weakness().unwrap();
        assert!(w.contains("fewer than 3"), "{w}");
        // A row that was not tuned (no rounds) carries no weakness.
        let mut untuned = result(converged, vec![], 1);
        untuned.rounds.clear();
        assert_eq!(untuned.weakness(), None);
    }

    #[test]
    fn rung_budgets_are_whole_checkpoint_intervals_and_the_schedule_is_validated() {
        let p = TuningProtocol {
            rungs: vec![1.0 / 9.0, 1.0 / 3.0, 1.0],
            halving: 3,
            extensions: 2,
            exhaustive_below: 16,
        };
        assert_eq!(p.validate(), Ok(()));
        assert_eq!(
            p.rung_budgets(2_000_000, 200_000),
            vec![400_000, 800_000, 2_000_000]
        );
        // Rounding up may merge rungs.
        assert_eq!(p.rung_budgets(300, 100), vec![100, 300]);
        assert_eq!((p.kept(26), p.kept(9), p.kept(1)), (9, 3, 1));
        assert_eq!(p.rungs_for(15, 2_000_000, 200_000), vec![2_000_000]);
        assert_eq!(p.rungs_for(16, 2_000_000, 200_000).len(), 3);
        for (bad, field) in [
            (vec![], "rungs"),
            (vec![0.5, 0.5, 1.0], "rungs"),
            (vec![0.0, 1.0], "rungs"),
            (vec![0.5], "rungs"),
        ] {
            let q = TuningProtocol {
                rungs: bad,
                ..p.clone()
            };
            assert_eq!(q.validate().unwrap_err().0, field);
        }
        let q = TuningProtocol {
            halving: 1,
            ..p.clone()
        };
        assert_eq!(q.validate().unwrap_err().0, "halving");
        // Halving by 2 is the smallest allowed.
        let two = TuningProtocol {
            halving: 2,
            ..p.clone()
        };
        assert_eq!(two.validate(), Ok(()));
        // A profile without `[tuning]` tunes exhaustively, without extension.
        let d = TuningProtocol::default();
        assert_eq!(
            (d.rungs.clone(), d.halving, d.extensions, d.exhaustive_below),
            (vec![1.0], 3, 0, 0)
        );
        assert_eq!(d.validate(), Ok(()));
        let parsed: TuningProtocol = serde_json::from_str("{}").unwrap();
        assert_eq!(parsed, d);
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
                    let h = e.horizon(t, kind);
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
