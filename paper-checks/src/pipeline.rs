//! The pipeline: run (or reuse) every configuration, then write the data, figures and reports.
//!
//! Every configuration's per-seed results are written atomically (temporary file + rename) to
//! `runs/<task>-<algorithm>.json` together with a hash of everything that determines them (the
//! row, its task's section and expert, the seed count, and the code version
//! [`Options::source_version`]); a rerun reuses a file whose hash matches unless `redo` is set.
//! The tuning, the Fig. 4.2 study and the theorem table are cached the same way, and files no row
//! of the profile produces are removed ([`remove_stale`]). Wall times go to `timings/` and
//! `timings.json` only, so every other CSV/JSON file is byte-identical across runs and thread
//! counts (each seed's RNG is derived from the configuration and the seed index alone, and
//! parallel results are collected in seed order).

use crate::config::{AlgorithmEntry, Profile, TaskSection};
use crate::error::Error;
use crate::experiment::{
    Bench, ReferencePolicy, RunSpec, TaskKind, baseline_seed, eval_key, run_key, run_key_of,
    run_spec,
};
use crate::grid::GridPoint;
use crate::naming::slug;
use crate::progress::Progress;
use crate::results::{
    BaselineResult, ConfigResult, ConfigTiming, ConfigWithTiming, GradientErrorResult, Results,
    TheoryTable,
};
use crate::shard::{Mode, Units, unit_key};
use crate::stats::fnv1a;
use crate::storage::{mkdir, read_json, to_json, write_atomic};
use crate::tuning::{
    PointResult, TuningResult, TuningRun, select, selection_score, tuning_eval_key, tuning_seed,
};
use ilopt::task::Horizon;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run.
#[derive(Debug, Clone)]
pub struct Options {
    /// Output directory.
    pub out: PathBuf,
    /// Recompute configurations even if their results exist.
    pub redo: bool,
    /// Show progress (bars on a terminal, plain lines otherwise); `false` = silent.
    pub progress: bool,
    /// The version of the code that computes the results; part of every cache key, so results
    /// computed by other code are never reused. [`Options::new`] takes the build's
    /// [`crate::build_info::SOURCE_HASH`].
    pub source_version: String,
    /// The command line recorded in the provenance ([`Options::new`]: this process's argv).
    pub command: Vec<String>,
    /// Compute everything missing ([`Mode::All`], [`Options::new`]'s default), one shard's
    /// share, or nothing (merge).
    pub mode: Mode,
}

impl Options {
    /// Write into `out`, reuse cached results computed by this build's sources, show progress,
    /// and record this process's argv.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Options {
            out: out.into(),
            redo: false,
            progress: true,
            source_version: crate::build_info::SOURCE_HASH.to_string(),
            command: std::env::args().collect(),
            mode: Mode::All,
        }
    }
}

/// What determines a task's runs apart from the algorithm rows: the section without its rows,
/// and the expert's identity.
fn section_key(kind: TaskKind, t: &TaskSection) -> String {
    let expert = (kind == TaskKind::Cartpole).then(|| t.expert.unwrap_or_default().identity());
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
fn task_key(
    profile: &Profile,
    kind: TaskKind,
    t: &TaskSection,
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
/// number of tuning seeds, and the code version.
fn tuning_key(
    profile: &Profile,
    kind: TaskKind,
    t: &TaskSection,
    e: &AlgorithmEntry,
    version: &str,
) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!(
            "tuning|{}|{}|{}|{}|code={version}",
            kind.name(),
            section_key(kind, t),
            serde_json::to_string(e).unwrap_or_default(),
            profile.tuning_seeds
        ))
    )
}

/// The cache key of the Fig. 4.2 study: its settings and the code version.
fn gradient_key(profile: &Profile, version: &str) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!(
            "gradient-error|{}|code={version}",
            profile.gradient_error.key_hash()
        ))
    )
}

/// The cache key of the theorem table: its size profile and the code version.
fn theory_key(profile: &Profile, version: &str) -> String {
    format!(
        "{:016x}",
        fnv1a(&format!("theory|{}|code={version}", profile.theory_profile))
    )
}

/// The cached theorem table (`runs/theory.json`): the check records and the key they were
/// computed under.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TheoryCache {
    /// The cache key of the profile's theorem table and of the code that computed the checks.
    pub key_hash: String,
    /// Every check of the table, in table order.
    pub checks: Vec<ilopt_theory::check::Check>,
}

/// Write `ilopt-theory`'s renderings of `checks` beside the appendix: its Markdown table
/// (`theory.md`) and its JSON report (`theory.json`).
fn write_theory_copies(
    markdown_file: &Path,
    json_file: &Path,
    checks: &[ilopt_theory::check::Check],
) -> Result<(), Error> {
    write_atomic(
        json_file,
        &to_json("theory", &ilopt_theory::report::json(checks))?,
    )?;
    write_atomic(
        markdown_file,
        ilopt_theory::report::markdown(checks).as_bytes(),
    )
}

/// The benches of a profile: one per (task, objective) used by its rows.
struct Benches(Vec<(TaskKind, Horizon, Bench)>);

impl Benches {
    fn new(profile: &Profile) -> Result<Self, Error> {
        let mut v: Vec<(TaskKind, Horizon, Bench)> = Vec::new();
        for (kind, t) in [
            (TaskKind::Obstacle, &profile.obstacle),
            (TaskKind::Cartpole, &profile.cartpole),
        ] {
            for e in &t.algorithms {
                let h = e.horizon(t, kind.name());
                if !v.iter().any(|(k, hh, _)| *k == kind && *hh == h) {
                    v.push((kind, h, Bench::new(kind, t, h)?));
                }
            }
        }
        Ok(Benches(v))
    }
    fn get(&self, kind: TaskKind, h: Horizon) -> &Bench {
        self.0
            .iter()
            .find(|(k, hh, _)| *k == kind && *hh == h)
            .map(|x| &x.2)
            .expect("a bench for every row's objective")
    }
    /// The task's bench under its default objective (baselines: no training).
    fn of_task(&self, kind: TaskKind) -> &Bench {
        self.0
            .iter()
            .find(|(k, _, _)| *k == kind)
            .map(|x| &x.2)
            .expect("every task has a row")
    }
}

/// A row with the hyper-parameters of `p` (no grid left).
fn at_point(e: &AlgorithmEntry, p: &GridPoint) -> AlgorithmEntry {
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
fn tune(
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
fn tuning_seeds_of(tuning: &[TuningResult]) -> std::collections::BTreeSet<u64> {
    tuning
        .iter()
        .flat_map(|t| &t.points)
        .flat_map(|p| &p.runs)
        .map(|r| r.seed)
        .collect()
}

type Rows = Vec<Vec<ConfigWithTiming>>;

/// How far the tuning and report runs got.
enum Experiments {
    /// Some tuning unit is neither stored nor this run's.
    TuningIncomplete,
    /// Every row is tuned; some report unit is neither stored nor this run's.
    ReportIncomplete,
    /// Everything: the tuning, every row's results, the configurations computed.
    Done(Vec<TuningResult>, Rows, Vec<String>),
}

/// The three concurrent stages' results (`None`: not this run's share, or missing in a merge).
struct Stages {
    theory: Option<TheoryTable>,
    gradient: Option<GradientErrorResult>,
    experiments: Experiments,
}

/// The progress bar over every seed run of the profile.
fn progress_for(profile: &Profile, opts: &Options) -> Progress {
    let tasks = [&profile.obstacle, &profile.cartpole];
    let tuning_total: usize = tasks
        .iter()
        .flat_map(|t| &t.algorithms)
        .filter(|e| !e.grid.is_empty() && e.hyper_parameters_of.is_none())
        .map(|e| e.grid_points().map_or(0, |p| p.len()) * profile.tuning_seeds as usize)
        .sum();
    let report_total: usize =
        tasks.iter().map(|t| t.algorithms.len()).sum::<usize>() * profile.seeds as usize;
    Progress::new(tuning_total + report_total, opts.progress)
}

/// Run everything the profile asks for (reusing finished configurations and stored units; in a
/// merge, computing nothing) and collect the results.
///
/// # Errors
/// Any experiment, I/O or theory failure; a report seed equal to a tuning seed;
/// [`Error::Incomplete`] when a merge finds units no shard has computed.
pub fn run(profile: &Profile, opts: &Options) -> Result<Results, Error> {
    let runs_dir = opts.out.join("runs");
    let timings_dir = opts.out.join("timings");
    mkdir(&runs_dir)?;
    mkdir(&timings_dir)?;
    let progress = progress_for(profile, opts);
    let benches = Benches::new(profile)?;
    let seeds: Vec<u32> = (0..profile.seeds).collect();
    let mode = match opts.mode {
        Mode::Shard(_) => Mode::All,
        m => m,
    };
    let units = Units::new(&runs_dir, mode, opts.redo);
    let st = stages(profile, opts, &progress, &benches, &units)?;
    let (theory, gradient_error, (tuning, rows, computed)) =
        match (st.theory, st.gradient, st.experiments) {
            (Some(t), Some(g), Experiments::Done(a, b, c)) => (t, g, (a, b, c)),
            (t, g, e) => {
                let mut what = Vec::new();
                if t.is_none() {
                    what.push("the theorem table".to_string());
                }
                if g.is_none() {
                    what.push("the Fig. 4.2 study".into());
                }
                match e {
                    Experiments::TuningIncomplete => what.push("tuning runs".into()),
                    Experiments::ReportIncomplete => what.push("report runs".into()),
                    Experiments::Done(..) => {}
                }
                return Err(Error::Incomplete {
                    missing: units.missing() + usize::from(t.is_none()) + usize::from(g.is_none()),
                    what: what.join(", "),
                    store: runs_dir.join("units").display().to_string(),
                });
            }
        };
    let baselines = progress.stage("reference policies (expert, straight to goal)", || {
        baselines_job(profile, &benches, &seeds)
    })?;
    write_atomic(
        &opts.out.join("baselines.json"),
        &to_json("baselines", &baselines)?,
    )?;
    let removed_stale = remove_stale(profile, &runs_dir, &timings_dir)?;
    if !removed_stale.is_empty() {
        progress.line(&format!(
            "removed {} cached files no row of this profile uses: {}",
            removed_stale.len(),
            removed_stale.join(", ")
        ));
    }
    progress.finish();
    let mut it = rows.into_iter();
    Ok(Results {
        gradient_error,
        obstacle: it.next().unwrap_or_default(),
        cartpole: it.next().unwrap_or_default(),
        baselines,
        tuning,
        theory,
        computed,
        removed_stale,
    })
}

/// What one shard did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShardSummary {
    /// Units this shard computed now.
    pub computed: usize,
    /// Whether every row's tuning is in the store (so the report runs could start).
    pub tuning_complete: bool,
    /// Whether everything of the profile is in the store (`paper-checks merge` can run).
    pub complete: bool,
}

/// Compute this shard's share (`opts.mode` must be [`Mode::Shard`]) into the unit store.
///
/// # Errors
/// As [`run`]; a mode other than a shard.
pub fn run_shard(profile: &Profile, opts: &Options) -> Result<ShardSummary, Error> {
    if !matches!(opts.mode, Mode::Shard(_)) {
        return Err(Error::experiment("shard", "the options name no shard"));
    }
    let runs_dir = opts.out.join("runs");
    mkdir(&runs_dir)?;
    mkdir(&opts.out.join("timings"))?;
    let progress = progress_for(profile, opts);
    let benches = Benches::new(profile)?;
    let units = Units::new(&runs_dir, opts.mode, opts.redo);
    let st = stages(profile, opts, &progress, &benches, &units)?;
    progress.finish();
    Ok(ShardSummary {
        computed: units.computed(),
        tuning_complete: !matches!(st.experiments, Experiments::TuningIncomplete),
        complete: units.missing() == 0
            && st.theory.is_some()
            && st.gradient.is_some()
            && matches!(st.experiments, Experiments::Done(..)),
    })
}

/// The theorem table, the Fig. 4.2 study, and the tuning and report runs, concurrently.
fn stages(
    profile: &Profile,
    opts: &Options,
    progress: &Progress,
    benches: &Benches,
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
    let theory_file = opts.out.join("theory.md");
    let theory_cache_file = runs_dir.join("theory.json");
    let tkey = theory_key(profile, &opts.source_version);
    let theory_cached: Option<TheoryCache> = if opts.redo {
        None
    } else {
        read_json::<TheoryCache>(&theory_cache_file).filter(|c| c.key_hash == tkey)
    };

    let seeds: Vec<u32> = (0..profile.seeds).collect();

    let theory_job = || -> Result<Option<TheoryTable>, Error> {
        let theory_json = opts.out.join("theory.json");
        if let Some(c) = theory_cached.clone() {
            if sharded.is_none() {
                // The copies beside the appendix follow the cached table the key names.
                write_theory_copies(&theory_file, &theory_json, &c.checks)?;
            }
            return Ok(Some(TheoryTable::Checks(c.checks)));
        }
        if profile.theory_profile == "none" {
            // No table this time: a table left by an earlier profile must not sit beside it.
            for f in [&theory_file, &theory_json, &theory_cache_file] {
                if sharded.is_none() && f.exists() {
                    std::fs::remove_file(f).map_err(|e| Error::io(f, e))?;
                }
            }
            return Ok(Some(TheoryTable::NotRun));
        }
        if !computes(&tkey) {
            return Ok(None);
        }
        let p = if profile.theory_profile == "full" {
            ilopt_theory::suite::Profile::Full
        } else {
            ilopt_theory::suite::Profile::Quick
        };
        // The whole table, real-environment rows included (as `ilopt-theory`'s binary prints it).
        let checks = ilopt_theory::suite::whole_table(p).map_err(Error::Theory)?;
        let cache = TheoryCache {
            key_hash: tkey.clone(),
            checks,
        };
        write_theory_copies(&theory_file, &theory_json, &cache.checks)?;
        write_atomic(&theory_cache_file, &to_json("theory cache", &cache)?)?;
        Ok(Some(TheoryTable::Checks(cache.checks)))
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
                let bench = benches.get(*kind, e.horizon(t, kind.name()));
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

/// Remove from `runs/` and `timings/` every file this profile does not produce (results of
/// rows an earlier profile had, left-over temporaries), so that the directory holds exactly the
/// data the appendix was built from. Returns the removed files (relative to the output
/// directory), sorted.
///
/// # Errors
/// [`Error::Io`] if a directory cannot be read or a file cannot be removed.
pub fn remove_stale(
    profile: &Profile,
    runs_dir: &Path,
    timings_dir: &Path,
) -> Result<Vec<String>, Error> {
    let mut keep_runs = vec!["gradient-error.json".to_string()];
    if profile.theory_profile != "none" {
        keep_runs.push("theory.json".into());
    }
    let mut keep_timings = vec!["gradient-error.json".to_string()];
    for (kind, t) in [
        (TaskKind::Obstacle, &profile.obstacle),
        (TaskKind::Cartpole, &profile.cartpole),
    ] {
        for e in &t.algorithms {
            let stem = format!("{}-{}.json", kind.name(), slug(&e.label));
            if !e.grid.is_empty() && e.hyper_parameters_of.is_none() {
                keep_runs.push(format!("tuning-{stem}"));
            }
            keep_runs.push(stem.clone());
            keep_timings.push(stem);
        }
    }
    let mut removed = Vec::new();
    for (dir, keep) in [(runs_dir, &keep_runs), (timings_dir, &keep_timings)] {
        let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(dir, e))?;
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_file() && !keep.contains(&name) {
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
                let sub = dir.file_name().map(|d| d.to_string_lossy().into_owned());
                removed.push(format!("{}/{name}", sub.unwrap_or_default()));
            }
        }
    }
    // Every configuration is assembled by now and its units removed: what is left in the unit
    // store belongs to other code versions or profiles.
    let units_dir = runs_dir.join("units");
    if units_dir.is_dir() {
        let entries = std::fs::read_dir(&units_dir).map_err(|e| Error::io(&units_dir, e))?;
        for entry in entries {
            let path = entry.map_err(|e| Error::io(&units_dir, e))?.path();
            if path.is_file() {
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
                let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
                removed.push(format!("runs/units/{}", name.unwrap_or_default()));
            }
        }
        // Empty now: a single run's directory has none.
        let _ = std::fs::remove_dir(&units_dir);
    }
    removed.sort();
    Ok(removed)
}

/// Evaluate every task's baselines on every seed's evaluation episodes (cheap: no training, so
/// never cached).
fn baselines_job(
    profile: &Profile,
    benches: &Benches,
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
                label: b.label(bench),
                runs,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_theory_cache_key_names_the_size_profile_and_the_code() {
        let mut p = Profile::from_toml(
            &std::fs::read_to_string(
                Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quick.toml"),
            )
            .expect("the quick profile"),
            Path::new("quick.toml"),
        )
        .expect("valid");
        let quick = theory_key(&p, "a");
        assert_eq!(quick, theory_key(&p, "a"));
        assert_ne!(quick, theory_key(&p, "b"));
        p.theory_profile = "full".into();
        assert_ne!(quick, theory_key(&p, "a"));
    }
}
