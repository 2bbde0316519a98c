//! The estimator kernel of the [`Logistic`] policy: sampling with φ's check folded into the
//! logit's, and the causal pass of eq. 3.15 with a compile-time dimension for 1 to 8 features.
//!
//! With `p = σ(θ·φ)`, `∇_θ l_t = 4(p − y)p(1 − p)φ` and `ψ_t = (a − p)φ` are multiples of φ
//! ([`brier`], [`score_coefficient`]), so the pass never stores them: per decision
//! `g_j += 4(p − y)p(1 − p)φ_j + l_t Σ_j` and `Σ_j += (a − p)φ_j`, the operations of the default
//! kernel in the same order.

use super::kernel::{EstimatorKernel, causal_sum_by_steps};
use super::products::{Baselines, ScoreProducts};
use crate::policy::logistic::{brier, finite_logit, score_coefficient, sigmoid_of_finite};
use crate::policy::softmax::check_action;
use crate::policy::{Logistic, Policy, PolicyError, check_out, check_vec_scalar, logistic_sigmoid};
use crate::problem::KitRng;
use crate::sampling::{dyadic_uniform, sample_binary};
use crate::scalar::{Real, Scalar};
use std::borrow::Borrow;

/// `z = θ·φ` with θ validated (checked by the caller) and φ checked: its length, and its entries'
/// finiteness — where non-finite numbers propagate through sums and products
/// ([`Scalar::NON_FINITE_PROPAGATES`]: floats, rationals), by one test of `z` instead of one per
/// entry, the entries being looked at only to name the culprit. The same result and errors as
/// `check_vec_scalar("phi", …)` followed by the dot product and the sigmoid's test of `z`.
#[inline]
fn validated_logit<S: Scalar>(theta: &[S], phi: &[S], features: usize) -> Result<S, PolicyError> {
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
/// and the roll-out's `θ·φ` would load it back from there, on the roll-out's critical path.
#[inline(always)]
fn non_finite_logit<S: Scalar>(phi: &[S]) -> PolicyError {
    let param = if phi.iter().all(Scalar::is_finite) {
        "logit"
    } else {
        "phi"
    };
    PolicyError::NonFinite { param }
}

/// Evaluates `$fixed` with the constant `$n` set to the feature count `$dim` when it is 1 to 8 (a
/// compile-time dimension: the loops unroll and the accumulators live in registers), else `$other`.
macro_rules! by_feature_count {
    ($dim:expr, $n:ident => $fixed:expr, _ => $other:expr $(,)?) => {
        $crate::oracle::by_feature_count!(@arms ($dim, $n, $fixed, $other) 1 2 3 4 5 6 7 8)
    };
    (@arms ($dim:expr, $n:ident, $fixed:expr, $other:expr) $($k:literal)*) => {
        match $dim {
            $($k => {
                const $n: usize = $k;
                $fixed
            })*
            _ => $other,
        }
    };
}
pub(crate) use by_feature_count;

/// θ as an array of its `N` entries (the fixed-dimension passes' view).
///
/// # Errors
/// [`PolicyError::Shape`] if θ does not have `N` entries.
fn fixed_theta<S, const N: usize>(theta: &[S]) -> Result<&[S; N], PolicyError> {
    theta.try_into().map_err(|_| PolicyError::Shape {
        param: "theta",
        expected: N,
        got: theta.len(),
    })
}

/// One decision's terms of eq. 3.15 for the logistic policy, whose `∇_θ l_t = dz φ` and
/// `ψ_t = c φ` are multiples of φ: `g_j += dz φ_j + l Σ_j`, then `Σ_j += c φ_j`, entry by entry
/// (the order of the default kernel's `accumulate`).
#[inline(always)]
fn add_decision<S: Scalar>(g: &mut [S], score_sum: &mut [S], phi: &[S], dz: &S, l: &S, c: &S) {
    for ((gj, sj), x) in g.iter_mut().zip(score_sum.iter_mut()).zip(phi) {
        *gj += dz.clone() * x + l.clone() * &*sj;
        *sj += c.clone() * x;
    }
}

/// One decision of the causal pass on a validated θ and φ, with the checks of
/// [`EstimatorKernel::causal_step_validated`]: adds `∇_θ l_t + l_t Σ_{i<t} ψ_i` to `g` and ψ_t to
/// `score_sum`, and returns `l_t`.
#[allow(clippy::too_many_arguments)] // the decision and the estimator's state
#[inline]
fn causal_step<S: Real>(
    features: usize,
    theta: &[S],
    phi: &[S],
    label: usize,
    action: usize,
    g: &mut [S],
    score_sum: &mut [S],
) -> Result<S, PolicyError> {
    let (l, c, dz) = decision_coefficients(theta, phi, label, action)?;
    check_out("g", g, features)?;
    check_out("score_sum", score_sum, features)?;
    add_decision(g, score_sum, phi, &dz, &l, &c);
    Ok(l)
}

/// One decision's loss `l_t`, score coefficient `c_t = a_t − p_t` and loss-gradient
/// coefficient `dz_t` on a validated θ and φ, with the checks of
/// [`EstimatorKernel::causal_step_validated`] in its order (label, logit, action).
#[inline]
fn decision_coefficients<S: Real>(
    theta: &[S],
    phi: &[S],
    label: usize,
    action: usize,
) -> Result<(S, S, S), PolicyError> {
    check_action(label, 2)?;
    let p = logistic_sigmoid(&crate::scalar::dot(theta, phi))?;
    let (l, dz) = brier(&p, label);
    check_action(action, 2)?;
    Ok((l, score_coefficient(p, action), dz))
}

/// The first half of the causal pass of eq. 3.15 for [`Logistic`] with `N` features known at
/// compile time, the decisions alone: per decision t its loss `l_t`, its score coefficient
/// `c_t = a_t − p_t` (ψ_t = c_t φ_t) and its loss-gradient coefficient
/// `dz_t = 4(p_t − y_t)p_t(1 − p_t)` (∇_θ l_t = dz_t φ_t), written into `losses`,
/// `coefficients` and `gradients` (the pass stops at the shortest of the decisions and the
/// three). `accumulate_fixed` then sums them.
///
/// Two loops instead of one: no accumulator is live across the call to `exp`, which would
/// otherwise keep them in memory around it; the second loop has no call.
///
/// The per-decision checks are not branches: their failures are collected in a flag, and `false`
/// tells the caller that some decision failed (the records are then unspecified), for the
/// default pass to find and report the first failure.
#[inline(never)]
fn record_fixed<S: Real, L: Borrow<usize>, const N: usize>(
    theta: &[S; N],
    features: &[S],
    labels: &[L],
    actions: &[usize],
    losses: &mut [S],
    coefficients: &mut [S],
    gradients: &mut [S],
) -> bool {
    let (rows, _) = features.as_chunks::<N>();
    let records = losses.iter_mut().zip(coefficients).zip(gradients);
    let mut failed = false;
    for (((phi, label), action), ((lo, co), gr)) in
        rows.iter().zip(labels).zip(actions).zip(records)
    {
        let (label, action) = (*label.borrow(), *action);
        let z = crate::scalar::dot(theta, phi);
        failed |= (label > 1) | (action > 1) | !finite_logit(&z);
        let p = sigmoid_of_finite(&z);
        let (l, dz) = brier(&p, label);
        *co = score_coefficient(p, action);
        *lo = l;
        *gr = dz;
    }
    !failed
}

/// The second half of the causal pass of `record_fixed`: `g += Σ_{t<n} [dz_t φ_t + l_t Σ_{i<t}
/// ψ_i]` with ψ_i = c_i φ_i over the n recorded decisions, per decision the operations of
/// [`EstimatorKernel::causal_step_validated`] in the same order (`add_decision`; so the same `g`
/// bit for bit), with `g` and `Σ_{i<t} ψ_i` in `[S; N]` locals (registers for `f64`); then, if
/// `losses` has an (n + 1)-th entry `l_n`, `g += l_n Σ_{i<n} ψ_i`. `g` has `N` entries; `l_t`
/// may carry a baseline's shift (it weighs `Σ_{i<t} ψ_i` only).
#[inline(never)]
fn accumulate_fixed<S: Scalar, const N: usize>(
    features: &[S],
    losses: &[S],
    coefficients: &[S],
    gradients: &[S],
    g: &mut [S],
) {
    let mut acc: [S; N] = std::array::from_fn(|j| g[j].clone());
    let mut score_sum: [S; N] = std::array::from_fn(|_| S::zero());
    let (rows, _) = features.as_chunks::<N>();
    let n = rows.len().min(coefficients.len()).min(gradients.len());
    let records = losses.iter().zip(coefficients).zip(gradients);
    for (phi, ((l, c), dz)) in rows.iter().zip(records) {
        add_decision(&mut acc, &mut score_sum, phi, dz, l, c);
    }
    if let Some(end) = losses.get(n) {
        for (a, s) in acc.iter_mut().zip(&score_sum) {
            *a += end.clone() * s;
        }
    }
    g.clone_from_slice(&acc);
}

impl<S: Real> EstimatorKernel<S> for Logistic {
    /// As [`Policy::sample`] without the θ check. `#[inline(always)]`: it is the policy's part of
    /// the roll-out's hot loop.
    #[inline(always)]
    fn sample_validated(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<usize, PolicyError> {
        let features = Policy::<S>::feature_dim(self);
        let p = logistic_sigmoid(&validated_logit(theta, phi, features)?)?;
        let u: S = dyadic_uniform(rng);
        Ok(sample_binary(&u, S::one() - &p, &p)?)
    }

    /// With `∇_θ l_t` and `ψ_t` used entry by entry, never stored (`grad` and `score` untouched).
    #[inline]
    fn causal_step_validated(
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
        let features = Policy::<S>::feature_dim(self);
        causal_step(features, theta, phi, *label, *action, g, score_sum)
    }

    /// With a compile-time dimension for 1 to 8 features in two loops (`record_fixed`, with the
    /// records in `scratch`, then `accumulate_fixed`, the `end` loss after them), else (and to report a failing decision) the default
    /// loop over [`EstimatorKernel::causal_step_validated`]. The policy notes nothing, so `notes`
    /// is ignored.
    #[inline]
    fn causal_sum_validated<L: Borrow<usize>>(
        &self,
        theta: &[S],
        features: &[S],
        _notes: Option<&[S]>,
        labels: &[L],
        actions: &[usize],
        end: Option<&S>,
        g: &mut [S],
        mut loss: Option<&mut S>,
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let (x, y) = (features, labels);
        let done = by_feature_count!(Policy::<S>::feature_dim(self), N => {
            let n = actions.len();
            // Losses (with the end's after them), then the two coefficients per decision.
            let with_end = n + usize::from(end.is_some());
            scratch.clear();
            scratch.resize(with_end + 2 * n, S::zero());
            let (losses, rest) = scratch.split_at_mut(with_end);
            let (coefficients, gradients) = rest.split_at_mut(n);
            let theta = fixed_theta::<S, N>(theta)?;
            check_out("g", g, N)?;
            let decisions = &mut losses[..n];
            record_fixed::<S, L, N>(theta, x, y, actions, decisions, coefficients, gradients) && {
                if let Some(total) = loss.as_deref_mut() {
                    for l in decisions.iter() {
                        *total += l;
                    }
                }
                if let Some(end) = end {
                    losses[n] = end.clone();
                }
                accumulate_fixed::<S, N>(x, losses, coefficients, gradients, g);
                true
            }
        }, _ => false);
        if done {
            return Ok(());
        }
        // More than 8 features, or a decision failed a check: the default pass reports the first.
        causal_sum_by_steps(
            self, theta, features, labels, actions, end, g, loss, scratch,
        )
    }

    /// Records each decision by two coefficients: `c_t = a_t − p_t` (ψ_t = c_t φ_t) in the first
    /// n entries of `records`, `dz_t` (∇_θ l_t = dz_t φ_t) in the next n. With a compile-time
    /// dimension for 1 to 8 features in one loop (`record_fixed`); else (and to report a failing
    /// decision) decision by decision with the checks of
    /// [`EstimatorKernel::causal_step_validated`]. The policy notes nothing: `notes` is ignored.
    fn record_validated<L: Borrow<usize>>(
        &self,
        theta: &[S],
        features: &[S],
        _notes: Option<&[S]>,
        labels: &[L],
        actions: &[usize],
        losses: &mut Vec<S>,
        records: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let dim = Policy::<S>::feature_dim(self);
        let n = actions.len();
        losses.clear();
        losses.resize(n, S::zero());
        records.clear();
        records.resize(2 * n, S::zero());
        let (coefficients, gradients) = records.split_at_mut(n);
        let (x, y, a) = (features, labels, actions);
        let done = by_feature_count!(dim, N => {
            let theta = fixed_theta::<S, N>(theta)?;
            record_fixed::<S, L, N>(theta, x, y, a, losses, coefficients, gradients)
        }, _ => false);
        if done {
            return Ok(());
        }
        let rows = features.chunks_exact(dim.max(1)).zip(labels).zip(actions);
        let records = losses.iter_mut().zip(coefficients).zip(gradients);
        for (((phi, label), action), ((lo, co), gr)) in rows.zip(records) {
            (*lo, *co, *gr) = decision_coefficients(theta, phi, *label.borrow(), *action)?;
        }
        Ok(())
    }

    /// From the coefficients of [`EstimatorKernel::record_validated`]: with a compile-time
    /// dimension for 1 to 8 features in registers (`accumulate_fixed`), else with `Σ_{i<t} ψ_i`
    /// in `scratch`, per decision the same operations.
    fn accumulate_recorded(
        &self,
        features: &[S],
        records: &[S],
        losses: &[S],
        g: &mut [S],
        scratch: &mut Vec<S>,
    ) {
        let dim = Policy::<S>::feature_dim(self);
        let (coefficients, gradients) = records.split_at(records.len() / 2);
        by_feature_count!(dim, N => {
            accumulate_fixed::<S, N>(features, losses, coefficients, gradients, g)
        }, _ => {
            scratch.clear();
            scratch.resize(dim, S::zero());
            let rows = features.chunks_exact(dim.max(1));
            let n = rows.len().min(coefficients.len());
            let records = losses.iter().zip(coefficients).zip(gradients);
            for (phi, ((l, c), dz)) in rows.zip(records) {
                add_decision(g, scratch, phi, dz, l, c);
            }
            if let Some(end) = losses.get(n) {
                for (gj, sj) in g.iter_mut().zip(scratch.iter()) {
                    *gj += end.clone() * sj;
                }
            }
        });
    }

    /// With ψ_i = c_i φ_i from the recorded coefficient: `g −= (b_i c_i) φ_i`, then
    /// `cross[i] += c_i (v·φ_i)` and `moment[i] += c_i² ‖φ_i‖²`, for 1 to 8 features with the rows,
    /// v and g in `[S; N]` locals (registers for `f64`); else ψ_i formed in `Vec`s and
    /// [`ScoreProducts::add_rows`]. The same products up to rounding. The linear state-dependent
    /// baseline's b_i are formed row by row in the correction's pass when its rows have the
    /// policy's N features and k is all of them ([`super::FixedLinearBaseline::next`]), else
    /// first: the same b_i and the same operations either way.
    fn score_products(&self, features: &[S], records: &[S], out: ScoreProducts<'_, S>) {
        let dim = Policy::<S>::feature_dim(self);
        let coefficients = &records[..records.len() / 2];
        by_feature_count!(dim, N => {
            let ScoreProducts { v, baseline, cross, moment, g } = out;
            // g has N entries (d = N for this policy) whenever there is a correction to make.
            let fused = match &baseline {
                Baselines::Linear { baseline, rows, stride, decisions } if *stride == N => {
                    baseline.fixed::<N>().map(|b| (b, *rows, *decisions))
                }
                _ => None,
            };
            if let Some((b, state_rows, decisions)) = fused {
                let (state_rows, _) = state_rows.as_chunks::<N>();
                let (rows, _) = features.as_chunks::<N>();
                let mut acc: [S; N] = std::array::from_fn(|j| g[j].clone());
                let mut index = S::zero();
                let decisions = rows.iter().zip(state_rows).zip(coefficients).take(decisions);
                for ((phi, state), c) in decisions {
                    let bc = b.next(state, &mut index) * c;
                    for (a, x) in acc.iter_mut().zip(phi) {
                        *a -= bc.clone() * x;
                    }
                }
                g.clone_from_slice(&acc);
            } else {
                let mut buf = Vec::new();
                let baseline = baseline.values(&mut buf);
                let (rows, _) = features.as_chunks::<N>();
                if !baseline.is_empty() {
                    let mut acc: [S; N] = std::array::from_fn(|j| g[j].clone());
                    for ((phi, c), b) in rows.iter().zip(coefficients).zip(baseline) {
                        let bc = b.clone() * c;
                        for (a, x) in acc.iter_mut().zip(phi) {
                            *a -= bc.clone() * x;
                        }
                    }
                    g.clone_from_slice(&acc);
                }
            }
            let v: [S; N] = std::array::from_fn(|j| v[j].clone());
            let (rows, _) = features.as_chunks::<N>();
            // The statistics, for as many decisions as `cross` has (none: the correction alone).
            let products = cross.iter_mut().zip(moment.iter_mut());
            for ((phi, c), (cr, mo)) in rows.iter().zip(coefficients).zip(products) {
                *cr += c.clone() * crate::scalar::dot(&v, phi);
                *mo += c.square() * crate::scalar::norm_sq(phi);
            }
        }, _ => {
            let corrected = match &out.baseline {
                Baselines::Given(b) => b.len(),
                Baselines::Linear { decisions, .. } => *decisions,
            };
            let rows = features.chunks_exact(dim.max(1)).zip(coefficients);
            let scores: Vec<Vec<S>> = rows
                .take(out.cross.len().max(corrected))
                .map(|(phi, c)| phi.iter().map(|x| c.clone() * x).collect())
                .collect();
            out.add_rows(scores.iter().map(Vec::as_slice));
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random θ ∈ [−2, 2)ⁿ, `steps` rows φ ∈ [−1, 1)ⁿ, and labels and actions in {0, 1}.
    fn random_trajectory(
        rng: &mut KitRng,
        n: usize,
        steps: usize,
    ) -> (Vec<f64>, Vec<f64>, Vec<usize>, Vec<usize>) {
        use rand::Rng;
        let theta = (0..n).map(|_| 4.0 * rng.random::<f64>() - 2.0).collect();
        let features = (0..n * steps)
            .map(|_| 2.0 * rng.random::<f64>() - 1.0)
            .collect();
        let labels = (0..steps).map(|_| rng.random_range(0..2)).collect();
        let actions = (0..steps).map(|_| rng.random_range(0..2)).collect();
        (theta, features, labels, actions)
    }

    /// The fixed-dimension causal pass (1 to 8 features) and the fallback (more features) against
    /// the default decision-by-decision pass, without and with an end loss: bit-for-bit, and the
    /// same first error.
    #[test]
    fn causal_sum_matches_the_default_bit_for_bit() {
        use rand::SeedableRng;
        let mut rng = KitRng::seed_from_u64(9);
        for n in 1..=10 {
            let pi = Logistic::new(n).unwrap();
            for steps in [1, 2, 7, 60] {
                let (theta, features, labels, actions) = random_trajectory(&mut rng, n, steps);
                // Without and with losses after the last decision (an absorbing tail).
                let run = |features: &[f64],
                           labels: &[usize],
                           actions: &[usize],
                           end: Option<&f64>,
                           fast: bool| {
                    let mut g = vec![0.0; n];
                    let mut scratch = Vec::new();
                    let r = if fast {
                        pi.causal_sum_validated(
                            &theta,
                            features,
                            None,
                            labels,
                            actions,
                            end,
                            &mut g,
                            None,
                            &mut scratch,
                        )
                    } else {
                        causal_sum_by_steps(
                            &pi,
                            &theta,
                            features,
                            labels,
                            actions,
                            end,
                            &mut g,
                            None,
                            &mut scratch,
                        )
                    };
                    r.map(|()| g.iter().map(|x: &f64| x.to_bits()).collect::<Vec<_>>())
                };
                let both = |features: &[f64], labels: &[usize], actions: &[usize]| {
                    let with_end = run(features, labels, actions, Some(&0.375), true);
                    assert_eq!(
                        with_end,
                        run(features, labels, actions, Some(&0.375), false),
                        "n = {n}, {steps} steps, with an end"
                    );
                    let fast = run(features, labels, actions, None, true);
                    assert_eq!(
                        fast,
                        run(features, labels, actions, None, false),
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

    /// The records (one loop for 1 to 8 features, the fallback for more) and their sum against
    /// the default that records `∇l_t` and ψ_t as rows: the same losses, and `dz_t φ_t`,
    /// ψ_t = c_t φ_t bit for bit from the recorded coefficients; the same sums bit for bit with
    /// the recorded losses, shifted losses and one more loss weighing every score (one summation
    /// order); with the recorded losses the plain pass's `g` bit for bit; the same first error
    /// when a decision fails.
    #[test]
    fn recorded_pass_matches_the_default_bit_for_bit() {
        use super::super::kernel::{accumulate_rows, record_rows};
        use rand::{Rng, SeedableRng};
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut rng = KitRng::seed_from_u64(11);
        for n in 1..=10 {
            let pi = Logistic::new(n).unwrap();
            for steps in [1, 2, 7, 60] {
                let (theta, features, labels, mut actions) = random_trajectory(&mut rng, n, steps);
                let record = |actions: &[usize], fast: bool| {
                    let (mut losses, mut records) = (vec![], vec![]);
                    let r = if fast {
                        pi.record_validated(
                            &theta,
                            &features,
                            None,
                            &labels,
                            actions,
                            &mut losses,
                            &mut records,
                        )
                    } else {
                        record_rows(
                            &pi,
                            &theta,
                            &features,
                            &labels,
                            actions,
                            &mut losses,
                            &mut records,
                        )
                    };
                    r.map(|()| (losses, records))
                };
                let (losses, coefficients) = record(&actions, true).unwrap();
                let (losses_rows, rows) = record(&actions, false).unwrap();
                assert_eq!(bits(&losses), bits(&losses_rows), "n = {n}, {steps} steps");
                assert_eq!(
                    rows.len(),
                    2 * n * steps,
                    "n = {n}: a row of 2n per decision"
                );
                for (t, row) in rows.chunks_exact(2 * n).enumerate() {
                    let phi = &features[t * n..(t + 1) * n];
                    let times = |c: f64| phi.iter().map(|x| c * x).collect::<Vec<_>>();
                    let (grad, psi) = row.split_at(n);
                    assert_eq!(bits(&times(coefficients[steps + t])), bits(grad), "∇l_{t}");
                    assert_eq!(bits(&times(coefficients[t])), bits(psi), "n = {n}, ψ_{t}");
                }
                let shifted: Vec<f64> = losses.iter().map(|l| l - rng.random::<f64>()).collect();
                let mut with_end = shifted.clone();
                with_end.push(rng.random());
                for l in [&losses, &shifted, &with_end] {
                    let (mut g, mut g_rows) = (vec![0.5; n], vec![0.5; n]);
                    pi.accumulate_recorded(&features, &coefficients, l, &mut g, &mut vec![]);
                    accumulate_rows(&rows, n, l, &mut g_rows, &mut vec![]);
                    assert_eq!(bits(&g), bits(&g_rows), "n = {n}, {steps} steps");
                }
                let (mut g, mut g_plain) = (vec![0.5; n], vec![0.5; n]);
                pi.accumulate_recorded(&features, &coefficients, &losses, &mut g, &mut vec![]);
                pi.causal_sum_validated(
                    &theta,
                    &features,
                    None,
                    &labels,
                    &actions,
                    None,
                    &mut g_plain,
                    None,
                    &mut vec![],
                )
                .unwrap();
                assert_eq!(bits(&g), bits(&g_plain), "n = {n}, {steps} steps");
                actions[steps / 2] = 2;
                let err = record(&actions, true).map(|_| ());
                assert_eq!(err, record(&actions, false).map(|_| ()));
                assert!(matches!(err, Err(PolicyError::Action { action: 2, .. })));
            }
        }
    }

    /// `sample_validated` of `pi` against `sample` (φ checked entry by entry): the same result.
    fn assert_validated_as_checked<S: Real>(pi: &Logistic, theta: &[S], phi: &[S]) {
        use rand::SeedableRng;
        let run = |validated: bool| {
            let mut rng = KitRng::seed_from_u64(3);
            if validated {
                pi.sample_validated(theta, phi, &mut rng)
            } else {
                pi.sample(theta, phi, &mut rng)
            }
        };
        assert_eq!(run(true), run(false), "phi = {phi:?}");
    }

    /// `sample_validated` (φ's finiteness checked through the logit, for floats) fails exactly as
    /// `sample` does: a non-finite feature is φ's error, an overflowing logit the logit's — in
    /// `f64`, and in duals (entry by entry, as in intervals, where `[0, 0]·[1, ∞]` is finite; see
    /// `sample_validated_checks_unbounded_interval_features`).
    #[test]
    fn sample_validated_fails_as_sample_does() {
        use crate::scalar::Dual;
        use rand::SeedableRng;
        let pi = Logistic::new(3).unwrap();
        let theta = [0.0, 2.0, -1.0];
        let big = f64::MAX;
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, big, 0.5] {
            for j in 0..3 {
                let mut phi = [0.25, -0.5, 1.0];
                phi[j] = bad;
                assert_validated_as_checked(&pi, &theta, &phi);
                assert_validated_as_checked(
                    &pi,
                    &theta.map(Dual::constant),
                    &phi.map(Dual::constant),
                );
            }
        }
        // The three outcomes occur: φ's error, the logit's, and a sample.
        let sample =
            |phi: [f64; 3]| pi.sample_validated(&theta, &phi, &mut KitRng::seed_from_u64(3));
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
    fn sample_validated_checks_unbounded_interval_features() {
        use crate::scalar::Interval;
        use rand::SeedableRng;
        let pi = Logistic::new(3).unwrap();
        let theta = [0.0, 2.0, -1.0].map(|x| Interval::from_binary64(x).unwrap());
        let unbounded = Interval::try_from((1.0, f64::INFINITY)).unwrap();
        let phi = [unbounded, Interval::one(), Interval::one()];
        assert!((theta[0] * unbounded).is_finite());
        assert_eq!(
            pi.sample_validated(&theta, &phi, &mut KitRng::seed_from_u64(3)),
            Err(PolicyError::NonFinite { param: "phi" })
        );
        assert_validated_as_checked(&pi, &theta, &phi);
    }
}
