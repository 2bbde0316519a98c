//! A PPO expert for CartPole-v1, trained by the kit itself (thesis §2.6.4 and §4.2: the thesis's
//! CartPole expert is a PPO policy).
//!
//! # Algorithm
//! Proximal policy optimisation with the clipped surrogate objective (Schulman, Wolski, Dhariwal,
//! Radford & Klimov 2017, "Proximal Policy Optimization Algorithms", arXiv:1707.06347, eq. 7) and
//! generalised advantage estimation (Schulman, Moritz, Levine, Jordan & Abbeel 2016,
//! "High-Dimensional Continuous Control Using Generalized Advantage Estimation", ICLR, eq. 16):
//!
//! ```text
//! rₜ(θ)   = π_θ(aₜ|sₜ) / π_θold(aₜ|sₜ)
//! L(θ)    = Ê[ min(rₜ(θ) Âₜ, clip(rₜ(θ), 1 − ε, 1 + ε) Âₜ) ] + c_H Ê[ H(π_θ(·|sₜ)) ]      (maximised)
//! δₜ      = Rₜ + γ V(sₜ₊₁) − V(sₜ),      Âₜ = δₜ + γλ Âₜ₊₁   (Rₜ = 1 the reward of step t; the chain restarts at episode ends)
//! V-loss  = ½ Ê[ (V_φ(sₜ) − (Âₜ + V_φold(sₜ)))² ]                                                (minimised)
//! ```
//!
//! (the thesis's step 4 writes the ratio as `r_t(θ)/r_t(θ_k)` with `r_t` the probability of the
//! action; that is the same `π_θ/π_θk`). The actor is an [`MlpSoftmax`] (one tanh hidden layer,
//! softmax over CartPole's two actions) and the critic an [`Mlp`] with one output; both use the
//! MLP's analytic back-propagation. Gradients with respect to the logits `z` (to be minimised,
//! per sample, before averaging over the mini-batch):
//!
//! ```text
//! surrogate:  −Â r (e_a − π)   when r Â ≤ clip(r, 1 − ε, 1 + ε) Â,  else 0  (the clipped branch is flat)
//! entropy:    c_H π_b (ln π_b + H)   (the gradient of −c_H H, H = −Σ_b π_b ln π_b)
//! ```
//!
//! Each network has its own Adam optimiser (Kingma & Ba 2015), the kit's
//! [`crate::algo::adam::AdamRule`] on the flat `f64` weights with the learning rate annealed per
//! step, after optional global-norm gradient clipping. [`PpoConfig::envs`] copies of CartPole are stepped one after the
//! other (as Gymnasium's synchronous vector environment with auto-reset), each for
//! [`PpoConfig::steps_per_env`] steps per iteration; then [`PpoConfig::epochs`] passes over the
//! shuffled batch in mini-batches. With [`PpoConfig::anneal`], the learning rates and ε decay
//! linearly to 0 over the run (as the `lin_` schedules of the rl-baselines3-zoo).
//!
//! **Truncation.** CartPole-v1 ends an episode either by *termination* (the pole fell or the cart
//! left the track: an absorbing state, `V = 0`) or by *truncation* at 500 steps (the state is not
//! terminal; the episode was only cut). GAE bootstraps from `V(s_final)` at a truncation and from 0
//! at a termination, and in both cases stops the `λ` chain at the episode's end; the value of the
//! last step of a rollout that did not end is bootstrapped from the next observation. A step that
//! is both terminated and truncated counts as terminated.
//!
//! **Determinism.** Everything is `f64`, single-threaded, and every draw (network initialisation,
//! resets, action samples, mini-batch shuffles) comes from one [`KitRng`] seeded with the run's
//! seed, in a fixed order: the same configuration and seed give bit-identical weights (on one
//! platform: `exp`/`ln` come from the system's libm). The trainer evaluates the networks with
//! `f64` batch passes over each mini-batch that perform the generic [`Mlp`] passes' operations
//! in the same order (`tests.rs` compares them, and the update, bit for bit). A NaN or infinity
//! anywhere in training is a [`PpoError`] naming the iteration, never a silent NaN.
//!
//! # The stored expert and how to retrain it
//! `experts/cartpole-ppo.json` holds the configuration, the seed, both networks' weights, the
//! training summary and the greedy actor's [`Evaluation`] ([`PpoExpertFile`]). It is rewritten by
//!
//! ```text
//! cargo run --release --example train_ppo -- --seed 1 --out experts/cartpole-ppo.json
//! ```
//!
//! (the default [`PpoConfig`], 100 096 environment steps in 391 iterations, single-threaded; its
//! time and where it goes are in `benches/README.md`, "PPO expert training"). With the default
//! configuration, training seeds 1 to 8 each gave a greedy mean return of 500 (every episode
//! 500) on the standard evaluation; the stored expert is seed 1. `tests/environments/ppo.rs`
//! retrains it (an ignored test, run in release) and checks the weights bit for bit.
//!
//! [`PpoExpert::load`] validates a file: format and version, the configuration
//! ([`PpoConfig::validate`]), the number of weights of each network (from the hidden width) and
//! that every weight is a finite number; each failure is an error naming the field.
//!
//! # Evaluation
//! [`evaluate_cartpole`] runs episode `i` of CartPole-v1 from a [`KitRng`] seeded with
//! `first_seed + i` (the protocol of `tests/environments/cartpole.rs`), so different controllers can be compared
//! on the same initial states. On seeds `0..100` (`tests/environments/ppo.rs` checks both are ≥ 495):
//!
//! | expert | mean return | min return |
//! |---|---|---|
//! | LQR ([`super::lqr::LqrExpert::cartpole`], bang-bang) | 500 | 500 |
//! | PPO (greedy, `experts/cartpole-ppo.json`) | 500 | 500 |

use crate::env::cartpole::{CartPole, MAX_EPISODE_STEPS};
use crate::env::{Env, EnvError};
use crate::policy::{Mlp, MlpSoftmax, PolicyError, from_f64_exact};
use crate::problem::KitRng;
use crate::scalar::{Real, Scalar, Undecidable};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::fmt::Display;
use std::path::Path;

/// Observation size of CartPole: `(x, ẋ, θ, θ̇)`.
pub const OBSERVATION_DIM: usize = 4;
/// CartPole's actions: 0 (push left), 1 (push right).
pub const ACTIONS: usize = 2;
/// Episodes of the standard evaluation ([`evaluate_cartpole`]).
pub const EVAL_EPISODES: usize = 100;
/// First seed of the standard evaluation: episodes use seeds `0..100`.
pub const EVAL_FIRST_SEED: u64 = 0;
/// The mean return over [`EVAL_EPISODES`] episodes the stored expert must reach.
pub const TARGET_MEAN_RETURN: f64 = 495.0;
/// The `format` field of a stored expert.
pub const FILE_FORMAT: &str = "ilopt-ppo-cartpole";
/// The `version` field of a stored expert this module writes and reads.
pub const FILE_VERSION: u32 = 1;

/// Why PPO could not train, act, or load.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PpoError {
    /// A hyper-parameter is out of its domain.
    #[error("invalid PPO configuration: `{field}` {reason}")]
    InvalidConfig {
        /// The [`PpoConfig`] field.
        field: &'static str,
        /// What is wrong, with the value.
        reason: String,
    },
    /// A loss, gradient, advantage or weight became NaN or infinite during training.
    #[error("non-finite {what} at PPO iteration {iteration}")]
    NonFinite {
        /// The training iteration (1-based).
        iteration: usize,
        /// Which quantity.
        what: &'static str,
    },
    /// A network evaluation failed during training (a non-finite activation or weight).
    #[error("network evaluation failed at PPO iteration {iteration}: {source}")]
    Network {
        /// The training iteration (1-based).
        iteration: usize,
        /// The policy-layer error.
        source: PolicyError,
    },
    /// The environment failed during training.
    #[error("environment failed at PPO iteration {iteration}: {source}")]
    Env {
        /// The training iteration (1-based).
        iteration: usize,
        /// The environment error.
        source: EnvError,
    },
    /// The expert could not act (a non-finite state or activation).
    #[error("the PPO expert could not act: {0}")]
    Act(#[source] PolicyError),
    /// A controller failed during [`evaluate_cartpole`].
    #[error("evaluation episode with seed {seed} failed at step {step}: {message}")]
    Evaluation {
        /// The episode's seed.
        seed: u64,
        /// The step (1-based) that failed.
        step: usize,
        /// The controller's or the environment's error.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A stored expert is not valid JSON of the expected shape.
    #[error("{path}: not a PPO expert file: {source}")]
    Json {
        /// The file.
        path: String,
        /// The parser's error (with line and column).
        source: serde_json::Error,
    },
    /// A stored expert is well-formed JSON but its content is invalid.
    #[error("{path}: invalid field `{field}`: {reason}")]
    InvalidFile {
        /// The file.
        path: String,
        /// The offending field (`actor[17]`, `config.gamma`, …).
        field: String,
        /// What is wrong.
        reason: String,
    },
}

/// The hyper-parameters of PPO on CartPole-v1.
///
/// The defaults follow the rl-baselines3-zoo's tuned CartPole-v1 PPO (8 environments × 32 steps,
/// mini-batch 256, 20 epochs, linear schedules from `lr = 10⁻³` and `ε = 0.2`, no entropy bonus,
/// gradient norm 0.5), with the kit's one-hidden-layer tanh networks of 64 units and separate
/// actor and critic optimisers, except for the discount and GAE parameter: `γ = 0.99`, `λ = 0.95`
/// (the common defaults of Schulman et al. 2017 and most implementations). With the zoo's
/// `γ = 0.98`, `λ = 0.8` the kit's networks plateaued: seed 1 ended at a greedy mean return of
/// about 131 after 100 000 steps (the cart drifted off the track), while `γ = 0.99`, `λ = 0.95`
/// reached 500 on seeds 1, 2 and 3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PpoConfig {
    /// Hidden tanh units of the actor and of the critic. Default 64.
    pub hidden: usize,
    /// CartPole copies stepped per iteration. Default 8.
    pub envs: usize,
    /// Steps of each copy per iteration (the rollout is `envs × steps_per_env`). Default 32.
    pub steps_per_env: usize,
    /// Environment steps of the whole run (rounded up to whole iterations). Default 100 000.
    pub total_steps: usize,
    /// Passes over each rollout. Default 20.
    pub epochs: usize,
    /// Samples per mini-batch (at most the rollout size; the last mini-batch of an epoch may be
    /// smaller). Default 256.
    pub minibatch_size: usize,
    /// Discount `γ ∈ [0, 1]`. Default 0.99.
    pub gamma: f64,
    /// GAE parameter `λ ∈ [0, 1]`. Default 0.95.
    pub gae_lambda: f64,
    /// Clip range `ε > 0` of the surrogate (its initial value if annealed). Default 0.2.
    pub clip_epsilon: f64,
    /// Adam step size of the actor (initial value if annealed). Default 10⁻³.
    pub actor_learning_rate: f64,
    /// Adam step size of the critic (initial value if annealed). Default 10⁻³.
    pub critic_learning_rate: f64,
    /// Decay the learning rates and `ε` linearly to 0 over the run: iteration `k` of `K` uses the
    /// factor `1 − (k − 1)/K`. Default true.
    pub anneal: bool,
    /// Entropy bonus `c_H ≥ 0`. Default 0.
    pub entropy_coefficient: f64,
    /// Rescale each network's gradient to this global Euclidean norm when it is larger; `None`
    /// disables clipping. Default `Some(0.5)`.
    pub max_grad_norm: Option<f64>,
    /// Standardise the advantages within each mini-batch (mean 0, population standard deviation 1,
    /// with `10⁻⁸` added to the deviation). Default true.
    pub normalize_advantages: bool,
    /// Adam's `β₁ ∈ [0, 1)`. Default 0.9.
    pub adam_beta1: f64,
    /// Adam's `β₂ ∈ [0, 1)`. Default 0.999.
    pub adam_beta2: f64,
    /// Adam's `ε > 0`. Default 10⁻⁵ (as PyTorch-based PPO implementations use).
    pub adam_epsilon: f64,
}

impl Default for PpoConfig {
    fn default() -> Self {
        PpoConfig {
            hidden: 64,
            envs: 8,
            steps_per_env: 32,
            total_steps: 100_000,
            epochs: 20,
            minibatch_size: 256,
            gamma: 0.99,
            gae_lambda: 0.95,
            clip_epsilon: 0.2,
            actor_learning_rate: 1e-3,
            critic_learning_rate: 1e-3,
            anneal: true,
            entropy_coefficient: 0.0,
            max_grad_norm: Some(0.5),
            normalize_advantages: true,
            adam_beta1: 0.9,
            adam_beta2: 0.999,
            adam_epsilon: 1e-5,
        }
    }
}

fn invalid(field: &'static str, reason: String) -> PpoError {
    PpoError::InvalidConfig { field, reason }
}

fn check_at_least(field: &'static str, value: usize, min: usize) -> Result<(), PpoError> {
    if value < min {
        return Err(invalid(
            field,
            format!("must be at least {min}, got {value}"),
        ));
    }
    Ok(())
}

fn check_range(
    field: &'static str,
    value: f64,
    ok: impl Fn(f64) -> bool,
    domain: &str,
) -> Result<(), PpoError> {
    if !value.is_finite() || !ok(value) {
        return Err(invalid(field, format!("must be in {domain}, got {value}")));
    }
    Ok(())
}

impl PpoConfig {
    /// Steps per iteration, `envs × steps_per_env` (saturating).
    pub fn rollout_size(&self) -> usize {
        self.envs.saturating_mul(self.steps_per_env)
    }

    /// Training iterations, `⌈total_steps / rollout_size⌉`.
    pub fn iterations(&self) -> usize {
        self.total_steps.div_ceil(self.rollout_size().max(1))
    }

    /// Checks every field's domain (documented on the field).
    ///
    /// # Errors
    /// [`PpoError::InvalidConfig`] naming the first offending field.
    pub fn validate(&self) -> Result<(), PpoError> {
        check_at_least("hidden", self.hidden, 1)?;
        check_at_least("envs", self.envs, 1)?;
        check_at_least("steps_per_env", self.steps_per_env, 1)?;
        if self.envs.checked_mul(self.steps_per_env).is_none() {
            return Err(invalid(
                "steps_per_env",
                "envs × steps_per_env overflows".into(),
            ));
        }
        check_at_least("total_steps", self.total_steps, 1)?;
        check_at_least("epochs", self.epochs, 1)?;
        check_at_least("minibatch_size", self.minibatch_size, 1)?;
        if self.minibatch_size > self.rollout_size() {
            return Err(invalid(
                "minibatch_size",
                format!(
                    "must be at most the rollout size envs × steps_per_env = {}, got {}",
                    self.rollout_size(),
                    self.minibatch_size
                ),
            ));
        }
        let unit = |x: f64| (0.0..=1.0).contains(&x);
        let positive = |x: f64| x > 0.0;
        let half_open = |x: f64| (0.0..1.0).contains(&x);
        check_range("gamma", self.gamma, unit, "[0, 1]")?;
        check_range("gae_lambda", self.gae_lambda, unit, "[0, 1]")?;
        check_range("clip_epsilon", self.clip_epsilon, positive, "(0, ∞)")?;
        check_range(
            "actor_learning_rate",
            self.actor_learning_rate,
            positive,
            "(0, ∞)",
        )?;
        check_range(
            "critic_learning_rate",
            self.critic_learning_rate,
            positive,
            "(0, ∞)",
        )?;
        check_range(
            "entropy_coefficient",
            self.entropy_coefficient,
            |x| x >= 0.0,
            "[0, ∞)",
        )?;
        if let Some(m) = self.max_grad_norm {
            check_range("max_grad_norm", m, positive, "(0, ∞) or null")?;
        }
        check_range("adam_beta1", self.adam_beta1, half_open, "[0, 1)")?;
        check_range("adam_beta2", self.adam_beta2, half_open, "[0, 1)")?;
        check_range("adam_epsilon", self.adam_epsilon, positive, "(0, ∞)")?;
        Ok(())
    }
}

mod adam;
mod batch;
mod file;
mod greedy;
mod network;
mod trainer;

#[cfg(test)]
mod tests;

use crate::algo::adam::AdamRule;
use adam::{adam, adam_step, clip_global_norm};
use batch::BatchMlp;
pub use file::{COMMITTED_CARTPOLE_EXPERT, COMMITTED_CARTPOLE_EXPERT_PATH, PpoExpertFile};
pub use greedy::{FAST_TANH_F32_ERROR, PpoGreedy, fast_tanh_f32};
pub use network::{Evaluation, PpoExpert, evaluate_cartpole};
use trainer::networks;
pub use trainer::{IterationStats, PpoTrainer, TrainingSummary, train};
