//! Environments as imitation-learning problems: the eq. 3.15 oracle on the real tasks.
//!
//! A [`Task`] is an episodic simulator with an expert (CartPole with the LQR expert, the obstacle
//! task with the velocity-obstacle expert); a [`crate::policy::Policy`] is the learner over the
//! task's features. [`TaskProblem`] joins them into an [`IlProblem`](crate::problem::IlProblem): roll-outs with seeded RNGs,
//! expert labels at every visited state, and on a trajectory with decisions t = 1..n the passes of
//! [`crate::oracle`]:
//!
//! * the causal estimator of eq. 3.15, `g = Σ_t ∇l_t + Σ_{i<n} ψ_i Σ_{t>i} l_t`;
//! * the full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i`;
//! * the importance-weighted old-point estimates of math.md §4, with per-decision ratios
//!   `π_old(a_i|s_i)/π_new(a_i|s_i) = exp(log π_old − log π_new)`
//!   ([`LikelihoodRatio`](crate::policy::LikelihoodRatio)).
//!
//! What one trajectory is, and so which objective the estimators are unbiased for, is the
//! problem's [`Horizon`]:
//!
//! * [`Horizon::Fixed`] (the thesis's F, eqs. 3.1–3.16): a stream of exactly `steps` decisions.
//!   When an episode ends early the stream either **resets** (a fresh start from the task's reset
//!   law; the thesis's CartPole protocol) and goes on, with eq. 3.15 unchanged and its score sum
//!   running across resets (the reset time depends on earlier actions), or **absorbs**: the
//!   remaining steps take no decision and each costs the task's [`Task::absorbing_loss`] of the
//!   end state (obstacle task: 0 after reaching the goal, the loss's supremum after a crash).
//!   The absorbing losses enter the loss-to-go of every decision before them, the last one
//!   included (its action caused the end); absorbing steps cost no gradient evaluation. Both are
//!   the thesis's setting on an augmented MDP.
//! * [`Horizon::Episodic`]: one episode, ending when the task says so; F(θ) = E Σ_{t=1}^{n} l(s_t, θ)
//!   with the random episode length n. Eq. 3.15 is unbiased for it too, but a short episode is
//!   cheap, so its minimisers include policies that end the episode at once (a labelled control,
//!   not the thesis's objective).

pub mod cartpole;
mod env_task;
mod horizon;
pub mod obstacle;
mod problem;
mod rollout;
mod trajectory;

pub use env_task::{EnvEpisode, EnvTask};
pub use horizon::{AfterEnd, Horizon};
pub use problem::TaskProblem;
pub use trajectory::{INLINE_FEATURES, TaskExample, TaskTrajectory};

use crate::problem::{KitRng, OracleError};
use crate::scalar::Scalar;

/// An episodic environment with an expert, over the scalar `S`.
pub trait Task<S: Scalar> {
    /// The per-episode simulator state.
    type Episode: Clone;
    /// The expert's label at a state (what the loss compares the policy's output with).
    type Label: Clone + std::fmt::Debug;
    /// An action in the environment.
    type Action: Clone + std::fmt::Debug;

    /// Start an episode (seeded reset).
    ///
    /// # Errors
    /// [`OracleError::Environment`] if the environment cannot start.
    fn start(&self, rng: &mut KitRng) -> Result<Self::Episode, OracleError>;
    /// The learner's features φ(s) of the current state.
    fn features(&self, episode: &Self::Episode) -> Vec<S>;
    /// Append φ(s) of the current state to `out` (the same values as [`Task::features`]).
    ///
    /// The roll-out stores the features of a trajectory in one flat buffer through this method;
    /// the default calls [`Task::features`] (one allocation), the kit's tasks override it with a
    /// version that writes in place (with the capacity reserved from
    /// [`Task::max_episode_steps`], a step then allocates nothing).
    fn push_features(&self, episode: &Self::Episode, out: &mut Vec<S>) {
        out.extend(self.features(episode));
    }
    /// Append φ(s) to `out` as [`Task::push_features`] does, and hand the same values to `f`
    /// (the roll-out's learner acts on them).
    ///
    /// The default hands `f` the entries just appended. A task whose φ has a length known at
    /// compile time should override it to build φ in a local array, append a copy and hand `f`
    /// the array (see [`cartpole::CartPoleTask`]): inlined into the roll-out, the policy's `θ·φ`
    /// then reads φ from registers instead of loading back what was just stored, a store-to-load
    /// round trip on the roll-out's critical path.
    fn push_features_then<R>(
        &self,
        episode: &Self::Episode,
        out: &mut Vec<S>,
        f: impl FnOnce(&[S]) -> R,
    ) -> R {
        let start = out.len();
        self.push_features(episode, out);
        f(&out[start..])
    }
    /// An upper bound on the number of decisions of an episode, if the task has one (a time
    /// limit). The roll-out reserves the trajectory's storage for that many steps up front, so
    /// that the per-step loop never grows a buffer. `None` (the default): buffers grow
    /// geometrically as usual.
    fn max_episode_steps(&self) -> Option<usize> {
        None
    }
    /// The expert's label and the action the expert would take at the current state.
    ///
    /// # Errors
    /// [`OracleError`] if the expert cannot decide (undecidable comparison, no solution).
    fn expert(&self, episode: &Self::Episode) -> Result<(Self::Label, Self::Action), OracleError>;
    /// The loss per remaining step when a [`Horizon::Fixed`] stream with [`AfterEnd::Absorb`]
    /// ends in this state (called after [`Task::advance`] returned `true`): 0 for an end that
    /// is a success, the per-step loss's supremum for a failure. `None` (the default): the task
    /// defines no absorbing loss, and an absorbing roll-out is an error.
    fn absorbing_loss(&self, episode: &Self::Episode) -> Option<S> {
        let _ = episode;
        None
    }
    /// Apply an action; `Ok(true)` when the episode is over (terminated or truncated).
    ///
    /// # Errors
    /// [`OracleError::Environment`] for an invalid action or a failed step.
    fn advance(
        &self,
        episode: &mut Self::Episode,
        action: &Self::Action,
    ) -> Result<bool, OracleError>;
}
