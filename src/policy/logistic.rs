//! The logistic policy: two actions, one parameter vector, `π_θ(1|s) = σ(θ·φ(s))`.
//!
//! It is the two-action softmax with logits `(0, θ·φ)` and half the parameters. With
//! `p = σ(z)`, `z = θ·φ`, `σ′ = p(1 − p)` and the expert's label `y = 1[a*(s) = 1]`:
//!
//! | quantity | formula |
//! |---|---|
//! | Brier loss (math.md §1.2, n = 2) | `l = 2(p − y)²`, `∇_θ l = 4(p − y)p(1 − p)φ` |
//! | score | `∇_θ log π(1\|s) = (1 − p)φ`, `∇_θ log π(0\|s) = −pφ`, i.e. `(a − p)φ` |
//! | log-probability | `log π(1\|s) = −softplus(−z)`, `log π(0\|s) = −softplus(z)` |
//!
//! **Layout of θ**: `θ ∈ Sⁿ`, the weight of feature j at index j.

use super::softmax::check_action;
use super::{LikelihoodRatio, Policy, PolicyError, check_out, check_size, check_vec};
use crate::problem::KitRng;
use crate::sampling::{dyadic_uniform, sample_binary};
use crate::scalar::{Real, Scalar};

/// Whether the logit `z` and its `f64` approximation are finite (the check of
/// [`logistic_sigmoid`] and [`softplus`]).
#[inline]
pub(crate) fn finite_logit<S: Scalar>(z: &S) -> bool {
    z.is_finite() & z.to_f64().is_finite()
}

/// The sign of the f64 approximation of `z` (decides which of two exact formulas is overflow-free).
#[inline]
fn nonnegative<S: Scalar>(z: &S, param: &'static str) -> Result<bool, PolicyError> {
    if !finite_logit(z) {
        return Err(PolicyError::NonFinite { param });
    }
    Ok(z.to_f64() >= 0.0)
}

/// [`logistic_sigmoid`] without its check (for a `z` checked with [`finite_logit`]).
#[inline]
pub(crate) fn sigmoid_of_finite<S: Real>(z: &S) -> S {
    if z.to_f64() >= 0.0 {
        S::one() / (S::one() + (-z.clone()).exp())
    } else {
        let e = z.exp();
        e.clone() / (S::one() + e)
    }
}

/// `σ(z) = 1/(1 + e^{−z})`, evaluated as `1/(1 + e^{−z})` for `z ≥ 0` and `e^z/(1 + e^z)` otherwise.
/// Both are exact identities, so branching on the `f64` approximation of z keeps intervals rigorous;
/// the branch only avoids overflow.
///
/// # Errors
/// [`PolicyError::NonFinite`] for a non-finite `z`.
#[inline]
pub fn logistic_sigmoid<S: Real>(z: &S) -> Result<S, PolicyError> {
    if !finite_logit(z) {
        return Err(PolicyError::NonFinite { param: "logit" });
    }
    Ok(sigmoid_of_finite(z))
}

/// `softplus(z) = ln(1 + e^z)`, evaluated as `z + ln(1 + e^{−z})` for `z ≥ 0` (exact identity,
/// overflow-free) and `ln(1 + e^z)` otherwise.
///
/// # Errors
/// [`PolicyError::NonFinite`] for a non-finite `z`.
pub fn softplus<S: Real>(z: &S) -> Result<S, PolicyError> {
    if nonnegative(z, "logit")? {
        Ok(z.clone() + (S::one() + (-z.clone()).exp()).ln())
    } else {
        Ok((S::one() + z.exp()).ln())
    }
}

/// The Brier loss of the logistic policy and its derivative in the logit: `(l, ∂l/∂z)` with
/// `l = 2(p − y)²` and `∂l/∂z = 4(p − y)p(1 − p)`, `y = 1[label = 1]`, for `p = σ(z)`. The one place
/// this arithmetic is written: the loss, its in-place form and the estimator kernel all call it.
#[inline(always)]
pub(crate) fn brier<S: Scalar>(p: &S, label: usize) -> (S, S) {
    let r = if label == 1 {
        p.clone() - S::one()
    } else {
        p.clone()
    };
    let dz = S::from_i64(4) * &r * p * (S::one() - p);
    (S::from_i64(2) * r.square(), dz)
}

/// The score's coefficient `a − p` (`∇_θ log π_θ(a|s) = (a − p)φ` for `p = π_θ(1|s)`).
#[inline(always)]
pub(crate) fn score_coefficient<S: Scalar>(p: S, action: usize) -> S {
    if action == 1 { S::one() - p } else { -p }
}

/// `l = 2(p − y)²` with `4(p − y)p(1 − p)φ` written into `grad` ([`brier`]).
#[inline]
fn brier_into<S: Scalar>(p: &S, label: usize, phi: &[S], grad: &mut [S]) -> S {
    let (l, dz) = brier(p, label);
    for (g, x) in grad.iter_mut().zip(phi) {
        *g = dz.clone() * x;
    }
    l
}

/// `(a − p)φ` written into `score`.
#[inline]
fn score_of<S: Scalar>(p: S, action: usize, phi: &[S], score: &mut [S]) {
    let c = score_coefficient(p, action);
    for (s, x) in score.iter_mut().zip(phi) {
        *s = c.clone() * x;
    }
}

/// The logistic policy over `n ≥ 1` features (actions 0 and 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Logistic {
    features: usize,
}

impl Logistic {
    /// A validated policy.
    ///
    /// # Errors
    /// [`PolicyError::TooSmall`] for `features = 0`.
    pub fn new(features: usize) -> Result<Self, PolicyError> {
        check_size("features", features, 1)?;
        Ok(Self { features })
    }

    /// The logit `z = θ·φ`.
    ///
    /// # Errors
    /// [`PolicyError::Shape`] / [`PolicyError::NonFinite`] for a bad θ or φ.
    #[inline]
    pub fn logit<S: Scalar>(&self, theta: &[S], phi: &[S]) -> Result<S, PolicyError> {
        check_vec("theta", theta, self.features)?;
        check_vec("phi", phi, self.features)?;
        Ok(crate::scalar::dot(theta, phi))
    }

    /// `p = π_θ(1|s) = σ(θ·φ)`.
    ///
    /// # Errors
    /// As [`Logistic::logit`].
    #[inline]
    pub fn prob_one<S: Real>(&self, theta: &[S], phi: &[S]) -> Result<S, PolicyError> {
        logistic_sigmoid(&self.logit(theta, phi)?)
    }

    /// `log π_θ(a|s)`: `−softplus(−z)` for a = 1, `−softplus(z)` for a = 0.
    ///
    /// # Errors
    /// As [`Logistic::logit`], and [`PolicyError::Action`] for `a > 1`.
    pub fn log_prob<S: Real>(&self, theta: &[S], phi: &[S], a: usize) -> Result<S, PolicyError> {
        check_action(a, 2)?;
        let z = self.logit(theta, phi)?;
        Ok(if a == 1 {
            -softplus(&-z)?
        } else {
            -softplus(&z)?
        })
    }
}

impl<S: Real> Policy<S> for Logistic {
    type Action = usize;
    type Label = usize;

    fn param_dim(&self) -> usize {
        self.features
    }
    fn feature_dim(&self) -> usize {
        self.features
    }

    /// `l = 2(p − y)²` with `y = 1[label = 1]`, writing `∇l = 4(p − y)p(1 − p)φ` into `grad`.
    #[inline]
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(*label, 2)?;
        check_out("grad", grad, self.features)?;
        let p = self.prob_one(theta, phi)?;
        Ok(brier_into(&p, *label, phi, grad))
    }

    /// `∇_θ log π(a|s) = (a − p)φ` written into `score`.
    #[inline]
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &usize,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        check_action(*action, 2)?;
        check_out("score", score, self.features)?;
        let p = self.prob_one(theta, phi)?;
        score_of(p, *action, phi, score);
        Ok(())
    }

    /// Loss, gradient and score with `p = σ(θ·φ)` computed once.
    #[inline]
    fn loss_score_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        action: &usize,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(*label, 2)?;
        check_out("grad", grad, self.features)?;
        let p = self.prob_one(theta, phi)?;
        let l = brier_into(&p, *label, phi, grad);
        check_action(*action, 2)?;
        check_out("score", score, self.features)?;
        score_of(p, *action, phi, score);
        Ok(l)
    }

    /// One dyadic uniform `u`; action 0 if `u < 1 − p`, else 1 (as the two-action softmax).
    #[inline]
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<usize, PolicyError> {
        let p = self.prob_one(theta, phi)?;
        let u: S = dyadic_uniform(rng);
        Ok(sample_binary(&u, S::one() - &p, &p)?)
    }
}

impl<S: Real> LikelihoodRatio<S> for Logistic {
    fn log_prob(&self, theta: &[S], phi: &[S], action: &usize) -> Result<S, PolicyError> {
        Logistic::log_prob(self, theta, phi, *action)
    }
}
