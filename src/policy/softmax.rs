//! Softmax over linear features for discrete actions: `π_Θ(a|s) = softmax(Θφ(s))_a`.
//!
//! With logits `z = Θφ` and `π = softmax(z)`:
//!
//! | quantity | formula |
//! |---|---|
//! | Jacobian of the softmax | `∂π_a/∂z_b = π_a(δ_ab − π_b)` |
//! | Brier loss (math.md §1.2 L-Brier) | `l = Σ_a (π_a − 1[a = a*])²`, `∂l/∂z_b = 2π_b(r_b − Σ_a r_a π_a)`, `r_a = π_a − 1[a = a*]` |
//! | score | `∇_z log π_a = e_a − π`, so `∇_Θ log π(a\|s) = (e_a − π)φᵀ` |
//! | log-probability | `log π_a = (z_a − c) − ln Σ_b exp(z_b − c)` |
//!
//! and every gradient with respect to Θ is `(∂/∂z) φᵀ`. The logit-level functions
//! ([`softmax_probs`], [`brier_logit_gradient`]) are shared with the MLP head.
//!
//! **Stability without losing rigour.** `softmax(z) = softmax(z − c)` for *any* constant c, exactly.
//! The shift c is the largest logit's `f64` approximation, converted exactly to `S`
//! ([`from_f64_exact`](super::from_f64_exact)): in `f64` this is the usual max-shift (no overflow),
//! and in intervals it is an exact point, so the enclosure stays rigorous.
//!
//! **Layout of θ**: Θ ∈ S^{A×n} row-major, `θ[a·n + j] = Θ_aj`.

use super::{
    LikelihoodRatio, Policy, PolicyError, check_size, check_vec, from_f64_exact, mat_vec, outer,
};
use crate::problem::KitRng;
use crate::scalar::{Real, Scalar};
use crate::toy::{dyadic_uniform, sample_categorical};

/// The exact shift used by [`softmax_probs`] and [`log_softmax`]: the largest logit's `f64` value.
fn shift<S: Scalar>(logits: &[S]) -> Result<S, PolicyError> {
    let mut max = f64::NEG_INFINITY;
    for z in logits {
        let x = z.to_f64();
        if !x.is_finite() || !z.is_finite() {
            return Err(PolicyError::NonFinite { param: "logits" });
        }
        max = max.max(x);
    }
    from_f64_exact(max, "logits")
}

/// `π = softmax(z)`, computed as `exp(z_a − c)/Σ_b exp(z_b − c)` with the exact shift described in
/// the module docs.
///
/// # Errors
/// [`PolicyError::NonFinite`] for an empty or non-finite logit vector.
pub fn softmax_probs<S: Real>(logits: &[S]) -> Result<Vec<S>, PolicyError> {
    if logits.is_empty() {
        return Err(PolicyError::NonFinite { param: "logits" });
    }
    let c = shift(logits)?;
    let e: Vec<S> = logits.iter().map(|z| (z.clone() - &c).exp()).collect();
    let total = crate::scalar::sum(&e);
    let p: Vec<S> = e.into_iter().map(|x| x / &total).collect();
    if !p.iter().all(Scalar::is_finite) {
        return Err(PolicyError::NonFinite { param: "softmax" });
    }
    Ok(p)
}

/// `log softmax(z)_a = (z_a − c) − ln Σ_b exp(z_b − c)` (same shift as [`softmax_probs`]).
///
/// # Errors
/// As [`softmax_probs`], and [`PolicyError::Action`] for `a` out of range.
pub fn log_softmax<S: Real>(logits: &[S], a: usize) -> Result<S, PolicyError> {
    if a >= logits.len() {
        return Err(PolicyError::Action {
            action: a,
            actions: logits.len(),
        });
    }
    let c = shift(logits)?;
    let total = logits
        .iter()
        .fold(S::zero(), |acc, z| acc + (z.clone() - &c).exp());
    Ok(logits[a].clone() - &c - total.ln())
}

/// The Brier loss `l = Σ_a (π_a − 1[a = a*])²` of math.md §1.2 and its gradient with respect to the
/// logits, `∂l/∂z_b = 2π_b(r_b − Σ_a r_a π_a)` with `r_a = π_a − 1[a = a*]` (from
/// `∂π_a/∂z_b = π_a(δ_ab − π_b)`). Needs only field operations.
///
/// `expert` must be `< probs.len()` (callers check it).
pub fn brier_logit_gradient<S: Scalar>(probs: &[S], expert: usize) -> (S, Vec<S>) {
    let r: Vec<S> = probs
        .iter()
        .enumerate()
        .map(|(a, p)| {
            if a == expert {
                p.clone() - S::one()
            } else {
                p.clone()
            }
        })
        .collect();
    let loss = crate::scalar::norm_sq(&r);
    let mean_r = crate::scalar::dot(&r, probs);
    let grad = probs
        .iter()
        .zip(&r)
        .map(|(p, rb)| S::from_i64(2) * p * (rb.clone() - &mean_r))
        .collect();
    (loss, grad)
}

/// `e_a − π`: the score with respect to the logits.
pub(crate) fn score_logits<S: Scalar>(probs: &[S], a: usize) -> Vec<S> {
    probs
        .iter()
        .enumerate()
        .map(|(b, p)| if a == b { S::one() - p } else { -p.clone() })
        .collect()
}

/// Sample a category: one dyadic uniform `u = k/2⁵³` (the toy engine's draw), then the first
/// action whose cumulative probability certainly exceeds `u`.
#[inline]
pub(crate) fn sample_probs<S: Scalar>(probs: &[S], rng: &mut KitRng) -> Result<usize, PolicyError> {
    let u: S = dyadic_uniform(rng);
    Ok(sample_categorical(probs, &u)?)
}

#[inline]
pub(crate) fn check_action(a: usize, actions: usize) -> Result<(), PolicyError> {
    if a >= actions {
        return Err(PolicyError::Action { action: a, actions });
    }
    Ok(())
}

/// The linear softmax policy with `A ≥ 2` actions over `n ≥ 1` features.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Softmax {
    actions: usize,
    features: usize,
}

impl Softmax {
    /// A validated policy.
    ///
    /// # Errors
    /// [`PolicyError::TooSmall`] for `actions < 2` or `features = 0`.
    pub fn new(actions: usize, features: usize) -> Result<Self, PolicyError> {
        check_size("actions", actions, 2)?;
        check_size("features", features, 1)?;
        Ok(Self { actions, features })
    }

    /// Number of actions A.
    pub fn actions(&self) -> usize {
        self.actions
    }

    /// The logits `z = Θφ`.
    ///
    /// # Errors
    /// [`PolicyError::Shape`] / [`PolicyError::NonFinite`] for a bad θ or φ.
    pub fn logits<S: Scalar>(&self, theta: &[S], phi: &[S]) -> Result<Vec<S>, PolicyError> {
        check_vec("theta", theta, self.actions * self.features)?;
        check_vec("phi", phi, self.features)?;
        Ok(mat_vec(theta, phi, self.actions))
    }

    /// The action probabilities `π_Θ(·|s) = softmax(Θφ)`.
    ///
    /// # Errors
    /// As [`Softmax::logits`] and [`softmax_probs`].
    pub fn probs<S: Real>(&self, theta: &[S], phi: &[S]) -> Result<Vec<S>, PolicyError> {
        softmax_probs(&self.logits(theta, phi)?)
    }

    /// `log π_Θ(a|s)` (for importance weights).
    ///
    /// # Errors
    /// As [`log_softmax`].
    pub fn log_prob<S: Real>(&self, theta: &[S], phi: &[S], a: usize) -> Result<S, PolicyError> {
        log_softmax(&self.logits(theta, phi)?, a)
    }
}

impl<S: Real> Policy<S> for Softmax {
    type Action = usize;
    type Label = usize;

    fn param_dim(&self) -> usize {
        self.actions * self.features
    }
    fn feature_dim(&self) -> usize {
        self.features
    }

    /// Brier loss against the expert action `label`: `∇_Θ l = (∂l/∂z)φᵀ` with ∂l/∂z from
    /// [`brier_logit_gradient`].
    fn loss(&self, theta: &[S], phi: &[S], label: &usize) -> Result<(S, Vec<S>), PolicyError> {
        check_action(*label, self.actions)?;
        let p = self.probs(theta, phi)?;
        let (l, dz) = brier_logit_gradient(&p, *label);
        Ok((l, outer(&dz, phi)))
    }

    /// `∇_Θ log π(a|s) = (e_a − π)φᵀ`.
    fn score(&self, theta: &[S], phi: &[S], action: &usize) -> Result<Vec<S>, PolicyError> {
        check_action(*action, self.actions)?;
        let p = self.probs(theta, phi)?;
        Ok(outer(&score_logits(&p, *action), phi))
    }

    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<usize, PolicyError> {
        sample_probs(&self.probs(theta, phi)?, rng)
    }
}

impl<S: Real> LikelihoodRatio<S> for Softmax {
    fn log_likelihood_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &usize,
    ) -> Result<S, PolicyError> {
        Ok(self.log_prob(theta, phi, *action)? - self.log_prob(theta_other, phi, *action)?)
    }
}
