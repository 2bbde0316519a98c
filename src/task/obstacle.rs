//! The moving-obstacle task as an imitation-learning problem (thesis §4.1): the velocity-obstacle
//! expert (eq. 4.1) labels every visited state with the velocity it would command; the learner is
//! a linear-Gaussian policy (P3) over
//! φ(s) = (goal − agent, obstacle − agent, obstacle velocity, agent velocity, 1) ∈ ℝ⁹.
//! Actions are velocities; the environment clips them to the maximum speed.
//!
//! Actions and labels are `Vec<f64>` by default (the action type of
//! [`LinearGaussian<f64>`](crate::policy::LinearGaussian)); `ObstacleTask<[f64; 2]>` with
//! `LinearGaussian<f64, [f64; 2]>` ([`ObstacleTask::with_actions`],
//! [`LinearGaussian::with_actions`](crate::policy::LinearGaussian::with_actions)) stores them
//! inline, so that a roll-out allocates nothing per step. Both give the same numbers.

use super::Task;
use crate::env::obstacle::{
    ObstacleConfig, ObstacleEnv, ObstacleObs, VoExpertParams, VoExpertPolicy,
};
use crate::policy::ActionVector;
use crate::problem::{KitRng, OracleError};
use std::marker::PhantomData;

/// Number of features.
pub const FEATURES: usize = 9;

/// The obstacle task with its expert; actions and labels are stored as `A` (module docs).
#[derive(Debug, Clone)]
pub struct ObstacleTask<A = Vec<f64>> {
    env: ObstacleEnv,
    expert: VoExpertPolicy,
    goal: [f64; 2],
    action_type: PhantomData<fn() -> A>,
}

/// One episode: the environment and its last observation.
#[derive(Debug, Clone)]
pub struct ObstacleEpisode {
    env: ObstacleEnv,
    obs: ObstacleObs,
}

impl ObstacleTask {
    /// The task with the given configuration and expert parameters.
    ///
    /// # Errors
    /// [`OracleError::Environment`] for an invalid configuration.
    pub fn new(config: ObstacleConfig, params: VoExpertParams) -> Result<Self, OracleError> {
        let env_err =
            |e: crate::env::obstacle::ObstacleError| OracleError::Environment(e.to_string());
        let expert = VoExpertPolicy::new(&config, params).map_err(env_err)?;
        let goal = config.goal;
        Ok(Self {
            env: ObstacleEnv::new(config).map_err(env_err)?,
            expert,
            goal,
            action_type: PhantomData,
        })
    }

    /// The thesis's defaults (`ObstacleConfig::default()`, `VoExpertParams::default()`).
    ///
    /// # Errors
    /// As [`ObstacleTask::new`].
    pub fn thesis() -> Result<Self, OracleError> {
        Self::new(ObstacleConfig::default(), VoExpertParams::default())
    }
}

impl<A> ObstacleTask<A> {
    /// The same task with actions and labels stored as `B` (e.g. `[f64; 2]`, inline).
    pub fn with_actions<B: ActionVector<f64>>(self) -> ObstacleTask<B> {
        ObstacleTask {
            env: self.env,
            expert: self.expert,
            goal: self.goal,
            action_type: PhantomData,
        }
    }
}

/// φ(s) of the module docs.
pub fn features(obs: &ObstacleObs, goal: [f64; 2]) -> Vec<f64> {
    feature_array(obs, goal).to_vec()
}

/// φ(s) of the module docs, on the stack.
pub fn feature_array(obs: &ObstacleObs, goal: [f64; 2]) -> [f64; FEATURES] {
    [
        goal[0] - obs.agent_pos[0],
        goal[1] - obs.agent_pos[1],
        obs.obstacle_pos[0] - obs.agent_pos[0],
        obs.obstacle_pos[1] - obs.agent_pos[1],
        obs.obstacle_vel[0],
        obs.obstacle_vel[1],
        obs.agent_vel[0],
        obs.agent_vel[1],
        1.0,
    ]
}

impl<A: ActionVector<f64>> Task<f64> for ObstacleTask<A> {
    type Episode = ObstacleEpisode;
    type Label = A;
    type Action = A;

    fn start(&self, rng: &mut KitRng) -> Result<ObstacleEpisode, OracleError> {
        let mut env = self.env.clone();
        let obs = env.reset(rng);
        Ok(ObstacleEpisode { env, obs })
    }

    fn features(&self, ep: &ObstacleEpisode) -> Vec<f64> {
        features(&ep.obs, self.goal)
    }

    fn push_features(&self, ep: &ObstacleEpisode, out: &mut Vec<f64>) {
        out.extend_from_slice(&feature_array(&ep.obs, self.goal));
    }

    fn max_episode_steps(&self) -> Option<usize> {
        Some(self.env.config().max_steps as usize)
    }

    fn expert(&self, ep: &ObstacleEpisode) -> Result<(A, A), OracleError> {
        let v = self
            .expert
            .act(&ep.obs)
            .map_err(|e| OracleError::Environment(e.to_string()))?;
        Ok((A::build(2, |i| v[i]), A::build(2, |i| v[i])))
    }

    fn advance(&self, ep: &mut ObstacleEpisode, action: &A) -> Result<bool, OracleError> {
        let action: &[f64] = action.borrow();
        if action.len() != 2 {
            return Err(OracleError::Environment(format!(
                "a velocity has 2 components, got {}",
                action.len()
            )));
        }
        let s = ep
            .env
            .step([action[0], action[1]])
            .map_err(|e| OracleError::Environment(e.to_string()))?;
        ep.obs = s.obs;
        Ok(s.terminated || s.truncated)
    }
}
