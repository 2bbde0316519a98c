//! `ilopt run --config FILE.toml --out DIR [--threads N] [--overwrite] [--quiet]`: train a learner
//! on a task as a config file says, for every seed, and write per-checkpoint CSV and JSON into
//! `DIR`.
//!
//! | module | what |
//! |---|---|
//! | [`config`] | the TOML schema and its loading |
//! | `resolve` | defaults, absolute paths, range checks |
//! | [`integer_keys`] | the integer keys' ranges, in the user's words |
//! | `algorithm_keys` | unknown keys of `[algorithm]`; its numbers as written |
//! | [`runnable`] | what a run needs of a task: [`RunTask`] (built-in or a program's own) |
//! | [`task`] | the config's built-in task, expert, policy and objective as an IL problem |
//! | [`plugin`] | a program's own environment and expert as a task ([`EnvRun`]) |
//! | [`evaluation`] | the deterministic evaluation of θ (reward, success, loss; toy: exact F) |
//! | [`oracle`] | the config's oracle (baseline, m trajectories) for any computation on it |
//! | [`first_step`] | the least cost of the first step, against the budget |
//! | [`driver`] | one seed's run with its checkpoints |
//! | [`parallel`] | the seeds on a thread pool, with a progress bar |
//! | [`records`] | what is recorded: checkpoints, runs, timings, saved θ |
//! | [`output`] | the output directory, written atomically |
//! | [`table`] | the summary as a table a person reads |
//!
//! The output directory holds `config.toml` (the resolved config), per seed `seed-<n>.csv`,
//! `seed-<n>.json` and `theta-seed-<n>.json`, `summary.json`, `summary.txt` (the table), and
//! `timings.json`, the only file with wall times: every other file is byte-identical across
//! reruns and thread counts. `config.toml`, `seed-<n>.json` and `summary.json` record the build
//! that wrote them ([`crate::provenance`]).

mod algorithm_keys;
pub mod config;
pub mod driver;
pub mod error;
pub mod evaluation;
pub mod first_step;
pub mod integer_keys;
pub mod oracle;
pub mod output;
pub mod parallel;
pub mod plugin;
pub mod records;
mod resolve;
pub mod runnable;
pub mod table;
pub mod task;

pub use config::{LoadedConfig, RunFile};
pub use error::RunError;
pub use plugin::EnvRun;
pub use runnable::RunTask;

use clap::Args;
use records::SeedRun;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use task::task_learner;

/// The keys of a config file, for `ilopt run --help` (docs/run.md has the full reference).
pub const CONFIG_KEYS: &str = "\
CONFIG KEYS (docs/run.md has types, defaults and ranges; relative paths are relative to the config file)
  [task]        name = \"cartpole\" | \"obstacle\" | \"toy\"
                expert = \"ppo\" (built in) | \"lqr\"           cartpole; default ppo
                expert_file = \"path.json\"                   cartpole: a PPO expert file instead
                mdp = \"path.json\"                           toy: the MDP file (required)
                horizon = \"fixed\" | \"episodic\"              default fixed
                steps = T                                   fixed: default cartpole 500, obstacle 200
                after_end = \"reset\" | \"absorb\"              fixed: default cartpole reset, obstacle absorb
  [policy]      kind = \"softmax\" | \"logistic\"               cartpole; default softmax
                sigma = 0.1                                 obstacle: σ > 0 of the linear-Gaussian learner
                features = { kind = \"basic\" } | { kind = \"rbf\", per_axis, width, x_range, y_range }
  [algorithm]   algorithm = \"sgd\" | \"storm\" | \"storm-plus\" | \"adam\" | \"rms-prop\" | \"o2nc\"
                          | \"bc\" | \"dagger\" | \"rrm\" | \"smile\" | \"forward-training\" | …
                and that algorithm's hyper-parameters (the schema of ilopt's AlgorithmConfig)
  [run]         budget_calls = N                            budget in gradient calls, ≥ 1 (required)
                seeds = [1, 2, 3]                           non-empty, distinct (required)
                trajectories_per_gradient = 1               oracle methods, ≥ 1
                baseline = { kind = \"leave-one-out\" } | …     oracle methods; default none
                theta0 = \"zero\" | [numbers]                 default zero
                norm_bound = 1e4                            ‖θ‖₂ above it ends the run as diverged; > 0
  [evaluation]  every_calls = N                             checkpoint spacing, 1..=budget; default budget/10
                episodes = 10                               deterministic episodes per checkpoint
Examples: examples/run/*.toml";

/// Arguments of `ilopt run`.
#[derive(Debug, Args)]
#[command(after_long_help = CONFIG_KEYS)]
pub struct RunArgs {
    /// The config file (TOML; `--help` lists its keys, docs/run.md describes each one).
    #[arg(long, value_name = "FILE.toml")]
    pub config: PathBuf,
    /// The output directory: created if needed; one that holds files is refused unless
    /// `--overwrite`.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Use a non-empty `--out`: first remove the files `ilopt run` writes there (config.toml,
    /// seed-*.csv, seed-*.json, theta-seed-*.json, summary.json, summary.txt, timings.json) and
    /// keep every other file.
    #[arg(long)]
    pub overwrite: bool,
    /// Print nothing on stderr but errors: no progress bar, no per-checkpoint lines, no final
    /// table (`summary.txt` is still written).
    #[arg(long)]
    pub quiet: bool,
    /// Threads running seeds in parallel (default: the available parallelism); the output does
    /// not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
}

/// Run `ilopt run`: returns the summary (also written to `summary.json`).
///
/// # Errors
/// [`RunError`] naming the file and key at fault, or the seed whose run failed.
pub fn run(args: &RunArgs) -> Result<Value, RunError> {
    let config = RunFile::load(&args.config)?;
    let threads = args.threads.map(|n| n as usize);
    let options = RunOptions {
        overwrite: args.overwrite,
        quiet: args.quiet,
    };
    Ok(execute(&config, Some(&args.out), threads, options)?.summary)
}

/// How a run treats its output directory and stderr.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunOptions {
    /// Use a non-empty output directory, first removing the kit's own files there
    /// ([`output::OutputDir::prepare`]).
    pub overwrite: bool,
    /// Print nothing on stderr (no progress, no closing table).
    pub quiet: bool,
}

/// What a run gives: the summary (`summary.json`) and every seed's run and wall times, in the
/// config's seed order.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// The summary, as `summary.json` holds it.
    pub summary: Value,
    /// Each seed's run (what `seed-<n>.json` holds; its checkpoints are `seed-<n>.csv`'s rows).
    pub runs: Vec<SeedRun>,
    /// Each seed's wall times (what `timings.json` lists).
    pub timings: Vec<records::SeedTiming>,
}

/// Run a loaded config on its built-in task ([`TaskLearner`](task::TaskLearner)) through [`execute_task`]: the
/// route of `ilopt run` and of the Python package's `ilopt.run`.
///
/// # Errors
/// As [`execute_task`], and [`RunError`] if the task cannot be built.
pub fn execute(
    config: &LoadedConfig,
    out: Option<&Path>,
    threads: Option<usize>,
    options: RunOptions,
) -> Result<RunOutcome, RunError> {
    let learner = task_learner(config)?;
    ilopt::with_task_learner!(&learner, t => execute_task(t, config, out, threads, options))
}

/// Train on `task` as `config` says, for every seed, on up to `threads` threads (default: the
/// available parallelism; capped by [`RunTask::max_threads`]), and write the outputs of
/// `ilopt run` into `out`: the entry point for a built-in task and a program's own alike. The
/// config's `[task]` and `[policy]` sections describe a built-in task; a plug-in task brings its
/// own, and its config has `task.name = "custom"` (the default when `[task]` is left out).
/// Returns the summary (also written to `summary.json`).
///
/// # Errors
/// [`RunError`] naming the file and key at fault, or the seed whose run failed;
/// [`RunError::OutputNotEmpty`] for a non-empty `out` without `options.overwrite`.
pub fn run_task<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
    out: &Path,
    threads: Option<usize>,
    options: RunOptions,
) -> Result<Value, RunError> {
    Ok(execute_task(task, config, Some(out), threads, options)?.summary)
}

/// [`run_task`] with the output directory optional (without one nothing is written and nothing
/// is printed but the progress) and every seed's run returned beside the summary.
///
/// # Errors
/// As [`run_task`].
pub fn execute_task<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
    out: Option<&Path>,
    threads: Option<usize>,
    options: RunOptions,
) -> Result<RunOutcome, RunError> {
    driver::check_config(task, config)?;
    let out = out
        .map(|o| output::OutputDir::prepare(o, options.overwrite))
        .transpose()?;
    if let Some(out) = &out {
        let toml = config
            .to_toml()
            .map_err(|message| RunError::Evaluation(format!("writing config.toml: {message}")))?;
        out.write_config(&toml)?;
    }
    let threads = threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, std::num::NonZero::get));
    let started = std::time::Instant::now();
    let results = parallel::run_seeds(task, config, out.as_ref(), threads, options.quiet)?;
    let (runs, timings): (Vec<SeedRun>, Vec<records::SeedTiming>) = results.into_iter().unzip();
    let summary = summary(config, task, &runs.iter().collect::<Vec<_>>());
    let table = table::render(&summary);
    if let Some(out) = &out {
        out.write_json("summary.json", &summary)?;
        out.write("summary.txt", &table)?;
        out.write_json(
            "timings.json",
            &json!({
                "threads": threads.min(task.max_threads()),
                "total_seconds": started.elapsed().as_secs_f64(),
                "seeds": timings,
            }),
        )?;
    }
    if !options.quiet {
        eprint!("{table}");
    }
    Ok(RunOutcome {
        summary,
        runs,
        timings,
    })
}

/// The summary: per seed its termination and final checkpoint, and the mean over seeds of the
/// final checkpoint's metrics.
fn summary<T: RunTask + ?Sized>(config: &LoadedConfig, task: &T, runs: &[&SeedRun]) -> Value {
    let f = &config.file;
    let mean = |get: &dyn Fn(&records::Checkpoint) -> Option<f64>| -> Option<f64> {
        let v: Vec<f64> = runs
            .iter()
            .filter_map(|r| r.checkpoints.last().and_then(get))
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    json!({
        "ilopt": crate::provenance::BUILD,
        "task": task.task_name(),
        "policy": task.policy_name(),
        "algorithm": runs.first().map(|r| r.algorithm.clone()),
        "budget_calls": f.run.budget_calls,
        "norm_bound": f.run.norm_bound,
        "dim": task.dim(),
        "seeds": f.run.seeds,
        "final_mean": {
            "score": mean(&|c| c.score),
            "reward": mean(&|c| c.reward),
            "eval_loss": mean(&|c| c.eval_loss),
            "objective": mean(&|c| c.objective),
            "train_loss": mean(&|c| c.train_loss),
        },
        "runs": runs.iter().map(|r| json!({
            "seed": r.seed,
            "termination": r.termination,
            "iterations": r.iterations,
            "cost": r.cost,
            "final": r.checkpoints.last(),
        })).collect::<Vec<_>>(),
    })
}
