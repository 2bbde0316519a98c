//! The two real tasks of check 6 under the thesis's fixed-horizon objectives: CartPole (softmax
//! learner, LQR expert) and the obstacle task (speed-limited linear-Gaussian learner,
//! velocity-obstacle expert), with the parameters the rows are evaluated at.

use ilopt::env::obstacle::ObstacleConfig;
use ilopt::policy::{LinearGaussian, Softmax, SpeedLimitedGaussian};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, TaskProblem};
use nalgebra::DVector;

/// The CartPole problem of the checks: softmax learner over the task's features, LQR expert, the
/// thesis's objective (T = 500 decisions, a reset after every crash).
///
/// # Errors
/// A message if the task cannot be built.
pub fn cartpole_fixed() -> Result<TaskProblem<CartPoleTask<f64>, Softmax>, String> {
    TaskProblem::fixed(
        CartPoleTask::with_lqr().map_err(|e| e.to_string())?,
        Softmax::new(2, cartpole::FEATURES).map_err(|e| e.to_string())?,
        500,
        AfterEnd::Reset,
    )
    .map_err(|e| e.to_string())
}

/// CartPole's θ: a partly competent learner (push right when the pole leans right).
pub fn cartpole_theta() -> DVector<f64> {
    DVector::from_vec(vec![0.0, 0.0, -2.0, -0.5, 0.0, 0.0, 0.0, 2.0, 0.5, 0.0])
}

/// The obstacle task's problem (the experiments' types).
pub use ilopt::evaluate::builtin::ObstacleProblem;

/// The obstacle problem of the checks: the experiments' learner (linear-Gaussian over the basic
/// features, σ = `sigma`, loss of the executed speed-clipped velocity), the velocity-obstacle
/// expert, and `horizon`.
///
/// # Errors
/// A message if the task cannot be built.
pub fn obstacle_problem(sigma: f64, horizon: Horizon) -> Result<ObstacleProblem, String> {
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let v_max = ObstacleConfig::default().agent_max_speed;
    let inner = LinearGaussian::new(2, obstacle::FEATURES, sigma)
        .and_then(LinearGaussian::with_actions::<[f64; 2]>)
        .map_err(|x| e(&x))?;
    Ok(TaskProblem {
        task: ObstacleTask::thesis()
            .map_err(|x| e(&x))?
            .with_actions::<[f64; 2]>(),
        policy: SpeedLimitedGaussian::new(inner, v_max).map_err(|x| e(&x))?,
        horizon,
    })
}

/// The obstacle task's θ: a proportional pull towards the goal, v = 0.05·(goal − agent) (the
/// θ of the experiments' gradient-error figure).
pub fn obstacle_theta() -> DVector<f64> {
    let mut theta = DVector::zeros(2 * obstacle::FEATURES);
    theta[0] = 0.05;
    theta[obstacle::FEATURES + 1] = 0.05;
    theta
}
