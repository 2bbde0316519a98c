//! The kit's built-in tasks paired with the learners of the thesis's experiments
//! ([`TaskLearner`]), shared by `ilopt run` and paper-checks: each crate parses its own
//! configuration into the plain parameters of the constructors here, trains on the variant's IL
//! problem and evaluates θ with [`TaskLearner::evaluate`].
//!
//! * CartPole ([`CartPoleLearner`]): the softmax learner (or the logistic one) over
//!   φ(s) = (x, ẋ, θ, θ̇, 1), labelled by the PPO or LQR expert, episodes truncated at 500 steps.
//! * The obstacle task ([`ObstacleLearner`]): the linear-Gaussian learner over the task's
//!   features, trained on the loss of the executed (speed-clipped) velocity, velocities stored
//!   inline as `[f64; 2]` (no allocation per step).
//! * A toy MDP ([`ToyLearner`]): the tabular problem its file defines, evaluated by its exact
//!   objective.
//!
//! The evaluation is the thesis's chapter 4: the policy acts deterministically (the softmax's most
//! probable action, the logistic policy's action of probability > ½, the executed linear-Gaussian
//! mean) on seeded episodes, and the per-decision supervised loss against the expert is tallied
//! on the visited states ([`crate::evaluate::episodes`]). Episode j starts from an RNG seeded by
//! `seed_of(j)`, a function the caller passes, so that every checkpoint of a run meets the same
//! episodes (common random numbers) under the caller's own seed derivation.

use super::Evaluation;
use super::episodes::{ObstacleAct, TaskAct, cartpole_episodes, obstacle_episodes};
use crate::env::cartpole::MAX_EPISODE_STEPS;
use crate::env::obstacle::ObstacleConfig;
use crate::expert::vo_policy::{VoExpertParams, VoExpertPolicy};
use crate::policy::{Greedy, LinearGaussian, Logistic, PolicyExt, Softmax, SpeedLimitedGaussian};
use crate::problem::IlProblem;
use crate::task::cartpole::{self, CartPoleExpert, CartPoleTask};
use crate::task::obstacle::{ObstacleFeatures, ObstacleTask};
use crate::task::{Horizon, TaskProblem};
use crate::toy::{ToyMdp, ToyProblem};

/// The obstacle task's IL problem: linear-Gaussian learner over the task's features, trained on
/// the loss of the executed (speed-clipped) velocity ([`SpeedLimitedGaussian`]); velocities
/// stored inline as `[f64; 2]`.
pub type ObstacleProblem = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

/// Why a built-in task and its learner cannot be built; the message is that of the failing
/// constructor, the variant says which parameter (if any) it concerns.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// The obstacle task's features cannot be used.
    #[error("{0}")]
    Features(String),
    /// The linear-Gaussian learner's standard deviation σ is invalid.
    #[error("{0}")]
    Sigma(String),
    /// The environment, the expert or the policy cannot be built.
    #[error("{0}")]
    Task(String),
}

/// CartPole's learner: the policy over φ(s) = (x, ẋ, θ, θ̇, 1) choosing between the two pushes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CartPolePolicy {
    /// [`Softmax`] over the two actions (2 × 5 parameters).
    Softmax,
    /// [`Logistic`]: the probability of pushing right (5 parameters).
    Logistic,
}

/// CartPole with a softmax or logistic learner `P`.
#[derive(Debug, Clone)]
pub struct CartPoleLearner<P> {
    /// The IL problem.
    pub problem: TaskProblem<CartPoleTask<f64>, P>,
    /// `"softmax"` or `"logistic"`.
    pub policy_name: &'static str,
}

/// The obstacle task: the IL problem, and the environment and expert its evaluation episodes
/// need.
#[derive(Debug, Clone)]
pub struct ObstacleLearner {
    /// The IL problem.
    pub problem: ObstacleProblem,
    /// The environment's configuration (evaluation episodes).
    pub env: ObstacleConfig,
    /// The velocity-obstacle expert (evaluation loss).
    pub expert: VoExpertPolicy,
}

/// A toy MDP as its file defines it (horizon, termination and loss included).
#[derive(Debug, Clone)]
pub struct ToyLearner {
    /// The IL problem.
    pub problem: ToyProblem<f64>,
}

/// A built-in task with its learner, its IL problem and its evaluation.
// One or two instances per run: the size difference between the variants costs nothing.
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

/// `$body` with `$t` bound to the learner inside a [`TaskLearner`]
/// ([`CartPoleLearner`], [`ObstacleLearner`] or [`ToyLearner`], each with its IL problem in
/// `$t.problem`): one generic code path for every built-in task.
#[macro_export]
macro_rules! with_task_learner {
    ($learner:expr, $t:ident => $body:expr) => {
        match $learner {
            $crate::evaluate::builtin::TaskLearner::CartPoleSoftmax($t) => $body,
            $crate::evaluate::builtin::TaskLearner::CartPoleLogistic($t) => $body,
            $crate::evaluate::builtin::TaskLearner::Obstacle($t) => $body,
            $crate::evaluate::builtin::TaskLearner::Toy($t) => $body,
        }
    };
}

impl TaskLearner {
    /// CartPole-v1 (500-step truncation) labelled by `expert`, with the `policy` learner over
    /// φ(s) = (x, ẋ, θ, θ̇, 1), on the objective `horizon`.
    ///
    /// # Errors
    /// [`BuildError::Task`] if the expert or the policy cannot be built.
    pub fn cartpole(
        expert: CartPoleExpert,
        policy: CartPolePolicy,
        horizon: Horizon,
    ) -> Result<Self, BuildError> {
        let task_err = |e: &dyn std::fmt::Display| BuildError::Task(e.to_string());
        let task = CartPoleTask::new(expert, MAX_EPISODE_STEPS).map_err(|e| task_err(&e))?;
        Ok(match policy {
            CartPolePolicy::Softmax => TaskLearner::CartPoleSoftmax(CartPoleLearner {
                problem: TaskProblem {
                    task,
                    policy: Softmax::new(2, cartpole::FEATURES).map_err(|e| task_err(&e))?,
                    horizon,
                },
                policy_name: "softmax",
            }),
            CartPolePolicy::Logistic => TaskLearner::CartPoleLogistic(CartPoleLearner {
                problem: TaskProblem {
                    task,
                    policy: Logistic::new(cartpole::FEATURES).map_err(|e| task_err(&e))?,
                    horizon,
                },
                policy_name: "logistic",
            }),
        })
    }

    /// The obstacle task with the default environment and velocity-obstacle expert, the
    /// linear-Gaussian learner of standard deviation `sigma` over `features`, trained on the loss
    /// of the executed velocity, on the objective `horizon`.
    ///
    /// # Errors
    /// [`BuildError::Features`] if the task rejects `features`, [`BuildError::Sigma`] if the
    /// learner rejects `sigma`, [`BuildError::Task`] if the speed limit or the expert cannot be
    /// built.
    pub fn obstacle(
        sigma: f64,
        features: ObstacleFeatures,
        horizon: Horizon,
    ) -> Result<Self, BuildError> {
        let env = ObstacleConfig::default();
        let params = VoExpertParams::default();
        let task = ObstacleTask::new(env.clone(), params)
            .and_then(|t| t.with_features(features))
            .map_err(|e| BuildError::Features(e.to_string()))?
            .with_actions::<[f64; 2]>();
        let inner = LinearGaussian::new(2, task.feature_dim(), sigma)
            .and_then(LinearGaussian::with_actions::<[f64; 2]>)
            .map_err(|e| BuildError::Sigma(e.to_string()))?;
        Ok(TaskLearner::Obstacle(ObstacleLearner {
            problem: TaskProblem {
                policy: SpeedLimitedGaussian::new(inner, env.agent_max_speed)
                    .map_err(|e| BuildError::Task(e.to_string()))?,
                task,
                horizon,
            },
            expert: VoExpertPolicy::new(&env, params)
                .map_err(|e| BuildError::Task(e.to_string()))?,
            env,
        }))
    }

    /// The toy MDP `mdp` (its own horizon, termination and loss).
    pub fn toy(mdp: &ToyMdp) -> Self {
        TaskLearner::Toy(ToyLearner {
            problem: ToyProblem::new(mdp),
        })
    }

    /// The task's name in the records: `"cartpole"`, `"obstacle"` or `"toy"`.
    pub fn task_name(&self) -> &'static str {
        match self {
            TaskLearner::CartPoleSoftmax(_) | TaskLearner::CartPoleLogistic(_) => "cartpole",
            TaskLearner::Obstacle(_) => "obstacle",
            TaskLearner::Toy(_) => "toy",
        }
    }

    /// The policy's name in the records: `"softmax"`, `"logistic"`, `"linear-gaussian"` or
    /// `"toy"`.
    pub fn policy_name(&self) -> &'static str {
        match self {
            TaskLearner::CartPoleSoftmax(l) => l.policy_name,
            TaskLearner::CartPoleLogistic(l) => l.policy_name,
            TaskLearner::Obstacle(_) => "linear-gaussian",
            TaskLearner::Toy(_) => "toy",
        }
    }

    /// The objective of the task's IL problem; `None` for a toy MDP (its file fixes its horizon
    /// and termination).
    pub fn horizon(&self) -> Option<Horizon> {
        match self {
            TaskLearner::CartPoleSoftmax(l) => Some(l.problem.horizon),
            TaskLearner::CartPoleLogistic(l) => Some(l.problem.horizon),
            TaskLearner::Obstacle(l) => Some(l.problem.horizon),
            TaskLearner::Toy(_) => None,
        }
    }

    /// The number of policy parameters.
    pub fn dim(&self) -> usize {
        with_task_learner!(self, t => IlProblem::<f64>::dim(&t.problem))
    }

    /// The deterministic evaluation of θ on `episodes` episodes, episode j seeded by `seed_of(j)`
    /// (a toy MDP: its exact objective, no episodes).
    ///
    /// # Errors
    /// A message if an episode, the expert or the policy fails.
    pub fn evaluate(
        &self,
        theta: &[f64],
        episodes: u32,
        seed_of: &dyn Fn(u64) -> u64,
    ) -> Result<Evaluation, String> {
        match self {
            TaskLearner::CartPoleSoftmax(l) => l.evaluate(theta, episodes, seed_of),
            TaskLearner::CartPoleLogistic(l) => l.evaluate(theta, episodes, seed_of),
            TaskLearner::Obstacle(l) => l.evaluate(theta, episodes, seed_of),
            TaskLearner::Toy(l) => l.evaluate(theta),
        }
    }
}

impl<P> CartPoleLearner<P> {
    /// CartPole episodes driven by `act(episode, φ(s), expert's action) = (action, its loss)`
    /// ([`cartpole_episodes`]): an episode that completes 500 steps is a success.
    ///
    /// # Errors
    /// The first error of `act`, the environment or the expert, as a message.
    pub fn episodes(
        &self,
        act: &mut TaskAct<'_, CartPoleTask<f64>>,
        episodes: u32,
        seed_of: &dyn Fn(u64) -> u64,
    ) -> Result<Evaluation, String> {
        cartpole_episodes(&self.problem.task, act, episodes, seed_of)
            .map(|s| Evaluation::cartpole(&s))
    }

    /// The learner's evaluation at θ: its deterministic action ([`Greedy`]) and its per-decision
    /// supervised loss against the expert's action on [`CartPoleLearner::episodes`].
    ///
    /// # Errors
    /// A message if an episode, the expert or the policy fails.
    pub fn evaluate(
        &self,
        theta: &[f64],
        episodes: u32,
        seed_of: &dyn Fn(u64) -> u64,
    ) -> Result<Evaluation, String>
    where
        P: Greedy<f64, Action = usize, Label = usize>,
    {
        let policy = &self.problem.policy;
        self.episodes(
            &mut |_, phi, label| {
                let (l, _) =
                    PolicyExt::<f64>::loss(policy, theta, phi, label).map_err(|e| e.to_string())?;
                Ok((policy.greedy(theta, phi).map_err(|e| e.to_string())?, l))
            },
            episodes,
            seed_of,
        )
    }
}

impl ObstacleLearner {
    /// Obstacle episodes driven by the velocity `act(observation, φ(observation))`
    /// ([`obstacle_episodes`], φ the learner's features): successes, crashes, time-outs and the
    /// loss against the expert's velocity.
    ///
    /// # Errors
    /// The first error of `act`, the environment or the expert, as a message.
    pub fn episodes(
        &self,
        act: &mut ObstacleAct<'_>,
        episodes: u32,
        seed_of: &dyn Fn(u64) -> u64,
    ) -> Result<Evaluation, String> {
        obstacle_episodes(
            &self.env,
            &|obs| self.problem.task.observation_features(obs),
            &self.expert,
            act,
            episodes,
            seed_of,
        )
        .map(|s| Evaluation::obstacle(&s, episodes))
    }

    /// The learner's evaluation at θ: the executed (speed-clipped) mean velocity on
    /// [`ObstacleLearner::episodes`].
    ///
    /// # Errors
    /// A message if an episode, the expert or the policy fails.
    pub fn evaluate(
        &self,
        theta: &[f64],
        episodes: u32,
        seed_of: &dyn Fn(u64) -> u64,
    ) -> Result<Evaluation, String> {
        let policy = &self.problem.policy;
        self.episodes(
            &mut |_, phi| {
                let m = policy
                    .executed_mean(theta, phi)
                    .map_err(|e| e.to_string())?;
                Ok([m[0], m[1]])
            },
            episodes,
            seed_of,
        )
    }
}

impl ToyLearner {
    /// The toy MDP's evaluation: its exact objective F(θ) (eq. 3.1, by the forward pass; no
    /// episodes).
    ///
    /// # Errors
    /// A message if the forward pass fails.
    pub fn evaluate(&self, theta: &[f64]) -> Result<Evaluation, String> {
        let f = crate::exact::forward::forward(&self.problem, theta).map_err(|e| e.to_string())?;
        Ok(Evaluation {
            objective: Some(f.objective),
            ..Evaluation::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed_of(j: u64) -> u64 {
        j * 7 + 1
    }

    /// The obstacle learner's evaluation is its episodes with the executed mean as the action, and
    /// the parameters' errors name the parameter.
    #[test]
    fn the_obstacle_evaluation_acts_with_the_executed_mean() {
        let b = TaskLearner::obstacle(0.1, ObstacleFeatures::default(), Horizon::Episodic).unwrap();
        let TaskLearner::Obstacle(o) = &b else {
            panic!("not the obstacle task: {b:?}");
        };
        assert_eq!(
            (b.task_name(), b.policy_name()),
            ("obstacle", "linear-gaussian")
        );
        let theta: Vec<f64> = (0..b.dim()).map(|i| 0.01 * i as f64).collect();
        let direct = o
            .episodes(
                &mut |_, phi| {
                    let m = o.problem.policy.executed_mean(&theta, phi).unwrap();
                    Ok([m[0], m[1]])
                },
                3,
                &seed_of,
            )
            .unwrap();
        assert_eq!(b.evaluate(&theta, 3, &seed_of).unwrap(), direct);
        assert_eq!(
            direct.successes.unwrap() + direct.crashes.unwrap() + direct.timeouts.unwrap(),
            3
        );
        assert!(matches!(
            TaskLearner::obstacle(-1.0, ObstacleFeatures::default(), Horizon::Episodic),
            Err(BuildError::Sigma(_))
        ));
        assert!(b.evaluate(&theta[1..], 1, &seed_of).is_err());
    }

    /// CartPole's evaluation: the greedy action with its Brier loss; the expert itself completes
    /// every episode; the logistic learner has 5 parameters.
    #[test]
    fn the_cartpole_evaluation_acts_greedily() {
        let expert = || {
            crate::expert::lqr::LqrExpert::cartpole()
                .map(|e| CartPoleExpert::Lqr(Box::new(e)))
                .unwrap()
        };
        let b =
            TaskLearner::cartpole(expert(), CartPolePolicy::Softmax, Horizon::Episodic).unwrap();
        let TaskLearner::CartPoleSoftmax(c) = &b else {
            panic!("not CartPole with softmax: {b:?}");
        };
        assert_eq!(b.dim(), 10);
        let ex = c
            .episodes(&mut |_, _, label| Ok((*label, 0.0)), 2, &seed_of)
            .unwrap();
        assert_eq!(
            (ex.successes, ex.crashes, ex.loss),
            (Some(2), Some(0), Some(0.0))
        );
        let zero = b.evaluate(&[0.0; 10], 2, &seed_of).unwrap();
        // At θ = 0 both actions have probability ½: the Brier loss is (½)² + (½)² at every state;
        // the greedy action (the first of equal logits) crashes every episode.
        assert_eq!(
            (zero.loss, zero.successes),
            (Some(0.5), Some(0)),
            "{zero:?}"
        );
        let l =
            TaskLearner::cartpole(expert(), CartPolePolicy::Logistic, Horizon::Episodic).unwrap();
        assert_eq!((l.dim(), l.policy_name()), (5, "logistic"));
    }
}
