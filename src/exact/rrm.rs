//! The exact repeated-risk-minimisation map of math.md §6 (eq. 3.29) for the direct
//! parameterisation (P1) with the Brier loss.
//!
//! RRM picks `θ_{k+1} = argmin_φ Σ_{t=1}^{T−1} E_{s∼d_t^{θ_k}} l(s, φ)`. Under P1 with groups, the
//! Brier loss of group o is minimised by the visitation-weighted frequency of the expert's labels:
//! `G(θ)_o = Σ_t Σ_{s: o(s)=o} d_t^θ(s) e_{a*(s)} / Σ_t Σ_{s: o(s)=o} d_t^θ(s)`
//! (the block keeps the first A − 1 entries). Absorbing states (math.md §8) take no decision and
//! their loss does not depend on φ, so they are left out of the sums.

use super::ExactError;
use super::forward::visitation;
use crate::scalar::Scalar;
use crate::toy::{PolicyKind, ToyProblem};

/// G(θ), the population RRM map, exactly.
///
/// # Errors
/// [`ExactError::NotApplicable`] unless the policy is `direct`, or if a group is never visited
/// (its minimiser is not unique); [`ExactError::Oracle`] if θ is off the open simplex.
pub fn rrm_map<S: Scalar>(problem: &ToyProblem<S>, theta: &[S]) -> Result<Vec<S>, ExactError> {
    let m = problem.mdp();
    if m.policy.kind != PolicyKind::Direct {
        return Err(ExactError::NotApplicable(
            "the closed-form RRM map needs the direct parameterisation".into(),
        ));
    }
    let table = problem.table(theta)?;
    let d = visitation(problem, &table);
    let groups = m.policy.group_count();
    let mut mass = vec![S::zero(); groups];
    let mut label_mass = vec![vec![S::zero(); m.actions]; groups];
    for dt in &d {
        for (s, w) in dt.iter().enumerate() {
            if problem.is_absorbing(s) {
                // No decision there: its constant loss does not depend on the policy.
                continue;
            }
            let o = m.policy.groups[s];
            mass[o] += w;
            label_mass[o][m.expert[s]] += w;
        }
    }
    let mut out = Vec::with_capacity(groups * (m.actions - 1));
    for o in 0..groups {
        if !mass[o].is_certainly_positive() {
            return Err(ExactError::NotApplicable(format!(
                "group {o} is never visited; the RRM minimiser is not unique"
            )));
        }
        for a in 0..m.actions - 1 {
            out.push(label_mass[o][a].clone() / &mass[o]);
        }
    }
    Ok(out)
}
