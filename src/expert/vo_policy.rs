//! The velocity-obstacle expert policy of thesis §4.1.2 on the obstacle task
//! ([`crate::env::obstacle`]).
//!
//! [`VoExpertPolicy`] computes, from an observation, `r` = obstacle − agent, `v_o` = obstacle
//! velocity, `v_r` = agent velocity, `v_des = v_max·(g − p)/‖g − p‖` (eq. 4.1's third line), solves
//! eq. 4.1 globally with [`vo_expert_cone`] with `R = R_A + R_B + safety_margin`, and returns the
//! new velocity `v_r + u*` clipped to `v_max` like any action.

use crate::env::hypot::hypot;
use crate::env::obstacle::{ObstacleConfig, ObstacleError, ObstacleObs, clip, invalid};
use crate::expert::vo::{Cone, VoError, vo_expert_cone};
use serde::{Deserialize, Serialize};

/// Hyper-parameters of the velocity-obstacle expert policy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VoExpertParams {
    /// λ of eq. 4.1: the weight of the velocity change `‖u‖²` (choice: 0.5; the thesis does not
    /// state it). Must be ≥ 0.
    pub lam: f64,
    /// Added to `R = R_A + R_B` in the constraint (choice: 0.01), so that rounding and the
    /// discrete-time check never turn a grazing pass into a crash. Must be ≥ 0.
    pub safety_margin: f64,
    /// Which collision cone is excluded (choice: [`Cone::Double`], eq. 4.1 as written).
    pub cone: Cone,
}

impl Default for VoExpertParams {
    fn default() -> Self {
        Self {
            lam: 0.5,
            safety_margin: 0.01,
            cone: Cone::Double,
        }
    }
}

/// The expert policy of thesis §4.1.2: the new velocity `v_r + u*` with `u*` the global minimiser of
/// eq. 4.1, clipped to `v_max`.
///
/// When the agent is within `R = R_A + R_B + safety_margin` of the obstacle (eq. 4.1 then has no
/// feasible point) the expert moves straight away from the obstacle at full speed.
///
/// Clipping to `v_max` is not part of eq. 4.1: `‖v_r + u*‖` can exceed `v_max` (the projection is
/// taken from the obstacle's velocity `v_o`), and the rescaled velocity may re-enter the collision
/// cone slightly. The default `safety_margin` absorbs this (tests/environments/obstacle.rs: without it, 1000
/// seeded episodes show a few sub-`10⁻⁴` grazes, all after clipped steps).
#[derive(Debug, Clone, PartialEq)]
pub struct VoExpertPolicy {
    goal: [f64; 2],
    v_max: f64,
    big_r: f64,
    params: VoExpertParams,
}

impl VoExpertPolicy {
    /// The expert for a task.
    ///
    /// # Errors
    /// [`ObstacleError::InvalidConfig`] if the task is invalid, `lam` or `safety_margin` is negative
    /// or not finite.
    pub fn new(config: &ObstacleConfig, params: VoExpertParams) -> Result<Self, ObstacleError> {
        config.validate()?;
        if !(params.lam.is_finite() && params.lam >= 0.0) {
            return Err(invalid(
                "lam",
                format!("must be finite and ≥ 0, got {}", params.lam),
            ));
        }
        if !(params.safety_margin.is_finite() && params.safety_margin >= 0.0) {
            return Err(invalid(
                "safety_margin",
                format!("must be finite and ≥ 0, got {}", params.safety_margin),
            ));
        }
        Ok(Self {
            goal: config.goal,
            v_max: config.agent_max_speed,
            big_r: config.agent_radius + config.obstacle_radius + params.safety_margin,
            params,
        })
    }

    /// The expert's action for an observation: `clip(v_r + u*, v_max)` with `u*` solving eq. 4.1
    /// for `r = obstacle_pos − agent_pos`, `v_o = obstacle_vel`, `v_r = agent_vel`,
    /// `v_des = v_max·(goal − agent_pos)/‖goal − agent_pos‖` (zero at the goal), the policy's λ and
    /// `R = R_A + R_B + safety_margin`.
    ///
    /// # Errors
    /// [`VoError`] for a non-finite observation (an inside-the-obstacle state is not an error: the
    /// expert escapes, see the type's docs).
    pub fn act(&self, obs: &ObstacleObs) -> Result<[f64; 2], VoError> {
        let p = obs.agent_pos;
        let r = [obs.obstacle_pos[0] - p[0], obs.obstacle_pos[1] - p[1]];
        let g = [self.goal[0] - p[0], self.goal[1] - p[1]];
        let gn = hypot(g[0], g[1]);
        let v_des = if gn > 0.0 {
            [g[0] / gn * self.v_max, g[1] / gn * self.v_max]
        } else {
            [0.0; 2]
        };
        let v_r = obs.agent_vel;
        match vo_expert_cone(
            self.params.cone,
            r,
            obs.obstacle_vel,
            v_r,
            v_des,
            self.params.lam,
            self.big_r,
        ) {
            Ok(s) => Ok(clip([v_r[0] + s.u[0], v_r[1] + s.u[1]], self.v_max)),
            Err(VoError::InsideObstacle { .. }) => {
                let n = hypot(r[0], r[1]);
                Ok(if n > 0.0 {
                    [-r[0] / n * self.v_max, -r[1] / n * self.v_max]
                } else {
                    [-self.v_max, 0.0]
                })
            }
            Err(e) => Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::obstacle::{ObstacleEnv, Outcome};
    use crate::problem::KitRng;
    use rand::SeedableRng;

    #[test]
    fn expert_goes_straight_when_the_obstacle_is_out_of_the_way() {
        // Obstacle far below the path and not moving: the expert drives to the goal; with λ the
        // speed ramps up as (1 − (λ/(1+λ))^t)·v_max.
        let config = ObstacleConfig {
            obstacle_start_x: [0.0, 0.0],
            obstacle_start_y: [-3.0, -3.0],
            obstacle_step_x: [0.0, 0.0],
            obstacle_step_y: [0.0, 0.0],
            ..ObstacleConfig::default()
        };
        let mut env = ObstacleEnv::new(config.clone()).unwrap();
        let expert = VoExpertPolicy::new(&config, VoExpertParams::default()).unwrap();
        let mut obs = env.reset(&mut KitRng::seed_from_u64(4));
        let a = expert.act(&obs).unwrap();
        assert!(
            approx::abs_diff_eq!(a[0], 0.1 / 1.5, epsilon = 1e-15) && a[1] == 0.0,
            "{a:?}"
        );
        let mut outcome = Outcome::Running;
        while outcome == Outcome::Running {
            let s = env.step(expert.act(&obs).unwrap()).unwrap();
            obs = s.observation;
            outcome = s.outcome;
        }
        assert_eq!(outcome, Outcome::Success);
    }

    #[test]
    fn expert_escapes_when_too_close() {
        let config = ObstacleConfig::default();
        let expert = VoExpertPolicy::new(&config, VoExpertParams::default()).unwrap();
        let obs = ObstacleObs {
            agent_pos: [0.0, 0.0],
            agent_vel: [0.1, 0.0],
            // Distance 0.3 < R_A + R_B + margin = 0.46: escape along −r/‖r‖ = (−0.6, −0.8).
            obstacle_pos: [0.18, 0.24],
            obstacle_vel: [0.0, 0.0],
        };
        let a = expert.act(&obs).unwrap();
        assert!(
            approx::abs_diff_eq!(a[0], -0.06, epsilon = 1e-15)
                && approx::abs_diff_eq!(a[1], -0.08, epsilon = 1e-15),
            "{a:?}"
        );
    }

    #[test]
    fn expert_params_validated() {
        let c = ObstacleConfig::default();
        for params in [
            VoExpertParams {
                lam: -1.0,
                ..VoExpertParams::default()
            },
            VoExpertParams {
                safety_margin: f64::NAN,
                ..VoExpertParams::default()
            },
        ] {
            assert!(matches!(
                VoExpertPolicy::new(&c, params),
                Err(ObstacleError::InvalidConfig { .. })
            ));
        }
    }
}
