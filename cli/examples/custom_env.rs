//! Bring your own environment: an [`Env`] (Gymnasium's reset/step), a feature map and an expert
//! become a task of `ilopt run` ([`EnvRun`]), and [`run_task`] trains on it under the same config
//! schema as the built-in tasks — here IS-STORM and DAgger, 3 seeds each — writing the same files
//! (`seed-<n>.csv` with the checkpoints, `summary.json`, the saved θ) into
//! `target/custom-env/<algorithm>/`.
//!
//! ```text
//! cargo run --release -p ilopt-cli --example custom_env
//! ```
//!
//! The environment is a corridor: the agent starts at x ∈ [−1, 1], steps 0.1 left (action 0) or
//! right (action 1), and crashes at |x| > 2 (reward 1 per step survived). The expert walks
//! towards x = 0. The learner is the logistic policy over φ(x) = (x, 1); the objective is the
//! thesis's fixed horizon, 50 decisions per stream with a reset after a crash, the loss the Brier
//! loss against the expert's action. Evaluation episodes last at most 50 steps, so a policy that
//! never crashes scores 50.

use ilopt::env::{Env, EnvError, Step};
use ilopt::task::{AfterEnd, EnvTask, Horizon};
use ilopt::{policy::Logistic, problem::KitRng};
use ilopt_cli::run::{EnvRun, RunFile, RunOptions, run_task};
use rand::Rng;
use std::path::Path;

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
    let task = EnvRun::new(
        "corridor",
        "logistic",
        EnvTask::new(Corridor(0.0), |x: &f64| vec![*x, 1.0], expert),
        Logistic::new(2)?,
        Horizon::fixed(50, AfterEnd::Reset),
        50,
    )?;
    for (name, config) in [("is-storm", IS_STORM), ("dagger", DAGGER)] {
        let config = RunFile::parse(config, Path::new(name))?;
        let out = Path::new("target/custom-env").join(name);
        // A rerun replaces the example's own earlier outputs.
        let options = RunOptions {
            overwrite: true,
            quiet: true,
        };
        let summary = run_task(&task, &config, &out, None, options)?;
        let score = &summary["final_mean"]["score"];
        println!("{name}: final mean score {score} of 50 ({})", out.display());
    }
    Ok(())
}

const IS_STORM: &str = r#"
[algorithm]
algorithm = "storm"
form = "causal"
correction = "per-decision"
schedule = { kind = "constant", eta = 0.002, a = 0.5 }
[run]
budget_calls = 200000
seeds = [1, 2, 3]
[evaluation]
every_calls = 20000
"#;

const DAGGER: &str = r#"
[algorithm]
algorithm = "dagger"
trajectories_per_iteration = 1
aggregate = true
retrain = "warm-start"
beta = { kind = "exponential", p = 0.5 }
inner = { iterations = 20, rule = { rule = "adam", alpha = 0.05, beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8 } }
[run]
budget_calls = 20000
seeds = [1, 2, 3]
[evaluation]
every_calls = 2000
"#;
