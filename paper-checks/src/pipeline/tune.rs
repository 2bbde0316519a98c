//! The tuning stage: every row's grid on the tuning seeds, reused from storage when its key
//! matches.

use super::Options;
use super::benches::Benches;
use super::keys::tuning_key;
use crate::config::{AlgorithmEntry, Profile};
use crate::error::Error;
use crate::experiment::{RunSpec, TaskKind, run_key_of, run_spec};
use crate::grid::GridPoint;
use crate::naming::slug;
use crate::progress::Progress;
use crate::shard::{Mode, Units, unit_key};
use crate::storage::{read_json, to_json, write_atomic};
use crate::tuning::{
    PointResult, TuningResult, TuningRun, select, selection_score, tuning_eval_key, tuning_seed,
};
use rayon::prelude::*;

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
    x
}

/// Run (or reuse) the tuning of every row with a grid; rows without one get their single point.
/// `None` when some tuning unit is neither stored nor computed by this run (a shard, or a merge
/// before every shard has tuned).
pub(super) fn tune(
    profile: &Profile,
    opts: &Options,
    benches: &Benches,
    progress: &Progress,
    units: &Units,
) -> Result<Option<Vec<TuningResult>>, Error> {
    let runs_dir = opts.out.join("runs");
    let mut out: Vec<Option<TuningResult>> = Vec::new();
    // (slot, task, section, entry, key, file, points)
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
            if e.grid.is_empty() || e.hyper_parameters_of.is_some() {
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
                            score: f64::NAN,
                        })
                        .collect(),
                    selected: 0,
                    budget: t.budget,
                }));
                continue;
            }
            let cached: Option<TuningResult> = if opts.redo { None } else { read_json(&file) };
            match cached {
                Some(c) if c.key_hash == key => out.push(Some(c)),
                _ => {
                    todo.push((out.len(), kind, t, e, key, file, points));
                    out.push(None);
                }
            }
        }
    }
    let computed = todo
        .par_iter()
        .map(|(slot, kind, t, e, key, file, points)| {
            let h = e.horizon(t, kind.name());
            let bench = benches.get(*kind, h);
            let jobs: Vec<(usize, u32)> = (0..points.len())
                .flat_map(|i| (0..profile.tuning_seeds).map(move |s| (i, s)))
                .collect();
            let unit_keys: Vec<String> = jobs
                .iter()
                .map(|(i, s)| unit_key(key, &format!("point={i}|seed={s}")))
                .collect();
            let runs = jobs
                .par_iter()
                .zip(&unit_keys)
                .map(|(&(i, s), ukey)| {
                    units.get(ukey, || {
                        let p = &points[i];
                        let rk = run_key_of(*kind, &e.label, &p.config, p.m, h, &p.baseline);
                        let seed = tuning_seed(&rk, s);
                        let (run, _) = run_spec(
                            bench,
                            &RunSpec {
                                kind: *kind,
                                task: t,
                                config: &p.config,
                                m: p.m,
                                baseline: p.baseline.clone(),
                                key: format!("tuning|{rk}"),
                                seed,
                                seed_index: s,
                                eval_key: tuning_eval_key(*kind, s),
                                stop_at_convergence: true,
                                hyper_parameters: p.describe(),
                            },
                        )?;
                        progress.seed_done(&format!("tuning {} / {}", kind.name(), e.label));
                        Ok(TuningRun {
                            seed_index: s,
                            seed,
                            gradient_evaluations: run
                                .checkpoints
                                .last()
                                .map_or(0, |c| c.gradient_evaluations),
                            last_score: run.checkpoints.last().map(|c| c.score),
                            status: run.status,
                        })
                    })
                })
                .collect::<Result<Vec<_>, Error>>()?;
            let Some(runs) = runs.into_iter().collect::<Option<Vec<_>>>() else {
                return Ok((*slot, None));
            };
            let mut it = runs.into_iter();
            let points: Vec<PointResult> = points
                .iter()
                .map(|p| {
                    let runs: Vec<TuningRun> =
                        it.by_ref().take(profile.tuning_seeds as usize).collect();
                    let statuses: Vec<_> = runs.iter().map(|r| r.status.clone()).collect();
                    PointResult {
                        point: p.clone(),
                        score: selection_score(&statuses, t.budget),
                        runs,
                    }
                })
                .collect();
            let scores: Vec<f64> = points.iter().map(|p| p.score).collect();
            let r = TuningResult {
                task: *kind,
                label: e.label.clone(),
                key_hash: key.clone(),
                dims: e.grid.iter().map(|d| d.path.clone()).collect(),
                selected: select(&scores),
                points,
                budget: t.budget,
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
                    score: f64::NAN,
                }];
                r.selected = 0;
            }
        }
    }
    Ok(Some(all))
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
