//! The three concurrent stages: the theorem table, the Fig. 4.2 study, and the tuning and report
//! runs.

use super::Options;
use super::keys::{gradient_key, task_key, theory_key};
use super::task_learners::TaskLearners;
use super::theory_cache::{TheoryCache, write_theory_copies};
use super::tuning_stage::{at_point, tune, tuning_seeds_of};
use crate::config::{Profile, TheorySize};
use crate::error::Error;
use crate::experiment::{RunSpec, TaskKind, eval_key, run_key, run_spec};
use crate::naming::slug;
use crate::progress::Progress;
use crate::protocol::TuningResult;
use crate::results::{
    ConfigResult, ConfigTiming, ConfigWithTiming, GradientErrorResult, TheoryTable,
};
use crate::shard::{Mode, Units, unit_key};
use crate::storage::{read_json, to_json, write_atomic};
use rayon::prelude::*;
use std::time::Instant;

pub(super) type Rows = Vec<Vec<ConfigWithTiming>>;

/// How far the tuning and report runs got.
pub(super) enum Experiments {
    /// Some tuning unit is neither stored nor this run's.
    TuningIncomplete,
    /// Every row is tuned; some report unit is neither stored nor this run's.
    ReportIncomplete,
    /// Everything: the tuning, every row's results, the configurations computed.
    Done(Vec<TuningResult>, Rows, Vec<String>),
}

/// The three concurrent stages' results (`None`: not this run's share, or missing in a merge).
pub(super) struct Stages {
    pub(super) theory: Option<TheoryTable>,
    pub(super) gradient: Option<GradientErrorResult>,
    pub(super) experiments: Experiments,
}

/// The theorem table, and whether this call computed it: the cached one if its key matches, else
/// computed if `compute`, else `None` (a shard's or a merge's run, which leave it to the theory
/// job). With `copies`, the copies beside the appendix (`theory.md`, `theory.json`) follow the
/// table, and a profile without a table removes any left by an earlier one.
pub(super) fn theory_stage(
    profile: &Profile,
    opts: &Options,
    compute: bool,
    copies: bool,
) -> Result<(Option<TheoryTable>, bool), Error> {
    let runs_dir = opts.out.join("runs");
    let theory_file = opts.out.join("theory.md");
    let theory_json = opts.out.join("theory.json");
    let theory_cache_file = runs_dir.join("theory.json");
    let tkey = theory_key(profile, &opts.source_version);
    let cached = if opts.redo {
        None
    } else {
        read_json::<TheoryCache>(&theory_cache_file).filter(|c| c.key_hash == tkey)
    };
    if let Some(c) = cached {
        if copies {
            // The copies beside the appendix follow the cached table the key names.
            write_theory_copies(&theory_file, &theory_json, &c.checks)?;
        }
        return Ok((Some(TheoryTable::Checks(c.checks)), false));
    }
    if profile.theory_profile == TheorySize::None {
        // No table this time: a table left by an earlier profile must not sit beside it.
        for f in [&theory_file, &theory_json, &theory_cache_file] {
            if copies && f.exists() {
                std::fs::remove_file(f).map_err(|e| Error::io(f, e))?;
            }
        }
        return Ok((Some(TheoryTable::NotRun), false));
    }
    if !compute {
        return Ok((None, false));
    }
    let p = if profile.theory_profile == TheorySize::Full {
        ilopt_theory::suite::Profile::Full
    } else {
        ilopt_theory::suite::Profile::Quick
    };
    // The whole table, real-environment rows included (as `ilopt-theory`'s binary prints it).
    let checks = ilopt_theory::suite::whole_table(p).map_err(Error::Theory)?;
    let cache = TheoryCache {
        key_hash: tkey,
        checks,
    };
    if copies {
        write_theory_copies(&theory_file, &theory_json, &cache.checks)?;
    }
    write_atomic(&theory_cache_file, &to_json("theory cache", &cache)?)?;
    Ok((Some(TheoryTable::Checks(cache.checks)), true))
}

/// The theorem table, the Fig. 4.2 study, and the tuning and report runs, concurrently.
pub(super) fn stages(
    profile: &Profile,
    opts: &Options,
    progress: &Progress,
    benches: &TaskLearners,
    units: &Units,
) -> Result<Stages, Error> {
    let runs_dir = opts.out.join("runs");
    let timings_dir = opts.out.join("timings");
    let sharded = match opts.mode {
        Mode::Shard(s) => Some(s),
        _ => None,
    };
    // Whether this run computes a single job with this key.
    let computes = |key: &str| match opts.mode {
        Mode::All => true,
        Mode::Shard(s) => s.owns(key),
        Mode::Merge => false,
    };
    let tasks = [
        (TaskKind::Obstacle, &profile.obstacle),
        (TaskKind::Cartpole, &profile.cartpole),
    ];
    let gfile = runs_dir.join("gradient-error.json");
    let gkey = gradient_key(profile, &opts.source_version);
    let gcached: Option<GradientErrorResult> = if opts.redo { None } else { read_json(&gfile) };
    let gcached = gcached.filter(|g| g.key_hash == gkey);
    let seeds: Vec<u32> = (0..profile.seeds).collect();

    // A plain run computes the theorem table beside the other stages; a shard leaves it to the
    // theory job (`paper-checks theory`), which runs beside the shards' passes instead of
    // lengthening one of them; a merge reads it.
    let theory_job = || {
        theory_stage(
            profile,
            opts,
            matches!(opts.mode, Mode::All),
            sharded.is_none(),
        )
        .map(|(table, _)| table)
    };

    let gradient_job = || -> Result<Option<GradientErrorResult>, Error> {
        if let Some(g) = gcached.clone() {
            return Ok(Some(g));
        }
        if !computes(&gkey) {
            return Ok(None);
        }
        let mut g = crate::gradient_error::run(&profile.gradient_error)?;
        g.key_hash = gkey.clone();
        progress.line(&format!(
            "done: Fig. 4.2 (toy {:.1} s, obstacle {:.1} s)",
            g.toy.seconds, g.obstacle.seconds
        ));
        write_atomic(
            &timings_dir.join("gradient-error.json"),
            &to_json(
                "timings",
                &serde_json::json!({"toy_seconds": g.toy.seconds, "obstacle_seconds": g.obstacle.seconds}),
            )?,
        )?;
        write_atomic(&gfile, &to_json("gradient error", &g)?)?;
        Ok(Some(g))
    };

    let experiments_job = || -> Result<Experiments, Error> {
        let Some(tuning) = tune(profile, opts, benches, progress, units)? else {
            return Ok(Experiments::TuningIncomplete);
        };
        let used = tuning_seeds_of(&tuning);
        // The report rows at their selected hyper-parameters; which are already done?
        let mut todo = Vec::new();
        let mut results: Vec<Vec<Option<ConfigWithTiming>>> = Vec::new();
        for (kind, t) in tasks {
            let mut row = Vec::new();
            for e in &t.algorithms {
                let tr = tuning
                    .iter()
                    .find(|r| r.task == kind && r.label == e.label)
                    .ok_or_else(|| Error::experiment(&e.label, "no tuning result"))?;
                let chosen = tr.chosen();
                let eff = at_point(e, chosen);
                let rk = run_key(kind, t, &eff);
                for s in 0..profile.seeds {
                    let seed = crate::stats::derive_seed(&rk, u64::from(s));
                    if used.contains(&seed) {
                        return Err(Error::experiment(
                            &e.label,
                            format!("report seed {seed} equals a tuning seed"),
                        ));
                    }
                }
                let file = runs_dir.join(format!("{}-{}.json", kind.name(), slug(&e.label)));
                let key = task_key(profile, kind, t, &eff, &opts.source_version);
                let cached: Option<ConfigResult> = if opts.redo { None } else { read_json(&file) };
                match cached {
                    Some(c) if c.key_hash == key => {
                        let timing = read_json(&timings_dir.join(format!(
                            "{}-{}.json",
                            kind.name(),
                            slug(&e.label)
                        )));
                        row.push(Some((c, timing)));
                    }
                    _ => {
                        todo.push((kind, t, eff, chosen.describe(), key, file));
                        row.push(None);
                    }
                }
            }
            results.push(row);
        }
        let computed = todo
            .par_iter()
            .map(|(kind, t, e, hyper, key, file)| {
                let start = Instant::now();
                let bench = benches.get(*kind, e.horizon(t, *kind));
                let rk = run_key(*kind, t, e);
                let unit_keys: Vec<String> = seeds
                    .iter()
                    .map(|s| unit_key(key, &format!("seed={s}")))
                    .collect();
                let pairs = seeds
                    .par_iter()
                    .zip(&unit_keys)
                    .map(|(&s, ukey)| {
                        units.get(ukey, || {
                            let r = run_spec(
                                bench,
                                &RunSpec {
                                    kind: *kind,
                                    task: t,
                                    config: &e.config,
                                    m: e.m.unwrap_or(1),
                                    baseline: e.baseline.clone().unwrap_or_default(),
                                    key: rk.clone(),
                                    seed: crate::stats::derive_seed(&rk, u64::from(s)),
                                    seed_index: s,
                                    eval_key: eval_key(*kind, s),
                                    stop_at_convergence: false,
                                    hyper_parameters: hyper.clone(),
                                },
                            );
                            progress.seed_done(&format!("{} / {}", kind.name(), e.label));
                            r
                        })
                    })
                    .collect::<Result<Vec<_>, Error>>()?;
                let Some(pairs) = pairs.into_iter().collect::<Option<Vec<_>>>() else {
                    return Ok(None);
                };
                let (runs, timings): (Vec<_>, Vec<_>) = pairs.into_iter().unzip();
                let c = ConfigResult {
                    task: *kind,
                    label: e.label.clone(),
                    key_hash: key.clone(),
                    entry: e.clone(),
                    runs,
                };
                let tm = ConfigTiming {
                    task: *kind,
                    label: e.label.clone(),
                    runs: timings,
                    wall_seconds: start.elapsed().as_secs_f64(),
                };
                // Shards never write assembled files: two of them could assemble the same row.
                if sharded.is_none() {
                    write_atomic(
                        &timings_dir.join(format!("{}-{}.json", kind.name(), slug(&e.label))),
                        &to_json("timings", &tm)?,
                    )?;
                    write_atomic(file, &to_json("results", &c)?)?;
                    units.remove(&unit_keys);
                }
                progress.line(&format!(
                    "done: {} / {} ({} seeds, {:.1} s)",
                    kind.name(),
                    e.label,
                    profile.seeds,
                    tm.wall_seconds
                ));
                Ok(Some((*kind, e.label.clone(), c, tm)))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let Some(computed) = computed.into_iter().collect::<Option<Vec<_>>>() else {
            return Ok(Experiments::ReportIncomplete);
        };
        let mut names = Vec::new();
        for (kind, label, c, tm) in computed {
            names.push(format!("{} / {label}", kind.name()));
            let ti = usize::from(kind == TaskKind::Cartpole);
            let t = tasks[ti].1;
            if let Some(i) = t.algorithms.iter().position(|e| e.label == label) {
                results[ti][i] = Some((c, Some(tm)));
            }
        }
        let rows = results
            .into_iter()
            .map(|row| row.into_iter().flatten().collect::<Vec<_>>())
            .collect();
        Ok(Experiments::Done(tuning, rows, names))
    };

    let (theory, (gradient, experiments)) = rayon::join(
        || progress.stage("theorem-check table", theory_job),
        || {
            rayon::join(
                || progress.stage("Fig. 4.2 study", gradient_job),
                || progress.stage("tuning and report runs", experiments_job),
            )
        },
    );
    Ok(Stages {
        theory: theory?,
        gradient: gradient?,
        experiments: experiments?,
    })
}
