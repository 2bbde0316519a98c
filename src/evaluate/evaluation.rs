//! How a checkpoint's [`Evaluation`] is formed from a task's evaluation episodes, for every task
//! `ilopt run` and paper-checks evaluate: the score chapter 4 reports (the obstacle task's success
//! rate, CartPole's mean reward / 500), the episode outcomes and the supervised loss. The record
//! itself lives with the other records of a run ([`crate::algo::records`]), below the tasks.

use super::episodes::EpisodeStats;
pub use crate::algo::records::Evaluation;
use crate::env::cartpole::MAX_EPISODE_STEPS;

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
