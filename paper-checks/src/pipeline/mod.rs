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

use crate::config::Profile;
use crate::error::Error;
use crate::progress::Progress;
use crate::results::{Results, TheoryTable};
use crate::shard::{Mode, Units};
use crate::storage::{mkdir, to_json, write_atomic};
use stages::{Experiments, stages};
pub use stale::remove_stale;
use std::path::PathBuf;
use task_learners::{TaskLearners, baselines_job};
pub use theory_cache::TheoryCache;

mod keys;
mod stages;
mod stale;
mod task_learners;
#[cfg(test)]
mod tests;
mod theory_cache;
mod tuning_stage;

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

/// The progress bar over every seed run of the profile.
fn progress_for(profile: &Profile, opts: &Options) -> Progress {
    let tasks = [&profile.obstacle, &profile.cartpole];
    let tuning_total: usize = tasks
        .iter()
        .flat_map(|t| &t.algorithms)
        .filter(|e| e.has_grid() && e.hyper_parameters_of.is_none())
        .map(|e| {
            // Successive halving without extensions: n points at the first rung, ⌈n/halving⌉
            // at the next, … (runs that ended at a lower rung are not run again).
            let mut n = e.grid_points().map_or(0, |p| p.len());
            let rungs = profile.tuning.rungs_for(n, u64::MAX, 1).len();
            let mut total = 0;
            for r in 0..rungs {
                total += n;
                if r + 1 < rungs {
                    n = profile.tuning.kept(n);
                }
            }
            total * profile.tuning_seeds as usize
        })
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
    let benches = TaskLearners::new(profile)?;
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

/// What the theory job did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TheoryJob {
    /// It computed the theorem table and stored it.
    Computed,
    /// The store already held the table of this profile and code.
    Stored,
    /// The profile runs no theorem table.
    NotRun,
}

/// The theory job (`paper-checks theory`): compute the profile's theorem table into the output
/// directory's store, where the shards leave it. It shares nothing with the shards' units, so it
/// runs beside their passes, and `paper-checks merge` reads it.
///
/// # Errors
/// A theory or I/O failure.
pub fn run_theory(profile: &Profile, opts: &Options) -> Result<TheoryJob, Error> {
    let runs_dir = opts.out.join("runs");
    mkdir(&runs_dir)?;
    Ok(match stages::theory_stage(profile, opts, true, false)? {
        (Some(TheoryTable::NotRun), _) => TheoryJob::NotRun,
        (_, true) => TheoryJob::Computed,
        (_, false) => TheoryJob::Stored,
    })
}

/// What one shard did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShardSummary {
    /// Units this shard computed now.
    pub computed: usize,
    /// Whether every row's tuning is in the store (so the report runs could start).
    pub tuning_complete: bool,
    /// Whether the theorem table is in the store, or the profile runs none (else the theory
    /// job, `paper-checks theory`, has not finished).
    pub theory_stored: bool,
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
    let benches = TaskLearners::new(profile)?;
    let units = Units::new(&runs_dir, opts.mode, opts.redo);
    let st = stages(profile, opts, &progress, &benches, &units)?;
    progress.finish();
    Ok(ShardSummary {
        computed: units.computed(),
        tuning_complete: !matches!(st.experiments, Experiments::TuningIncomplete),
        theory_stored: st.theory.is_some(),
        complete: units.missing() == 0
            && st.theory.is_some()
            && st.gradient.is_some()
            && matches!(st.experiments, Experiments::Done(..)),
    })
}
