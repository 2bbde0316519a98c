//! What one checkpoint's evaluation gives ([`Evaluation`]), for every task `ilopt run` and
//! paper-checks evaluate: the score chapter 4 reports (the obstacle task's success rate,
//! CartPole's mean reward / 500), the episode outcomes and the supervised loss, or a toy MDP's
//! exact objective.

use super::episodes::EpisodeStats;
use crate::env::cartpole::MAX_EPISODE_STEPS;
use serde::Serialize;

/// What one evaluation gives.
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

impl Evaluation {
    /// CartPole's evaluation from its episodes ([`cartpole_episodes`](super::episodes::cartpole_episodes)):
    /// score = mean reward / 500; no time-outs.
    pub fn cartpole(s: &EpisodeStats) -> Self {
        Evaluation {
            score: Some(s.reward / MAX_EPISODE_STEPS as f64),
            reward: Some(s.reward),
            successes: Some(s.successes),
            crashes: Some(s.crashes),
            timeouts: None,
            loss: Some(s.loss),
            loss_xy: None,
            objective: None,
        }
    }

    /// The obstacle task's evaluation from its `episodes` episodes
    /// ([`obstacle_episodes`](super::episodes::obstacle_episodes)): score = successes / episodes.
    pub fn obstacle(s: &EpisodeStats, episodes: u32) -> Self {
        Evaluation {
            score: Some(f64::from(s.successes) / f64::from(episodes)),
            reward: Some(s.reward),
            successes: Some(s.successes),
            crashes: Some(s.crashes),
            timeouts: Some(s.timeouts),
            loss: Some(s.loss),
            loss_xy: s.loss_xy,
            objective: None,
        }
    }
}
