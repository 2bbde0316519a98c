//! A config's built-in task with its learner ([`task_learner`]: the config's `[task]` and
//! `[policy]` parsed into the parameters of the kit's [`TaskLearner`]), and `ilopt run`'s
//! [`RunTask`] for each of its learners: CartPole with the softmax or logistic learner and the PPO
//! (or LQR) expert, the obstacle task with the linear-Gaussian learner, a toy MDP as its file
//! gives it. Evaluation episode j of a seed draws from [`episode_seed`]`(seed, j)`.

use super::config::{HorizonKind, LoadedConfig, PolicyKind, RunFile, TaskName};
use super::error::RunError;
use super::evaluation::{Evaluation, episode_seed};
use super::runnable::{RunTask, horizon_decisions};
use ilopt::baseline::PerDecisionTerms;
pub use ilopt::evaluate::builtin::TaskLearner;
use ilopt::evaluate::builtin::{
    BuildError, CartPoleLearner, CartPolePolicy, ObstacleLearner, ObstacleProblem, ToyLearner,
};
use ilopt::expert::ppo::PpoExpert;
use ilopt::policy::Greedy;
use ilopt::problem::IlProblem;
use ilopt::task::cartpole::{CartPoleExpert, CartPoleExpertChoice, CartPoleTask};
use ilopt::task::{Horizon, TaskProblem};
use ilopt::toy::{ToyMdp, ToyProblem};

/// Build the config's built-in task with its learner ([`TaskLearner`]).
///
/// # Errors
/// [`RunError::Task`] or [`RunError::Invalid`] if a file cannot be read or the task, expert or
/// policy cannot be built; [`RunError::Invalid`] for `task.name = "custom"`, which only a program
/// passing its own task can run.
pub fn task_learner(config: &LoadedConfig) -> Result<TaskLearner, RunError> {
    let f = &config.file;
    let task_err = |e: &dyn std::fmt::Display| RunError::Task(e.to_string());
    let built = |e: BuildError| match e {
        BuildError::Features(e) => config.invalid("policy.features", e),
        BuildError::Sigma(e) => config.invalid("policy.sigma", e),
        BuildError::Task(e) => RunError::Task(e),
    };
    let horizon = horizon(f);
    match f.task.name {
        TaskName::Cartpole => {
            let expert = match (f.task.expert.unwrap_or_default(), &f.task.expert_file) {
                (CartPoleExpertChoice::Ppo, Some(path)) => PpoExpert::load(path)
                    .map(CartPoleExpert::Ppo)
                    .map_err(|e| config.invalid("task.expert_file", e))?,
                (choice, _) => choice.expert().map_err(|e| task_err(&e))?,
            };
            let policy = match f.policy.kind.unwrap_or(PolicyKind::Softmax) {
                PolicyKind::Softmax => CartPolePolicy::Softmax,
                PolicyKind::Logistic => CartPolePolicy::Logistic,
            };
            TaskLearner::cartpole(expert, policy, horizon).map_err(built)
        }
        TaskName::Obstacle => TaskLearner::obstacle(
            f.policy.sigma.unwrap_or(super::config::DEFAULT_SIGMA),
            f.policy.features.unwrap_or_default(),
            horizon,
        )
        .map_err(built),
        TaskName::Toy => {
            let path = f
                .task
                .mdp
                .as_ref()
                .ok_or_else(|| config.invalid("task.mdp", "required for the toy task"))?;
            let mdp = ToyMdp::load(path)
                .map_err(|e| config.invalid("task.mdp", format!("{}: {e}", path.display())))?;
            Ok(TaskLearner::toy(&mdp))
        }
        TaskName::Custom => Err(config.invalid("task.name", CUSTOM_NEEDS_A_TASK)),
    }
}

impl<P> RunTask for CartPoleLearner<P>
where
    P: Greedy<f64, Action = usize, Label = usize> + Clone + Sync,
    TaskProblem<CartPoleTask<f64>, P>: IlProblem<f64> + PerDecisionTerms<f64>,
{
    type Problem = TaskProblem<CartPoleTask<f64>, P>;
    fn problem(&self) -> &Self::Problem {
        &self.problem
    }
    fn task_name(&self) -> &str {
        "cartpole"
    }
    fn policy_name(&self) -> &str {
        self.policy_name
    }
    fn evaluate(&self, theta: &[f64], episodes: u32, seed: u64) -> Result<Evaluation, String> {
        CartPoleLearner::evaluate(self, theta, episodes, &|j| episode_seed(seed, j))
    }
    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        Some(horizon_decisions(&self.problem.horizon, "task.steps"))
    }
}

impl RunTask for ObstacleLearner {
    type Problem = ObstacleProblem;
    fn problem(&self) -> &ObstacleProblem {
        &self.problem
    }
    fn task_name(&self) -> &str {
        "obstacle"
    }
    fn policy_name(&self) -> &str {
        "linear-gaussian"
    }
    fn evaluate(&self, theta: &[f64], episodes: u32, seed: u64) -> Result<Evaluation, String> {
        ObstacleLearner::evaluate(self, theta, episodes, &|j| episode_seed(seed, j))
    }
    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        Some(horizon_decisions(&self.problem.horizon, "task.steps"))
    }
}

impl RunTask for ToyLearner {
    type Problem = ToyProblem<f64>;
    fn problem(&self) -> &ToyProblem<f64> {
        &self.problem
    }
    fn task_name(&self) -> &str {
        "toy"
    }
    fn policy_name(&self) -> &str {
        "toy"
    }
    fn evaluate(&self, theta: &[f64], _episodes: u32, _seed: u64) -> Result<Evaluation, String> {
        ToyLearner::evaluate(self, theta)
    }
    /// T − 1 decisions without absorbing states; none certain with them (the first state may
    /// absorb).
    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        let mdp = self.problem.mdp();
        match mdp.termination {
            ilopt::toy::Termination::Absorb { .. } => None,
            _ => Some((
                mdp.horizon.saturating_sub(1) as u64,
                "(the MDP's horizon − 1)",
            )),
        }
    }
}

/// Why `ilopt run` refuses `task.name = "custom"`.
pub const CUSTOM_NEEDS_A_TASK: &str = "names no built-in task (cartpole, obstacle or toy): a \
     config without [task], or with name = \"custom\", is for a plug-in task, which only a program \
     passing its own task runs (Rust: ilopt_cli::run::run_task with an EnvRun; Python: \
     ilopt.run(config, task=ilopt.GymTask(...)))";

/// The config's objective (toy MDPs: their file's; the value here is unused).
pub fn horizon(f: &RunFile) -> Horizon {
    match (f.task.horizon, f.task.steps, f.task.after_end) {
        (Some(HorizonKind::Episodic), _, _) => Horizon::Episodic,
        (_, Some(steps), Some(after_end)) => Horizon::fixed(steps, after_end),
        _ => Horizon::Episodic,
    }
}
