//! Learner policies over feature vectors φ(s) ∈ Sⁿ: the parameterisations the
//! environments use, each generic over the weakest scalar layer that works, with **analytic**
//! gradients of the loss and of the log-probability (the two ingredients of the estimator of
//! eq. 3.15, math.md §1.1).
//!
//! | policy | actions | needs | loss on the output (math.md §1.2, erratum E1) |
//! |---|---|---|---|
//! | [`LinearGaussian`] (P3, math.md §1.3) | a ∈ Sᵐ | [`Scalar`] (log-density: [`Real`](crate::scalar::Real)) | ‖Wφ − π*(s)‖² |
//! | [`Softmax`] | a ∈ {0..A−1} | [`Real`](crate::scalar::Real) | Brier on π = softmax(Θφ) |
//! | [`Logistic`] | a ∈ {0, 1} | [`Real`](crate::scalar::Real) | Brier, `2(p − y)²` |
//! | [`MlpSoftmax`], [`MlpGaussian`] | as above | [`Real`](crate::scalar::Real) | as above, through one tanh layer |
//!
//! The loss is always a function of the policy's deterministic **output** (mean or probabilities),
//! never of the sampled action (erratum E1): otherwise eq. 3.15 is biased.
//!
//! Parameters are flat slices `θ ∈ Sᵈ` (so the algorithms can treat every policy alike); each
//! policy documents its layout. Gradients are returned in the same layout.
//!
//! **Sampling draws randomness the same way for every scalar**: a standard normal or a uniform is
//! drawn as an `f64` from the [`KitRng`] and converted *exactly* with
//! [`from_f64_exact`] (every finite `f64` is a dyadic rational). An `f64` run and an interval run
//! with one seed therefore follow the same path, as long as interval comparisons stay decidable.

mod greedy;
mod linear_gaussian;
pub(crate) mod logistic;
mod mlp;
pub(crate) mod softmax;
mod speed_limited;

pub use greedy::Greedy;
pub use linear_gaussian::{ActionVector, LinearGaussian};
pub use logistic::{Logistic, logistic_sigmoid, softplus};
pub use mlp::{Forward, Mlp, MlpGaussian, MlpSoftmax, tanh};
pub use softmax::{Softmax, brier_logit_gradient, log_softmax, softmax_probs};
pub use speed_limited::SpeedLimitedGaussian;

use crate::problem::KitRng;
use crate::scalar::{Scalar, Undecidable};

/// Why a policy could not be built or evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PolicyError {
    /// A vector or matrix argument has the wrong number of entries.
    #[error("`{param}` has {got} entries, expected {expected}")]
    Shape {
        /// The offending parameter.
        param: &'static str,
        /// Entries expected.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A size that must be positive is zero.
    #[error("`{param}` must be at least {min}, got {got}")]
    TooSmall {
        /// The offending parameter.
        param: &'static str,
        /// The smallest admissible value.
        min: usize,
        /// The value given.
        got: usize,
    },
    /// A value that must be certainly > 0 is not (e.g. σ_π).
    #[error("`{param}` must be certainly positive, got {value}")]
    NotPositive {
        /// The offending parameter.
        param: &'static str,
        /// Its (lossy) value, for the message.
        value: f64,
    },
    /// A value that must be finite is NaN, ±∞ or an unbounded interval.
    #[error("`{param}` contains a non-finite value")]
    NonFinite {
        /// The offending parameter (or the intermediate quantity).
        param: &'static str,
    },
    /// An action index is out of range.
    #[error("action {action} is out of range (the policy has {actions} actions)")]
    Action {
        /// The action given.
        action: usize,
        /// Number of actions.
        actions: usize,
    },
    /// Interval arithmetic could not decide a branch (sampling).
    #[error(transparent)]
    Undecidable(#[from] Undecidable),
}

/// The exact value of a finite `f64` in scalar `S`: every finite double is a dyadic rational
/// `k·2ᵉ`, so `S::from_rational` of it is exact in `BigRational`, a singleton in `Interval`, and the
/// same double again in `f64` (and in `Dual<·>` of these). `f32` rounds it to nearest: f32 runs
/// follow the f64 path only approximately.
///
/// This is how the policies turn the RNG's `f64` draws into scalars, so that one seed gives one
/// path in every scalar type.
///
/// # Errors
/// [`PolicyError::NonFinite`] for NaN and ±∞ (`param` names the quantity).
pub fn from_f64_exact<S: Scalar>(x: f64, param: &'static str) -> Result<S, PolicyError> {
    S::from_binary64(x).ok_or(PolicyError::NonFinite { param })
}

/// The interface the gradient oracle needs from a learner over features (eq. 3.15): the loss on
/// the policy's output with its gradient, the score ∇_θ log π_θ(a|s), and sampling.
///
/// The required methods are the in-place ones, which every policy implements without allocating
/// (the oracle's hot loop); the allocating conveniences `loss` and `score` are
/// [`PolicyExt`]'s, built on them for every policy and not overridable.
pub trait Policy<S: Scalar> {
    /// A sampled action.
    type Action: Clone + std::fmt::Debug;
    /// The expert's label at a state (a target output or an action).
    type Label: ?Sized;

    /// Number of parameters d.
    fn param_dim(&self) -> usize;
    /// Number of features n (length of φ).
    fn feature_dim(&self) -> usize;

    /// The loss `l(s, θ)` on the policy's output, returned, and its gradient `∇_θ l` (layout of
    /// θ) written into `grad` (length [`Policy::param_dim`]).
    ///
    /// # Errors
    /// [`PolicyError::Shape`] for a θ, φ, label or `grad` of the wrong size;
    /// [`PolicyError::NonFinite`] if the output is not finite.
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        grad: &mut [S],
    ) -> Result<S, PolicyError>;

    /// The score `∇_θ log π_θ(a|s)` (layout of θ) written into `score` (length
    /// [`Policy::param_dim`]).
    ///
    /// # Errors
    /// As [`Policy::loss_into`], plus [`PolicyError::Action`] for an impossible action.
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &Self::Action,
        score: &mut [S],
    ) -> Result<(), PolicyError>;

    /// Sample `a ∼ π_θ(·|s)`, drawing `f64` randomness and converting it exactly.
    ///
    /// # Errors
    /// As [`Policy::loss_into`], plus [`PolicyError::Undecidable`] when an interval cannot be
    /// ordered.
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng)
    -> Result<Self::Action, PolicyError>;

    /// Both per-decision terms of eq. 3.15 at one state: `l` (returned), `∇_θ l` into `grad` and
    /// `∇_θ log π_θ(a|s)` into `score`, as [`Policy::loss_into`] then [`Policy::score_into`] (the
    /// default). A policy may override it to share work between the two (the logistic policy
    /// computes `σ(θ·φ)` once); the values stay bit-for-bit those of the separate calls.
    ///
    /// # Errors
    /// As [`Policy::loss_into`] and [`Policy::score_into`], the loss's error first.
    fn loss_score_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        action: &Self::Action,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        let l = self.loss_into(theta, phi, label, grad)?;
        self.score_into(theta, phi, action, score)?;
        Ok(l)
    }
}

/// The allocating forms of [`Policy`]'s in-place methods, for every policy (a blanket
/// implementation, so no policy can give them other values): each allocates its result of
/// [`Policy::param_dim`] entries and fills it with the in-place method, bit for bit its values
/// and its errors.
pub trait PolicyExt<S: Scalar>: Policy<S> {
    /// The loss `l(s, θ)` on the policy's output and its gradient `∇_θ l` (layout of θ):
    /// [`Policy::loss_into`] into a fresh vector.
    ///
    /// # Errors
    /// As [`Policy::loss_into`].
    fn loss(&self, theta: &[S], phi: &[S], label: &Self::Label)
    -> Result<(S, Vec<S>), PolicyError>;

    /// The score `∇_θ log π_θ(a|s)` (layout of θ): [`Policy::score_into`] into a fresh vector.
    ///
    /// # Errors
    /// As [`Policy::score_into`].
    fn score(&self, theta: &[S], phi: &[S], action: &Self::Action) -> Result<Vec<S>, PolicyError>;
}

impl<S: Scalar, P: Policy<S> + ?Sized> PolicyExt<S> for P {
    fn loss(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
    ) -> Result<(S, Vec<S>), PolicyError> {
        let mut grad = vec![S::zero(); self.param_dim()];
        let l = self.loss_into(theta, phi, label, &mut grad)?;
        Ok((l, grad))
    }

    fn score(&self, theta: &[S], phi: &[S], action: &Self::Action) -> Result<Vec<S>, PolicyError> {
        let mut score = vec![S::zero(); self.param_dim()];
        self.score_into(theta, phi, action, &mut score)?;
        Ok(score)
    }
}

/// Check that a parameter (σ_π, a speed limit) is finite and certainly > 0.
///
/// # Errors
/// [`PolicyError::NonFinite`] or [`PolicyError::NotPositive`] naming `param`.
pub(crate) fn check_positive<S: Scalar>(param: &'static str, x: &S) -> Result<(), PolicyError> {
    if !x.is_finite() {
        return Err(PolicyError::NonFinite { param });
    }
    if !x.is_certainly_positive() {
        return Err(PolicyError::NotPositive {
            param,
            value: x.to_f64(),
        });
    }
    Ok(())
}

/// Check that a slice (an input, or an output buffer of a `*_into` method) has `expected` entries.
#[inline]
pub(crate) fn check_out<S>(
    param: &'static str,
    out: &[S],
    expected: usize,
) -> Result<(), PolicyError> {
    if out.len() != expected {
        return Err(PolicyError::Shape {
            param,
            expected,
            got: out.len(),
        });
    }
    Ok(())
}

/// The log-probability of an action and the per-decision likelihood ratio of importance-weighted
/// estimates (math.md §4): `log π_θ(a|s) − log π_θ'(a|s)`, so that the weight of one decision is
/// its exponential and the trajectory weight `w_{θ→θ'}` is the exponential of the sum over
/// decisions.
pub trait LikelihoodRatio<S: Scalar>: Policy<S> {
    /// `log π_θ(a|s)` up to an additive term that does not depend on θ (the Gaussian policies
    /// leave out their normaliser, so that the value exists in every scalar of their layer).
    ///
    /// # Errors
    /// As [`Policy::score_into`].
    fn log_prob(&self, theta: &[S], phi: &[S], action: &Self::Action) -> Result<S, PolicyError>;

    /// `log π_θ(a|s) − log π_{θ_other}(a|s)`. The default is the difference of
    /// [`LikelihoodRatio::log_prob`]s; a policy may override it with an exact or cheaper form
    /// (the linear-Gaussian policy's).
    ///
    /// # Errors
    /// As [`Policy::score_into`].
    fn log_likelihood_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &Self::Action,
    ) -> Result<S, PolicyError> {
        Ok(self.log_prob(theta, phi, action)? - self.log_prob(theta_other, phi, action)?)
    }
}

/// Check that a slice has `expected` entries, all finite.
#[inline]
pub(crate) fn check_vec<S: Scalar>(
    param: &'static str,
    xs: &[S],
    expected: usize,
) -> Result<(), PolicyError> {
    check_out(param, xs, expected)?;
    // Without early exit: a branch-free pass over the (short) vectors of the hot loop.
    if !xs.iter().fold(true, |ok, x| ok & x.is_finite()) {
        return Err(PolicyError::NonFinite { param });
    }
    Ok(())
}

/// [`check_vec`] (the same result) reading the entries one by one, with an early exit: for a
/// vector that was written entry by entry just before (the features of the roll-out's current
/// state), a vectorised pass would load it with wide loads that the CPU cannot forward from the
/// narrow stores, a stall on the roll-out's step-to-step dependency chain.
#[inline]
pub(crate) fn check_vec_scalar<S: Scalar>(
    param: &'static str,
    xs: &[S],
    expected: usize,
) -> Result<(), PolicyError> {
    check_out(param, xs, expected)?;
    if !xs.iter().all(Scalar::is_finite) {
        return Err(PolicyError::NonFinite { param });
    }
    Ok(())
}

/// Check a size is at least `min`.
pub(crate) fn check_size(param: &'static str, got: usize, min: usize) -> Result<(), PolicyError> {
    if got < min {
        return Err(PolicyError::TooSmall { param, min, got });
    }
    Ok(())
}

/// `y = Mx` for a row-major `rows × x.len()` matrix `m`.
pub(crate) fn mat_vec<S: Scalar>(m: &[S], x: &[S], rows: usize) -> Vec<S> {
    let cols = x.len();
    (0..rows)
        .map(|i| crate::scalar::dot(&m[i * cols..(i + 1) * cols], x))
        .collect()
}

/// `y = Mx` with each row's sum taken left to right from 0, whatever its length (not the floats'
/// partial sums of [`crate::scalar::Scalar::dot_slices`]): the tanh MLP's layers, whose order the
/// PPO expert's greedy pass repeats operation for operation and with which the committed expert
/// was trained.
pub(crate) fn mat_vec_in_order<S: Scalar>(m: &[S], x: &[S], rows: usize) -> Vec<S> {
    let cols = x.len();
    (0..rows)
        .map(|i| {
            m[i * cols..(i + 1) * cols]
                .iter()
                .zip(x)
                .fold(S::zero(), |acc, (a, b)| acc + a.clone() * b)
        })
        .collect()
}
