//! The causal estimator with a baseline subtracted, `g − Σ_i b_i ψ_i` ([`crate::baseline`]): the
//! baseline `b_i` may depend on anything before decision i, so the estimate stays unbiased.

use super::{DecisionTerms, Given};
use super::{Decisions, features_valid, policy_error, terms_pass};
use crate::oracle::EstimatorKernel;
use crate::policy::LikelihoodRatio;
use crate::problem::OracleError;
use crate::scalar::Real;
use std::borrow::Borrow;

/// Adds the baselined causal estimate to `g` (zeros, [`crate::policy::Policy::param_dim`]
/// entries), for a baseline that covers the trajectory's scored decisions (n − 1; n when it
/// absorbed).
///
/// Without an absorbing tail, on a trajectory whose features are known valid, the baseline is
/// folded into the plain estimator's loop as per-decision loss shifts `δ_t = b_t − b_{t−1}`
/// ([`EstimatorKernel::causal_sum_validated`]); otherwise the estimate is assembled from the
/// [`DecisionTerms`] of [`terms_pass`].
pub(crate) fn baselined_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &Decisions<'_, S, L, A>,
    baseline: Given<'_, S>,
    g: &mut [S],
) -> Result<(), OracleError>
where
    S: Real,
    P: LikelihoodRatio<S, Action = A> + EstimatorKernel<S>,
    L: Borrow<P::Label>,
{
    let (n, scored) = (t.len(), t.scored());
    if t.absorbed.is_none() && features_valid(policy, t) {
        // δ_t = b_t − b_{t−1} with b_0 = 0 and b_t = 0 after the last scored decision: for
        // one constant only the first and the first unscored decision shift.
        let mut shifts = vec![S::zero(); n];
        match baseline {
            Given::Constant(b) => {
                if scored > 0 {
                    shifts[0] = b.clone();
                    shifts[scored] = -b.clone();
                }
            }
            Given::TimeIndexed(bs) | Given::Leading(bs) => {
                // A leading list stops early: b_t = 0 from its end on.
                let k = scored.min(bs.len());
                let mut previous = S::zero();
                for (shift, b) in shifts.iter_mut().zip(&bs[..k]) {
                    *shift = b.clone() - &previous;
                    previous = b.clone();
                }
                shifts[k] = -previous;
            }
        }
        let mut scratch = Vec::new();
        policy
            .causal_sum_validated(
                theta,
                t.feature_data,
                None,
                t.labels,
                t.actions,
                Some(&shifts),
                None,
                g,
                None,
                &mut scratch,
            )
            .map_err(policy_error)?;
    } else {
        let mut terms = DecisionTerms::new();
        terms_pass(policy, theta, None, t, &mut terms)?;
        terms.finish();
        terms.estimate_into(|i| baseline.at(i).cloned(), g);
    }
    Ok(())
}
