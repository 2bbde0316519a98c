//! Replaying an action sequence through CartPole-v1's float64 dynamics from a given state, and the
//! text forms of the state and the actions (`X,XDOT,THETA,THETADOT` and `0,1,1,…`) that
//! `ilopt replay cartpole` reads.
//!
//! Each step is [`CartPoleDynamics::step`] in `f64`, bit-for-bit Gymnasium's. Stepping goes on
//! after a terminal state, as `env.unwrapped.step` does in Gymnasium, and there is no time limit;
//! [`Replay::first_terminal_step`] and [`Replay::steps_after_termination`] say whether that
//! happened. The initial state is read as Python's `float()` reads it (correctly rounded).

use super::EnvError;
use super::cartpole::{CartPoleDynamics, STATE_NAMES};

/// A non-empty sequence of CartPole actions (each 0 or 1).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Actions(pub Vec<usize>);

/// Why `ilopt replay cartpole` failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReplayError {
    /// `--init` does not have exactly four components.
    #[error("--init: expected 4 comma-separated numbers X,XDOT,THETA,THETADOT, got {count}")]
    InitCount {
        /// How many components were given.
        count: usize,
    },
    /// A component of `--init` is not a number.
    #[error("--init: component {index} ({name}) {text:?} is not a number")]
    InitNotANumber {
        /// 1-based position.
        index: usize,
        /// The component's name.
        name: &'static str,
        /// The offending text.
        text: String,
    },
    /// A component of `--init` is NaN or infinite.
    #[error("--init: component {index} ({name}) {text:?} is not finite")]
    InitNotFinite {
        /// 1-based position.
        index: usize,
        /// The component's name.
        name: &'static str,
        /// The offending text.
        text: String,
    },
    /// `--actions` is empty.
    #[error("--actions: at least one action is needed")]
    NoActions,
    /// An action is not `0` or `1`.
    #[error("--actions: action {index} is {text:?}; expected 0 (push left) or 1 (push right)")]
    BadAction {
        /// 1-based position.
        index: usize,
        /// The offending text.
        text: String,
    },
    /// The dynamics failed (the state left the finite floats).
    #[error("step {step}: {source}")]
    Step {
        /// 1-based step number.
        step: usize,
        /// What failed.
        source: EnvError,
    },
}

/// Parses `X,XDOT,THETA,THETADOT` (surrounding spaces of each component ignored).
///
/// # Errors
/// [`ReplayError::InitCount`], [`ReplayError::InitNotANumber`], [`ReplayError::InitNotFinite`].
pub fn parse_init(text: &str) -> Result<[f64; 4], ReplayError> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 4 {
        return Err(ReplayError::InitCount {
            count: if text.trim().is_empty() {
                0
            } else {
                parts.len()
            },
        });
    }
    let mut init = [0.0; 4];
    for (i, part) in parts.iter().enumerate() {
        let (index, name, text) = (i + 1, STATE_NAMES[i], (*part).to_owned());
        let v: f64 = part.parse().map_err(|_| ReplayError::InitNotANumber {
            index,
            name,
            text: text.clone(),
        })?;
        if !v.is_finite() {
            return Err(ReplayError::InitNotFinite { index, name, text });
        }
        init[i] = v;
    }
    Ok(init)
}

/// Parses `0,1,1,…` (surrounding spaces of each action ignored).
///
/// # Errors
/// [`ReplayError::NoActions`], [`ReplayError::BadAction`].
pub fn parse_actions(text: &str) -> Result<Actions, ReplayError> {
    if text.trim().is_empty() {
        return Err(ReplayError::NoActions);
    }
    text.split(',')
        .enumerate()
        .map(|(i, part)| match part.trim() {
            "0" => Ok(0),
            "1" => Ok(1),
            other => Err(ReplayError::BadAction {
                index: i + 1,
                text: other.to_owned(),
            }),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Actions)
}

/// The states after each step of a replay and whether each is terminal.
#[derive(Debug, Clone, PartialEq)]
pub struct Replay {
    /// The float64 state `[x, ẋ, θ, θ̇]` after each step.
    pub states: Vec<[f64; 4]>,
    /// Whether the state after each step is terminal.
    pub terminated: Vec<bool>,
}

impl Replay {
    /// The 1-based step whose state is the first terminal one, if any.
    #[must_use]
    pub fn first_terminal_step(&self) -> Option<usize> {
        self.terminated.iter().position(|&t| t).map(|i| i + 1)
    }

    /// How many steps were taken after the first terminal state (0 if none).
    #[must_use]
    pub fn steps_after_termination(&self) -> usize {
        self.first_terminal_step()
            .map_or(0, |step| self.terminated.len() - step)
    }
}

/// Replays `actions` from `init` through CartPole-v1's float64 dynamics.
///
/// # Errors
/// [`ReplayError::NoActions`] for an empty action list, [`ReplayError::InitNotFinite`] for a
/// non-finite initial state, and [`ReplayError::Step`] if a state becomes non-finite or an action
/// is invalid.
pub fn replay(init: [f64; 4], actions: &Actions) -> Result<Replay, ReplayError> {
    if actions.0.is_empty() {
        return Err(ReplayError::NoActions);
    }
    for (i, v) in init.iter().enumerate() {
        if !v.is_finite() {
            return Err(ReplayError::InitNotFinite {
                index: i + 1,
                name: STATE_NAMES[i],
                text: v.to_string(),
            });
        }
    }
    let dynamics = CartPoleDynamics::<f64>::new();
    let mut state = init;
    let mut states = Vec::with_capacity(actions.0.len());
    let mut terminated = Vec::with_capacity(actions.0.len());
    for (i, &a) in actions.0.iter().enumerate() {
        let (next, term) = dynamics
            .step(&state, a)
            .map_err(|source| ReplayError::Step {
                step: i + 1,
                source,
            })?;
        states.push(next);
        terminated.push(term);
        state = next;
    }
    Ok(Replay { states, terminated })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_forms_parse_and_bad_text_is_named() {
        assert_eq!(
            parse_init(" -1e-3, -2,-3.5 ,-0").unwrap(),
            [-1e-3, -2.0, -3.5, -0.0]
        );
        assert_eq!(parse_actions("0, 1,1").unwrap(), Actions(vec![0, 1, 1]));
        assert_eq!(parse_init(""), Err(ReplayError::InitCount { count: 0 }));
        assert!(matches!(
            parse_init("0,0,NaN,0"),
            Err(ReplayError::InitNotFinite { index: 3, .. })
        ));
        assert!(matches!(
            parse_actions("0,,1"),
            Err(ReplayError::BadAction { index: 2, .. })
        ));
        assert_eq!(parse_actions(" "), Err(ReplayError::NoActions));
    }

    #[test]
    fn replay_counts_the_steps_after_termination() {
        // θ' = θ + τ θ̇ = 0.2 + 0.02 > θ_max ≈ 0.2094 after the first step.
        let r = replay([0.0, 0.0, 0.2, 1.0], &Actions(vec![1, 1, 0])).unwrap();
        assert_eq!(r.terminated.len(), 3);
        assert!(r.terminated[0]);
        assert_eq!(r.first_terminal_step(), Some(1));
        assert_eq!(r.steps_after_termination(), 2);
        let calm = replay([0.0; 4], &Actions(vec![1, 0])).unwrap();
        assert_eq!(calm.first_terminal_step(), None);
        assert_eq!(calm.steps_after_termination(), 0);
        assert!(matches!(
            replay([0.0, 0.0, 0.0, 1e200], &Actions(vec![1, 1])),
            Err(ReplayError::Step { step: 1, .. })
        ));
    }
}
