//! Building a config's task, expert, policy and objective into an IL problem ([`TaskLearner`]), with
//! the choices of the thesis's experiments: CartPole with the softmax learner over
//! φ(s) = (x, ẋ, θ, θ̇, 1) and the PPO expert, T = 500 with a reset after a crash; the obstacle
//! task with the linear-Gaussian learner, the loss of the executed (speed-clipped) velocity and
//! velocities stored inline, T = 200 with an absorbing end; a toy MDP as its file gives it.

use super::config::{
    ExpertChoice, HorizonKind, LoadedConfig, PolicyKind, RunFile, TaskName, Theta0,
};
use super::error::RunError;
use ilopt::env::cartpole::MAX_EPISODE_STEPS;
use ilopt::env::obstacle::ObstacleConfig;
use ilopt::expert::ppo::{PpoExpert, PpoExpertFile};
use ilopt::expert::vo_policy::{VoExpertParams, VoExpertPolicy};
use ilopt::policy::{LinearGaussian, Logistic, Softmax, SpeedLimitedGaussian};
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

/// CartPole's IL problem with the softmax learner.
pub type CartPoleSoftmax = TaskProblem<CartPoleTask<f64>, Softmax>;

/// CartPole's IL problem with the logistic learner.
pub type CartPoleLogistic = TaskProblem<CartPoleTask<f64>, Logistic>;

/// A config's task as an IL problem, with what its evaluation needs.
// One instance per run: the size difference between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum TaskLearner {
    /// CartPole with the softmax learner.
    CartPoleSoftmax(CartPoleSoftmax),
    /// CartPole with the logistic learner.
    CartPoleLogistic(CartPoleLogistic),
    /// The obstacle task.
    Obstacle {
        /// The IL problem.
        problem: ObstacleProblem,
        /// The environment's configuration (evaluation episodes).
        env: ObstacleConfig,
        /// The velocity-obstacle expert (evaluation loss).
        expert: VoExpertPolicy,
    },
    /// A toy MDP.
    Toy(ToyProblem<f64>),
}

impl TaskLearner {
    /// Build the config's task.
    ///
    /// # Errors
    /// [`RunError::Task`] or [`RunError::Invalid`] if a file cannot be read or the task, expert
    /// or policy cannot be built.
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
                    PolicyKind::Softmax => TaskLearner::CartPoleSoftmax(TaskProblem {
                        task: expert,
                        policy: Softmax::new(2, cartpole::FEATURES).map_err(|e| task_err(&e))?,
                        horizon,
                    }),
                    PolicyKind::Logistic => TaskLearner::CartPoleLogistic(TaskProblem {
                        task: expert,
                        policy: Logistic::new(cartpole::FEATURES).map_err(|e| task_err(&e))?,
                        horizon,
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
                TaskLearner::Obstacle {
                    problem: TaskProblem {
                        policy: SpeedLimitedGaussian::new(inner, env.agent_max_speed)
                            .map_err(|e| task_err(&e))?,
                        task,
                        horizon,
                    },
                    expert: VoExpertPolicy::new(&env, params).map_err(|e| task_err(&e))?,
                    env,
                }
            }
            TaskName::Toy => {
                let path = f
                    .task
                    .mdp
                    .as_ref()
                    .ok_or_else(|| config.invalid("task.mdp", "required for the toy task"))?;
                let mdp = ToyMdp::load(path)
                    .map_err(|e| config.invalid("task.mdp", format!("{}: {e}", path.display())))?;
                TaskLearner::Toy(ToyProblem::new(&mdp))
            }
        })
    }

    /// The number of policy parameters.
    pub fn dim(&self) -> usize {
        match self {
            TaskLearner::CartPoleSoftmax(p) => IlProblem::<f64>::dim(p),
            TaskLearner::CartPoleLogistic(p) => IlProblem::<f64>::dim(p),
            TaskLearner::Obstacle { problem, .. } => IlProblem::<f64>::dim(problem),
            TaskLearner::Toy(p) => IlProblem::<f64>::dim(p),
        }
    }

    /// A short description of the policy (`"softmax"`, `"logistic"`, `"linear-gaussian"`,
    /// `"toy"`), recorded with a saved θ.
    pub fn policy_name(&self) -> &'static str {
        match self {
            TaskLearner::CartPoleSoftmax(_) => "softmax",
            TaskLearner::CartPoleLogistic(_) => "logistic",
            TaskLearner::Obstacle { .. } => "linear-gaussian",
            TaskLearner::Toy(_) => "toy",
        }
    }

    /// θ₀ of the config, checked against the policy's dimension.
    ///
    /// # Errors
    /// [`RunError::Invalid`] for `run.theta0` of the wrong length.
    pub fn theta0(&self, config: &LoadedConfig) -> Result<DVector<f64>, RunError> {
        let d = self.dim();
        match &config.file.run.theta0 {
            Theta0::Zero => Ok(DVector::zeros(d)),
            Theta0::Values(v) if v.len() == d => Ok(DVector::from_column_slice(v)),
            Theta0::Values(v) => Err(config.invalid(
                "run.theta0",
                format!(
                    "has {} entries, the {} policy has {d} parameters",
                    v.len(),
                    self.policy_name()
                ),
            )),
        }
    }
}

/// The config's objective (toy MDPs: their file's; the value here is unused).
pub fn horizon(f: &RunFile) -> Horizon {
    match (f.task.horizon, f.task.steps, f.task.after_end) {
        (Some(HorizonKind::Episodic), _, _) => Horizon::Episodic,
        (_, Some(steps), Some(after_end)) => Horizon::fixed(steps, after_end),
        _ => Horizon::Episodic,
    }
}
