//! The moving-obstacle task as an imitation-learning problem (thesis §4.1): the velocity-obstacle
//! expert (eq. 4.1) labels every visited state with the velocity it would command; the learner is
//! a linear-Gaussian policy (P3) over features φ(s) ([`ObstacleFeatures`]): by default the basic
//! φ(s) = (goal − agent, obstacle − agent, obstacle velocity, agent velocity, 1) ∈ ℝ⁹, or those
//! extended by radial basis functions of the obstacle's relative position
//! ([`ObstacleFeatures::Rbf`]), in which the expert's avoidance manoeuvre is (nearly) linear.
//! Actions are velocities; the environment clips them to the maximum speed.
//!
//! Actions and labels are `Vec<f64>` by default (the action type of
//! [`LinearGaussian<f64>`](crate::policy::LinearGaussian)); `ObstacleTask<[f64; 2]>` with
//! `LinearGaussian<f64, [f64; 2]>` ([`ObstacleTask::with_actions`],
//! [`LinearGaussian::with_actions`](crate::policy::LinearGaussian::with_actions)) stores them
//! inline, so that a roll-out allocates nothing per step. Both give the same numbers.

use super::Task;
use crate::env::hypot::hypot;
use crate::env::obstacle::{ObstacleConfig, ObstacleEnv, ObstacleObs, Outcome};
use crate::expert::vo_policy::{VoExpertParams, VoExpertPolicy};
use crate::policy::ActionVector;
use crate::problem::{KitRng, OracleError};
use std::marker::PhantomData;

/// Number of basic features ([`ObstacleFeatures::Basic`]).
pub const FEATURES: usize = 9;

/// The learner's features φ(s) (the thesis does not state them).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ObstacleFeatures {
    /// The 9 basic features of [`feature_array`].
    #[default]
    Basic,
    /// The basic features, the unit vector towards the goal (2), and for each centre `c` of a
    /// `per_axis × per_axis` grid over the obstacle's relative position `r = obstacle − agent`
    /// (x in `x_range`, y in `y_range`, both ends included) the bump
    /// `e_c = exp(−‖r − c‖²/(2·width²))` and its products with the obstacle's velocity
    /// `e_c·v_o/s` (`s` = the obstacle's maximum speed): `9 + 2 + 3·per_axis²` features. The
    /// avoidance manoeuvre depends on where the obstacle is relative to the agent and how it
    /// moves; the bumps make that dependence linear in θ, so the learner stays P3.
    Rbf {
        /// Centres per axis (≥ 2).
        per_axis: usize,
        /// Bump width (> 0, finite).
        width: f64,
        /// Range of the centres' x coordinate (lo < hi).
        x_range: [f64; 2],
        /// Range of the centres' y coordinate (lo < hi).
        y_range: [f64; 2],
    },
}

impl ObstacleFeatures {
    /// The RBF map with its default grid: 9 × 9 centres over x ∈ [−0.5, 2], y ∈ [−1, 1] (the
    /// obstacle ahead of the agent, where the expert deviates), width 0.2 (about half the grid
    /// spacing in x, 0.8 times that in y).
    pub fn rbf_default() -> Self {
        ObstacleFeatures::Rbf {
            per_axis: 9,
            width: 0.2,
            x_range: [-0.5, 2.0],
            y_range: [-1.0, 1.0],
        }
    }

    /// Number of features.
    pub fn dim(&self) -> usize {
        match self {
            ObstacleFeatures::Basic => FEATURES,
            ObstacleFeatures::Rbf { per_axis, .. } => FEATURES + 2 + 3 * per_axis * per_axis,
        }
    }

    /// Check the parameters.
    ///
    /// # Errors
    /// [`OracleError::Environment`] naming the bad parameter.
    pub fn validate(&self) -> Result<(), OracleError> {
        if let ObstacleFeatures::Rbf {
            per_axis,
            width,
            x_range,
            y_range,
        } = self
        {
            let bad = |m: &str| Err(OracleError::Environment(format!("RBF features: {m}")));
            if *per_axis < 2 || *per_axis > 64 {
                return bad(&format!("per_axis must lie in 2..=64, got {per_axis}"));
            }
            if !(width.is_finite() && *width > 0.0) {
                return bad(&format!("width must be finite and > 0, got {width}"));
            }
            for (name, r) in [("x_range", x_range), ("y_range", y_range)] {
                if !(r[0].is_finite() && r[1].is_finite() && r[0] < r[1]) {
                    return bad(&format!("{name} must be finite with lo < hi, got {r:?}"));
                }
            }
        }
        Ok(())
    }

    /// Append φ(s) to `out` (no allocation when `out` has the capacity).
    pub fn push(&self, obs: &ObstacleObs, goal: [f64; 2], obstacle_speed: f64, out: &mut Vec<f64>) {
        let basic = feature_array(obs, goal);
        out.extend_from_slice(&basic);
        if let ObstacleFeatures::Rbf {
            per_axis,
            width,
            x_range,
            y_range,
        } = *self
        {
            let (dx, dy) = (basic[0], basic[1]);
            let n = hypot(dx, dy);
            if n > 0.0 {
                out.extend_from_slice(&[dx / n, dy / n]);
            } else {
                out.extend_from_slice(&[0.0, 0.0]);
            }
            let (rx, ry) = (basic[2], basic[3]);
            let s = if obstacle_speed > 0.0 {
                obstacle_speed
            } else {
                1.0
            };
            let (vx, vy) = (obs.obstacle_vel[0] / s, obs.obstacle_vel[1] / s);
            let k = (per_axis - 1) as f64;
            let c = -1.0 / (2.0 * width * width);
            let centre =
                |range: [f64; 2], i: usize| range[0] + (range[1] - range[0]) * i as f64 / k;
            // The Gaussian is separable, exp(c(Δx² + Δy²)) = exp(cΔx²)·exp(cΔy²): 2n `exp`s
            // instead of n² (the y factors on the stack; a grid wider than the buffer takes the
            // two-dimensional form).
            let mut ey = [0.0f64; SEPARABLE_MAX];
            let separable = per_axis <= SEPARABLE_MAX;
            if separable {
                for (j, e) in ey.iter_mut().enumerate().take(per_axis) {
                    *e = (c * (ry - centre(y_range, j)).powi(2)).exp();
                }
            }
            for i in 0..per_axis {
                let cx = centre(x_range, i);
                let ex = (c * (rx - cx).powi(2)).exp();
                for j in 0..per_axis {
                    let e = if separable {
                        ex * ey[j]
                    } else {
                        (c * ((rx - cx).powi(2) + (ry - centre(y_range, j)).powi(2))).exp()
                    };
                    out.extend_from_slice(&[e, e * vx, e * vy]);
                }
            }
        }
    }
}

/// The widest RBF grid (centres per axis) whose features are computed in the separable form.
const SEPARABLE_MAX: usize = 64;

/// The obstacle task with its expert; actions and labels are stored as `A` (module docs).
#[derive(Debug, Clone)]
pub struct ObstacleTask<A = Vec<f64>> {
    env: ObstacleEnv,
    expert: VoExpertPolicy,
    goal: [f64; 2],
    features: ObstacleFeatures,
    obstacle_speed: f64,
    action_type: PhantomData<fn() -> A>,
}

/// One episode: the environment, its last observation and how its last step ended.
#[derive(Debug, Clone)]
pub struct ObstacleEpisode {
    env: ObstacleEnv,
    obs: ObstacleObs,
    outcome: Outcome,
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
        let obstacle_speed = config.obstacle_max_speed;
        Ok(Self {
            env: ObstacleEnv::new(config).map_err(env_err)?,
            expert,
            goal,
            features: ObstacleFeatures::Basic,
            obstacle_speed,
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
            features: self.features,
            obstacle_speed: self.obstacle_speed,
            action_type: PhantomData,
        }
    }

    /// The same task with the learner's features `features`.
    ///
    /// # Errors
    /// [`OracleError::Environment`] for invalid feature parameters.
    pub fn with_features(mut self, features: ObstacleFeatures) -> Result<Self, OracleError> {
        features.validate()?;
        self.features = features;
        Ok(self)
    }

    /// The learner's features.
    pub fn feature_map(&self) -> &ObstacleFeatures {
        &self.features
    }

    /// Number of features, [`ObstacleFeatures::dim`].
    pub fn feature_dim(&self) -> usize {
        self.features.dim()
    }

    /// φ(s) of an observation (as the roll-outs compute it).
    pub fn observation_features(&self, obs: &ObstacleObs) -> Vec<f64> {
        let mut v = Vec::with_capacity(self.features.dim());
        self.features
            .push(obs, self.goal, self.obstacle_speed, &mut v);
        v
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
        Ok(ObstacleEpisode {
            env,
            obs,
            outcome: Outcome::Running,
        })
    }

    fn features(&self, ep: &ObstacleEpisode) -> Vec<f64> {
        self.observation_features(&ep.obs)
    }

    fn push_features(&self, ep: &ObstacleEpisode, out: &mut Vec<f64>) {
        self.features
            .push(&ep.obs, self.goal, self.obstacle_speed, out);
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

    /// 0 per remaining step after reaching the goal; `(2 v_max)²` after a crash or a time-out,
    /// the supremum of the squared distance between two velocities of norm ≤ `v_max` (the
    /// speed-limited learner's loss and the clipped expert's).
    fn absorbing_loss(&self, ep: &ObstacleEpisode) -> Option<f64> {
        Some(match ep.outcome {
            Outcome::Success => 0.0,
            _ => (2.0 * self.env.config().agent_max_speed).powi(2),
        })
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
        ep.obs = s.observation;
        ep.outcome = s.outcome;
        Ok(s.terminated || s.truncated)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(r: [f64; 2], v_o: [f64; 2]) -> ObstacleObs {
        ObstacleObs {
            agent_pos: [-1.0, 0.25],
            agent_vel: [0.1, 0.0],
            obstacle_pos: [-1.0 + r[0], 0.25 + r[1]],
            obstacle_vel: v_o,
        }
    }

    #[test]
    fn basic_features_are_the_feature_array() {
        let o = obs([0.5, -0.2], [0.01, 0.0]);
        let mut v = Vec::new();
        ObstacleFeatures::Basic.push(&o, [2.5, 0.0], 0.02, &mut v);
        assert_eq!(v, feature_array(&o, [2.5, 0.0]).to_vec());
        assert_eq!(ObstacleFeatures::Basic.dim(), FEATURES);
    }

    #[test]
    fn rbf_features_put_a_unit_bump_on_the_obstacle_and_scale_it_by_its_velocity() {
        let f = ObstacleFeatures::Rbf {
            per_axis: 3,
            width: 0.5,
            x_range: [0.0, 2.0],
            y_range: [-1.0, 1.0],
        };
        // The obstacle exactly at the centre (1, −1) (i = 1, j = 0), moving at half its speed.
        let o = obs([1.0, -1.0], [0.01, -0.005]);
        let mut v = Vec::new();
        f.push(&o, [2.5, 0.0], 0.02, &mut v);
        assert_eq!(v.len(), f.dim());
        assert_eq!(f.dim(), 9 + 2 + 27);
        // Unit vector towards the goal: (3.5, −0.25)/‖·‖.
        let n = 3.5f64.hypot(0.25);
        assert_eq!(v[9..11], [3.5 / n, -0.25 / n]);
        let bump = |i: usize, j: usize| &v[11 + 3 * (3 * i + j)..11 + 3 * (3 * i + j) + 3];
        assert_eq!(bump(1, 0), [1.0, 0.5, -0.25]);
        // A neighbour at distance 1 (centre (1, 0)): e = exp(−1/(2·0.25)) = e⁻².
        let e = (-2.0f64).exp();
        let b = bump(1, 1);
        approx::assert_abs_diff_eq!(b[0], e, epsilon = 1e-15);
        approx::assert_abs_diff_eq!(b[1], 0.5 * e, epsilon = 1e-15);
        // The far corner (2, 1): distance √5, e = exp(−10).
        approx::assert_abs_diff_eq!(bump(2, 2)[0], (-10.0f64).exp(), epsilon = 1e-18);
    }

    /// The separable form against the two-dimensional Gaussian, on a grid that takes the
    /// separable path and one wider than its buffer (the two-dimensional path).
    #[test]
    fn separable_rbf_features_agree_with_the_two_dimensional_gaussian() {
        for per_axis in [9, SEPARABLE_MAX + 1] {
            let f = ObstacleFeatures::Rbf {
                per_axis,
                width: 0.2,
                x_range: [-0.5, 2.0],
                y_range: [-1.0, 1.0],
            };
            for (k, pos) in [[0.3, 0.1], [1.7, -0.9], [-0.4, 0.8], [5.0, 3.0]]
                .iter()
                .enumerate()
            {
                let o = obs(*pos, [0.01, 0.002 * k as f64]);
                let mut v = Vec::new();
                f.push(&o, [2.5, 0.0], 0.02, &mut v);
                let r = feature_array(&o, [2.5, 0.0]);
                let (rx, ry) = (r[2], r[3]);
                let step =
                    |lo: f64, hi: f64, i: usize| lo + (hi - lo) * i as f64 / (per_axis - 1) as f64;
                for i in 0..per_axis {
                    for j in 0..per_axis {
                        let (cx, cy) = (step(-0.5, 2.0, i), step(-1.0, 1.0, j));
                        let want = (-((rx - cx).powi(2) + (ry - cy).powi(2)) / 0.08).exp();
                        let got = v[FEATURES + 2 + 3 * (per_axis * i + j)];
                        assert!(
                            approx::abs_diff_eq!(got, want, epsilon = 1e-12 * want),
                            "per_axis {per_axis}, centre ({i}, {j}): {got:e} vs {want:e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn bad_rbf_parameters_are_named() {
        let base = ObstacleFeatures::rbf_default();
        let with = |f: &dyn Fn(&mut ObstacleFeatures)| {
            let mut x = base;
            f(&mut x);
            x.validate().unwrap_err().to_string()
        };
        let set = |p: usize, w: f64, xr: [f64; 2]| {
            move |x: &mut ObstacleFeatures| {
                if let ObstacleFeatures::Rbf {
                    per_axis,
                    width,
                    x_range,
                    ..
                } = x
                {
                    *per_axis = p;
                    *width = w;
                    *x_range = xr;
                }
            }
        };
        assert!(with(&set(1, 0.2, [0.0, 1.0])).contains("per_axis"));
        assert!(with(&set(9, 0.0, [0.0, 1.0])).contains("width"));
        assert!(with(&set(9, f64::NAN, [0.0, 1.0])).contains("width"));
        assert!(with(&set(9, 0.2, [1.0, 1.0])).contains("x_range"));
        assert!(base.validate().is_ok());
        let task = ObstacleTask::thesis().unwrap();
        assert!(
            task.with_features(ObstacleFeatures::Rbf {
                per_axis: 0,
                width: 0.2,
                x_range: [0.0, 1.0],
                y_range: [0.0, 1.0],
            })
            .is_err()
        );
    }

    #[test]
    fn roll_outs_store_the_chosen_features() {
        use crate::policy::LinearGaussian;
        use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem};
        use crate::task::TaskProblem;
        use rand::SeedableRng;
        let task = ObstacleTask::thesis()
            .unwrap()
            .with_features(ObstacleFeatures::rbf_default())
            .unwrap();
        let d = task.feature_dim();
        assert_eq!(d, 9 + 2 + 3 * 81);
        let mut p = TaskProblem {
            task,
            policy: LinearGaussian::new(2, d, 0.02).unwrap(),
            horizon: crate::task::Horizon::Episodic,
        };
        let theta = nalgebra::DVector::zeros(2 * d);
        let mut rng = KitRng::seed_from_u64(5);
        let mut cost = Cost::default();
        let t = p
            .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
            .unwrap();
        assert_eq!(t.feature_dim(), d);
        assert_eq!(t.feature(0).len(), d);
        let g = p
            .estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
            .unwrap();
        assert_eq!(g.len(), 2 * d);
        assert!(g.iter().all(|x| x.is_finite()));
    }
}
