//! Building a config's task, expert, policy and objective into an IL problem ([`TaskLearner`]), with
//! the choices of the thesis's experiments: CartPole with the softmax learner over
//! φ(s) = (x, ẋ, θ, θ̇, 1) and the PPO expert, T = 500 with a reset after a crash; the obstacle
//! task with the linear-Gaussian learner, the loss of the executed (speed-clipped) velocity and
//! velocities stored inline, T = 200 with an absorbing end; a toy MDP as its file gives it.

use super::config::{ExpertChoice, HorizonKind, LoadedConfig, PolicyKind, RunFile, TaskName};
use super::error::RunError;
use super::evaluation::{Evaluation, evaluate_cartpole, evaluate_obstacle, evaluate_toy};
use super::runnable::{RunTask, horizon_decisions};
use ilopt::baseline::PerDecisionTerms;
use ilopt::env::cartpole::MAX_EPISODE_STEPS;
use ilopt::env::obstacle::ObstacleConfig;
use ilopt::expert::ppo::{PpoExpert, PpoExpertFile};
use ilopt::expert::vo_policy::{VoExpertParams, VoExpertPolicy};
use ilopt::policy::{Greedy, LinearGaussian, Logistic, Softmax, SpeedLimitedGaussian};
use ilopt::problem::IlProblem;
use ilopt::task::cartpole::{self, CartPoleExpert, CartPoleTask};
use ilopt::task::obstacle::ObstacleTask;
use ilopt::task::{Horizon, TaskProblem};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;

/// The committed PPO expert, built into the binary so that a run works from any directory.
pub const PPO_EXPERT: &str = include_str!("../../../experts/cartpole-ppo.json");

/// The obstacle task's IL problem: linear-Gaussian learner over the task's features, trained on
/// the loss of the executed (speed-clipped) velocity; velocities stored inline as `[f64; 2]`.
pub type ObstacleProblem = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

/// CartPole with a softmax or logistic learner ([`RunTask`]; its evaluation in
/// [`super::evaluation`]).
#[derive(Debug, Clone)]
pub struct CartPoleLearner<P> {
    /// The IL problem.
    pub problem: TaskProblem<CartPoleTask<f64>, P>,
    /// `"softmax"` or `"logistic"`.
    pub policy_name: &'static str,
}

/// The obstacle task ([`RunTask`]): the IL problem, and the environment and expert its evaluation
/// episodes need.
#[derive(Debug, Clone)]
pub struct ObstacleLearner {
    /// The IL problem.
    pub problem: ObstacleProblem,
    /// The environment's configuration (evaluation episodes).
    pub env: ObstacleConfig,
    /// The velocity-obstacle expert (evaluation loss).
    pub expert: VoExpertPolicy,
}

/// A toy MDP ([`RunTask`]; evaluated by its exact objective).
#[derive(Debug, Clone)]
pub struct ToyLearner(pub ToyProblem<f64>);

/// A config's built-in task as an IL problem, with what its evaluation needs.
// One instance per run: the size difference between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum TaskLearner {
    /// CartPole with the softmax learner.
    CartPoleSoftmax(CartPoleLearner<Softmax>),
    /// CartPole with the logistic learner.
    CartPoleLogistic(CartPoleLearner<Logistic>),
    /// The obstacle task.
    Obstacle(ObstacleLearner),
    /// A toy MDP.
    Toy(ToyLearner),
}

/// `$body` with `$t` bound to the [`RunTask`] inside a [`TaskLearner`] (one generic code path
/// for every built-in task).
macro_rules! with_learner {
    ($learner:expr, $t:ident => $body:expr) => {
        match $learner {
            $crate::run::task::TaskLearner::CartPoleSoftmax($t) => $body,
            $crate::run::task::TaskLearner::CartPoleLogistic($t) => $body,
            $crate::run::task::TaskLearner::Obstacle($t) => $body,
            $crate::run::task::TaskLearner::Toy($t) => $body,
        }
    };
}
pub(crate) use with_learner;

impl TaskLearner {
    /// Build the config's task.
    ///
    /// # Errors
    /// [`RunError::Task`] or [`RunError::Invalid`] if a file cannot be read or the task, expert
    /// or policy cannot be built; [`RunError::Invalid`] for `task.name = "custom"`, which only a
    /// program passing its own task can run.
    pub fn new(config: &LoadedConfig) -> Result<Self, RunError> {
        let f = &config.file;
        let task_err = |e: &dyn std::fmt::Display| RunError::Task(e.to_string());
        let horizon = horizon(f);
        Ok(match f.task.name {
            TaskName::Cartpole => {
                let expert = match (f.task.expert, &f.task.expert_file) {
                    (Some(ExpertChoice::Lqr), _) => CartPoleTask::with_lqr(),
                    (_, Some(path)) => PpoExpert::load(path)
                        .map_err(|e| config.invalid("task.expert_file", e))
                        .map(|e| CartPoleTask::new(CartPoleExpert::Ppo(e), MAX_EPISODE_STEPS))?,
                    (_, None) => {
                        let e = PpoExpertFile::parse(PPO_EXPERT, "experts/cartpole-ppo.json")
                            .and_then(|f| f.expert())
                            .map_err(|e| task_err(&e))?;
                        CartPoleTask::new(CartPoleExpert::Ppo(e), MAX_EPISODE_STEPS)
                    }
                }
                .map_err(|e| task_err(&e))?;
                match f.policy.kind.unwrap_or(PolicyKind::Softmax) {
                    PolicyKind::Softmax => TaskLearner::CartPoleSoftmax(CartPoleLearner {
                        problem: TaskProblem {
                            task: expert,
                            policy: Softmax::new(2, cartpole::FEATURES)
                                .map_err(|e| task_err(&e))?,
                            horizon,
                        },
                        policy_name: "softmax",
                    }),
                    PolicyKind::Logistic => TaskLearner::CartPoleLogistic(CartPoleLearner {
                        problem: TaskProblem {
                            task: expert,
                            policy: Logistic::new(cartpole::FEATURES).map_err(|e| task_err(&e))?,
                            horizon,
                        },
                        policy_name: "logistic",
                    }),
                }
            }
            TaskName::Obstacle => {
                let env = ObstacleConfig::default();
                let params = VoExpertParams::default();
                let task = ObstacleTask::new(env.clone(), params)
                    .and_then(|t| t.with_features(f.policy.features.unwrap_or_default()))
                    .map_err(|e| config.invalid("policy.features", e))?
                    .with_actions::<[f64; 2]>();
                let sigma = f.policy.sigma.unwrap_or(super::config::DEFAULT_SIGMA);
                let inner = LinearGaussian::new(2, task.feature_dim(), sigma)
                    .and_then(LinearGaussian::with_actions::<[f64; 2]>)
                    .map_err(|e| config.invalid("policy.sigma", e))?;
                TaskLearner::Obstacle(ObstacleLearner {
                    problem: TaskProblem {
                        policy: SpeedLimitedGaussian::new(inner, env.agent_max_speed)
                            .map_err(|e| task_err(&e))?,
                        task,
                        horizon,
                    },
                    expert: VoExpertPolicy::new(&env, params).map_err(|e| task_err(&e))?,
                    env,
                })
            }
            TaskName::Toy => {
                let path = f
                    .task
                    .mdp
                    .as_ref()
                    .ok_or_else(|| config.invalid("task.mdp", "required for the toy task"))?;
                let mdp = ToyMdp::load(path)
                    .map_err(|e| config.invalid("task.mdp", format!("{}: {e}", path.display())))?;
                TaskLearner::Toy(ToyLearner(ToyProblem::new(&mdp)))
            }
            TaskName::Custom => return Err(config.invalid("task.name", CUSTOM_NEEDS_A_TASK)),
        })
    }

    /// The number of policy parameters.
    pub fn dim(&self) -> usize {
        with_learner!(self, t => t.dim())
    }

    /// A short description of the policy (`"softmax"`, `"logistic"`, `"linear-gaussian"`,
    /// `"toy"`), recorded with a saved θ.
    pub fn policy_name(&self) -> &str {
        with_learner!(self, t => t.policy_name())
    }

    /// θ₀ of the config, checked against the policy's dimension.
    ///
    /// # Errors
    /// [`RunError::Invalid`] for `run.theta0` of the wrong length.
    pub fn theta0(&self, config: &LoadedConfig) -> Result<DVector<f64>, RunError> {
        with_learner!(self, t => super::runnable::theta0(t, config))
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
        evaluate_cartpole(&self.problem, theta, episodes, seed)
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
        evaluate_obstacle(
            &self.problem,
            &self.env,
            &self.expert,
            theta,
            episodes,
            seed,
        )
    }
    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        Some(horizon_decisions(&self.problem.horizon, "task.steps"))
    }
}

impl RunTask for ToyLearner {
    type Problem = ToyProblem<f64>;
    fn problem(&self) -> &ToyProblem<f64> {
        &self.0
    }
    fn task_name(&self) -> &str {
        "toy"
    }
    fn policy_name(&self) -> &str {
        "toy"
    }
    fn evaluate(&self, theta: &[f64], _episodes: u32, _seed: u64) -> Result<Evaluation, String> {
        evaluate_toy(&self.0, theta)
    }
    /// T − 1 decisions without absorbing states; none certain with them (the first state may
    /// absorb).
    fn least_decisions(&self) -> Option<(u64, &'static str)> {
        let mdp = self.0.mdp();
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
