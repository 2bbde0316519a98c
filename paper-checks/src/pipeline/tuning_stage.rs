//! The tuning stage: every row's grid on the tuning seeds, reused from storage when its key
//! matches.

use super::Options;
use super::keys::tuning_key;
use super::task_learners::TaskLearners;
use crate::config::{AlgorithmEntry, Profile, TaskExperiment};
use crate::error::Error;
use crate::experiment::{AppendixRun, Evaluated};
use crate::experiment::{RunSpec, TaskKind, run_key_of, run_spec};
use crate::grid::GridPoint;
use crate::naming::slug;
use crate::progress::Progress;
use crate::protocol::{
    PointResult, Round, RungRecord, Score, TuningResult, TuningRun, promoted, ranking, tied_with,
    tuning_eval_key, tuning_seed,
};
use crate::shard::{Mode, Units, unit_key};
use crate::storage::{read_json, to_json, write_atomic};
use rayon::prelude::*;
use std::collections::HashMap;

/// A row with the hyper-parameters of `p` (no grid left).
pub(super) fn at_point(e: &AlgorithmEntry, p: &GridPoint) -> AlgorithmEntry {
    let mut x = e.clone();
    x.config = p.config.clone();
    x.m = Some(p.m);
    x.baseline = match &p.baseline {
        ilopt::baseline::Baseline::None => None,
        b => Some(b.clone()),
    };
    x.grid.clear();
    x.grids.clear();
    x
}

/// Run (or reuse) the tuning of every row with a grid; rows without one get their single point.
/// `None` when some tuning unit is neither stored nor computed by this run (a shard, or a merge
/// before every shard has tuned).
pub(super) fn tune(
    profile: &Profile,
    opts: &Options,
    benches: &TaskLearners,
    progress: &Progress,
    units: &Units,
) -> Result<Option<Vec<TuningResult>>, Error> {
    let runs_dir = opts.out.join("runs");
    let mut out: Vec<Option<TuningResult>> = Vec::new();
    // (slot, task, section, entry, key, file)
    let mut todo = Vec::new();
    for (kind, t) in [
        (TaskKind::Obstacle, &profile.obstacle),
        (TaskKind::Cartpole, &profile.cartpole),
    ] {
        for e in &t.algorithms {
            let points = e
                .grid_points()
                .map_err(|m| Error::experiment(&e.label, m))?;
            let key = tuning_key(profile, kind, t, e, &opts.source_version);
            let file = runs_dir.join(format!("tuning-{}-{}.json", kind.name(), slug(&e.label)));
            if !e.has_grid() || e.hyper_parameters_of.is_some() {
                out.push(Some(TuningResult {
                    task: kind,
                    label: e.label.clone(),
                    key_hash: key,
                    dims: Vec::new(),
                    points: points
                        .into_iter()
                        .map(|point| PointResult {
                            point,
                            runs: Vec::new(),
                            score: None,
                            rung: 0,
                        })
                        .collect(),
                    selected: 0,
                    budget: t.budget,
                    rounds: Vec::new(),
                    on_edge: Vec::new(),
                    tied_with: Vec::new(),
                    tuning_seeds: 0,
                }));
                continue;
            }
            let cached: Option<TuningResult> = if opts.redo { None } else { read_json(&file) };
            match cached {
                Some(c) if c.key_hash == key => out.push(Some(c)),
                _ => {
                    todo.push((out.len(), kind, t, e, key, file));
                    out.push(None);
                }
            }
        }
    }
    let computed = todo
        .par_iter()
        .map(|(slot, kind, t, e, key, file)| {
            let row = Row {
                profile,
                benches,
                progress,
                units,
                kind: *kind,
                task: t,
                entry: e,
                key,
            };
            let Some((r, unit_keys)) = row.tune()? else {
                return Ok((*slot, None));
            };
            // Shards never write assembled files: two of them could assemble the same row.
            if !matches!(units.mode(), Mode::Shard(_)) {
                write_atomic(file, &to_json("tuning", &r)?)?;
                units.remove(&unit_keys);
            }
            progress.line(&format!(
                "tuned: {} / {} → {}",
                kind.name(),
                e.label,
                r.chosen().describe()
            ));
            Ok((*slot, Some(r)))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    for (slot, r) in computed {
        match r {
            Some(r) => out[slot] = Some(r),
            None => return Ok(None),
        }
    }
    // Borrowed hyper-parameters (control rows).
    let mut all: Vec<TuningResult> = out.into_iter().flatten().collect();
    for (kind, t) in [
        (TaskKind::Obstacle, &profile.obstacle),
        (TaskKind::Cartpole, &profile.cartpole),
    ] {
        for e in &t.algorithms {
            let Some(of) = &e.hyper_parameters_of else {
                continue;
            };
            let chosen = all
                .iter()
                .find(|r| r.task == kind && &r.label == of)
                .map(|r| r.chosen().clone())
                .ok_or_else(|| Error::experiment(&e.label, format!("no row `{of}`")))?;
            if let Some(r) = all
                .iter_mut()
                .find(|r| r.task == kind && r.label == e.label)
            {
                let mut p = chosen;
                p.index = 0;
                r.points = vec![PointResult {
                    point: p,
                    runs: Vec::new(),
                    score: None,
                    rung: 0,
                }];
                r.selected = 0;
            }
        }
    }
    Ok(Some(all))
}

/// One row's tuning: rounds of successive halving over its grid, the grid grown at the pick's
/// log edges between rounds ([`crate::protocol`]).
struct Row<'a> {
    profile: &'a Profile,
    benches: &'a TaskLearners,
    progress: &'a Progress,
    units: &'a Units,
    kind: TaskKind,
    task: &'a TaskExperiment,
    entry: &'a AlgorithmEntry,
    key: &'a str,
}

/// The longest run so far of each (run key, tuning seed).
type Memo = HashMap<(String, u32), TuningRun>;

impl Row<'_> {
    /// The row's tuning and the unit keys it read, `None` when a unit is missing (a shard's
    /// pass, or a merge before every shard has run).
    fn tune(&self) -> Result<Option<(TuningResult, Vec<String>)>, Error> {
        let (kind, t, e) = (self.kind, self.task, self.entry);
        let protocol = &self.profile.tuning;
        let seeds = self.profile.tuning_seeds;
        let h = e.horizon(t, kind);
        let mut grids = e.subgrids();
        let mut memo = Memo::new();
        let mut unit_keys = Vec::new();
        let mut rounds = Vec::new();
        loop {
            let points = e
                .points_of(&grids)
                .map_err(|m| Error::experiment(&e.label, m))?;
            let texts: Vec<String> = points.iter().map(GridPoint::describe).collect();
            let rks: Vec<String> = points
                .iter()
                .map(|p| run_key_of(kind, &e.label, &p.config, p.m, h, &p.baseline))
                .collect();
            let budgets = protocol.rungs_for(points.len(), t.budget, t.checkpoint_every);
            let mut reached: Vec<Option<PointResult>> = vec![None; points.len()];
            let mut alive: Vec<usize> = (0..points.len()).collect();
            let mut rungs = Vec::new();
            for (r, &b) in budgets.iter().enumerate() {
                let jobs: Vec<(usize, u32)> = alive
                    .iter()
                    .flat_map(|&i| (0..seeds).map(move |s| (i, s)))
                    .collect();
                let got = jobs
                    .par_iter()
                    .map(|&(i, s)| self.run_at(&memo, &points[i], &rks[i], s, b, h))
                    .collect::<Result<Vec<_>, Error>>()?;
                let mut by_point: HashMap<usize, Vec<TuningRun>> = HashMap::new();
                for (&(i, s), g) in jobs.iter().zip(got) {
                    let Some((run, ukey)) = g else {
                        return Ok(None);
                    };
                    unit_keys.extend(ukey);
                    let slot = memo
                        .entry((rks[i].clone(), s))
                        .or_insert_with(|| run.clone());
                    if slot.scores.len() < run.scores.len() || (!slot.is_final() && run.is_final())
                    {
                        *slot = run.clone();
                    }
                    by_point.entry(i).or_default().push(run);
                }
                let scored: Vec<(usize, Score)> = alive
                    .iter()
                    .map(|&i| {
                        let runs = &by_point[&i];
                        (i, Score::of(&points[i], runs, b, t.checkpoint_every))
                    })
                    .collect();
                for (i, score) in &scored {
                    reached[*i] = Some(PointResult {
                        point: points[*i].clone(),
                        runs: by_point[i].clone(),
                        score: Some(score.clone()),
                        rung: r,
                    });
                }
                let order = ranking(
                    &scored
                        .iter()
                        .map(|(i, sc)| (*i, sc, texts[*i].clone()))
                        .collect::<Vec<_>>(),
                );
                let last = r + 1 == budgets.len();
                let keep = if last {
                    1
                } else {
                    promoted(&order, protocol.kept(alive.len()), &scored)
                };
                rungs.push(RungRecord {
                    budget: b,
                    points: alive.len(),
                    kept: keep,
                });
                alive = order.into_iter().take(keep).collect();
                alive.sort_unstable();
            }
            let pick = alive[0];
            // The pick's log dimensions at an end of their range.
            let sub = grids[points[pick].subgrid].clone();
            let mut edges: Vec<(usize, bool)> = Vec::new();
            for (d, dim) in sub.iter().enumerate() {
                let (Some(from), Some(to)) = (dim.from, dim.to) else {
                    continue;
                };
                let v = points[pick]
                    .values
                    .iter()
                    .find(|(p, _)| p == &dim.path)
                    .and_then(|(_, v)| v.as_f64());
                if v == Some(from) {
                    edges.push((d, false));
                }
                if v == Some(to) {
                    edges.push((d, true));
                }
            }
            let may_extend = rounds.len() < protocol.extensions as usize;
            let mut extended = Vec::new();
            if may_extend {
                let g = points[pick].subgrid;
                for &(d, up) in &edges {
                    if let Some(grown) = grids[g][d].extended(up) {
                        extended.push(format!(
                            "{} {} to {}",
                            grown.path,
                            if up { "up" } else { "down" },
                            if up {
                                grown.to.unwrap_or(f64::NAN)
                            } else {
                                grown.from.unwrap_or(f64::NAN)
                            }
                        ));
                        grids[g][d] = grown;
                    }
                }
            }
            rounds.push(Round {
                points: points.len(),
                rungs,
                pick: texts[pick].clone(),
                extended: extended.clone(),
            });
            if extended.is_empty() {
                let final_score = reached[pick]
                    .as_ref()
                    .and_then(|p| p.score.clone())
                    .ok_or_else(|| Error::experiment(&e.label, "the pick has no score"))?;
                let points: Vec<PointResult> = reached.into_iter().flatten().collect();
                let ties = tied_with(&points, pick, &final_score);
                let on_edge = edges
                    .iter()
                    .map(|&(d, up)| {
                        format!(
                            "{} ({} end)",
                            sub[d].path,
                            if up { "upper" } else { "lower" }
                        )
                    })
                    .collect();
                let selected = points
                    .iter()
                    .position(|p| p.point.index == pick)
                    .unwrap_or(0);
                unit_keys.sort();
                unit_keys.dedup();
                return Ok(Some((
                    TuningResult {
                        task: kind,
                        label: e.label.clone(),
                        key_hash: self.key.to_string(),
                        dims: grids.iter().flatten().map(|d| d.path.clone()).collect(),
                        points,
                        selected,
                        budget: t.budget,
                        rounds,
                        on_edge,
                        tied_with: ties,
                        tuning_seeds: seeds,
                    },
                    unit_keys,
                )));
            }
        }
    }

    /// Tuning seed `s` of `point` to the budget `b`: from the memo when a run there covers it
    /// (a longer run, or one that converged or diverged before `b`), else from its unit.
    /// `None` when the unit is neither stored nor computed by this process.
    fn run_at(
        &self,
        memo: &Memo,
        point: &GridPoint,
        rk: &str,
        s: u32,
        b: u64,
        h: ilopt::task::Horizon,
    ) -> Result<Option<(TuningRun, Option<String>)>, Error> {
        let every = self.task.checkpoint_every;
        if let Some(prev) = memo.get(&(rk.to_string(), s))
            && let Some(run) = prev.at_budget(b, every)
        {
            return Ok(Some((run, None)));
        }
        let ukey = unit_key(self.key, &format!("point={rk}|seed={s}|budget={b}"));
        let got = self.units.get(&ukey, || {
            let mut task = self.task.clone();
            task.budget = b;
            let seed = tuning_seed(rk, s);
            let bench = self.benches.get(self.kind, h);
            let (run, _) = run_spec(
                bench,
                &RunSpec {
                    kind: self.kind,
                    task: &task,
                    config: &point.config,
                    m: point.m,
                    baseline: point.baseline.clone(),
                    key: format!("tuning|{rk}"),
                    seed,
                    seed_index: s,
                    eval_key: tuning_eval_key(self.kind, s),
                    stop_at_convergence: true,
                    hyper_parameters: point.describe(),
                },
            )?;
            self.progress.seed_done(&format!(
                "tuning {} / {}",
                self.kind.name(),
                self.entry.label
            ));
            Ok(TuningRun {
                seed_index: s,
                seed,
                budget: b,
                gradient_evaluations: run.checkpoints.last().map_or(0, |c| c.gradient_evaluations),
                scores: run.checkpoints.iter().map(|c| c.score()).collect(),
                calls: run
                    .checkpoints
                    .iter()
                    .map(|c| c.gradient_evaluations)
                    .collect(),
                status: run.status().clone(),
            })
        })?;
        Ok(got.map(|run| (run, Some(ukey))))
    }
}

/// Every tuning seed of the results (the seeds actually used, or those a grid would use).
pub(super) fn tuning_seeds_of(tuning: &[TuningResult]) -> std::collections::BTreeSet<u64> {
    tuning
        .iter()
        .flat_map(|t| &t.points)
        .flat_map(|p| &p.runs)
        .map(|r| r.seed)
        .collect()
}
