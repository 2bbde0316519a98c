//! The causal estimator's decisions recorded, summed later with losses chosen after every
//! trajectory's pass ([`RecordedPass`], leave-one-out).

use super::RecordedPass;
use super::causal::usable_notes;
use super::{Decisions, policy_error};
use crate::oracle::EstimatorKernel;
use crate::problem::OracleError;
use crate::scalar::{Real, Scalar};
use std::borrow::Borrow;

/// Fills `out` on a trajectory whose θ and features are validated: the per-step losses `l_t`,
/// then `L_abs` when it absorbed; the number of scored decisions (n − 1; n when it absorbed);
/// and the decisions' records in the policy's form ([`EstimatorKernel::record_validated`], with
/// the roll-out's notes where usable).
pub(crate) fn record_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &Decisions<'_, S, L, A>,
    out: &mut RecordedPass<S>,
) -> Result<(), OracleError>
where
    S: Real,
    P: EstimatorKernel<S, Action = A>,
    L: Borrow<P::Label>,
{
    out.estimate.clear();
    out.score_rows = false;
    policy
        .record_validated(
            theta,
            t.feature_data,
            usable_notes(policy, theta, t),
            t.labels,
            t.actions,
            &mut out.losses,
            &mut out.scores,
        )
        .map_err(policy_error)?;
    if let Some(tail) = t.absorbed {
        out.losses.push(tail.clone());
    }
    out.tail = t.absorbed.is_some();
    out.decisions = t.scored();
    Ok(())
}

/// `g += Σ_t [∇l_t + l'_t Σ_{i<min(t, s)} ψ_i]` from the records of [`record_pass`] on the same
/// trajectory, s its scored decisions, with the losses `l'` given (one per entry of
/// [`RecordedPass::losses`]; the absorbing tail's entry weighs every score), or `None` for the
/// recorded losses, read in place. With the recorded losses it is the causal estimate of eq. 3.15
/// (the plain pass's, bit for bit, without a tail).
pub(crate) fn sum_recorded<S, P, L, A>(
    policy: &P,
    t: &Decisions<'_, S, L, A>,
    recorded: &mut RecordedPass<S>,
    losses: Option<&[S]>,
    g: &mut [S],
) where
    S: Scalar,
    P: EstimatorKernel<S, Action = A>,
    L: Borrow<P::Label>,
{
    let RecordedPass {
        scores,
        work,
        losses: own,
        ..
    } = recorded;
    let losses = losses.map_or(own.as_slice(), |l| l);
    policy.accumulate_recorded(t.feature_data, scores, losses, g, work);
}
