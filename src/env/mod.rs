//! Environments with Gymnasium's semantics, generic over the scalar (conventions.md, "Data flow").
//!
//! An [`Env`] is reset with the run's seeded [`KitRng`] and stepped with an action; a step returns
//! a [`Step`]: the next observation, the reward, and the two end-of-episode flags of Gymnasium's
//! API (`terminated`: the MDP reached a terminal state; `truncated`: a time limit or other
//! outside condition cut the episode short). Both may be true on the same step.
//!
//! Differences from Gymnasium, on purpose:
//! * stepping before the first reset, or after an episode has ended, is an error
//!   ([`EnvError::NotReset`], [`EnvError::EpisodeOver`]) rather than an assertion or a warning;
//! * a comparison the scalar cannot decide (an interval straddling a termination threshold) is an
//!   error ([`EnvError::Undecidable`]), never a guess (conventions.md 3);
//! * a non-finite state is an error ([`EnvError::NonFinite`]), never a silent NaN.

use crate::problem::KitRng;
use crate::scalar::{Scalar, Undecidable};

pub mod cartpole;

pub mod cartpole_replay;

pub mod hypot;

pub mod obstacle;

/// What one environment step returns (Gymnasium's `(observation, reward, terminated, truncated,
/// info)` without `info`).
#[derive(Debug, Clone, PartialEq)]
pub struct Step<S, O> {
    /// The observation after the step.
    pub observation: O,
    /// The reward of this step.
    pub reward: S,
    /// The episode reached a terminal state of the MDP.
    pub terminated: bool,
    /// The episode was cut short by a condition outside the MDP (the time limit).
    pub truncated: bool,
}

impl<S, O> Step<S, O> {
    /// A step's outcome: the observation, the reward, and Gymnasium's two end-of-episode flags.
    pub fn new(observation: O, reward: S, terminated: bool, truncated: bool) -> Self {
        Self {
            observation,
            reward,
            terminated,
            truncated,
        }
    }

    /// `terminated || truncated`: the episode is over and the environment needs a reset.
    pub fn done(&self) -> bool {
        self.terminated || self.truncated
    }
}

/// An environment with Gymnasium's reset/step semantics over the scalar `S`.
pub trait Env<S: Scalar> {
    /// What the agent observes.
    type Obs;
    /// What the agent does.
    type Action;

    /// Starts a new episode, drawing the initial state from `rng`, and returns the first
    /// observation.
    fn reset(&mut self, rng: &mut KitRng) -> Self::Obs;

    /// Applies `action` for one time step.
    ///
    /// # Errors
    /// [`EnvError`]: no episode is running, the action is not in the action space, the scalar
    /// cannot decide a branch of the dynamics, or the state left the finite numbers. After an error
    /// the episode is over; call [`Env::reset`].
    fn step(&mut self, action: Self::Action) -> Result<Step<S, Self::Obs>, EnvError>;
}

/// Why an environment could not step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EnvError {
    /// `step` was called before the first `reset`.
    #[error("step called before reset")]
    NotReset,
    /// `step` was called after the episode ended (terminated, truncated, or failed).
    #[error("step called after the episode ended; call reset")]
    EpisodeOver,
    /// The action is not in the environment's action space.
    #[error("invalid action {action}: expected {expected}")]
    InvalidAction {
        /// The action given, as text.
        action: String,
        /// The action space, as text.
        expected: &'static str,
    },
    /// A branch of the dynamics (a termination test) could not be decided by the scalar.
    #[error(transparent)]
    Undecidable(#[from] Undecidable),
    /// A component of the state became NaN or infinite (or an unbounded interval).
    #[error("the state became non-finite: {what}")]
    NonFinite {
        /// Which component.
        what: &'static str,
    },
    /// An environment outside the kit (a Gymnasium one driven from Python) failed; its message.
    #[error("{0}")]
    External(String),
}
