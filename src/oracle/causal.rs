//! The causal estimator of eq. 3.15 (math.md §1.1), optionally importance-weighted (math.md §4),
//! in one pass over a trajectory.

use super::{Decisions, Scratch, features_valid, policy_error};
use crate::oracle::EstimatorKernel;
use crate::oracle::kernel::accumulate;
use crate::policy::LikelihoodRatio;
use crate::problem::OracleError;
use crate::scalar::Real;
use std::borrow::Borrow;

/// The causal estimator `Σ_t [w_{1:t−1} ∇l_t + w_{1:t−1} l_t Σ_{i<t} ψ_i]` in one pass over the
/// trajectory (math.md §4 for the weights): with `ratio = None` every weight is 1 (eq. 3.15);
/// with `Some(θ_new)` the per-decision prefix weights `w_{1:t−1} = exp(Σ_{i<t} log π_θ(a_i|s_i) −
/// log π_θnew(a_i|s_i))` are accumulated along the way. Returns `g` and the log of the whole
/// trajectory's weight: the sum of the log-ratios of every decision that weighs a loss
/// (decisions 1..n−1; 1..n when the trajectory absorbed), zero without `ratio`.
///
/// An absorbed trajectory adds its absorbing losses `L_abs = Σ_{t>n} l_t` to the loss-to-go of
/// every decision: `+ w_{1:n} L_abs Σ_{i≤n} ψ_i` (they carry no `∇l`: they do not depend on θ
/// but through the law of the end state).
///
/// With `loss`, every step's `l_t` (at θ) is added to it in order, as
/// [`crate::problem::IlProblem::trajectory_loss`] sums them (start it at the absorbing tail's
/// value): the trajectory loss from the same pass.
///
/// On validated features without per-decision weights, the whole pass (the tail's
/// term included) is the policy's [`EstimatorKernel::causal_sum_validated`] (with the roll-out's notes where usable),
/// after the trajectory's log-ratios when `ratio` is given: the weight multiplies the whole
/// estimate, so it does not enter the sum, and a failing ratio is reported before a failing
/// loss. Otherwise, per decision: one
/// [`Policy::loss_score_into`](crate::policy::Policy::loss_score_into) into preallocated buffers
/// and O(d) field operations ([`accumulate`]), no allocation; the first failing decision's error
/// is reported (its loss before its ratio).
pub(crate) fn causal_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    ratio: Option<&[S]>,
    per_decision: bool,
    t: &Decisions<'_, S, L, A>,
    mut loss: Option<&mut S>,
) -> Result<(Vec<S>, S), OracleError>
where
    S: Real,
    P: LikelihoodRatio<S, Action = A> + EstimatorKernel<S>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let scored = t.scored();
    let mut g = vec![S::zero(); d];
    let mut log_w = S::zero();
    // θ has been checked by the caller; with every φ checked here once, the policy's pass can
    // skip its own checks. Otherwise the checked calls below report the first failure.
    // Per-decision weights need each decision's weight inside the sum, which the policy's pass
    // does not form.
    let validated = !per_decision && features_valid(policy, t);
    let tail = t.absorbed;
    if validated {
        // The whole-trajectory weight first (so that a failing ratio is reported before a
        // failing loss, as in the checked loop below), then the plain causal estimator: the
        // whole pass in the policy (one loop it may specialise), the absorbing tail's term after
        // it. The weight multiplies the whole estimate, so it does not enter the sum.
        if let Some(theta_new) = ratio {
            for (phi, a) in t.feature_rows().zip(t.actions).take(scored) {
                log_w += policy
                    .log_likelihood_ratio(theta, theta_new, phi, a)
                    .map_err(policy_error)?;
            }
        }
        let (rows, actions, labels) = (t.feature_data, t.actions, t.labels);
        // Scratch only if the policy's pass asks for it (the logistic policy's records its
        // decisions there: one buffer per call).
        let mut scratch = Vec::new();
        policy
            .causal_sum_validated(
                theta,
                rows,
                usable_notes(policy, theta, t),
                labels,
                actions,
                tail,
                &mut g,
                loss,
                &mut scratch,
            )
            .map_err(policy_error)?;
        return Ok((g, log_w));
    }
    let mut scratch = Scratch::new(d);
    let (grad, score, score_sum) = scratch.parts();
    // `w_{1:t−1}` of the current step t (per-decision weights): `exp` of the log-ratios so far.
    let mut w = log_w.exp();
    for (step, ((phi, a), y)) in t.feature_rows().zip(t.actions).zip(t.labels).enumerate() {
        let l = policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
        if per_decision {
            accumulate(&mut g, Some(&w), &l, grad, score, score_sum);
        } else {
            accumulate(&mut g, None, &l, grad, score, score_sum);
        }
        if let Some(total) = loss.as_deref_mut() {
            *total += l;
        }
        if let Some(theta_new) = ratio.filter(|_| step < scored) {
            log_w += policy
                .log_likelihood_ratio(theta, theta_new, phi, a)
                .map_err(policy_error)?;
            if per_decision {
                w = log_w.exp();
            }
        }
    }
    if let Some(tail) = tail {
        // `score_sum` now holds Σ_{i≤n} ψ_i.
        let wl = if per_decision {
            log_w.exp() * tail
        } else {
            tail.clone()
        };
        for (gj, sj) in g.iter_mut().zip(score_sum.iter()) {
            *gj += wl.clone() * sj;
        }
    }
    Ok((g, log_w))
}

/// The trajectory's notes ([`EstimatorKernel::sample_noting`]) when the estimate may read them:
/// they were taken at this very θ (entry by entry equal, and for floats the same bits, so that
/// `−0` and `0` differ) and hold [`EstimatorKernel::note_len`] entries for every feature row.
pub(crate) fn usable_notes<'a, S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &Decisions<'a, S, L, A>,
) -> Option<&'a [S]>
where
    S: Real,
    P: EstimatorKernel<S>,
{
    let (values, noted_at) = t.notes?;
    let k = policy.note_len();
    let same_theta = noted_at.len() == theta.len()
        && noted_at
            .iter()
            .zip(theta)
            .all(|(a, b)| a == b && a.bit_key() == b.bit_key());
    (k > 0 && same_theta && values.len() == k * t.rows).then_some(values)
}
