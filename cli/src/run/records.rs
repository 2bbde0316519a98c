//! What a run records: its checkpoints ([`Checkpoint`]), its deterministic result ([`SeedRun`]),
//! its wall times ([`SeedTiming`], kept apart so that every other file is byte-identical across
//! reruns) and its final θ ([`SavedTheta`], what `ilopt eval` loads).

use super::evaluation::Evaluation;
use ilopt::problem::Cost;
use serde::{Deserialize, Serialize};

/// One checkpoint of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The nominal call count (0, `every_calls`, …, the budget); the checkpoint is the first
    /// iterate whose cumulative gradient calls reach it.
    pub at_calls: u64,
    /// The iteration (0 = θ₀).
    pub iteration: u64,
    /// Cumulative per-state gradient evaluations ("gradient calls").
    pub gradient_evaluations: u64,
    /// Cumulative trajectories rolled out.
    pub trajectories: u64,
    /// Cumulative environment steps.
    pub env_steps: u64,
    /// Cumulative expert queries.
    pub expert_queries: u64,
    /// The last step's training-loss estimate (the sampled trajectory's loss, or the dataset
    /// loss).
    pub train_loss: Option<f64>,
    /// ‖the last step's direction‖ (the oracle estimate, STORM's d, …); none for dataset
    /// learners.
    pub gradient_norm: Option<f64>,
    /// CartPole: mean reward / 500; obstacle: success rate.
    pub score: Option<f64>,
    /// Mean evaluation episode reward.
    pub reward: Option<f64>,
    /// Evaluation episodes that succeeded (obstacle: goal; CartPole: 500 steps).
    pub successes: Option<u32>,
    /// Evaluation episodes that crashed.
    pub crashes: Option<u32>,
    /// Evaluation episodes that timed out (obstacle).
    pub timeouts: Option<u32>,
    /// Mean per-decision supervised loss on the evaluation states.
    pub eval_loss: Option<f64>,
    /// Toy: the exact objective F(θ).
    pub objective: Option<f64>,
}

impl Checkpoint {
    /// A checkpoint from the run's state and an evaluation.
    pub fn new(
        at_calls: u64,
        iteration: u64,
        cost: &Cost,
        train_loss: Option<f64>,
        gradient_norm: Option<f64>,
        ev: &Evaluation,
    ) -> Self {
        Checkpoint {
            at_calls,
            iteration,
            gradient_evaluations: cost.gradient_evaluations,
            trajectories: cost.trajectories,
            env_steps: cost.env_steps,
            expert_queries: cost.expert_queries,
            train_loss,
            gradient_norm,
            score: ev.score,
            reward: ev.reward,
            successes: ev.successes,
            crashes: ev.crashes,
            timeouts: ev.timeouts,
            eval_loss: ev.loss,
            objective: ev.objective,
        }
    }

    /// The CSV header of [`Checkpoint::csv_row`].
    pub const CSV_HEADER: &'static str = "at_calls,iteration,gradient_evaluations,trajectories,env_steps,expert_queries,train_loss,gradient_norm,score,reward,successes,crashes,timeouts,eval_loss,objective";

    /// The checkpoint as one CSV row (an empty cell for a missing value; floats in Rust's
    /// shortest round-trip form, so the text is a function of the values).
    pub fn csv_row(&self) -> String {
        fn f(x: Option<f64>) -> String {
            x.map_or_else(String::new, |v| v.to_string())
        }
        fn u(x: Option<u32>) -> String {
            x.map_or_else(String::new, |v| v.to_string())
        }
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            self.at_calls,
            self.iteration,
            self.gradient_evaluations,
            self.trajectories,
            self.env_steps,
            self.expert_queries,
            f(self.train_loss),
            f(self.gradient_norm),
            f(self.score),
            f(self.reward),
            u(self.successes),
            u(self.crashes),
            u(self.timeouts),
            f(self.eval_loss),
            f(self.objective),
        )
    }
}

/// One seed's run (deterministic: a function of the config and the seed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedRun {
    /// The seed.
    pub seed: u64,
    /// The algorithm's name.
    pub algorithm: String,
    /// Why the run ended: `gradient-budget`, `finished` (the algorithm's own schedule) or
    /// `diverged: …` (a failing step, a non-finite θ, or `‖θ‖ = 3.200e5 > 1e4` when ‖θ‖₂
    /// exceeds `run.norm_bound`; the checkpoints reached are kept).
    pub termination: String,
    /// Iterations taken.
    pub iterations: u64,
    /// The total cost.
    pub cost: Cost,
    /// The final θ.
    pub theta: Vec<f64>,
    /// The checkpoints.
    pub checkpoints: Vec<Checkpoint>,
}

/// One seed's wall times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedTiming {
    /// The seed.
    pub seed: u64,
    /// Training time in seconds (evaluations excluded).
    pub train_seconds: f64,
    /// Evaluation time in seconds.
    pub evaluation_seconds: f64,
    /// Training time up to each checkpoint.
    pub checkpoint_seconds: Vec<f64>,
}

/// A saved policy parameter: `theta-seed-<n>.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedTheta {
    /// The task (`cartpole`, `obstacle`, `toy`).
    pub task: String,
    /// The policy (`softmax`, `logistic`, `linear-gaussian`, `toy`).
    pub policy: String,
    /// The seed of the run that produced it.
    pub seed: u64,
    /// θ.
    pub theta: Vec<f64>,
}
