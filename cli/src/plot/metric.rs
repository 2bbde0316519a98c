//! What `ilopt plot` draws: the metric on the y axis (a column of `seed-<n>.csv`, with its range
//! per task) and the quantity on the x axis.

use crate::run::config::TaskName;
use clap::ValueEnum;

/// A per-checkpoint metric of `seed-<n>.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Metric {
    /// CartPole: mean evaluation reward / 500; obstacle: success rate.
    #[value(name = "score")]
    Score,
    /// Mean evaluation episode reward.
    #[value(name = "reward")]
    Reward,
    /// Mean per-decision supervised loss on the evaluation states.
    #[value(name = "eval_loss")]
    EvalLoss,
    /// Toy: the exact objective F(θ).
    #[value(name = "objective")]
    Objective,
    /// The last step's training-loss estimate.
    #[value(name = "train_loss")]
    TrainLoss,
    /// The norm of the last step's direction.
    #[value(name = "gradient_norm")]
    GradientNorm,
}

impl Metric {
    /// Every metric, in the CSV's column order.
    pub const ALL: [Metric; 6] = [
        Metric::TrainLoss,
        Metric::GradientNorm,
        Metric::Score,
        Metric::Reward,
        Metric::EvalLoss,
        Metric::Objective,
    ];

    /// The metric drawn when none is asked for: the task's evaluation score, or the exact
    /// objective on a toy MDP.
    pub fn default_for(task: TaskName) -> Self {
        match task {
            TaskName::Cartpole | TaskName::Obstacle | TaskName::Custom => Metric::Score,
            TaskName::Toy => Metric::Objective,
        }
    }

    /// Its column in `seed-<n>.csv` (and its name on the command line).
    pub fn column(self) -> &'static str {
        match self {
            Metric::Score => "score",
            Metric::Reward => "reward",
            Metric::EvalLoss => "eval_loss",
            Metric::Objective => "objective",
            Metric::TrainLoss => "train_loss",
            Metric::GradientNorm => "gradient_norm",
        }
    }

    /// The y-axis description on `task`.
    pub fn label(self, task: TaskName) -> &'static str {
        match (self, task) {
            (Metric::Score, TaskName::Cartpole) => "score (mean evaluation reward / 500)",
            (Metric::Score, TaskName::Custom) => "score (mean evaluation episode return)",
            (Metric::Score, _) => "success rate (fraction of evaluation episodes)",
            (Metric::Reward, _) => "mean evaluation episode reward",
            (Metric::EvalLoss, _) => "evaluation loss (per decision, against the expert)",
            (Metric::Objective, _) => "objective F(θ) (exact)",
            (Metric::TrainLoss, _) => "training loss (the last step's estimate)",
            (Metric::GradientNorm, _) => "norm of the last step's direction",
        }
    }

    /// The values the metric can take on `task`, `[min, max]` (either end may be infinite):
    /// the band is clamped to it. A score is a fraction; CartPole's reward counts at most 500
    /// steps; losses, the objective and norms are non-negative; the obstacle task's reward
    /// (progress plus a crash penalty) and a plug-in task's score and reward (its mean episode
    /// return) have no bound.
    pub fn range(self, task: TaskName) -> (f64, f64) {
        match (self, task) {
            (Metric::Score | Metric::Reward, TaskName::Custom) => {
                (f64::NEG_INFINITY, f64::INFINITY)
            }
            (Metric::Score, _) => (0.0, 1.0),
            (Metric::Reward, TaskName::Cartpole) => {
                (0.0, ilopt::env::cartpole::MAX_EPISODE_STEPS as f64)
            }
            (Metric::Reward, _) => (f64::NEG_INFINITY, f64::INFINITY),
            (
                Metric::EvalLoss | Metric::Objective | Metric::TrainLoss | Metric::GradientNorm,
                _,
            ) => (0.0, f64::INFINITY),
        }
    }
}

/// The quantity on the x axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum XAxis {
    /// Cumulative gradient calls (per-state gradient evaluations).
    Calls,
    /// Iterations (parameter updates of an oracle method; rounds of a dataset learner).
    Iterations,
}

impl XAxis {
    /// Its column in `seed-<n>.csv`.
    pub fn column(self) -> &'static str {
        match self {
            XAxis::Calls => "gradient_evaluations",
            XAxis::Iterations => "iteration",
        }
    }

    /// The x-axis description.
    pub fn label(self) -> &'static str {
        match self {
            XAxis::Calls => "gradient calls (per-state gradient evaluations, mean over seeds)",
            XAxis::Iterations => "iterations (mean over seeds)",
        }
    }
}

/// How several runs are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Layout {
    /// Every run on one plot.
    Overlay,
    /// One panel per run, on shared axes.
    Panels,
}
