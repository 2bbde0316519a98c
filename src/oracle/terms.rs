//! The per-decision terms of the causal estimator, from which a baseline is subtracted
//! ([`crate::baseline`], math.md §s on baselines).

use super::DecisionTerms;
use super::{Decisions, Scratch, policy_error};
use crate::policy::LikelihoodRatio;
use crate::problem::{OracleError, Weighting};
use crate::scalar::Real;
use std::borrow::Borrow;

/// The causal estimator's [`DecisionTerms`] on a task trajectory with decisions t = 1..n, for
/// the baselined estimator of [`crate::baseline`]: direct part `Σ_t w_{1:t−1} ∇l_t`, per step
/// the loss `w_{1:t−1} l_t` (then the absorbing tail's `w_{1:n} L_abs`, with no decision), per
/// scored decision (1..n−1; 1..n when the trajectory absorbed, as in [`causal_pass`]) its score
/// ψ_i with the prefix weight `w_{1:i}` (per-decision weighting) — or the whole weight as the
/// estimate's scale (trajectory weighting). Same per-decision calls as [`causal_pass`], into the
/// reused buffers of `out`: no allocation per step.
pub(crate) fn terms_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    ratio: Option<(&[S], Weighting)>,
    t: &Decisions<'_, S, L, A>,
    out: &mut DecisionTerms<S>,
) -> Result<(), OracleError>
where
    S: Real,
    P: LikelihoodRatio<S, Action = A>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let n = t.len();
    let tail = t.absorbed;
    let scored = t.scored();
    let per_decision = matches!(ratio, Some((_, Weighting::PerDecision)));
    out.begin(d, n);
    let mut scratch = Scratch::new(d);
    let (grad, score, _) = scratch.parts();
    let mut log_w = S::zero();
    // `w_{1:t−1}` of the current step t (per-decision weights), formed once per decision.
    let mut w = log_w.exp();
    for (step, ((phi, a), y)) in t.feature_rows().zip(t.actions).zip(t.labels).enumerate() {
        let l = policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
        if per_decision {
            for (o, g) in out.direct_mut().iter_mut().zip(grad.iter()) {
                *o += w.clone() * g;
            }
            out.push_loss(w.clone() * l);
        } else {
            for (o, g) in out.direct_mut().iter_mut().zip(grad.iter()) {
                *o += g;
            }
            out.push_loss(l);
        }
        if step < scored {
            if let Some((theta_new, _)) = ratio {
                log_w += policy
                    .log_likelihood_ratio(theta, theta_new, phi, a)
                    .map_err(policy_error)?;
            }
            if per_decision {
                w = log_w.exp();
            }
            out.push_score_from(per_decision.then(|| w.clone()), score);
        }
    }
    if let Some(tail) = tail {
        out.push_loss(if per_decision { w * tail } else { tail.clone() });
    }
    if matches!(ratio, Some((_, Weighting::Trajectory))) {
        out.set_scale(log_w.exp());
    }
    Ok(())
}
