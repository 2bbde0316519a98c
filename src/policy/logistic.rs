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
use super::{
    LikelihoodRatio, Policy, PolicyError, causal_sum_by_steps, check_out, check_size, check_vec,
    check_vec_scalar,
};
use crate::problem::KitRng;
use crate::sampling::{dyadic_uniform, sample_binary};
use crate::scalar::{Real, Scalar};
use std::borrow::Borrow;

/// Whether the logit `z` and its `f64` approximation are finite (the check of
/// [`logistic_sigmoid`] and [`softplus`]).
#[inline]
fn finite_logit<S: Scalar>(z: &S) -> bool {
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
fn sigmoid_of_finite<S: Real>(z: &S) -> S {
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

/// `l = 2(p − y)²` with `4(p − y)p(1 − p)φ` written into `grad` (the same operations, in the same
/// order, as [`Policy::loss`] of [`Logistic`]).
#[inline]
fn brier_into<S: Scalar>(p: &S, label: usize, phi: &[S], grad: &mut [S]) -> S {
    let r = if label == 1 {
        p.clone() - S::one()
    } else {
        p.clone()
    };
    let dz = S::from_i64(4) * &r * p * (S::one() - p);
    for (g, x) in grad.iter_mut().zip(phi) {
        *g = dz.clone() * x;
    }
    S::from_i64(2) * r.square()
}

/// `(a − p)φ` written into `score`.
#[inline]
fn score_of<S: Scalar>(p: S, action: usize, phi: &[S], score: &mut [S]) {
    let c = if action == 1 { S::one() - p } else { -p };
    for (s, x) in score.iter_mut().zip(phi) {
        *s = c.clone() * x;
    }
}

/// `z = θ·φ` with θ trusted (checked by the caller) and φ checked: its length, and its entries'
/// finiteness — where non-finite numbers propagate through sums and products
/// ([`Scalar::NON_FINITE_PROPAGATES`]: floats, rationals), by one test of `z` instead of one per
/// entry, the entries being looked at only to name the culprit. The same result and errors as
/// `check_vec_scalar("phi", …)` followed by the dot product and the sigmoid's test of `z`.
#[inline]
fn trusted_logit<S: Scalar>(theta: &[S], phi: &[S], features: usize) -> Result<S, PolicyError> {
    if S::NON_FINITE_PROPAGATES {
        check_out("phi", phi, features)?;
    } else {
        check_vec_scalar("phi", phi, features)?;
    }
    let z = crate::scalar::dot(theta, phi);
    if S::NON_FINITE_PROPAGATES && !z.is_finite() {
        return Err(non_finite_logit(phi));
    }
    Ok(z)
}

/// The error for a non-finite `θ·φ` with a finite θ: φ's if one of its entries is non-finite,
/// else the logit's (an overflow).
///
/// Inlined although it is an error path: a call that takes φ's address would keep a φ built in
/// a local array in memory ([`Task::push_features_then`](crate::task::Task::push_features_then)),
/// and the roll-out's `θ·φ` would load it back from there (measured about 8 % of the CartPole
/// roll-out, issue 8).
#[inline(always)]
fn non_finite_logit<S: Scalar>(phi: &[S]) -> PolicyError {
    let param = if phi.iter().all(Scalar::is_finite) {
        "logit"
    } else {
        "phi"
    };
    PolicyError::NonFinite { param }
}

/// [`Policy::causal_sum_trusted`] of [`Logistic`] with `N` features known at compile time: the
/// operations of [`Policy::causal_step_trusted`] in the same order, with `g` and `Σ_{i<t} ψ_i` in
/// `[S; N]` locals (registers for `f64`) and fully unrolled loops.
///
/// The per-decision checks (label and action in {0, 1}, a finite logit) are not branches: their
/// failures are collected in a flag, and `Ok(false)` (with `g` untouched) tells the caller that
/// some decision failed, for the default pass to find and report the first failure.
///
/// Not inlined: a function of its own per dimension, whose accumulators the register allocator
/// sees alone (inlined into the oracle's estimate, next to the other dimensions and the fallback
/// paths, it measured a few per cent slower).
#[inline(never)]
fn causal_sum_fixed<S: Real, L: Borrow<usize>, const N: usize>(
    theta: &[S],
    features: &[S],
    labels: &[L],
    actions: &[usize],
    g: &mut [S],
) -> Result<bool, PolicyError> {
    let theta: &[S; N] = theta.try_into().map_err(|_| PolicyError::Shape {
        param: "theta",
        expected: N,
        got: theta.len(),
    })?;
    check_out("g", g, N)?;
    let mut acc: [S; N] = std::array::from_fn(|j| g[j].clone());
    let mut score_sum: [S; N] = std::array::from_fn(|_| S::zero());
    let (rows, _) = features.as_chunks::<N>();
    let mut failed = false;
    for ((phi, label), action) in rows.iter().zip(labels).zip(actions) {
        let label = *label.borrow();
        let z = crate::scalar::dot(theta, phi);
        failed |= (label > 1) | (*action > 1) | !finite_logit(&z);
        let p = sigmoid_of_finite(&z);
        let r = if label == 1 {
            p.clone() - S::one()
        } else {
            p.clone()
        };
        let dz = S::from_i64(4) * &r * &p * (S::one() - &p);
        let l = S::from_i64(2) * r.square();
        let c = if *action == 1 { S::one() - p } else { -p };
        for ((gj, sj), x) in acc.iter_mut().zip(score_sum.iter_mut()).zip(phi) {
            *gj += dz.clone() * x + l.clone() * &*sj;
            *sj += c.clone() * x;
        }
    }
    if failed {
        return Ok(false);
    }
    g.clone_from_slice(&acc);
    Ok(true)
}

/// [`causal_sum_fixed`] with the per-decision loss shifts of [`Policy::causal_sum_shifted_trusted`]
/// (a baseline): the score sum is multiplied by `l_t + δ_t`, one addition per decision more.
#[inline(never)]
fn causal_sum_shifted_fixed<S: Real, L: Borrow<usize>, const N: usize>(
    theta: &[S],
    features: &[S],
    labels: &[L],
    actions: &[usize],
    shifts: &[S],
    g: &mut [S],
) -> Result<bool, PolicyError> {
    let theta: &[S; N] = theta.try_into().map_err(|_| PolicyError::Shape {
        param: "theta",
        expected: N,
        got: theta.len(),
    })?;
    check_out("g", g, N)?;
    let mut acc: [S; N] = std::array::from_fn(|j| g[j].clone());
    let mut score_sum: [S; N] = std::array::from_fn(|_| S::zero());
    let (rows, _) = features.as_chunks::<N>();
    let mut failed = false;
    for (((phi, label), action), delta) in rows.iter().zip(labels).zip(actions).zip(shifts) {
        let label = *label.borrow();
        let z = crate::scalar::dot(theta, phi);
        failed |= (label > 1) | (*action > 1) | !finite_logit(&z);
        let p = sigmoid_of_finite(&z);
        let r = if label == 1 {
            p.clone() - S::one()
        } else {
            p.clone()
        };
        let dz = S::from_i64(4) * &r * &p * (S::one() - &p);
        let l = S::from_i64(2) * r.square() + delta;
        let c = if *action == 1 { S::one() - p } else { -p };
        for ((gj, sj), x) in acc.iter_mut().zip(score_sum.iter_mut()).zip(phi) {
            *gj += dz.clone() * x + l.clone() * &*sj;
            *sj += c.clone() * x;
        }
    }
    if failed {
        return Ok(false);
    }
    g.clone_from_slice(&acc);
    Ok(true)
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

    /// `l = 2(p − y)²`, `∇l = 4(p − y)p(1 − p)φ` with `y = 1[label = 1]`.
    fn loss(&self, theta: &[S], phi: &[S], label: &usize) -> Result<(S, Vec<S>), PolicyError> {
        check_action(*label, 2)?;
        let p = self.prob_one(theta, phi)?;
        let r = if *label == 1 {
            p.clone() - S::one()
        } else {
            p.clone()
        };
        let dz = S::from_i64(4) * &r * &p * (S::one() - &p);
        Ok((
            S::from_i64(2) * r.square(),
            phi.iter().map(|x| dz.clone() * x).collect(),
        ))
    }

    /// `∇_θ log π(a|s) = (a − p)φ`.
    fn score(&self, theta: &[S], phi: &[S], action: &usize) -> Result<Vec<S>, PolicyError> {
        check_action(*action, 2)?;
        let p = self.prob_one(theta, phi)?;
        let c = if *action == 1 { S::one() - p } else { -p };
        Ok(phi.iter().map(|x| c.clone() * x).collect())
    }

    /// As [`Policy::loss`], writing `4(p − y)p(1 − p)φ` into `grad`.
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

    /// As [`Policy::score`], writing `(a − p)φ` into `score`.
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

    /// As [`Policy::sample`] without the θ check (θ validated once by the caller).
    /// `#[inline(always)]`: it is the policy's part of the roll-out's hot loop.
    #[inline(always)]
    fn sample_trusted(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<usize, PolicyError> {
        let p = logistic_sigmoid(&trusted_logit(theta, phi, self.features)?)?;
        let u: S = dyadic_uniform(rng);
        Ok(sample_binary(&u, S::one() - &p, &p)?)
    }

    /// With `∇_θ l_t = 4(p − y)p(1 − p)φ` and `ψ_t = (a − p)φ` used entry by entry, never stored:
    /// `g_j += 4(p − y)p(1 − p)φ_j + l_t Σ_j`, `Σ_j += (a − p)φ_j` (the same operations in the same
    /// order as the default).
    #[inline]
    fn causal_step_trusted(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        action: &usize,
        _grad: &mut [S],
        _score: &mut [S],
        g: &mut [S],
        score_sum: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(*label, 2)?;
        let p = logistic_sigmoid(&crate::scalar::dot(theta, phi))?;
        let r = if *label == 1 {
            p.clone() - S::one()
        } else {
            p.clone()
        };
        let dz = S::from_i64(4) * &r * &p * (S::one() - &p);
        let l = S::from_i64(2) * r.square();
        check_action(*action, 2)?;
        let c = if *action == 1 { S::one() - p } else { -p };
        check_out("g", g, self.features)?;
        check_out("score_sum", score_sum, self.features)?;
        for ((gj, sj), x) in g.iter_mut().zip(score_sum.iter_mut()).zip(phi) {
            *gj += dz.clone() * x + l.clone() * &*sj;
            *sj += c.clone() * x;
        }
        Ok(l)
    }

    /// With a compile-time dimension for 1 to 8 features (`causal_sum_fixed`), else the default
    /// loop over [`Policy::causal_step_trusted`].
    #[inline]
    fn causal_sum_trusted<L: Borrow<usize>>(
        &self,
        theta: &[S],
        features: &[S],
        labels: &[L],
        actions: &[usize],
        g: &mut [S],
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        macro_rules! fixed {
            ($($n:literal)*) => {
                match self.features {
                    $($n => {
                        if causal_sum_fixed::<S, L, $n>(theta, features, labels, actions, g)? {
                            Ok(())
                        } else {
                            // Some decision failed a check: the default pass reports the first.
                            causal_sum_by_steps(self, theta, features, labels, actions, g, scratch)
                        }
                    })*
                    _ => causal_sum_by_steps(self, theta, features, labels, actions, g, scratch),
                }
            };
        }
        fixed!(1 2 3 4 5 6 7 8)
    }

    /// With a compile-time dimension for 1 to 8 features (`causal_sum_shifted_fixed`), else the
    /// default.
    #[inline]
    fn causal_sum_shifted_trusted<L: Borrow<usize>>(
        &self,
        theta: &[S],
        features: &[S],
        labels: &[L],
        actions: &[usize],
        shifts: &[S],
        g: &mut [S],
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let by_steps = |g: &mut [S], scratch: &mut Vec<S>| {
            let d = self.features;
            scratch.clear();
            scratch.resize(3 * d, S::zero());
            let (grad, rest) = scratch.split_at_mut(d);
            let (score, score_sum) = rest.split_at_mut(d);
            for (((phi, y), a), delta) in features
                .chunks_exact(d)
                .zip(labels)
                .zip(actions)
                .zip(shifts)
            {
                for (gj, sj) in g.iter_mut().zip(score_sum.iter()) {
                    *gj += delta.clone() * sj;
                }
                self.causal_step_trusted(theta, phi, y.borrow(), a, grad, score, g, score_sum)?;
            }
            Ok(())
        };
        macro_rules! fixed {
            ($($n:literal)*) => {
                match self.features {
                    $($n => {
                        if causal_sum_shifted_fixed::<S, L, $n>(theta, features, labels, actions, shifts, g)? {
                            Ok(())
                        } else {
                            by_steps(g, scratch)
                        }
                    })*
                    _ => by_steps(g, scratch),
                }
            };
        }
        fixed!(1 2 3 4 5 6 7 8)
    }
}

impl<S: Real> LikelihoodRatio<S> for Logistic {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sample_categorical;
    use crate::scalar::Interval;

    /// The fixed-dimension causal pass (1 to 8 features) and the fallback (more features) against
    /// the default decision-by-decision pass: bit-for-bit, and the same first error.
    #[test]
    fn causal_sum_matches_the_default_bit_for_bit() {
        use crate::policy::causal_sum_by_steps;
        use rand::{Rng, SeedableRng};
        let mut rng = KitRng::seed_from_u64(9);
        for n in 1..=10 {
            let pi = Logistic::new(n).unwrap();
            for steps in [1, 2, 7, 60] {
                let theta: Vec<f64> = (0..n).map(|_| 4.0 * rng.random::<f64>() - 2.0).collect();
                let features: Vec<f64> = (0..n * steps)
                    .map(|_| 2.0 * rng.random::<f64>() - 1.0)
                    .collect();
                let labels: Vec<usize> = (0..steps).map(|_| rng.random_range(0..2)).collect();
                let actions: Vec<usize> = (0..steps).map(|_| rng.random_range(0..2)).collect();
                let run = |features: &[f64], labels: &[usize], actions: &[usize], fast: bool| {
                    let mut g = vec![0.0; n];
                    let mut scratch = Vec::new();
                    let r = if fast {
                        pi.causal_sum_trusted(
                            &theta,
                            features,
                            labels,
                            actions,
                            &mut g,
                            &mut scratch,
                        )
                    } else {
                        causal_sum_by_steps(
                            &pi,
                            &theta,
                            features,
                            labels,
                            actions,
                            &mut g,
                            &mut scratch,
                        )
                    };
                    r.map(|()| g.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                };
                let both = |features: &[f64], labels: &[usize], actions: &[usize]| {
                    let fast = run(features, labels, actions, true);
                    assert_eq!(
                        fast,
                        run(features, labels, actions, false),
                        "n = {n}, {steps} steps"
                    );
                    fast
                };
                assert!(both(&features, &labels, &actions).is_ok());
                // Failing decisions: a bad action, a bad label, an overflowing logit, and two of
                // them (the first is reported, in the default's order within a decision: label,
                // logit, action).
                let (early, late) = (steps / 3, steps / 2);
                let mut bad_actions = actions.clone();
                bad_actions[late] = 2;
                let mut bad_labels = labels.clone();
                bad_labels[early] = 7;
                let mut overflow = features.clone();
                for (j, x) in overflow[late * n..(late + 1) * n].iter_mut().enumerate() {
                    *x = f64::MAX.copysign(theta[j]);
                }
                let err = both(&features, &labels, &bad_actions);
                assert!(matches!(err, Err(PolicyError::Action { action: 2, .. })));
                let err = both(&features, &bad_labels, &actions);
                assert!(matches!(err, Err(PolicyError::Action { action: 7, .. })));
                // The row's logit Σ|θ_j|·MAX overflows unless Σ|θ_j| < 1 (then both passes
                // agree on an infinite gradient instead).
                let overflows = !theta
                    .iter()
                    .fold(0.0, |z, t| z + t.abs() * f64::MAX)
                    .is_finite();
                let logit = PolicyError::NonFinite { param: "logit" };
                let err = both(&overflow, &labels, &actions);
                assert_eq!(err.is_err(), overflows);
                if overflows {
                    assert_eq!(err, Err(logit.clone()));
                }
                let err = both(&overflow, &bad_labels, &bad_actions);
                assert!(matches!(err, Err(PolicyError::Action { action: 7, .. })));
                let mut same_step = bad_actions.clone();
                same_step[early] = 3;
                let err = both(&overflow, &labels, &same_step);
                let first = if early == late && overflows {
                    logit
                } else {
                    PolicyError::Action {
                        action: 3,
                        actions: 2,
                    }
                };
                assert_eq!(err, Err(first));
            }
        }
    }

    /// `sample_trusted` of `pi` against `sample` (φ checked entry by entry): the same result.
    fn assert_trusted_as_checked<S: Real>(pi: &Logistic, theta: &[S], phi: &[S]) {
        use rand::SeedableRng;
        let run = |trusted: bool| {
            let mut rng = KitRng::seed_from_u64(3);
            if trusted {
                pi.sample_trusted(theta, phi, &mut rng)
            } else {
                pi.sample(theta, phi, &mut rng)
            }
        };
        assert_eq!(run(true), run(false), "phi = {phi:?}");
    }

    /// `sample_trusted` (φ's finiteness checked through the logit, for floats) fails exactly as
    /// `sample` does: a non-finite feature is φ's error, an overflowing logit the logit's — in
    /// `f64`, and in duals (entry by entry, as in intervals, where `[0, 0]·[1, ∞]` is finite; see
    /// `sample_trusted_checks_unbounded_interval_features`).
    #[test]
    fn sample_trusted_fails_as_sample_does() {
        use crate::scalar::Dual;
        use rand::SeedableRng;
        let pi = Logistic::new(3).unwrap();
        let theta = [0.0, 2.0, -1.0];
        let big = f64::MAX;
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, big, 0.5] {
            for j in 0..3 {
                let mut phi = [0.25, -0.5, 1.0];
                phi[j] = bad;
                assert_trusted_as_checked(&pi, &theta, &phi);
                assert_trusted_as_checked(
                    &pi,
                    &theta.map(Dual::constant),
                    &phi.map(Dual::constant),
                );
            }
        }
        // The three outcomes occur: φ's error, the logit's, and a sample.
        let sample = |phi: [f64; 3]| pi.sample_trusted(&theta, &phi, &mut KitRng::seed_from_u64(3));
        assert_eq!(
            sample([0.0, f64::NAN, 0.0]),
            Err(PolicyError::NonFinite { param: "phi" })
        );
        assert_eq!(
            sample([f64::INFINITY, 0.0, 0.0]),
            Err(PolicyError::NonFinite { param: "phi" })
        );
        assert_eq!(
            sample([0.0, big, -big]),
            Err(PolicyError::NonFinite { param: "logit" })
        );
        assert!(sample([0.0; 3]).is_ok());
    }

    /// An unbounded interval feature with a zero weight gives a finite logit (`[0, 0]·[1, ∞] =
    /// [0, 0]`), and is still φ's error.
    #[cfg(feature = "mpfr")]
    #[test]
    fn sample_trusted_checks_unbounded_interval_features() {
        use rand::SeedableRng;
        let pi = Logistic::new(3).unwrap();
        let theta = [0.0, 2.0, -1.0].map(|x| Interval::from_binary64(x).unwrap());
        let unbounded = Interval::try_from((1.0, f64::INFINITY)).unwrap();
        let phi = [unbounded, Interval::one(), Interval::one()];
        assert!((theta[0] * unbounded).is_finite());
        assert_eq!(
            pi.sample_trusted(&theta, &phi, &mut KitRng::seed_from_u64(3)),
            Err(PolicyError::NonFinite { param: "phi" })
        );
        assert_trusted_as_checked(&pi, &theta, &phi);
    }

    /// `sample_binary` is `sample_categorical` on `[q, p]`: same actions, same errors.
    #[test]
    fn sample_binary_is_the_two_action_categorical() {
        let points = [
            0.0,
            0.25,
            0.5,
            0.75,
            1.0,
            f64::MIN_POSITIVE,
            1.0 - f64::EPSILON / 2.0,
        ];
        for &p in &points {
            for &u in &points {
                let q = 1.0 - p;
                assert_eq!(
                    sample_binary(&u, q, &p),
                    sample_categorical(&[q, p], &u),
                    "p = {p}, u = {u}"
                );
            }
        }
        // Both probabilities zero, and intervals: decided, undecidable.
        assert_eq!(
            sample_binary(&0.5, 0.0, &0.0),
            sample_categorical(&[0.0, 0.0], &0.5)
        );
        let iv = |a: f64, b: f64| Interval::try_from((a, b)).unwrap();
        for (u, q) in [
            (iv(0.1, 0.1), iv(0.4, 0.5)),
            (iv(0.45, 0.45), iv(0.4, 0.5)),
            (iv(0.6, 0.6), iv(0.4, 0.5)),
            (iv(0.3, 0.3), iv(0.0, 0.0)),
        ] {
            let p = Interval::one() - q;
            assert_eq!(sample_binary(&u, q, &p), sample_categorical(&[q, p], &u));
        }
        assert!(sample_binary(&iv(0.45, 0.45), iv(0.4, 0.5), &iv(0.5, 0.6)).is_err());
    }
}
