//! CartPole-v1 as an imitation-learning task (thesis §4.2): an expert (the LQR controller, or the
//! kit's PPO-trained policy as in the thesis) labels every visited state with its action; the
//! learner sees φ(s) = (x, ẋ, θ, θ̇, 1). An episode is the Gymnasium environment's
//! ([`CartPoleEpisode`] of [`crate::env::cartpole`]: the same step under the same time limit),
//! started from the same reset law converted to `S` exactly.

use super::Task;
pub use crate::env::cartpole::CartPoleEpisode;
use crate::env::cartpole::{CartPoleDynamics, MAX_EPISODE_STEPS};
use crate::expert::lqr::{LqrExpert, LqrGain};
use crate::expert::ppo::{PpoExpert, PpoGreedy};
use crate::problem::{KitRng, OracleError};
use crate::scalar::Real;

/// Number of features: the state and a constant.
pub const FEATURES: usize = 5;

/// The expert that labels CartPole states.
#[derive(Debug, Clone)]
pub enum CartPoleExpert {
    /// The LQR controller of [`crate::expert::lqr`].
    Lqr(Box<LqrExpert>),
    /// The PPO-trained policy of [`crate::expert::ppo`] (greedy).
    Ppo(PpoExpert),
}

/// Which expert labels CartPole's states, as the configuration files name it (`"ppo"`,
/// `"lqr"`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CartPoleExpertChoice {
    /// The committed PPO expert `experts/cartpole-ppo.json` (thesis §4.2.1: "We use PPO as
    /// expert"), acting greedily.
    #[default]
    Ppo,
    /// The LQR controller on the linearised dynamics ([`crate::expert::lqr`]).
    Lqr,
}

impl CartPoleExpertChoice {
    /// The chosen expert: the LQR controller, or the committed PPO expert (built into the
    /// library).
    ///
    /// # Errors
    /// [`OracleError::Environment`] if the LQR design fails or the committed PPO file does not
    /// validate.
    pub fn expert(self) -> Result<CartPoleExpert, OracleError> {
        let environment = |e: &dyn std::fmt::Display| OracleError::Environment(e.to_string());
        match self {
            CartPoleExpertChoice::Lqr => LqrExpert::cartpole()
                .map(|e| CartPoleExpert::Lqr(Box::new(e)))
                .map_err(|e| environment(&e)),
            CartPoleExpertChoice::Ppo => crate::expert::ppo::PpoExpertFile::committed_cartpole()
                .and_then(|f| f.expert())
                .map(CartPoleExpert::Ppo)
                .map_err(|e| environment(&e)),
        }
    }

    /// `"PPO"` / `"LQR"`.
    pub fn name(self) -> &'static str {
        match self {
            CartPoleExpertChoice::Ppo => "PPO",
            CartPoleExpertChoice::Lqr => "LQR",
        }
    }
}

/// CartPole with an expert, episodes truncated at `max_steps` (Gymnasium: 500).
#[derive(Debug, Clone)]
pub struct CartPoleTask<S> {
    dynamics: CartPoleDynamics<S>,
    labeller: Labeller<S>,
    max_steps: usize,
}

/// The expert as the task queries it: the LQR gain already in `S` (the labels of a roll-out
/// without a conversion per state), or the PPO network.
#[derive(Debug, Clone)]
enum Labeller<S> {
    Lqr(LqrGain<S>),
    Ppo(PpoGreedy<S>),
}

impl<S: Real> CartPoleTask<S> {
    /// CartPole-v1 with the LQR expert and Gymnasium's 500-step truncation.
    ///
    /// # Errors
    /// [`OracleError::Environment`] if the LQR design fails.
    pub fn with_lqr() -> Result<Self, OracleError> {
        Self::new(
            CartPoleExpert::Lqr(Box::new(
                LqrExpert::cartpole().map_err(|e| OracleError::Environment(e.to_string()))?,
            )),
            MAX_EPISODE_STEPS,
        )
    }

    /// CartPole-v1 with the PPO expert stored at `path` (e.g. `experts/cartpole-ppo.json`).
    ///
    /// # Errors
    /// [`OracleError::Environment`] if the file cannot be loaded.
    pub fn with_ppo(path: &std::path::Path) -> Result<Self, OracleError> {
        let e = PpoExpert::load(path).map_err(|e| OracleError::Environment(e.to_string()))?;
        Self::new(CartPoleExpert::Ppo(e), MAX_EPISODE_STEPS)
    }

    /// A task with a given expert and truncation (≥ 1 step).
    ///
    /// # Errors
    /// [`OracleError::Environment`] for `max_steps = 0`.
    pub fn new(expert: CartPoleExpert, max_steps: usize) -> Result<Self, OracleError> {
        if max_steps == 0 {
            return Err(OracleError::Environment("max_steps must be ≥ 1".into()));
        }
        Ok(Self {
            dynamics: CartPoleDynamics::new(),
            labeller: match expert {
                CartPoleExpert::Lqr(e) => Labeller::Lqr(e.gain_in()),
                CartPoleExpert::Ppo(e) => Labeller::Ppo(
                    e.greedy_in()
                        .map_err(|e| OracleError::Environment(e.to_string()))?,
                ),
            },
            max_steps,
        })
    }
}

/// The PPO expert's action, out of line: the network is not inlined anyway, and keeping its call
/// out of [`Task::expert`] leaves the roll-out's hot loop with the LQR expert alone. The state
/// comes by value, copied at the call (only on this path), so that the episode's own state
/// is never handed to an opaque function by reference.
#[cold]
#[inline(never)]
fn ppo_action<S: Real>(e: &PpoGreedy<S>, state: [S; 4]) -> Result<usize, OracleError> {
    e.action(&state)
        .map_err(|e| OracleError::Environment(e.to_string()))
}

/// An environment error as an oracle error, out of the roll-out's hot loop.
#[cold]
#[inline(never)]
fn env_error(e: crate::env::EnvError) -> OracleError {
    OracleError::Environment(e.to_string())
}

impl<S: Real> Task<S> for CartPoleTask<S> {
    type Episode = CartPoleEpisode<S>;
    type Label = usize;
    type Action = usize;

    fn start(&self, rng: &mut KitRng) -> Result<Self::Episode, OracleError> {
        Ok(CartPoleEpisode::reset(rng))
    }

    fn features(&self, ep: &Self::Episode) -> Vec<S> {
        let mut f = Vec::with_capacity(FEATURES);
        self.push_features(ep, &mut f);
        f
    }

    #[inline]
    fn push_features(&self, ep: &Self::Episode, out: &mut Vec<S>) {
        self.push_features_then(ep, out, |_| ());
    }

    /// φ(s) built in a local array, appended to `out` and handed to `f` from the array (so that
    /// the learner's `θ·φ` reads it from registers; see [`Task::push_features_then`]).
    #[inline(always)]
    fn push_features_then<R>(
        &self,
        ep: &Self::Episode,
        out: &mut Vec<S>,
        f: impl FnOnce(&[S]) -> R,
    ) -> R {
        let [x, x_dot, theta, theta_dot] = &ep.state;
        let phi: [S; FEATURES] = [
            x.clone(),
            x_dot.clone(),
            theta.clone(),
            theta_dot.clone(),
            S::one(),
        ];
        out.extend_from_slice(&phi);
        f(&phi)
    }

    fn max_episode_steps(&self) -> Option<usize> {
        Some(self.max_steps)
    }

    #[inline]
    fn expert(&self, ep: &Self::Episode) -> Result<(usize, usize), OracleError> {
        let a = match &self.labeller {
            Labeller::Lqr(k) => k.action(&ep.state)?,
            Labeller::Ppo(e) => ppo_action(e, ep.state.clone())?,
        };
        Ok((a, a))
    }

    /// 2 per remaining step: every end is a failure (the pole fell or the cart left the track;
    /// the time limit is the horizon), and 2 is the supremum of the Brier loss
    /// `Σ_a (π(a|s) − 1[a = a*(s)])²` over two actions that the kit's CartPole policies use.
    fn absorbing_loss(&self, _episode: &Self::Episode) -> Option<S> {
        Some(S::from_i64(2))
    }

    #[inline(always)]
    fn advance(&self, ep: &mut Self::Episode, action: &usize) -> Result<bool, OracleError> {
        let end = ep
            .advance(&self.dynamics, *action, self.max_steps)
            .map_err(env_error)?;
        Ok(end.terminated || end.truncated)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The configuration files' names, the PPO default, and each choice's expert.
    #[test]
    fn expert_choices_read_their_names_and_build_their_experts() {
        let read = |s: &str| serde_json::from_str::<CartPoleExpertChoice>(s);
        assert_eq!(read("\"ppo\"").unwrap(), CartPoleExpertChoice::Ppo);
        assert_eq!(read("\"lqr\"").unwrap(), CartPoleExpertChoice::Lqr);
        assert!(read("\"LQR\"").is_err());
        assert_eq!(CartPoleExpertChoice::default(), CartPoleExpertChoice::Ppo);
        assert!(matches!(
            CartPoleExpertChoice::Ppo.expert(),
            Ok(CartPoleExpert::Ppo(_))
        ));
        assert!(matches!(
            CartPoleExpertChoice::Lqr.expert(),
            Ok(CartPoleExpert::Lqr(_))
        ));
    }
}
