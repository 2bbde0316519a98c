//! The obstacle-avoidance task of thesis §4.1.1 as a Gymnasium-style environment.
//!
//! # The task
//!
//! A disc-shaped agent (radius `R_A` = 0.05) starts at rest at (−2.5, 0) and must reach the goal
//! (2.5, 0) while avoiding one moving disc-shaped obstacle (radius `R_B` = 0.4). Time is discrete and
//! speeds are per step (the thesis's "0.1 maximum velocity" and "0.02 metres per second" are read
//! with a unit time step).
//!
//! * **Action**: the agent's new velocity `a ∈ ℝ²`, *clipped* to the maximum speed: if
//!   `‖a‖ > v_max` it is rescaled to `v_max·a/‖a‖` (direction kept). The agent then moves by it.
//! * **Obstacle**: at [`ObstacleEnv::reset`] its centre is drawn uniformly from
//!   `obstacle_start_x × obstacle_start_y` (default [−0.5, 0.5]², the thesis's "between −0.5 and
//!   0.5") and its per-step displacement `(s_x, s_y)` uniformly from
//!   `obstacle_step_x × obstacle_step_y` (default [−0.02, 0.02]², the thesis's "predetermined
//!   range"); if `‖s‖` exceeds `obstacle_max_speed` (default 0.02, the thesis's obstacle speed) it
//!   is rescaled to it. Start and step vary "from instance to instance" (thesis), i.e. per episode;
//!   within an episode the obstacle moves with that constant step.
//! * **Step order**: clip the action, move the agent, move the obstacle, count the step, then decide
//!   the outcome in this priority: **crash** if the distance between the centres is
//!   `< R_A + R_B` (checked at the end of each step); else **success** if the agent's centre is
//!   within `goal_tolerance` (default 0.1 = one full step, so an agent driving at full speed at the
//!   goal cannot step over the tolerance disc) of the goal; else **time-out** if `max_steps`
//!   (default 200, four times the 50 steps of the straight path at full speed) steps have been
//!   taken; else running. Crash and success *terminate* the episode, time-out *truncates* it
//!   (Gymnasium semantics).
//! * **Reward** (the thesis does not use one; imitation learning needs none): progress towards the
//!   goal, `‖p_{t−1} − g‖ − ‖p_t − g‖`, plus `success_reward` on success and `crash_reward` on a
//!   crash.
//! * **Observation** ([`ObstacleObs`]): agent position and velocity, obstacle position and velocity
//!   (its constant per-step displacement) — what the expert of eq. 4.1 needs.
//!
//! Every parameter the thesis leaves open is a documented field of [`ObstacleConfig`], validated
//! by [`ObstacleConfig::validate`].

//!
//! The velocity-obstacle expert that labels this task's states is
//! [`crate::expert::vo_policy::VoExpertPolicy`].

use super::hypot::hypot;
use crate::problem::KitRng;
use rand::Rng;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Parameters of the obstacle-avoidance task (thesis §4.1.1). Defaults are the thesis's values
/// where it states them, and documented choices where it does not.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObstacleConfig {
    /// The agent's start position (thesis: (−2.5, 0)). The agent starts at rest.
    pub agent_start: [f64; 2],
    /// The goal position (thesis: (2.5, 0)).
    pub goal: [f64; 2],
    /// The agent's maximum speed per step, `v_max` (thesis: 0.1); actions are clipped to it.
    pub agent_max_speed: f64,
    /// The agent's radius `R_A` (thesis: 0.05).
    pub agent_radius: f64,
    /// The obstacle's radius `R_B` (thesis: 0.4).
    pub obstacle_radius: f64,
    /// The cap on the norm of the obstacle's per-step displacement (thesis: speed 0.02).
    pub obstacle_max_speed: f64,
    /// Range `[lo, hi]` of the obstacle's initial x coordinate (thesis: between −0.5 and 0.5).
    pub obstacle_start_x: [f64; 2],
    /// Range `[lo, hi]` of the obstacle's initial y coordinate (choice: the same as x).
    pub obstacle_start_y: [f64; 2],
    /// Range `[lo, hi]` of the obstacle's per-step x displacement (thesis: "a predetermined
    /// range"; choice: ±`obstacle_max_speed`).
    pub obstacle_step_x: [f64; 2],
    /// Range `[lo, hi]` of the obstacle's per-step y displacement (choice: as x).
    pub obstacle_step_y: [f64; 2],
    /// Success when the agent's centre is within this distance of the goal (choice: 0.1, one full
    /// step).
    pub goal_tolerance: f64,
    /// Time-out: the episode is truncated after this many steps (choice: 200).
    pub max_steps: u32,
    /// Reward added on the step that reaches the goal (choice: 1).
    pub success_reward: f64,
    /// Reward added on the step that crashes (choice: −1).
    pub crash_reward: f64,
}

impl Default for ObstacleConfig {
    fn default() -> Self {
        Self {
            agent_start: [-2.5, 0.0],
            goal: [2.5, 0.0],
            agent_max_speed: 0.1,
            agent_radius: 0.05,
            obstacle_radius: 0.4,
            obstacle_max_speed: 0.02,
            obstacle_start_x: [-0.5, 0.5],
            obstacle_start_y: [-0.5, 0.5],
            obstacle_step_x: [-0.02, 0.02],
            obstacle_step_y: [-0.02, 0.02],
            goal_tolerance: 0.1,
            max_steps: 200,
            success_reward: 1.0,
            crash_reward: -1.0,
        }
    }
}

pub(crate) fn invalid(field: &'static str, reason: impl Into<String>) -> ObstacleError {
    ObstacleError::InvalidConfig {
        field,
        reason: reason.into(),
    }
}

impl ObstacleConfig {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`ObstacleError::InvalidConfig`] naming the field when: a number is not finite; a speed,
    /// radius or the goal tolerance is not positive (the obstacle's maximum speed may be 0); a range
    /// has `lo > hi`; `max_steps` is 0; some possible obstacle start overlaps the agent's start
    /// (distance from `agent_start` to the start box `≤ R_A + R_B`); or the agent starts within
    /// `goal_tolerance` of the goal.
    pub fn validate(&self) -> Result<(), ObstacleError> {
        let vectors: [(&'static str, [f64; 2]); 7] = [
            ("agent_start", self.agent_start),
            ("goal", self.goal),
            ("obstacle_start_x", self.obstacle_start_x),
            ("obstacle_start_y", self.obstacle_start_y),
            ("obstacle_step_x", self.obstacle_step_x),
            ("obstacle_step_y", self.obstacle_step_y),
            (
                "success_reward/crash_reward",
                [self.success_reward, self.crash_reward],
            ),
        ];
        for (field, v) in vectors {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(invalid(field, format!("must be finite, got {v:?}")));
            }
        }
        let positives = [
            ("agent_max_speed", self.agent_max_speed),
            ("agent_radius", self.agent_radius),
            ("obstacle_radius", self.obstacle_radius),
            ("goal_tolerance", self.goal_tolerance),
        ];
        for (field, x) in positives {
            if !(x.is_finite() && x > 0.0) {
                return Err(invalid(field, format!("must be finite and > 0, got {x}")));
            }
        }
        if !(self.obstacle_max_speed.is_finite() && self.obstacle_max_speed >= 0.0) {
            return Err(invalid(
                "obstacle_max_speed",
                format!("must be finite and ≥ 0, got {}", self.obstacle_max_speed),
            ));
        }
        for (field, [lo, hi]) in [
            ("obstacle_start_x", self.obstacle_start_x),
            ("obstacle_start_y", self.obstacle_start_y),
            ("obstacle_step_x", self.obstacle_step_x),
            ("obstacle_step_y", self.obstacle_step_y),
        ] {
            if lo > hi {
                return Err(invalid(field, format!("range [{lo}, {hi}] has lo > hi")));
            }
        }
        if self.max_steps == 0 {
            return Err(invalid("max_steps", "must be ≥ 1"));
        }
        // Distance from the agent's start to the box of obstacle starts.
        let gap = |p: f64, [lo, hi]: [f64; 2]| (lo - p).max(p - hi).max(0.0);
        let dx = gap(self.agent_start[0], self.obstacle_start_x);
        let dy = gap(self.agent_start[1], self.obstacle_start_y);
        let radius = self.agent_radius + self.obstacle_radius;
        if hypot(dx, dy) <= radius {
            return Err(invalid(
                "agent_start",
                format!(
                    "an obstacle may start overlapping the agent: distance to the start box {} ≤ R_A + R_B = {radius}",
                    hypot(dx, dy)
                ),
            ));
        }
        if dist(self.agent_start, self.goal) <= self.goal_tolerance {
            return Err(invalid(
                "goal",
                "the agent starts within goal_tolerance of the goal",
            ));
        }
        Ok(())
    }

    /// Clips a velocity to the agent's maximum speed, keeping its direction.
    #[must_use]
    pub fn clip_speed(&self, a: [f64; 2]) -> [f64; 2] {
        clip(a, self.agent_max_speed)
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    hypot(a[0] - b[0], a[1] - b[1])
}

pub(crate) fn clip(a: [f64; 2], max: f64) -> [f64; 2] {
    let n = hypot(a[0], a[1]);
    if n > max {
        let s = max / n;
        [a[0] * s, a[1] * s]
    } else {
        a
    }
}

/// Errors of the obstacle task.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ObstacleError {
    /// A configuration parameter is invalid.
    #[error("invalid obstacle config `{field}`: {reason}")]
    InvalidConfig {
        /// The offending field.
        field: &'static str,
        /// Why.
        reason: String,
    },
    /// [`ObstacleEnv::step`] before the first [`ObstacleEnv::reset`].
    #[error("step called before reset")]
    NotReset,
    /// [`ObstacleEnv::step`] after the episode ended (terminated or truncated); call reset.
    #[error("step called after the episode ended ({0:?}); call reset")]
    EpisodeOver(Outcome),
    /// The action has a NaN or infinite component.
    #[error("non-finite action {0:?}")]
    NonFiniteAction([f64; 2]),
}

/// What the agent sees: enough for the expert of eq. 4.1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ObstacleObs {
    /// Agent centre.
    pub agent_pos: [f64; 2],
    /// Agent velocity (the last clipped action; zero at reset).
    pub agent_vel: [f64; 2],
    /// Obstacle centre.
    pub obstacle_pos: [f64; 2],
    /// Obstacle velocity (its constant per-step displacement).
    pub obstacle_vel: [f64; 2],
}

impl ObstacleObs {
    /// The observation as a flat vector
    /// `[p_x, p_y, v_x, v_y, o_x, o_y, w_x, w_y]` (agent position, agent velocity, obstacle
    /// position, obstacle velocity).
    #[must_use]
    pub fn to_array(&self) -> [f64; 8] {
        let (p, v, o, w) = (
            self.agent_pos,
            self.agent_vel,
            self.obstacle_pos,
            self.obstacle_vel,
        );
        [p[0], p[1], v[0], v[1], o[0], o[1], w[0], w[1]]
    }
}

/// The state of an episode after a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Outcome {
    /// Neither terminated nor truncated.
    Running,
    /// The agent's centre is within `goal_tolerance` of the goal (terminated).
    Success,
    /// The distance between the centres is `< R_A + R_B` (terminated).
    Crash,
    /// `max_steps` steps taken without success or crash (truncated).
    TimeOut,
}

/// The result of [`ObstacleEnv::step`] (Gymnasium's `(obs, reward, terminated, truncated)` plus the
/// outcome).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ObstacleStep {
    /// The observation after the step.
    pub observation: ObstacleObs,
    /// Progress towards the goal plus the success/crash reward (module docs).
    pub reward: f64,
    /// Success or crash.
    pub terminated: bool,
    /// Time-out.
    pub truncated: bool,
    /// The outcome of the step.
    pub outcome: Outcome,
}

#[derive(Debug, Clone, Copy)]
struct State {
    obs: ObstacleObs,
    steps: u32,
    outcome: Outcome,
}

/// The obstacle-avoidance environment (thesis §4.1.1; module docs for the dynamics).
#[derive(Debug, Clone)]
pub struct ObstacleEnv {
    config: ObstacleConfig,
    state: Option<State>,
}

impl ObstacleEnv {
    /// A new environment; call [`ObstacleEnv::reset`] before stepping.
    ///
    /// # Errors
    /// [`ObstacleError::InvalidConfig`] (see [`ObstacleConfig::validate`]).
    pub fn new(config: ObstacleConfig) -> Result<Self, ObstacleError> {
        config.validate()?;
        Ok(Self {
            config,
            state: None,
        })
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &ObstacleConfig {
        &self.config
    }

    /// Steps taken in the current episode.
    #[must_use]
    pub fn steps(&self) -> u32 {
        self.state.map_or(0, |s| s.steps)
    }

    /// Starts an episode: the agent at rest at `agent_start`, the obstacle's start and per-step
    /// displacement drawn from `rng` (module docs): one uniform draw per coordinate range with
    /// `lo < hi` (a degenerate range `lo = hi` is its value and draws nothing).
    pub fn reset(&mut self, rng: &mut KitRng) -> ObstacleObs {
        let c = &self.config;
        let draw = |rng: &mut KitRng, [lo, hi]: [f64; 2]| {
            if lo < hi {
                rng.random_range(lo..=hi)
            } else {
                lo
            }
        };
        let obstacle_pos = [draw(rng, c.obstacle_start_x), draw(rng, c.obstacle_start_y)];
        let step = [draw(rng, c.obstacle_step_x), draw(rng, c.obstacle_step_y)];
        let obs = ObstacleObs {
            agent_pos: c.agent_start,
            agent_vel: [0.0; 2],
            obstacle_pos,
            obstacle_vel: clip(step, c.obstacle_max_speed),
        };
        self.state = Some(State {
            obs,
            steps: 0,
            outcome: Outcome::Running,
        });
        obs
    }

    /// One step: the action (the agent's new velocity) is clipped to `agent_max_speed`, then agent
    /// and obstacle move and the outcome is decided (crash before success before time-out).
    ///
    /// # Errors
    /// [`ObstacleError::NotReset`], [`ObstacleError::EpisodeOver`],
    /// [`ObstacleError::NonFiniteAction`]; the state is unchanged on error.
    pub fn step(&mut self, action: [f64; 2]) -> Result<ObstacleStep, ObstacleError> {
        let c = &self.config;
        let state = self.state.as_mut().ok_or(ObstacleError::NotReset)?;
        if state.outcome != Outcome::Running {
            return Err(ObstacleError::EpisodeOver(state.outcome));
        }
        if !(action[0].is_finite() && action[1].is_finite()) {
            return Err(ObstacleError::NonFiniteAction(action));
        }
        let a = clip(action, c.agent_max_speed);
        let o = &mut state.obs;
        let before = dist(o.agent_pos, c.goal);
        o.agent_vel = a;
        o.agent_pos = [o.agent_pos[0] + a[0], o.agent_pos[1] + a[1]];
        o.obstacle_pos = [
            o.obstacle_pos[0] + o.obstacle_vel[0],
            o.obstacle_pos[1] + o.obstacle_vel[1],
        ];
        state.steps += 1;
        let after = dist(o.agent_pos, c.goal);
        let mut reward = before - after;
        state.outcome = if dist(o.agent_pos, o.obstacle_pos) < c.agent_radius + c.obstacle_radius {
            reward += c.crash_reward;
            Outcome::Crash
        } else if after <= c.goal_tolerance {
            reward += c.success_reward;
            Outcome::Success
        } else if state.steps >= c.max_steps {
            Outcome::TimeOut
        } else {
            Outcome::Running
        };
        Ok(ObstacleStep {
            observation: *o,
            reward,
            terminated: matches!(state.outcome, Outcome::Success | Outcome::Crash),
            truncated: state.outcome == Outcome::TimeOut,
            outcome: state.outcome,
        })
    }
}

impl super::Env<f64> for ObstacleEnv {
    type Obs = ObstacleObs;
    type Action = [f64; 2];

    fn reset(&mut self, rng: &mut KitRng) -> ObstacleObs {
        ObstacleEnv::reset(self, rng)
    }

    fn step(&mut self, action: [f64; 2]) -> Result<super::Step<f64, ObstacleObs>, super::EnvError> {
        use super::EnvError;
        let s = ObstacleEnv::step(self, action).map_err(|e| match e {
            ObstacleError::NotReset => EnvError::NotReset,
            ObstacleError::EpisodeOver(_) => EnvError::EpisodeOver,
            ObstacleError::NonFiniteAction(a) => EnvError::InvalidAction {
                action: format!("{a:?}"),
                expected: "a finite velocity [vx, vy]",
            },
            // Configurations are validated at construction; `step` never reports one.
            other => EnvError::InvalidAction {
                action: other.to_string(),
                expected: "a valid step",
            },
        })?;
        Ok(super::Step {
            observation: s.observation,
            reward: s.reward,
            terminated: s.terminated,
            truncated: s.truncated,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn default_is_valid_and_matches_thesis() {
        let c = ObstacleConfig::default();
        c.validate().unwrap();
        assert_eq!(c.agent_start, [-2.5, 0.0]);
        assert_eq!(c.goal, [2.5, 0.0]);
        assert_eq!((c.agent_max_speed, c.agent_radius), (0.1, 0.05));
        assert_eq!((c.obstacle_radius, c.obstacle_max_speed), (0.4, 0.02));
        assert_eq!(c.obstacle_start_x, [-0.5, 0.5]);
    }

    #[test]
    fn invalid_configs_are_rejected_with_their_field() {
        let field_of = |c: ObstacleConfig| match ObstacleEnv::new(c) {
            Err(ObstacleError::InvalidConfig { field, .. }) => field,
            other => panic!("expected InvalidConfig, got {other:?}"),
        };
        let d = ObstacleConfig::default;
        assert_eq!(
            field_of(ObstacleConfig {
                agent_max_speed: 0.0,
                ..d()
            }),
            "agent_max_speed"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                agent_radius: f64::NAN,
                ..d()
            }),
            "agent_radius"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                obstacle_max_speed: -0.1,
                ..d()
            }),
            "obstacle_max_speed"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                obstacle_step_x: [0.1, -0.1],
                ..d()
            }),
            "obstacle_step_x"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                goal: [f64::INFINITY, 0.0],
                ..d()
            }),
            "goal"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                max_steps: 0,
                ..d()
            }),
            "max_steps"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                obstacle_start_x: [-2.2, 0.5],
                ..d()
            }),
            "agent_start"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                goal: [-2.45, 0.0],
                ..d()
            }),
            "goal"
        );
        assert_eq!(
            field_of(ObstacleConfig {
                goal_tolerance: 0.0,
                ..d()
            }),
            "goal_tolerance"
        );
    }

    #[test]
    fn config_serde_round_trip_and_defaults() {
        let c = ObstacleConfig {
            max_steps: 17,
            ..ObstacleConfig::default()
        };
        let s = serde_json::to_string(&c).unwrap();
        assert_eq!(serde_json::from_str::<ObstacleConfig>(&s).unwrap(), c);
        let partial: ObstacleConfig = serde_json::from_str(r#"{"max_steps": 5}"#).unwrap();
        assert_eq!(partial.max_steps, 5);
        assert_eq!(partial.goal, [2.5, 0.0]);
        assert!(serde_json::from_str::<ObstacleConfig>(r#"{"max_stepz": 5}"#).is_err());
    }

    #[test]
    fn step_errors_and_clipping() {
        let mut env = ObstacleEnv::new(ObstacleConfig::default()).unwrap();
        assert_eq!(env.step([0.1, 0.0]), Err(ObstacleError::NotReset));
        let mut rng = KitRng::seed_from_u64(1);
        let obs0 = env.reset(&mut rng);
        assert_eq!(obs0.agent_pos, [-2.5, 0.0]);
        assert!(obs0.obstacle_vel[0].hypot(obs0.obstacle_vel[1]) <= 0.02 + 1e-17);
        assert!(matches!(
            env.step([f64::NAN, 0.0]),
            Err(ObstacleError::NonFiniteAction(_))
        ));
        assert_eq!(env.steps(), 0);
        // (3, 4) is clipped to speed 0.1 along the same direction: (0.06, 0.08).
        let s = env.step([3.0, 4.0]).unwrap();
        approx::assert_abs_diff_eq!(s.observation.agent_vel[0], 0.06, epsilon = 1e-15);
        approx::assert_abs_diff_eq!(s.observation.agent_vel[1], 0.08, epsilon = 1e-15);
        approx::assert_abs_diff_eq!(s.observation.agent_pos[0], -2.44, epsilon = 1e-15);
        assert_eq!(s.outcome, Outcome::Running);
        // The obstacle moved by its step.
        assert_eq!(
            s.observation.obstacle_pos,
            [
                obs0.obstacle_pos[0] + obs0.obstacle_vel[0],
                obs0.obstacle_pos[1] + obs0.obstacle_vel[1]
            ]
        );
    }

    #[test]
    fn timeout_when_standing_still() {
        let config = ObstacleConfig {
            max_steps: 3,
            ..ObstacleConfig::default()
        };
        let mut env = ObstacleEnv::new(config).unwrap();
        env.reset(&mut KitRng::seed_from_u64(2));
        for _ in 0..2 {
            let s = env.step([0.0, 0.0]).unwrap();
            assert!(!s.terminated && !s.truncated);
        }
        let s = env.step([0.0, 0.0]).unwrap();
        assert_eq!(s.outcome, Outcome::TimeOut);
        assert!(s.truncated && !s.terminated);
        assert_eq!(
            env.step([0.0, 0.0]),
            Err(ObstacleError::EpisodeOver(Outcome::TimeOut))
        );
    }

    #[test]
    fn driving_straight_into_a_still_obstacle_crashes() {
        let config = ObstacleConfig {
            obstacle_start_x: [0.0, 0.0],
            obstacle_start_y: [0.0, 0.0],
            obstacle_step_x: [0.0, 0.0],
            obstacle_step_y: [0.0, 0.0],
            ..ObstacleConfig::default()
        };
        let mut env = ObstacleEnv::new(config).unwrap();
        env.reset(&mut KitRng::seed_from_u64(3));
        // Crash when x > −0.45, i.e. after 21 steps of 0.1 from −2.5 (x = −0.4).
        let mut last = None;
        for _ in 0..30 {
            let s = env.step([1.0, 0.0]).unwrap();
            last = Some(s);
            if s.terminated {
                break;
            }
        }
        let s = last.unwrap();
        assert_eq!(s.outcome, Outcome::Crash);
        assert_eq!(env.steps(), 21);
        assert!(s.reward < 0.0);
    }
}
