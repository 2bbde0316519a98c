//! `ilopt eval --config FILE.toml --theta THETA.json [--episodes N] [--seed S]`: evaluate a
//! saved policy parameter (`theta-seed-<n>.json` of `ilopt run`) on the config's task.
//!
//! Prints one JSON object: the Monte-Carlo objective `F̂(θ)` with its standard error over
//! `episodes` roll-outs of the stochastic learner under the config's objective
//! ([`ilopt::evaluate::objective`]), and the deterministic evaluation of `ilopt run`'s
//! checkpoints (CartPole: mean reward and 500-step episodes; obstacle: success rate; toy: the
//! exact F(θ)).

use super::run::RunError;
use super::run::RunTask;
use super::run::config::RunFile;
use super::run::records::SavedTheta;
use super::run::task::task_learner;
use clap::Args;
use ilopt::evaluate::objective;
use nalgebra::DVector;
use serde_json::{Value, json};
use std::path::PathBuf;

/// Arguments of `ilopt eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The config file whose task and policy θ belongs to (e.g. the run's `config.toml`).
    #[arg(long, value_name = "FILE.toml")]
    pub config: PathBuf,
    /// The saved θ (`theta-seed-<n>.json` of `ilopt run`).
    #[arg(long, value_name = "FILE.json")]
    pub theta: PathBuf,
    /// Roll-outs and evaluation episodes (default: the config's `evaluation.episodes`).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub episodes: Option<u32>,
    /// Seed of the roll-outs and episodes.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
}

/// Run `ilopt eval`.
///
/// # Errors
/// [`RunError`] for a bad config, an unreadable θ file, a θ that does not fit the config's
/// policy, or a failing roll-out.
pub fn run(args: &EvalArgs) -> Result<Value, RunError> {
    let config = RunFile::load(&args.config)?;
    let bench = task_learner(&config)?;
    let text = std::fs::read_to_string(&args.theta).map_err(|e| RunError::io(&args.theta, e))?;
    let bad = |message: String| RunError::Theta {
        path: args.theta.clone(),
        message,
    };
    let saved: SavedTheta = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    let task = config.file.task.name.name();
    if saved.task != task || saved.policy != bench.policy_name() {
        return Err(bad(format!(
            "θ of a {} policy on the {} task; the config has a {} policy on the {task} task",
            saved.policy,
            saved.task,
            bench.policy_name()
        )));
    }
    if saved.theta.len() != bench.dim() {
        return Err(bad(format!(
            "θ has {} entries, the config's {} policy has {} parameters",
            saved.theta.len(),
            bench.policy_name(),
            bench.dim()
        )));
    }
    if let Some(i) = saved.theta.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!("entry {i} (0-based) of θ is not finite")));
    }
    let episodes = args
        .episodes
        .or(config.file.evaluation.episodes)
        .unwrap_or(super::run::config::DEFAULT_EPISODES);
    let mut out =
        ilopt::with_task_learner!(&bench, t => eval_task(t, &saved.theta, episodes, args.seed))?;
    out["theta_seed"] = json!(saved.seed);
    Ok(out)
}

/// `ilopt eval` on any task ([`RunTask`]: built in or a program's own): the objective F̂(θ)
/// estimated from `episodes` roll-outs seeded by `seed`, and the deterministic evaluation of the
/// run's checkpoints on `episodes` episodes.
///
/// # Errors
/// [`RunError::Evaluation`] if a roll-out or an episode fails.
pub fn eval_task<T: RunTask + ?Sized>(
    task: &T,
    theta: &[f64],
    episodes: u32,
    seed: u64,
) -> Result<Value, RunError> {
    let obj = objective(
        &mut task.problem().clone(),
        &DVector::from_column_slice(theta),
        episodes as usize,
        seed,
    )
    .map_err(|e| RunError::Evaluation(e.to_string()))?;
    let ev = task
        .evaluate(theta, episodes, seed)
        .map_err(RunError::Evaluation)?;
    Ok(json!({
        "task": task.task_name(),
        "policy": task.policy_name(),
        "dim": task.dim(),
        "seed": seed,
        "episodes": episodes,
        "objective": {
            "mean": obj.mean,
            "standard_error": obj.standard_error,
            "rollouts": obj.rollouts,
        },
        "evaluation": ev,
    }))
}
