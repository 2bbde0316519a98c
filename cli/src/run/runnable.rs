//! What `ilopt run` needs of a task ([`RunTask`]): an IL problem the algorithms train on, names for
//! the records, and the deterministic evaluation of θ at the checkpoints. The built-in tasks
//! ([`TaskLearner`](super::task::TaskLearner)) and a program's own environment
//! ([`EnvRun`](super::plugin::EnvRun), Python's `ilopt.GymTask`) are run by the same
//! [`run_task`](super::run_task()) with the same config schema and outputs.

use super::config::{LoadedConfig, Theta0};
use super::error::RunError;
use super::evaluation::Evaluation;
use ilopt::baseline::PerDecisionTerms;
use ilopt::problem::IlProblem;
use ilopt::task::{AfterEnd, Horizon};
use nalgebra::DVector;

/// A task `ilopt run` can train and evaluate on.
pub trait RunTask: Sync {
    /// The IL problem (eq. 3.1's F with its oracle, eq. 3.15) the algorithms run on; every
    /// baseline of `[run] baseline` and every `trajectories_per_gradient` wrap it.
    type Problem: IlProblem<f64> + PerDecisionTerms<f64> + Clone + Sync;

    /// The IL problem.
    fn problem(&self) -> &Self::Problem;

    /// The task's name in the records (`"cartpole"`, `"obstacle"`, `"toy"`, or a plug-in's own).
    fn task_name(&self) -> &str;

    /// The policy's name in the records (`"softmax"`, `"linear-gaussian"`, …).
    fn policy_name(&self) -> &str;

    /// The deterministic evaluation of θ on `episodes` episodes keyed by `seed` (episode j draws
    /// from [`episode_seed`](super::evaluation::episode_seed)`(seed, j)`).
    ///
    /// # Errors
    /// A message if an episode, the expert or the policy fails.
    fn evaluate(&self, theta: &[f64], episodes: u32, seed: u64) -> Result<Evaluation, String>;

    /// The most threads the seeds may run on (a task whose environment lives in a Python
    /// interpreter steps one seed at a time; with one thread the seeds run on the calling one).
    fn max_threads(&self) -> usize {
        usize::MAX
    }

    /// Called before each seed's run, on the thread that runs it (before the first checkpoint's
    /// evaluation): a task whose environment keeps a random generator across runs reseeds it
    /// here, so that a seed's run does not depend on the runs before it. The default does
    /// nothing.
    fn seed_started(&self, _seed: u64) {}

    /// The number of policy parameters.
    fn dim(&self) -> usize {
        IlProblem::<f64>::dim(self.problem())
    }

    /// The decisions every trajectory of the problem certainly has (one gradient call each in
    /// eq. 3.15), with what fixes that count in words, for the first step's least cost
    /// ([`super::first_step`]); `None` when a trajectory may have none. The default: at least one.
    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        Some(AT_LEAST_ONE)
    }
}

/// A trajectory of at least one decision (an episode or an absorbing end may stop after it).
pub const AT_LEAST_ONE: (u64, &str) = (1, "(at least 1 decision per trajectory)");

/// [`RunTask::least_decisions`] of a [`Horizon`]: exactly `steps` on a fixed horizon with a reset
/// after an early end (named `steps_key`), else [`AT_LEAST_ONE`].
pub fn horizon_decisions(horizon: &Horizon, steps_key: &'static str) -> (u64, &'static str) {
    match *horizon {
        Horizon::Fixed {
            steps,
            after_end: AfterEnd::Reset,
        } => (steps as u64, steps_key),
        _ => AT_LEAST_ONE,
    }
}

/// θ₀ of the config, checked against the task's dimension.
///
/// # Errors
/// [`RunError::Invalid`] for `run.theta0` of the wrong length.
pub fn theta0<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
) -> Result<DVector<f64>, RunError> {
    let d = task.dim();
    match &config.file.run.theta0 {
        Theta0::Zero => Ok(DVector::zeros(d)),
        Theta0::Values(v) if v.len() == d => Ok(DVector::from_column_slice(v)),
        Theta0::Values(v) => Err(config.invalid(
            "run.theta0",
            format!(
                "has {} entries, the {} policy has {d} parameters",
                v.len(),
                task.policy_name()
            ),
        )),
    }
}
