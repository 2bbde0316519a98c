//! A program's own environment as a task of `ilopt run` ([`EnvRun`]): an [`EnvTask`] (an [`Env`]
//! with Gymnasium's reset/step, a feature map φ and an expert), a policy with a deterministic
//! action ([`Greedy`]) and the thesis's objective ([`Horizon`]), trained by
//! [`run_task`](super::run_task()) under the same config schema, with the same checkpoints and
//! files as a built-in task. `cli/examples/custom_env.rs` runs one; Python's
//! `ilopt.GymTask` is one over a Gymnasium environment.
//!
//! **Evaluation.** Episode j of a checkpoint's evaluation starts from an RNG seeded by
//! [`episode_seed`]`(seed, j)`, so that every checkpoint meets the same episodes; the policy takes
//! its deterministic action until the episode ends (terminated or truncated) or `eval_steps`
//! decisions are made. The score is the mean episode return (the rewards' sum), recorded as
//! `score` and `reward`; the loss is the mean per-decision supervised loss against the expert on
//! the visited states.
//!
//! **An environment with state of its own.** [`EnvTask`] copies its environment for every
//! episode; one that lives outside the program (a Python interpreter's Gymnasium environment)
//! is the same environment in every copy, and its random generator runs on across episodes.
//! Two settings keep such a run reproduced by its seed alone:
//! [`EnvRun::on_each_seed`] is called before each seed's run (the environment reseeds there), and
//! [`EnvRun::with_evaluation_env`] gives the checkpoints' evaluation episodes an environment of
//! their own, so that evaluating does not move the training's generator.

use super::evaluation::{Evaluation, episode_seed};
use super::runnable::{RunTask, horizon_decisions};
use ilopt::baseline::PerDecisionTerms;
use ilopt::env::Env;
use ilopt::evaluate::episodes::task_episodes;
use ilopt::policy::{Greedy, PolicyExt};
use ilopt::problem::IlProblem;
use ilopt::task::{EnvEpisode, EnvTask, Horizon, Task, TaskProblem};
use std::borrow::Borrow;

/// A plug-in task (module docs): the IL problem over a program's own environment, with the names
/// its records carry and the evaluation episodes' length.
pub struct EnvRun<E: Env<f64>, F, X, P> {
    name: String,
    policy_name: String,
    problem: TaskProblem<EnvTask<E, F, X, f64>, P>,
    evaluation: Option<EnvTask<E, F, X, f64>>,
    on_seed: Option<SeedHook>,
    eval_steps: usize,
    max_threads: usize,
}

/// What [`EnvRun::on_each_seed`] calls before a seed's run, with the seed.
type SeedHook = std::sync::Arc<dyn Fn(u64) + Send + Sync>;

impl<E: Env<f64>, F, X, P> Clone for EnvRun<E, F, X, P>
where
    TaskProblem<EnvTask<E, F, X, f64>, P>: Clone,
    EnvTask<E, F, X, f64>: Clone,
{
    fn clone(&self) -> Self {
        EnvRun {
            name: self.name.clone(),
            policy_name: self.policy_name.clone(),
            problem: self.problem.clone(),
            evaluation: self.evaluation.clone(),
            on_seed: self.on_seed.clone(),
            eval_steps: self.eval_steps,
            max_threads: self.max_threads,
        }
    }
}

impl<E: Env<f64>, F, X, P> std::fmt::Debug for EnvRun<E, F, X, P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvRun")
            .field("name", &self.name)
            .field("policy_name", &self.policy_name)
            .field("eval_steps", &self.eval_steps)
            .field("own_evaluation_env", &self.evaluation.is_some())
            .field("on_each_seed", &self.on_seed.is_some())
            .finish_non_exhaustive()
    }
}

/// Why an [`EnvRun`] cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PluginError {
    /// The task or policy name is empty or not one word of `[a-z0-9_-]`.
    #[error("the {what} name {name:?} must be non-empty and use only a-z, 0-9, '-' and '_'")]
    Name {
        /// `"task"` or `"policy"`.
        what: &'static str,
        /// The name given.
        name: String,
    },
    /// `eval_steps = 0`.
    #[error("eval_steps must be at least 1")]
    EvalSteps,
    /// The name of a built-in task.
    #[error("{0:?} is a built-in task's name; give the plug-in task another")]
    BuiltIn(String),
}

fn check_name(what: &'static str, name: &str) -> Result<(), PluginError> {
    let ok = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_');
    if ok {
        Ok(())
    } else {
        Err(PluginError::Name {
            what,
            name: name.to_string(),
        })
    }
}

impl<E: Env<f64>, F, X, P> EnvRun<E, F, X, P> {
    /// The task `name` (recorded in every output, as `"cartpole"` is for the built-in task)
    /// training `policy` (recorded as `policy_name`) on `task` with the objective `horizon`;
    /// evaluation episodes end after at most `eval_steps` decisions.
    ///
    /// # Errors
    /// [`PluginError`] for a name that is empty, not one lower-case word, or a built-in task's,
    /// and for `eval_steps = 0`.
    pub fn new(
        name: &str,
        policy_name: &str,
        task: EnvTask<E, F, X, f64>,
        policy: P,
        horizon: Horizon,
        eval_steps: usize,
    ) -> Result<Self, PluginError> {
        check_name("task", name)?;
        check_name("policy", policy_name)?;
        if ["cartpole", "obstacle", "toy", "custom"].contains(&name) {
            return Err(PluginError::BuiltIn(name.to_string()));
        }
        if eval_steps == 0 {
            return Err(PluginError::EvalSteps);
        }
        Ok(EnvRun {
            name: name.to_string(),
            policy_name: policy_name.to_string(),
            problem: TaskProblem {
                task,
                policy,
                horizon,
            },
            evaluation: None,
            on_seed: None,
            eval_steps,
            max_threads: usize::MAX,
        })
    }

    /// The same task, its checkpoints' evaluation episodes on `env` (copied for each episode)
    /// instead of the training's environment, with the same features and expert: for an
    /// environment whose copies share one random generator (module docs).
    #[must_use]
    pub fn with_evaluation_env(mut self, env: E) -> Self
    where
        EnvTask<E, F, X, f64>: Clone,
    {
        self.evaluation = Some(self.problem.task.clone().with_env(env));
        self
    }

    /// The same task, `hook(seed)` called before each seed's run (before its first checkpoint's
    /// evaluation and its first training episode), on the thread that runs the seed: where an
    /// environment with a random generator of its own reseeds (module docs).
    #[must_use]
    pub fn on_each_seed(mut self, hook: impl Fn(u64) + Send + Sync + 'static) -> Self {
        self.on_seed = Some(std::sync::Arc::new(hook));
        self
    }

    /// The same task, its seeds run one at a time on the calling thread (an environment that
    /// lives in one Python interpreter, or is not safe to step from two threads).
    #[must_use]
    pub fn one_seed_at_a_time(mut self) -> Self {
        self.max_threads = 1;
        self
    }

    /// The IL problem.
    pub fn problem(&self) -> &TaskProblem<EnvTask<E, F, X, f64>, P> {
        &self.problem
    }
}

impl<E, F, X, P> RunTask for EnvRun<E, F, X, P>
where
    E: Env<f64> + Sync,
    F: Sync,
    X: Sync,
    P: Greedy<f64> + Sync,
    EnvTask<E, F, X, f64>: Task<f64, Episode = EnvEpisode<E, E::Obs, f64>, Action = P::Action>,
    <EnvTask<E, F, X, f64> as Task<f64>>::Label: Borrow<P::Label>,
    TaskProblem<EnvTask<E, F, X, f64>, P>: IlProblem<f64> + PerDecisionTerms<f64> + Clone + Sync,
{
    type Problem = TaskProblem<EnvTask<E, F, X, f64>, P>;

    fn problem(&self) -> &Self::Problem {
        &self.problem
    }

    fn task_name(&self) -> &str {
        &self.name
    }

    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        Some(horizon_decisions(
            &self.problem.horizon,
            "(the task's steps)",
        ))
    }

    fn policy_name(&self) -> &str {
        &self.policy_name
    }

    fn max_threads(&self) -> usize {
        self.max_threads
    }

    fn seed_started(&self, seed: u64) {
        if let Some(hook) = &self.on_seed {
            hook(seed);
        }
    }

    fn evaluate(&self, theta: &[f64], episodes: u32, seed: u64) -> Result<Evaluation, String> {
        let policy = &self.problem.policy;
        let s = task_episodes(
            self.evaluation.as_ref().unwrap_or(&self.problem.task),
            &mut |_, phi, label| {
                let (l, _) = PolicyExt::<f64>::loss(policy, theta, phi, label.borrow())
                    .map_err(|e| e.to_string())?;
                Ok((policy.greedy(theta, phi).map_err(|e| e.to_string())?, l))
            },
            episodes,
            &|j| episode_seed(seed, j),
            Some(self.eval_steps),
            &mut |ep, _, s| s.reward += *ep.total_reward(),
        )?;
        Ok(Evaluation {
            score: Some(s.reward),
            reward: Some(s.reward),
            loss: Some(s.loss),
            ..Evaluation::default()
        })
    }
}
