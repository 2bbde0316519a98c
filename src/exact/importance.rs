//! The importance-sampling identity (I3) and the bias of the unweighted old-point estimate (I4),
//! math.md §§1.4 and 4.
//!
//! (I3) `Σ_τ̄ p(τ̄; θ′) w_{θ→θ′}(τ̄) g(θ, τ̄) = ∇F(θ)` with `w = Π_{i≤T−2} π_θ(a_i|s_i)/π_θ′(a_i|s_i)`
//! (whole-trajectory) or the per-decision weights. (I4) `b(θ, θ′) = Σ p(τ̄; θ′) g(θ, τ̄) − ∇F(θ)`:
//! what the thesis's Algorithm 4 (E10) and Algorithm 5 (E11) actually estimate, minus ∇F.

use super::ExactError;
use super::enumerate::for_each_prefix;
use super::forward::forward;
use crate::problem::{Cost, IlProblem, Weighting};
use crate::scalar::Scalar;
use crate::toy::estimator::causal;
use crate::toy::{ToyProblem, ToyTrajectory};
use nalgebra::DVector;

/// `Σ_τ̄ p(τ̄; θ_new) · w · g(θ_old, τ̄)`, where `w · g` is the oracle's own
/// [`IlProblem::weighted_estimate`]. Equals ∇F(θ_old) exactly by (I3).
///
/// # Errors
/// If the tables cannot be built at either point, or enumeration is too large.
pub fn weighted_expectation<S: Scalar>(
    problem: &ToyProblem<S>,
    theta_old: &[S],
    theta_new: &[S],
    weighting: Weighting,
) -> Result<Vec<S>, ExactError> {
    let table_new = problem.table(theta_new)?;
    let (old, new) = (
        DVector::from_column_slice(theta_old),
        DVector::from_column_slice(theta_new),
    );
    let mut acc = vec![S::zero(); table_new.dim];
    let mut failure = None;
    let mut cost = Cost::default();
    let label = |s: &usize| problem.mdp().expert[*s];
    for_each_prefix(problem, &table_new, |states, actions, p| {
        if failure.is_some() {
            return;
        }
        // Complete the prefix into a trajectory: the last action and state do not matter.
        let mut st = states.to_vec();
        st.push(states[states.len() - 1]);
        let mut ac = actions.to_vec();
        ac.push(0);
        let traj = ToyTrajectory {
            labels: states.iter().map(label).collect(),
            states: st,
            actions: ac,
        };
        match problem.weighted_estimate(&old, &new, &traj, weighting, &mut cost) {
            Ok(g) => {
                for (a, x) in acc.iter_mut().zip(g.iter()) {
                    *a += p.clone() * x;
                }
            }
            Err(e) => failure = Some(e),
        }
    })?;
    match failure {
        Some(e) => Err(e.into()),
        None => Ok(acc),
    }
}

/// `Σ_τ̄ p(τ̄; θ_new) g(θ_old, τ̄)`: the mean of the thesis's unweighted old-point term.
///
/// # Errors
/// As [`weighted_expectation`].
pub fn unweighted_expectation<S: Scalar>(
    problem: &ToyProblem<S>,
    theta_old: &[S],
    theta_new: &[S],
) -> Result<Vec<S>, ExactError> {
    let table_new = problem.table(theta_new)?;
    let table_old = problem.table(theta_old)?;
    let mut acc = vec![S::zero(); table_old.dim];
    for_each_prefix(problem, &table_new, |states, actions, p| {
        let actions = problem.scored_actions(states, actions);
        for (a, x) in acc.iter_mut().zip(causal(&table_old, states, actions)) {
            *a += p.clone() * x;
        }
    })?;
    Ok(acc)
}

/// (I4) `b(θ, θ′) = Σ p(τ̄; θ′) g(θ, τ̄) − ∇F(θ)` (∇F by X2).
///
/// # Errors
/// As [`weighted_expectation`].
pub fn bias<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    theta_prime: &[S],
) -> Result<Vec<S>, ExactError> {
    let mean = unweighted_expectation(problem, theta, theta_prime)?;
    let grad = forward(problem, theta)?.gradient;
    Ok(mean.into_iter().zip(grad).map(|(m, g)| m - g).collect())
}
