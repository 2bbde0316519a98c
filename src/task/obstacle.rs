//! The moving-obstacle task as an imitation-learning problem (thesis §4.1): the velocity-obstacle
//! expert (eq. 4.1) labels every visited state with the velocity it would command; the learner is
//! a linear-Gaussian policy (P3) over
//! φ(s) = (goal − agent, obstacle − agent, obstacle velocity, agent velocity, 1) ∈ ℝ⁹.
//! Actions are velocities; the environment clips them to the maximum speed.

use super::Task;
use crate::env::obstacle::{
    ObstacleConfig, ObstacleEnv, ObstacleObs, VoExpertParams, VoExpertPolicy,
};
use crate::problem::{KitRng, OracleError};

/// Number of features.
pub const FEATURES: usize = 9;

/// The obstacle task with its expert.
#[derive(Debug, Clone)]
pub struct ObstacleTask {
    env: ObstacleEnv,
    expert: VoExpertPolicy,
    goal: [f64; 2],
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

/// φ(s) of the module docs.
pub fn features(obs: &ObstacleObs, goal: [f64; 2]) -> Vec<f64> {
    vec![
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

impl Task<f64> for ObstacleTask {
    type Episode = ObstacleEpisode;
    type Label = Vec<f64>;
    type Action = Vec<f64>;

    fn start(&self, rng: &mut KitRng) -> Result<ObstacleEpisode, OracleError> {
        let mut env = self.env.clone();
        let obs = env.reset(rng);
        Ok(ObstacleEpisode { env, obs })
    }

    fn features(&self, ep: &ObstacleEpisode) -> Vec<f64> {
        features(&ep.obs, self.goal)
    }

    fn expert(&self, ep: &ObstacleEpisode) -> Result<(Vec<f64>, Vec<f64>), OracleError> {
        let v = self
            .expert
            .act(&ep.obs)
            .map_err(|e| OracleError::Environment(e.to_string()))?;
        Ok((v.to_vec(), v.to_vec()))
    }

    fn advance(&self, ep: &mut ObstacleEpisode, action: &Vec<f64>) -> Result<bool, OracleError> {
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
