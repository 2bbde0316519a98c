//! What a run records: its checkpoints ([`Checkpoint`]), its result ([`SeedRun`]) and its
//! timings ([`SeedTiming`]).

use super::{RunStatus, TaskKind, cartpole_max_steps};
use ilopt::evaluate::episodes::EpisodeStats;
use ilopt::problem::Cost;
use serde::{Deserialize, Serialize};

/// The evaluation of one checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The checkpoint's nominal call count (0, `checkpoint_every`, …, budget): checkpoints of
    /// different runs are aligned by it.
    pub at_calls: u64,
    /// Iteration of the run (0 = θ₁).
    pub iteration: u64,
    /// Cumulative trajectories rolled out by the algorithm.
    pub trajectories: u64,
    /// Cumulative per-state gradient evaluations ("gradient calls").
    pub gradient_evaluations: u64,
    /// Cumulative expert queries.
    pub expert_queries: u64,
    /// Success rate (obstacle) or mean reward / 500 (CartPole).
    pub score: f64,
    /// Successful episodes (obstacle) or episodes that completed 500 steps (CartPole).
    pub successes: u32,
    /// Crashed episodes.
    pub crashes: u32,
    /// Timed-out episodes (obstacle only).
    pub timeouts: u32,
    /// Mean episode reward.
    pub reward: f64,
    /// Mean per-decision loss on the evaluation states.
    pub loss: f64,
    /// Its x part (obstacle).
    pub loss_x: Option<f64>,
    /// Its y part (obstacle).
    pub loss_y: Option<f64>,
    /// ‖x-row of the mean eq. 3.15 estimate‖ at θ (obstacle, `grad_trajectories` roll-outs).
    pub grad_x: Option<f64>,
    /// ‖y-row of it‖.
    pub grad_y: Option<f64>,
    /// Fig. 4.9 (CartPole): crashes (resets) before the deterministic policy completes one full
    /// 500-step episode, counting at most the task's `full_episode_cap` (= the cap: not completed).
    #[serde(default)]
    pub resets_to_full_episode: Option<u32>,
}

impl Checkpoint {
    /// A checkpoint from an evaluation and the run's cost so far.
    pub(super) fn from_eval(
        ev: &EpisodeStats,
        kind: TaskKind,
        episodes: u32,
        iteration: u64,
        cost: &Cost,
        grad: Option<(f64, f64)>,
    ) -> Self {
        let score = match kind {
            TaskKind::Obstacle => f64::from(ev.successes) / f64::from(episodes),
            TaskKind::Cartpole => ev.reward / cartpole_max_steps() as f64,
        };
        Checkpoint {
            at_calls: 0,
            resets_to_full_episode: None,
            iteration,
            trajectories: cost.trajectories,
            gradient_evaluations: cost.gradient_evaluations,
            expert_queries: cost.expert_queries,
            score,
            successes: ev.successes,
            crashes: ev.crashes,
            timeouts: ev.timeouts,
            reward: ev.reward,
            loss: ev.loss,
            loss_x: ev.loss_xy.map(|l| l.0),
            loss_y: ev.loss_xy.map(|l| l.1),
            grad_x: grad.map(|g| g.0),
            grad_y: grad.map(|g| g.1),
        }
    }
}

/// One seeded run (deterministic part).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedRun {
    /// The seed's index 0..seeds.
    pub seed_index: u32,
    /// The run's RNG seed, derived from (task, label, algorithm config, seed index).
    pub seed: u64,
    /// Why the run ended (ilopt's termination).
    pub termination: String,
    /// Final θ.
    pub theta: Vec<f64>,
    /// The checkpoints.
    pub checkpoints: Vec<Checkpoint>,
    /// Index of the sustained-convergence checkpoint (= `status`'s, for the tables).
    pub converged: Option<usize>,
    /// How the run ended ([`RunStatus`]); the verdicts read it.
    pub status: RunStatus,
    /// The hyper-parameters the run used (the selected grid point), e.g. `alpha=0.005, m=16`.
    pub hyper_parameters: String,
}

/// One seeded run's wall times (kept out of the deterministic results).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedTiming {
    /// The seed's index.
    pub seed_index: u32,
    /// Training wall time of the run in seconds.
    pub train_seconds: f64,
    /// Training wall time at each checkpoint.
    pub checkpoint_seconds: Vec<f64>,
    /// Training wall time to convergence, if converged.
    pub converge_seconds: Option<f64>,
}
