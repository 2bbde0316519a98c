//! The causal estimator with its scores recorded, for baselines fixed only after the pass
//! ([`RecordedPass`], leave-one-out).

use super::{Decisions, policy_error};
use crate::baseline::RecordedPass;
use crate::oracle::EstimatorKernel;
use crate::problem::OracleError;
use crate::scalar::Scalar;
use std::borrow::Borrow;

/// Fills `out` on a trajectory whose θ and features are validated: the plain causal estimate
/// `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]` plus, when it absorbed, `L_abs Σ_{i≤n} ψ_i` (as in
/// `causal_pass`); the per-step losses `l_t`, then `L_abs`; the number of scored decisions (n − 1;
/// n when it absorbed); and the scores in the policy's form
/// ([`EstimatorKernel::causal_sum_recorded`]).
pub(crate) fn recorded_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &Decisions<'_, S, L, A>,
    out: &mut RecordedPass<S>,
) -> Result<(), OracleError>
where
    S: Scalar,
    P: EstimatorKernel<S, Action = A>,
    L: Borrow<P::Label>,
{
    let n = t.len();
    out.estimate.clear();
    out.estimate.resize(policy.param_dim(), S::zero());
    out.score_rows = false;
    policy
        .causal_sum_recorded(
            theta,
            t.feature_data,
            t.labels,
            t.actions,
            &mut out.estimate,
            &mut out.losses,
            &mut out.scores,
        )
        .map_err(policy_error)?;
    if let Some(tail) = t.absorbed {
        policy.subtract_scores_trusted(
            t.feature_data,
            &out.scores,
            n,
            std::iter::repeat_n(-tail.clone(), n),
            &mut out.estimate,
        );
        out.losses.push(tail.clone());
    }
    out.decisions = t.scored();
    Ok(())
}
