//! A task with its learner, expert and evaluation ([`TaskLearner`]), and the reference policies
//! evaluated beside the learners ([`ReferencePolicy`]).

use super::{TaskKind, cartpole_max_steps};
use crate::config::{CartPoleExpertChoice, TaskSection};
use crate::error::Error;
use crate::stats::derive_seed;
use ilopt::env::cartpole::MAX_EPISODE_STEPS;
use ilopt::env::obstacle::ObstacleConfig;
use ilopt::evaluate::Evaluation;
use ilopt::evaluate::episodes::{ObstacleAct, TaskAct, cartpole_episodes, obstacle_episodes};
use ilopt::expert::vo_policy::{VoExpertParams, VoExpertPolicy};
use ilopt::policy::{Greedy, LinearGaussian, PolicyExt, Softmax, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError};
use ilopt::task::cartpole::{self, CartPoleExpert, CartPoleTask};
use ilopt::task::obstacle::{ObstacleFeatures, ObstacleTask};
use ilopt::task::{Horizon, Task, TaskProblem};
use nalgebra::DVector;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

/// A task with its learner, expert and evaluation settings.
// Two instances exist per run, so the size difference between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum TaskLearner {
    /// The obstacle task.
    Obstacle {
        /// The IL problem (velocities stored inline: no allocation per step).
        problem: ObstacleProblem,
        /// The environment configuration.
        env: ObstacleConfig,
        /// The expert (for the evaluation loss).
        expert: VoExpertPolicy,
    },
    /// CartPole.
    Cartpole {
        /// The IL problem.
        problem: TaskProblem<CartPoleTask<f64>, Softmax>,
        /// Which expert labels the states.
        expert: CartPoleExpertChoice,
    },
}

/// The obstacle task's IL problem: linear-Gaussian learner (P3) over the profile's features, with
/// the loss of the executed (speed-clipped) velocity ([`SpeedLimitedGaussian`]); velocities
/// stored inline as `[f64; 2]`.
pub type ObstacleProblem = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

/// A reference policy evaluated on the same episodes as the learners, without training: the
/// appendix's baseline rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferencePolicy {
    /// The task's expert (the velocity-obstacle expert; CartPole's PPO or LQR expert).
    Expert,
    /// Obstacle task: full speed straight at the goal, ignoring the obstacle,
    /// `v = v_max·(g − p)/‖g − p‖`.
    StraightToGoal,
}

impl ReferencePolicy {
    /// Its label in tables and figures.
    pub fn label(self, bench: &TaskLearner) -> String {
        match (self, bench) {
            (ReferencePolicy::Expert, TaskLearner::Obstacle { .. }) => "Expert (VO)".into(),
            (ReferencePolicy::Expert, TaskLearner::Cartpole { expert, .. }) => {
                format!("Expert ({})", expert.name())
            }
            (ReferencePolicy::StraightToGoal, _) => "Straight to goal".into(),
        }
    }

    /// The baselines of a task, in table order.
    pub fn of(kind: TaskKind) -> &'static [ReferencePolicy] {
        match kind {
            TaskKind::Obstacle => &[ReferencePolicy::Expert, ReferencePolicy::StraightToGoal],
            TaskKind::Cartpole => &[ReferencePolicy::Expert],
        }
    }
}

/// A CartPole policy for evaluation: (episode, φ(s), expert's action) ↦ (action, its loss).
type CartPoleAct<'a> = TaskAct<'a, CartPoleTask<f64>>;

impl TaskLearner {
    /// Build the task's bench.
    ///
    /// # Errors
    /// [`Error::Experiment`] if the environment, expert or policy cannot be built.
    pub fn new(kind: TaskKind, task: &TaskSection, horizon: Horizon) -> Result<Self, Error> {
        let e = |x: &dyn std::fmt::Display| Error::experiment(kind.name(), x);
        Ok(match kind {
            TaskKind::Obstacle => {
                let mut b = Self::obstacle(
                    task.sigma.unwrap_or(0.02),
                    task.features.unwrap_or_default(),
                )?;
                if let TaskLearner::Obstacle { problem, .. } = &mut b {
                    problem.horizon = horizon;
                }
                b
            }
            TaskKind::Cartpole => {
                let choice = task.expert.unwrap_or_default();
                let t = match choice {
                    CartPoleExpertChoice::Lqr => CartPoleTask::with_lqr(),
                    CartPoleExpertChoice::Ppo => CartPoleExpertChoice::ppo_expert()
                        .map_err(OracleError::Environment)
                        .and_then(|x| CartPoleTask::new(CartPoleExpert::Ppo(x), MAX_EPISODE_STEPS)),
                }
                .map_err(|x| e(&x))?;
                TaskLearner::Cartpole {
                    problem: TaskProblem {
                        task: t,
                        policy: Softmax::new(2, cartpole::FEATURES).map_err(|x| e(&x))?,
                        horizon,
                    },
                    expert: choice,
                }
            }
        })
    }

    /// The obstacle task's bench: the linear-Gaussian learner of standard deviation `sigma` over
    /// `features`, trained on the loss of the executed velocity.
    ///
    /// # Errors
    /// [`Error::Experiment`] if the environment, expert or policy cannot be built.
    pub fn obstacle(sigma: f64, features: ObstacleFeatures) -> Result<Self, Error> {
        let e = |x: &dyn std::fmt::Display| Error::experiment("obstacle", x);
        let env = ObstacleConfig::default();
        let params = VoExpertParams::default();
        let task = ObstacleTask::new(env.clone(), params)
            .and_then(|t| t.with_features(features))
            .map_err(|x| e(&x))?
            .with_actions::<[f64; 2]>();
        let inner = LinearGaussian::new(2, task.feature_dim(), sigma)
            .and_then(LinearGaussian::with_actions::<[f64; 2]>)
            .map_err(|x| e(&x))?;
        Ok(TaskLearner::Obstacle {
            problem: TaskProblem {
                policy: SpeedLimitedGaussian::new(inner, env.agent_max_speed).map_err(|x| e(&x))?,
                task,
                horizon: ilopt::task::Horizon::Episodic,
            },
            expert: VoExpertPolicy::new(&env, params).map_err(|x| e(&x))?,
            env,
        })
    }

    /// The objective of the bench's problem.
    pub fn horizon(&self) -> Horizon {
        match self {
            TaskLearner::Obstacle { problem, .. } => problem.horizon,
            TaskLearner::Cartpole { problem, .. } => problem.horizon,
        }
    }

    /// Fig. 4.9 as the thesis measures it (CartPole): the deterministic policy at θ plays
    /// seeded episodes, reset after every crash, until one completes the full 500 steps; the
    /// number of crashes before it, at most `cap` (= `cap`: none completed within the cap).
    pub(super) fn resets_to_full_episode(
        &self,
        theta: &[f64],
        cap: u32,
        key: &str,
    ) -> Result<Option<u32>, Error> {
        let TaskLearner::Cartpole { problem, .. } = self else {
            return Ok(None);
        };
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("Fig. 4.9 ({key})"), x);
        let task = &problem.task;
        for j in 0..cap {
            let mut rng = KitRng::seed_from_u64(derive_seed(&format!("{key}|full"), u64::from(j)));
            let mut ep = task.start(&mut rng).map_err(|x| err(&x))?;
            loop {
                let phi = task.features(&ep);
                let a = problem.policy.greedy(theta, &phi).map_err(|x| err(&x))?;
                if task.advance(&mut ep, &a).map_err(|x| err(&x))? {
                    break;
                }
            }
            if ep.steps >= cartpole_max_steps() {
                return Ok(Some(j));
            }
        }
        Ok(Some(cap))
    }

    /// Number of policy parameters.
    pub fn dim(&self) -> usize {
        match self {
            TaskLearner::Obstacle { problem, .. } => IlProblem::<f64>::dim(problem),
            TaskLearner::Cartpole { problem, .. } => IlProblem::<f64>::dim(problem),
        }
    }

    /// Evaluate the learner at θ (deterministic: the Gaussian mean, the most probable action).
    pub(super) fn evaluate(
        &self,
        theta: &[f64],
        episodes: u32,
        key: &str,
    ) -> Result<Evaluation, Error> {
        let err = |x: &dyn std::fmt::Display| x.to_string();
        match self {
            TaskLearner::Obstacle { problem, .. } => self.evaluate_obstacle(
                &mut |_, phi| {
                    let m = problem
                        .policy
                        .executed_mean(theta, phi)
                        .map_err(|x| err(&x))?;
                    Ok([m[0], m[1]])
                },
                episodes,
                key,
            ),
            TaskLearner::Cartpole { problem, .. } => self.evaluate_cartpole(
                &mut |_, phi, label| {
                    let (l, _) = PolicyExt::<f64>::loss(&problem.policy, theta, phi, label)
                        .map_err(|x| err(&x))?;
                    let a = problem.policy.greedy(theta, phi).map_err(|x| err(&x))?;
                    Ok((a, l))
                },
                episodes,
                key,
            ),
        }
    }

    /// Evaluate a baseline policy on the same episodes as the learners.
    pub(super) fn evaluate_baseline(
        &self,
        b: ReferencePolicy,
        episodes: u32,
        key: &str,
    ) -> Result<Evaluation, Error> {
        let err = |x: &dyn std::fmt::Display| x.to_string();
        match (self, b) {
            (TaskLearner::Obstacle { expert, .. }, ReferencePolicy::Expert) => self
                .evaluate_obstacle(
                    &mut |obs, _| expert.act(obs).map_err(|x| err(&x)),
                    episodes,
                    key,
                ),
            (TaskLearner::Obstacle { env, .. }, ReferencePolicy::StraightToGoal) => self
                .evaluate_obstacle(
                    &mut |obs, _| {
                        let d = [
                            env.goal[0] - obs.agent_pos[0],
                            env.goal[1] - obs.agent_pos[1],
                        ];
                        let n = d[0].hypot(d[1]);
                        Ok(if n > 0.0 {
                            let v = env.agent_max_speed / n;
                            [d[0] * v, d[1] * v]
                        } else {
                            [0.0, 0.0]
                        })
                    },
                    episodes,
                    key,
                ),
            (TaskLearner::Cartpole { .. }, ReferencePolicy::Expert) => {
                self.evaluate_cartpole(&mut |_, _, label| Ok((*label, 0.0)), episodes, key)
            }
            (TaskLearner::Cartpole { .. }, ReferencePolicy::StraightToGoal) => Err(
                Error::experiment(format!("baseline ({key})"), "CartPole has no goal"),
            ),
        }
    }

    /// Obstacle episodes driven by `act(observation, φ(s))` ([`obstacle_episodes`]).
    fn evaluate_obstacle(
        &self,
        act: &mut ObstacleAct<'_>,
        episodes: u32,
        key: &str,
    ) -> Result<Evaluation, Error> {
        let TaskLearner::Obstacle {
            env,
            expert,
            problem,
        } = self
        else {
            return Err(Error::experiment(key, "not the obstacle task"));
        };
        obstacle_episodes(
            env,
            &|obs| problem.task.observation_features(obs),
            expert,
            act,
            episodes,
            &|j| derive_seed(key, j),
        )
        .map(|s| Evaluation::obstacle(&s, episodes))
        .map_err(|x| Error::experiment(format!("evaluation ({key})"), x))
    }

    /// CartPole episodes driven by `act(episode, φ(s), expert's action) = (action, loss)`
    /// ([`cartpole_episodes`]); the loss is the learner's per-decision supervised loss (the expert's
    /// own is 0).
    fn evaluate_cartpole(
        &self,
        act: &mut CartPoleAct<'_>,
        episodes: u32,
        key: &str,
    ) -> Result<Evaluation, Error> {
        let TaskLearner::Cartpole { problem, .. } = self else {
            return Err(Error::experiment(key, "not CartPole"));
        };
        cartpole_episodes(&problem.task, act, episodes, &|j| derive_seed(key, j))
            .map(|s| Evaluation::cartpole(&s))
            .map_err(|x| Error::experiment(format!("evaluation ({key})"), x))
    }

    /// Norms of the x and y rows of the mean eq. 3.15 estimate over `n` learner roll-outs
    /// (obstacle task only).
    pub(super) fn gradient_xy(
        &self,
        theta: &DVector<f64>,
        n: u32,
        seed: u64,
    ) -> Result<Option<(f64, f64)>, Error> {
        let TaskLearner::Obstacle { problem, .. } = self else {
            return Ok(None);
        };
        if n == 0 {
            return Ok(None);
        }
        let g = mean_estimate(&mut problem.clone(), theta, u64::from(n), seed)?;
        Ok(Some(row_norms(&g)))
    }
}

fn row_norms(g: &DVector<f64>) -> (f64, f64) {
    let n = g.len() / 2;
    let x = g.rows(0, n).norm();
    let y = g.rows(n, n).norm();
    (x, y)
}

/// The mean of `n` eq. 3.15 estimates (causal form) at θ, roll-outs from one seeded RNG.
fn mean_estimate<P: IlProblem<f64>>(
    problem: &mut P,
    theta: &DVector<f64>,
    n: u64,
    seed: u64,
) -> Result<DVector<f64>, Error> {
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    let mut sum = DVector::zeros(theta.len());
    for _ in 0..n {
        let t = problem
            .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
            .map_err(|e| Error::experiment("gradient estimate", e))?;
        sum += problem
            .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
            .map_err(|e| Error::experiment("gradient estimate", e))?;
    }
    Ok(sum / n as f64)
}
