//! Bring your own environment: an [`Env`] (Gymnasium's reset/step), a feature map and an expert
//! become an imitation-learning problem (`EnvTask` + a policy + a horizon), and the kit's
//! algorithms run on it unchanged — here IS-STORM and DAgger (about 2·10⁵ gradient calls each),
//! then `ilopt::evaluate::objective` measures each learned policy (F̂ = 25 at θ = 0).
//!
//! ```text
//! cargo run --release --example custom_env
//! ```
//!
//! The environment is a corridor: the agent starts at x ∈ [−1, 1], steps 0.1 left (action 0) or
//! right (action 1), and crashes at |x| > 2. The expert walks towards x = 0. The learner is the
//! logistic policy over φ(x) = (x, 1); the objective is the thesis's fixed horizon, 50 decisions
//! per stream with a reset after a crash, the loss the Brier loss against the expert's action.

use ilopt::algo::{Runner, config::RunConfig};
use ilopt::env::{Env, EnvError, Step};
use ilopt::task::{AfterEnd, EnvTask, Horizon, TaskProblem};
use ilopt::{evaluate::objective, policy::Logistic, problem::KitRng};
use rand::Rng;

#[derive(Clone)]
struct Corridor(f64);

impl Env<f64> for Corridor {
    type Obs = f64;
    type Action = usize;
    fn reset(&mut self, rng: &mut KitRng) -> f64 {
        self.0 = rng.random_range(-1.0..1.0);
        self.0
    }
    fn step(&mut self, action: usize) -> Result<Step<f64, f64>, EnvError> {
        self.0 += if action == 1 { 0.1 } else { -0.1 };
        Ok(Step::new(self.0, 1.0, self.0.abs() > 2.0, false))
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let expert = |x: &f64| Ok::<_, String>(usize::from(*x < 0.0));
    let problem = TaskProblem {
        task: EnvTask::new(Corridor(0.0), |x: &f64| vec![*x, 1.0], expert),
        policy: Logistic::new(2)?,
        horizon: Horizon::fixed(50, AfterEnd::Reset),
    };
    for config in [IS_STORM, DAGGER] {
        let config: RunConfig = serde_json::from_str(config)?;
        let run = Runner::new(config.stop.clone())?.run_config(&config, &problem)?;
        let f = objective(&problem, &run.theta, 200, 1)?;
        let (mean, se) = (f.mean, f.standard_error);
        println!("θ = {:.3?}: F̂ = {mean:.2} ± {se:.2}", run.theta.as_slice());
    }
    Ok(())
}

const IS_STORM: &str = r#"{"theta0": [0, 0], "seed": 7, "stop": {"max_iterations": 2000},
  "algorithm": {"algorithm": "storm", "form": "causal", "correction": "per-decision",
                "schedule": {"kind": "constant", "eta": 0.002, "a": 0.5}}}"#;
const DAGGER: &str = r#"{"theta0": [0, 0], "seed": 7, "stop": {"max_iterations": 20},
  "algorithm": {"algorithm": "dagger", "trajectories_per_iteration": 1, "aggregate": true,
                "retrain": "warm-start", "beta": {"kind": "exponential", "p": 0.5},
                "inner": {"iterations": 20, "rule": {"rule": "adam", "alpha": 0.05,
                          "beta1": 0.9, "beta2": 0.999, "epsilon": 1e-8}}}}"#;
