//! What a seeded run records, for `ilopt run` and paper-checks alike: its checkpoints
//! ([`Checkpoint`], each with the [`Evaluation`] of its iterate), its deterministic result ([`SeedRun`], with how it ended as a
//! [`RecordedTermination`]) and its wall times ([`SeedTiming`], kept apart so that every other
//! file is byte-identical across reruns).
//!
//! The fields only the appendix fills (the obstacle task's loss and gradient rows, Fig. 4.9's
//! resets, a seed's index, the run's status and hyper-parameters) are left out of the JSON when
//! absent, so `ilopt run`'s files carry only what it records.

use super::observer::IterationMetrics;
use super::termination::RecordedTermination;
use crate::problem::Cost;
use serde::{Deserialize, Serialize};

/// What one evaluation of an iterate gives (formed from a task's evaluation episodes in
/// [`crate::evaluate`]; a toy MDP's is its exact objective).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Evaluation {
    /// CartPole: mean reward / 500; obstacle: success rate; toy: none.
    pub score: Option<f64>,
    /// Mean episode reward (CartPole, obstacle).
    pub reward: Option<f64>,
    /// Episodes that reached the goal (obstacle) or completed 500 steps (CartPole).
    pub successes: Option<u32>,
    /// Crashed episodes (CartPole: ended before 500 steps).
    pub crashes: Option<u32>,
    /// Timed-out episodes (obstacle).
    pub timeouts: Option<u32>,
    /// Mean per-decision supervised loss against the expert on the visited states.
    pub loss: Option<f64>,
    /// The obstacle task: the loss's x and y parts (their sum is `loss`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loss_xy: Option<(f64, f64)>,
    /// Toy: the exact objective F(θ).
    pub objective: Option<f64>,
}

/// One checkpoint of a run: the run's state at the first iterate whose cumulative gradient calls
/// reach the nominal call count `at_calls`, and the evaluation of that iterate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The nominal call count (0, `every_calls`, …, the budget): checkpoints of different runs
    /// are aligned by it.
    pub at_calls: u64,
    /// The iteration (0 = the starting θ).
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
    /// The obstacle task: the x part of `eval_loss`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_x: Option<f64>,
    /// The obstacle task: the y part of `eval_loss`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_y: Option<f64>,
    /// The obstacle task: ‖x-row of the mean eq. 3.15 estimate‖ at θ over the appendix's
    /// `grad_trajectories` roll-outs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grad_x: Option<f64>,
    /// ‖y-row of it‖.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grad_y: Option<f64>,
    /// Fig. 4.9 (CartPole): crashes (resets) before the deterministic policy completes one full
    /// 500-step episode, counting at most the appendix's `full_episode_cap` (= the cap: not
    /// completed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resets_to_full_episode: Option<u32>,
}

impl Checkpoint {
    /// A checkpoint at `at_calls` from the run's state (iteration, cumulative cost, the last
    /// step's loss estimate and direction norm) and the evaluation of its iterate; the
    /// appendix's extra measurements unset.
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
            loss_x: None,
            loss_y: None,
            grad_x: None,
            grad_y: None,
            resets_to_full_episode: None,
        }
    }

    /// The checkpoint of the iterate an observer is shown ([`IterationMetrics`]): its iteration
    /// and cumulative cost, the step's loss estimate and ‖direction‖ where they are finite, and
    /// `ev`, the evaluation of its θ; `at_calls` 0 (the caller sets the nominal call counts).
    pub fn of_iterate(m: &IterationMetrics<f64>, ev: &Evaluation) -> Self {
        let train_loss = m.loss.filter(|l| l.is_finite());
        let gradient_norm = m
            .estimate
            .as_ref()
            .map(|d| d.norm())
            .filter(|n| n.is_finite());
        Checkpoint::new(0, m.iteration, &m.cost, train_loss, gradient_norm, ev)
    }

    /// The CSV header of [`Checkpoint::csv_row`] (`ilopt run`'s `seed-<n>.csv`).
    pub const CSV_HEADER: &'static str = "at_calls,iteration,gradient_evaluations,trajectories,env_steps,expert_queries,train_loss,gradient_norm,score,reward,successes,crashes,timeouts,eval_loss,objective";

    /// The checkpoint as one CSV row of `ilopt run`'s `seed-<n>.csv` (an empty cell for a
    /// missing value; floats in Rust's shortest round-trip form, so the text is a function of
    /// the values).
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

/// One seed's run: a function of the configuration and the seed. `S` is the verdict a caller
/// records on the run (paper-checks' run status; `ilopt run` records none).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedRun<S = ()> {
    /// The run's RNG seed.
    pub seed: u64,
    /// The seed's index 0..seeds (paper-checks, which derives the seed from it and the run's
    /// key).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed_index: Option<u32>,
    /// The algorithm's name.
    pub algorithm: String,
    /// Why the run ended: `gradient-budget`, `finished` (the algorithm's own schedule),
    /// `diverged: …` (a failing step, a non-finite θ, or `‖θ‖ = 3.200e5 > 1e4` when ‖θ‖₂
    /// exceeds the norm bound; the checkpoints reached are kept), or an observer's reason.
    pub termination: RecordedTermination,
    /// Iterations taken.
    pub iterations: u64,
    /// The total cost.
    pub cost: Cost,
    /// The final θ.
    pub theta: Vec<f64>,
    /// The checkpoints.
    pub checkpoints: Vec<Checkpoint>,
    /// The caller's verdict on the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub status: Option<S>,
    /// The hyper-parameters the run used (paper-checks' selected grid point, e.g.
    /// `alpha=0.005, m=16`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hyper_parameters: Option<String>,
}

/// One seed's wall times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedTiming {
    /// The run's RNG seed.
    pub seed: u64,
    /// The seed's index (paper-checks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed_index: Option<u32>,
    /// Training time in seconds (evaluations excluded).
    pub train_seconds: f64,
    /// Evaluation time in seconds.
    pub evaluation_seconds: f64,
    /// Training time up to each checkpoint.
    pub checkpoint_seconds: Vec<f64>,
    /// Training time to the checkpoint the caller's verdict names (paper-checks: sustained
    /// convergence), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converge_seconds: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absent_appendix_fields_are_left_out_of_the_json() {
        let c = Checkpoint::new(
            100,
            3,
            &Cost::default(),
            None,
            None,
            &Evaluation {
                objective: Some(0.5),
                ..Evaluation::default()
            },
        );
        let json = serde_json::to_string(&c).unwrap();
        assert!(json.contains(r#""timeouts":null"#), "{json}");
        assert!(
            !json.contains("loss_x") && !json.contains("resets"),
            "{json}"
        );
        let run = SeedRun::<()> {
            seed: 7,
            seed_index: None,
            algorithm: "sgd".into(),
            termination: RecordedTermination::GradientBudget,
            iterations: 3,
            cost: Cost::default(),
            theta: vec![1.0],
            checkpoints: vec![c],
            status: None,
            hyper_parameters: None,
        };
        let json = serde_json::to_string(&run).unwrap();
        assert!(
            !json.contains("seed_index") && !json.contains("status"),
            "{json}"
        );
        assert_eq!(serde_json::from_str::<SeedRun>(&json).unwrap(), run);
    }
}
