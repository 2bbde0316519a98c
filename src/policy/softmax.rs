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
    LikelihoodRatio, Policy, PolicyError, check_out, check_size, check_vec, check_vec_scalar,
    from_f64_exact, mat_vec,
};
use crate::problem::KitRng;
use crate::sampling::{dyadic_uniform, sample_categorical};
use crate::scalar::{Real, Scalar};

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

/// `exp(x)`, with `exp(0) = 1` exactly, without calling `exp` when x is exactly zero (in every
/// component: a dual number with a non-zero derivative part is not zero). The shifted largest
/// logit `z_max − c` is zero whenever the logit is a point, so one `exp` of every softmax is
/// skipped; the value is the same, bit for bit in `f64` (`exp(±0) = 1`).
#[inline]
fn shifted_exp<S: Real>(x: &S) -> S {
    if *x == S::zero() { S::one() } else { x.exp() }
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
    let e: Vec<S> = logits
        .iter()
        .map(|z| shifted_exp(&(z.clone() - &c)))
        .collect();
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
        .fold(S::zero(), |acc, z| acc + shifted_exp(&(z.clone() - &c)));
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
    // Left to right, as the in-place pass sums it (whatever the number of actions).
    let mean_r = r
        .iter()
        .zip(probs)
        .fold(S::zero(), |acc, (x, p)| acc + x.clone() * p);
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

/// Up to this many actions, the per-call scratch of [`Softmax`] (logits, then probabilities) lives
/// on the stack: its `*_into` methods, [`Policy::sample`] and [`Softmax::log_prob`] then allocate
/// nothing (more actions: one scratch vector per call).
const INLINE_ACTIONS: usize = 16;

/// Run `f` on `len` zeros of scratch: on the stack for `len ≤ INLINE_ACTIONS`, else in a vector.
#[inline]
fn with_scratch<S: Scalar, R>(len: usize, f: impl FnOnce(&mut [S]) -> R) -> R {
    if len <= INLINE_ACTIONS {
        let mut buf: [S; INLINE_ACTIONS] = std::array::from_fn(|_| S::zero());
        f(&mut buf[..len])
    } else {
        f(&mut vec![S::zero(); len])
    }
}

/// `with_scratch(len, |p| body)`, with the body compiled a second time for two actions
/// (CartPole's) on scratch of exactly two entries: knowing the length, the compiler unrolls the
/// body's loops over the actions. The same operations in the same order either way. The body's
/// `?` returns from the closure or from the enclosing function, with the same error.
macro_rules! on_scratch {
    ($s:ty, $len:expr, |$p:ident| $body:expr) => {{
        let len = $len;
        if len == 2 {
            let mut buf = [<$s as Scalar>::zero(), <$s as Scalar>::zero()];
            let $p: &mut [$s] = &mut buf;
            $body
        } else {
            with_scratch::<$s, _>(len, |$p| $body)
        }
    }};
}

/// [`softmax_probs`] in place: the logits in `z` become the probabilities (the same operations in
/// the same order, so the same values and errors).
#[inline]
fn softmax_in_place<S: Real>(z: &mut [S]) -> Result<(), PolicyError> {
    if z.is_empty() {
        return Err(PolicyError::NonFinite { param: "logits" });
    }
    let c = shift(z)?;
    for x in z.iter_mut() {
        *x = shifted_exp(&(x.clone() - &c));
    }
    let total = crate::scalar::sum(&*z);
    for x in z.iter_mut() {
        *x = x.clone() / &total;
    }
    if !z.iter().all(Scalar::is_finite) {
        return Err(PolicyError::NonFinite { param: "softmax" });
    }
    Ok(())
}

/// The Brier loss `Σ_a (π_a − 1[a = a*])²` alone: the loss of [`brier_into`] (the same operations
/// in the same order).
#[inline]
fn brier_loss<S: Scalar>(probs: &[S], expert: usize) -> S {
    let mut loss = S::zero();
    for (a, p) in probs.iter().enumerate() {
        let r = if a == expert {
            p.clone() - S::one()
        } else {
            p.clone()
        };
        loss += r.square();
    }
    loss
}

/// [`brier_logit_gradient`] followed by the outer product with φ, written into `grad` (row-major
/// `A × n`) without intermediate vectors; returns the loss. The same operations in the same order.
#[inline]
fn brier_into<S: Scalar>(probs: &[S], expert: usize, phi: &[S], grad: &mut [S]) -> S {
    let r = |a: usize, p: &S| {
        if a == expert {
            p.clone() - S::one()
        } else {
            p.clone()
        }
    };
    let loss = brier_loss(probs, expert);
    let mut mean_r = S::zero();
    for (a, p) in probs.iter().enumerate() {
        mean_r += r(a, p) * p;
    }
    let n = phi.len();
    for ((a, p), row) in probs.iter().enumerate().zip(grad.chunks_exact_mut(n)) {
        let dz = S::from_i64(2) * p * (r(a, p) - &mean_r);
        for (g, x) in row.iter_mut().zip(phi) {
            *g = dz.clone() * x;
        }
    }
    loss
}

/// `(e_a − π)φᵀ` written into `score` (row-major `A × n`), as [`Policy::score_into`] of [`Softmax`].
#[inline]
fn score_into_rows<S: Scalar>(probs: &[S], action: usize, phi: &[S], score: &mut [S]) {
    let n = phi.len();
    for ((b, p), row) in probs.iter().enumerate().zip(score.chunks_exact_mut(n)) {
        let c = if action == b {
            S::one() - p
        } else {
            -p.clone()
        };
        for (s, x) in row.iter_mut().zip(phi) {
            *s = c.clone() * x;
        }
    }
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

    /// `log π_Θ(a|s)` (for importance weights). Allocates nothing for up to 16 actions.
    ///
    /// # Errors
    /// As [`Softmax::logits`] and [`log_softmax`].
    pub fn log_prob<S: Real>(&self, theta: &[S], phi: &[S], a: usize) -> Result<S, PolicyError> {
        on_scratch!(S, self.actions, |z| {
            self.logits_into(theta, phi, z)?;
            log_softmax(z, a)
        })
    }

    /// [`Softmax::logits`] into `z` (length A).
    #[inline]
    fn logits_into<S: Scalar>(
        &self,
        theta: &[S],
        phi: &[S],
        z: &mut [S],
    ) -> Result<(), PolicyError> {
        check_vec("theta", theta, self.actions * self.features)?;
        check_vec("phi", phi, self.features)?;
        self.logits_validated_into(theta, phi, z);
        Ok(())
    }

    /// [`Softmax::logits_into`] without its checks of θ and φ (callers have checked them).
    #[inline]
    fn logits_validated_into<S: Scalar>(&self, theta: &[S], phi: &[S], z: &mut [S]) {
        for (zi, row) in z.iter_mut().zip(theta.chunks_exact(self.features)) {
            *zi = crate::scalar::dot(row, phi);
        }
    }

    /// [`Softmax::probs`] into `p` (length A).
    #[inline]
    fn probs_into<S: Real>(&self, theta: &[S], phi: &[S], p: &mut [S]) -> Result<(), PolicyError> {
        self.logits_into(theta, phi, p)?;
        softmax_in_place(p)
    }

    /// [`Softmax::probs_into`] without its checks of θ and φ (callers have checked them): the
    /// same operations, so the same probabilities and the same softmax error.
    #[inline]
    fn probs_validated_into<S: Real>(
        &self,
        theta: &[S],
        phi: &[S],
        p: &mut [S],
    ) -> Result<(), PolicyError> {
        self.logits_validated_into(theta, phi, p);
        softmax_in_place(p)
    }

    /// [`Policy::sample`] for a θ the caller has checked (length and finiteness); φ is checked
    /// as [`Policy::sample`] checks it. For such a θ the same action and the same errors.
    ///
    /// # Errors
    /// As [`Policy::sample`].
    #[inline]
    pub(crate) fn sample_validated_theta<S: Real>(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<usize, PolicyError> {
        // Entry by entry: φ was just written by the roll-out (see `check_vec_scalar`).
        check_vec_scalar("phi", phi, self.features)?;
        on_scratch!(S, self.actions, |p| {
            self.probs_validated_into(theta, phi, p)?;
            sample_probs(p, rng)
        })
    }

    /// [`Policy::loss_score_into`] for a θ and φ the caller has checked (lengths and
    /// finiteness): the same operations after those checks, so the same values and, for such
    /// inputs, the same errors in the same order.
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`].
    #[inline]
    pub(crate) fn loss_score_validated<S: Real>(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        action: &usize,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(*label, self.actions)?;
        on_scratch!(S, self.actions, |p| {
            self.probs_validated_into(theta, phi, p)?;
            self.loss_score_from_probs(p, phi, *label, *action, grad, score)
        })
    }

    /// [`Softmax::loss_score_validated`] after the probabilities: from π = `probs` (those
    /// of θ at φ, e.g. noted when the action was sampled), the same operations, values and
    /// errors.
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`] for a bad label, action or buffer length.
    #[inline]
    pub(crate) fn loss_score_from_probs<S: Scalar>(
        &self,
        probs: &[S],
        phi: &[S],
        label: usize,
        action: usize,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(label, self.actions)?;
        check_out("grad", grad, self.actions * self.features)?;
        let l = brier_into(probs, label, phi, grad);
        check_action(action, self.actions)?;
        check_out("score", score, self.actions * self.features)?;
        score_into_rows(probs, action, phi, score);
        Ok(l)
    }

    /// [`Softmax::sample_validated_theta`], appending the probabilities π it sampled from to
    /// `notes` (A entries; nothing on an error).
    ///
    /// # Errors
    /// As [`Policy::sample`].
    #[inline]
    pub(crate) fn sample_noting_probs<S: Real>(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
        notes: &mut Vec<S>,
    ) -> Result<usize, PolicyError> {
        check_vec_scalar("phi", phi, self.features)?;
        on_scratch!(S, self.actions, |p| {
            self.probs_validated_into(theta, phi, p)?;
            notes.extend_from_slice(p);
            sample_probs(p, rng)
        })
    }

    /// The loss of [`Policy::loss_into`] without its gradient, for a θ and φ the caller has
    /// checked (lengths and finiteness): the same value and, for such inputs, the same errors.
    ///
    /// # Errors
    /// As [`Policy::loss_into`].
    #[inline]
    pub(crate) fn loss_only_validated<S: Real>(
        &self,
        theta: &[S],
        phi: &[S],
        label: usize,
    ) -> Result<S, PolicyError> {
        check_action(label, self.actions)?;
        on_scratch!(S, self.actions, |p| {
            self.probs_validated_into(theta, phi, p)?;
            Ok(brier_loss(p, label))
        })
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

    /// Allocates nothing for up to 16 actions (the probabilities in stack scratch).
    #[inline]
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<usize, PolicyError> {
        check_vec("theta", theta, self.actions * self.features)?;
        self.sample_validated_theta(theta, phi, rng)
    }

    /// Brier loss against the expert action `label`: `∇_Θ l = (∂l/∂z)φᵀ` with ∂l/∂z from
    /// [`brier_logit_gradient`], written into `grad`; allocates nothing for up to 16 actions.
    #[inline]
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(*label, self.actions)?;
        on_scratch!(S, self.actions, |p| {
            self.probs_into(theta, phi, p)?;
            check_out("grad", grad, self.actions * self.features)?;
            Ok(brier_into(p, *label, phi, grad))
        })
    }

    /// `∇_Θ log π(a|s) = (e_a − π)φᵀ` written into `score`; allocates nothing for up to 16
    /// actions.
    #[inline]
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &usize,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        check_action(*action, self.actions)?;
        on_scratch!(S, self.actions, |p| {
            self.probs_into(theta, phi, p)?;
            check_out("score", score, self.actions * self.features)?;
            score_into_rows(p, *action, phi, score);
            Ok(())
        })
    }

    /// Loss, gradient and score with the probabilities computed once (the values and the order of
    /// the errors of [`Policy::loss_into`] then [`Policy::score_into`]).
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
        check_action(*label, self.actions)?;
        check_vec("theta", theta, self.actions * self.features)?;
        check_vec("phi", phi, self.features)?;
        self.loss_score_validated(theta, phi, label, action, grad, score)
    }
}

impl<S: Real> LikelihoodRatio<S> for Softmax {
    fn log_prob(&self, theta: &[S], phi: &[S], action: &usize) -> Result<S, PolicyError> {
        Softmax::log_prob(self, theta, phi, *action)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::PolicyExt;
    use crate::scalar::Dual;
    use rand::{Rng, SeedableRng};

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// The allocation-free methods against the allocating computation (the Brier gradient and
    /// the score formed from `probs` as vectors, then their outer products with φ;
    /// `sample_categorical` on `probs`, `log_softmax` on `logits`): bit-for-bit, on random inputs,
    /// for action counts on both sides of the stack scratch's size.
    #[test]
    fn in_place_methods_match_the_allocating_computation_bit_for_bit() {
        let mut rng = KitRng::seed_from_u64(3);
        let mut checked = 0;
        for &(actions, features) in &[(2, 5), (2, 1), (3, 4), (16, 2), (17, 3), (40, 1)] {
            let pi = Softmax::new(actions, features).unwrap();
            let d = actions * features;
            for trial in 0..50 {
                let scale = [0.1, 1.0, 30.0, 400.0][trial % 4];
                let theta: Vec<f64> = (0..d)
                    .map(|_| scale * (rng.random::<f64>() - 0.5))
                    .collect();
                let phi: Vec<f64> = (0..features)
                    .map(|_| rng.random::<f64>() * 2.0 - 1.0)
                    .collect();
                let label = rng.random_range(0..actions);
                let action = rng.random_range(0..actions);
                // The allocating computation: the probabilities, ∂l/∂z and e_a − π as vectors,
                // then their outer products with φ.
                let outer = |u: &[f64]| -> Vec<f64> {
                    u.iter()
                        .flat_map(|a| phi.iter().map(move |b| a * b))
                        .collect()
                };
                let p = pi.probs(&theta, &phi).unwrap();
                let (l, dz) = brier_logit_gradient(&p, label);
                let g = outer(&dz);
                let s = outer(&score_logits(&p, action));
                let mut grad = vec![f64::NAN; d];
                let mut score = vec![f64::NAN; d];
                let l2 = pi.loss_into(&theta, &phi, &label, &mut grad).unwrap();
                assert_eq!((l.to_bits(), bits(&g)), (l2.to_bits(), bits(&grad)));
                assert_eq!(
                    l.to_bits(),
                    pi.loss_only_validated(&theta, &phi, label)
                        .unwrap()
                        .to_bits()
                );
                pi.score_into(&theta, &phi, &action, &mut score).unwrap();
                assert_eq!(bits(&s), bits(&score));
                grad.fill(f64::NAN);
                score.fill(f64::NAN);
                let l3 = pi
                    .loss_score_into(&theta, &phi, &label, &action, &mut grad, &mut score)
                    .unwrap();
                assert_eq!((l.to_bits(), bits(&g)), (l3.to_bits(), bits(&grad)));
                assert_eq!(bits(&s), bits(&score));
                let old = log_softmax(&pi.logits(&theta, &phi).unwrap(), action).unwrap();
                assert_eq!(
                    old.to_bits(),
                    pi.log_prob(&theta, &phi, action).unwrap().to_bits()
                );
                let mut r1 = KitRng::seed_from_u64(trial as u64);
                let mut r2 = r1.clone();
                let probs = pi.probs(&theta, &phi).unwrap();
                let u: f64 = dyadic_uniform(&mut r1);
                let a_old = sample_categorical(&probs, &u).unwrap();
                assert_eq!(a_old, Policy::sample(&pi, &theta, &phi, &mut r2).unwrap());
                assert_eq!(r1, r2, "the same draws");
                checked += 1;
            }
        }
        assert_eq!(checked, 300);
    }

    /// The same errors as the allocating computation, and dual numbers through the same path.
    #[test]
    fn in_place_methods_keep_the_errors_and_work_in_dual_numbers() {
        let pi = Softmax::new(3, 2).unwrap();
        let theta = [0.5, -1.0, 2.0, 0.25, -0.75, 1.5];
        let mut grad = [0.0; 6];
        let mut score = [0.0; 6];
        for phi in [[f64::NAN, 1.0], [1.0, f64::INFINITY], [1e308, 1e308]] {
            let old = pi.loss(&theta, &phi, &0).unwrap_err();
            assert_eq!(pi.loss_into(&theta, &phi, &0, &mut grad), Err(old.clone()));
            assert_eq!(
                pi.loss_score_into(&theta, &phi, &0, &1, &mut grad, &mut score),
                Err(old.clone())
            );
            assert_eq!(
                pi.score_into(&theta, &phi, &1, &mut score),
                Err(old.clone())
            );
            let mut rng = KitRng::seed_from_u64(1);
            assert_eq!(Policy::sample(&pi, &theta, &phi, &mut rng), Err(old));
        }
        let phi = [0.5, -0.5];
        assert_eq!(
            pi.loss_into(&theta, &phi, &3, &mut grad),
            pi.loss(&theta, &phi, &3).map(|(l, _)| l)
        );
        assert_eq!(
            pi.loss_only_validated(&theta, &phi, 3),
            pi.loss(&theta, &phi, &3).map(|(l, _)| l)
        );
        assert!(matches!(
            pi.loss_into(&theta, &phi, &1, &mut grad[..5]),
            Err(PolicyError::Shape { param: "grad", .. })
        ));
        assert_eq!(pi.log_prob(&theta, &phi, 3), log_softmax(&[0.0; 3], 3));
        // Dual numbers (derivatives with respect to θ): the in-place values are the allocating
        // ones, derivatives included.
        let th: Vec<Dual<f64>> = theta
            .iter()
            .enumerate()
            .map(|(i, &x)| Dual::variable(x, i, 6))
            .collect();
        let ph: Vec<Dual<f64>> = phi.iter().map(|&x| Dual::constant(x)).collect();
        let (l, g) = pi.loss(&th, &ph, &2).unwrap();
        let mut gi = vec![Dual::zero(); 6];
        let mut si = vec![Dual::zero(); 6];
        let li = pi
            .loss_score_into(&th, &ph, &2, &0, &mut gi, &mut si)
            .unwrap();
        assert_eq!(pi.loss_only_validated(&th, &ph, 2).unwrap(), l);
        assert_eq!((l, g), (li, gi));
        assert_eq!(pi.score(&th, &ph, &0).unwrap(), si);
    }

    /// The skipped `exp` gives `exp`'s value: ±0 and other numbers in `f64` (bit for bit), and a
    /// dual number at 0 with a non-zero derivative (not skipped: its derivative is exp's).
    #[test]
    fn shifted_exp_is_exp() {
        for x in [0.0f64, -0.0, 1e-300, -2.5, 3.0] {
            assert_eq!(shifted_exp(&x).to_bits(), x.exp().to_bits());
        }
        let d = Dual::variable(0.0, 0, 1);
        assert_eq!(shifted_exp(&d), d.exp());
        assert_ne!(shifted_exp(&d), Dual::<f64>::constant(1.0));
        let zero = <Dual<f64> as Scalar>::zero();
        assert_eq!(shifted_exp(&zero), zero.exp());
    }
}
