//! The full (non-causal) form of the estimator (eq. 3.16): every decision's score multiplies the
//! whole trajectory's loss.

use super::{Decisions, Scratch, policy_error};
use crate::policy::Policy;
use crate::problem::OracleError;
use crate::scalar::Scalar;
use std::borrow::Borrow;

/// The full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i`, in two passes (the total loss first), each
/// without per-decision allocation. An absorbed trajectory adds its absorbing losses to the total
/// and its last decision's score to the sum (`Σ_{i≤n} ψ_i`: that action caused the end).
pub(crate) fn full_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &Decisions<'_, S, L, A>,
) -> Result<Vec<S>, OracleError>
where
    S: Scalar,
    P: Policy<S, Action = A>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let mut scratch = Scratch::new(d);
    let (grad, score, _) = scratch.parts();
    let mut total = t.absorbed.cloned().unwrap_or_else(S::zero);
    for ((phi, a), y) in t.feature_rows().zip(t.actions).zip(t.labels) {
        total += policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
    }
    let scored = t.scored();
    let mut g = vec![S::zero(); d];
    for (step, ((phi, a), y)) in t.feature_rows().zip(t.actions).zip(t.labels).enumerate() {
        policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
        for ((gj, dj), sj) in g.iter_mut().zip(grad.iter()).zip(score.iter()) {
            *gj += dj;
            if step < scored {
                *gj += total.clone() * sj;
            }
        }
    }
    Ok(g)
}
