//! Learner policies over feature vectors φ(s) ∈ Sⁿ (issue 5, item 4): the parameterisations the
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

mod linear_gaussian;
mod logistic;
mod mlp;
mod softmax;
mod speed_limited;

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
pub trait Policy<S: Scalar> {
    /// A sampled action.
    type Action: Clone + std::fmt::Debug;
    /// The expert's label at a state (a target output or an action).
    type Label: ?Sized;

    /// Number of parameters d.
    fn param_dim(&self) -> usize;
    /// Number of features n (length of φ).
    fn feature_dim(&self) -> usize;

    /// The loss `l(s, θ)` on the policy's output and its gradient `∇_θ l` (layout of θ).
    ///
    /// # Errors
    /// [`PolicyError::Shape`] for a θ, φ or label of the wrong size; [`PolicyError::NonFinite`] if
    /// the output is not finite.
    fn loss(&self, theta: &[S], phi: &[S], label: &Self::Label)
    -> Result<(S, Vec<S>), PolicyError>;

    /// The score `∇_θ log π_θ(a|s)` (layout of θ).
    ///
    /// # Errors
    /// As [`Policy::loss`], plus [`PolicyError::Action`] for an impossible action.
    fn score(&self, theta: &[S], phi: &[S], action: &Self::Action) -> Result<Vec<S>, PolicyError>;

    /// Sample `a ∼ π_θ(·|s)`, drawing `f64` randomness and converting it exactly.
    ///
    /// # Errors
    /// As [`Policy::loss`], plus [`PolicyError::Undecidable`] when an interval cannot be ordered.
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng)
    -> Result<Self::Action, PolicyError>;

    /// The loss alone, `l` of [`Policy::loss_into`] bit for bit, for a θ and φ the caller has
    /// already checked (finite, of the policy's lengths): what a trajectory's loss needs, without
    /// the gradient. `scratch` has [`Policy::param_dim`] entries; its contents afterwards are
    /// unspecified.
    ///
    /// The default calls [`Policy::loss_into`] (the gradient is computed and discarded); the
    /// linear-Gaussian policies override it to skip the gradient and the per-call θ and φ checks.
    ///
    /// # Errors
    /// As [`Policy::loss_into`].
    fn loss_trusted(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        scratch: &mut [S],
    ) -> Result<S, PolicyError> {
        self.loss_into(theta, phi, label, scratch)
    }

    /// [`Policy::loss`] without allocating: writes `∇_θ l` into `grad` (length
    /// [`Policy::param_dim`]) and returns `l`. Bit-for-bit the values of [`Policy::loss`].
    ///
    /// The default calls [`Policy::loss`] and copies; the policies of this module override it
    /// with a version that allocates nothing (the hot loop of the oracle, issue 8).
    ///
    /// # Errors
    /// As [`Policy::loss`], and [`PolicyError::Shape`] for a `grad` of the wrong length.
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        let (l, g) = self.loss(theta, phi, label)?;
        copy_into("grad", &g, grad)?;
        Ok(l)
    }

    /// [`Policy::score`] without allocating: writes `∇_θ log π_θ(a|s)` into `score` (length
    /// [`Policy::param_dim`]). Bit-for-bit the values of [`Policy::score`]; the default calls it
    /// and copies.
    ///
    /// # Errors
    /// As [`Policy::score`], and [`PolicyError::Shape`] for a `score` of the wrong length.
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &Self::Action,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        let s = self.score(theta, phi, action)?;
        copy_into("score", &s, score)
    }

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

    /// [`Policy::sample`] for a θ the caller has already validated — `theta` has
    /// [`Policy::param_dim`] entries, all finite, as the oracle checks once per roll-out — so that
    /// a policy may skip its per-call θ check in the roll-out's hot loop. φ is still checked, length
    /// and finiteness, exactly as [`Policy::sample`] checks it: the oracle relies on this to mark a
    /// learner's roll-out as having finite features and to skip its own pass over them.
    ///
    /// For such a θ the action, the random draws and the errors are exactly those of
    /// [`Policy::sample`]; for any other θ the outcome is unspecified (an error, a panic or a
    /// meaningless action, never undefined behaviour). The default calls [`Policy::sample`].
    ///
    /// # Errors
    /// As [`Policy::sample`].
    #[inline]
    fn sample_trusted(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<Self::Action, PolicyError> {
        self.sample(theta, phi, rng)
    }

    /// One decision of the causal estimator of eq. 3.15 with unit weight, for inputs the caller
    /// has already validated (θ as in [`Policy::sample_trusted`], and φ with
    /// [`Policy::feature_dim`] entries, all finite — the oracle checks a whole trajectory once):
    /// returns `l_t` and updates `g += ∇_θ l_t + l_t Σ_{i<t} ψ_i` entry by entry, then
    /// `score_sum += ψ_t` (`score_sum` holds `Σ_{i<t} ψ_i` on entry). `grad` and `score` are
    /// scratch of length [`Policy::param_dim`] that the default fills with `∇_θ l_t` and `ψ_t`.
    ///
    /// The default is [`Policy::loss_score_into`] followed by those two loops; a policy may fuse
    /// them (the logistic policy never materialises `∇_θ l_t` and `ψ_t`, both multiples of φ).
    /// For validated inputs the results are bit-for-bit those of the default and the errors
    /// those of [`Policy::loss_score_into`]; for other inputs the outcome is unspecified (never
    /// undefined behaviour).
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`].
    #[allow(clippy::too_many_arguments)] // the estimator's whole per-decision state
    #[inline]
    fn causal_step_trusted(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        action: &Self::Action,
        grad: &mut [S],
        score: &mut [S],
        g: &mut [S],
        score_sum: &mut [S],
    ) -> Result<S, PolicyError> {
        let l = self.loss_score_into(theta, phi, label, action, grad, score)?;
        causal_accumulate(g, &l, grad, score, score_sum);
        Ok(l)
    }

    /// The whole unit-weight causal estimator of eq. 3.15 over one trajectory, for validated
    /// inputs (θ as in [`Policy::sample_trusted`]; `features` holds φ(s_1), …, φ(s_n) row after
    /// row, each with [`Policy::feature_dim`] finite entries; `labels` and `actions` have one entry
    /// per row): adds `Σ_t [∇_θ l_t + l_t Σ_{i<t} ψ_i]` to `g`. `scratch` is working storage
    /// that an implementation sizes as it needs (the default: `3 ·` [`Policy::param_dim`] zeros;
    /// the logistic policy's fixed-dimension loop needs none and leaves it empty, so the caller
    /// allocates nothing for it).
    ///
    /// The default runs [`Policy::causal_step_trusted`] decision after decision (`scratch` holds
    /// `∇l_t`, `ψ_t` and `Σ_{i<t} ψ_i`); a policy may override it with a faster loop (the logistic
    /// policy runs it with a compile-time dimension for up to 8 features). For validated inputs
    /// the results are bit-for-bit those of the default and the error is the default's (the first
    /// failing decision's); for other inputs the outcome is unspecified (never undefined
    /// behaviour).
    ///
    /// # Errors
    /// As [`Policy::causal_step_trusted`] at the first failing decision.
    #[inline]
    fn causal_sum_trusted<L: std::borrow::Borrow<Self::Label>>(
        &self,
        theta: &[S],
        features: &[S],
        labels: &[L],
        actions: &[Self::Action],
        g: &mut [S],
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        causal_sum_by_steps(self, theta, features, labels, actions, g, scratch)
    }

    /// [`Policy::causal_sum_trusted`] with a per-decision shift of the losses that multiply the
    /// score sums: adds `Σ_t [∇_θ l_t + (l_t + δ_t) Σ_{i<t} ψ_i]` to `g` (`shifts[t] = δ_t`, one
    /// per row). With `δ_t = b_t − b_{t−1}` (b_0 = 0, b_t = 0 after the last scored decision)
    /// this is the baselined estimator `g − Σ_i b_i ψ_i` of [`crate::baseline`], by summation by
    /// parts: `Σ_i b_i ψ_i = Σ_t (b_{t−1} − b_t) Σ_{i<t} ψ_i`. One addition per decision more
    /// than the plain pass.
    ///
    /// The default adds `δ_t Σ_{i<t} ψ_i` before each [`Policy::causal_step_trusted`]; a policy
    /// may override it with a faster loop (the logistic policy does). Inputs as for
    /// [`Policy::causal_sum_trusted`].
    ///
    /// # Errors
    /// As [`Policy::causal_step_trusted`] at the first failing decision.
    #[allow(clippy::too_many_arguments)] // the plain pass's arguments and the shifts
    #[inline]
    fn causal_sum_shifted_trusted<L: std::borrow::Borrow<Self::Label>>(
        &self,
        theta: &[S],
        features: &[S],
        labels: &[L],
        actions: &[Self::Action],
        shifts: &[S],
        g: &mut [S],
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let d = self.param_dim();
        scratch.clear();
        scratch.resize(3 * d, S::zero());
        let (grad, rest) = scratch.split_at_mut(d);
        let (score, score_sum) = rest.split_at_mut(d);
        let rows = features.chunks_exact(self.feature_dim().max(1));
        for (((phi, y), a), delta) in rows.zip(labels).zip(actions).zip(shifts) {
            for (gj, sj) in g.iter_mut().zip(score_sum.iter()) {
                *gj += delta.clone() * sj;
            }
            self.causal_step_trusted(theta, phi, y.borrow(), a, grad, score, g, score_sum)?;
        }
        Ok(())
    }
}

/// The default [`Policy::causal_sum_trusted`]: [`Policy::causal_step_trusted`] decision after
/// decision, with `scratch` resized to `3 · param_dim` zeros and split into `∇l_t`, `ψ_t` and
/// `Σ_{i<t} ψ_i`.
#[allow(clippy::too_many_arguments)] // the method's arguments and the policy
#[inline]
pub(crate) fn causal_sum_by_steps<S, P, L>(
    policy: &P,
    theta: &[S],
    features: &[S],
    labels: &[L],
    actions: &[P::Action],
    g: &mut [S],
    scratch: &mut Vec<S>,
) -> Result<(), PolicyError>
where
    S: Scalar,
    P: Policy<S> + ?Sized,
    L: std::borrow::Borrow<P::Label>,
{
    let d = policy.param_dim();
    scratch.clear();
    scratch.resize(3 * d, S::zero());
    let (grad, rest) = scratch.split_at_mut(d);
    let (score, score_sum) = rest.split_at_mut(d);
    let rows = features.chunks_exact(policy.feature_dim().max(1));
    for ((phi, y), a) in rows.zip(labels).zip(actions) {
        policy.causal_step_trusted(theta, phi, y.borrow(), a, grad, score, g, score_sum)?;
    }
    Ok(())
}

/// `g += ∇l_t + l_t Σ_{i<t} ψ_i` entry by entry, then `Σ_{i<t} ψ_i += ψ_t`: the unit-weight update
/// of the causal estimator (the default [`Policy::causal_step_trusted`]).
#[inline]
pub(crate) fn causal_accumulate<S: Scalar>(
    g: &mut [S],
    l: &S,
    grad: &[S],
    score: &[S],
    score_sum: &mut [S],
) {
    for ((gj, dj), sj) in g.iter_mut().zip(grad).zip(score_sum.iter()) {
        *gj += dj.clone() + l.clone() * sj;
    }
    for (sj, pj) in score_sum.iter_mut().zip(score) {
        *sj += pj;
    }
}

/// Copy `src` into `dst`, checking the length (the default `*_into` methods of [`Policy`]).
fn copy_into<S: Scalar>(param: &'static str, src: &[S], dst: &mut [S]) -> Result<(), PolicyError> {
    if src.len() != dst.len() {
        return Err(PolicyError::Shape {
            param,
            expected: src.len(),
            got: dst.len(),
        });
    }
    dst.clone_from_slice(src);
    Ok(())
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

/// The per-decision likelihood ratio of importance-weighted estimates (math.md §4):
/// `log π_θ(a|s) − log π_θ'(a|s)`, so that the weight of one decision is its exponential and the
/// trajectory weight `w_{θ→θ'}` is the exponential of the sum over decisions.
pub trait LikelihoodRatio<S: Scalar>: Policy<S> {
    /// `log π_θ(a|s) − log π_{θ_other}(a|s)`.
    ///
    /// # Errors
    /// As [`Policy::score`].
    fn log_likelihood_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &Self::Action,
    ) -> Result<S, PolicyError>;
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

/// The row-major outer product `u vᵀ` (the shape of every gradient with respect to a weight matrix).
pub(crate) fn outer<S: Scalar>(u: &[S], v: &[S]) -> Vec<S> {
    u.iter()
        .flat_map(|ui| v.iter().map(move |vj| ui.clone() * vj))
        .collect()
}
