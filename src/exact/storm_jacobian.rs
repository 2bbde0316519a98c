//! The mean linearisation of STORM's recursion on a toy MDP (math.md §10), exactly.
//!
//! STORM's direction obeys `d_{k+1} = g(θ_{k+1}, τ) + (1 − a)(d_k − g̃_k)` with θ_{k+1} = θ_k − η d_k.
//! To first order in η, `g(θ_{k+1}, τ) − g̃_k ≈ −η J̃_τ d_k`, so the mean error dynamics matrix is
//! `(1 − a)(I − η E[J̃])`. This module computes, at θ and over every positive-probability prefix τ̄
//! (X1 of math.md §1.4), with derivatives by forward-mode duals (no finite differences):
//!
//! * the unweighted old-point term `g̃ = g(θ_k, τ)` (the thesis's Algorithm 4, E10):
//!   `J_τ = ∂g(θ, τ)/∂θ` at a fixed trajectory and `E[J] = Σ_τ̄ p(τ̄; θ) J_τ̄(θ)`;
//! * the covariance term `C = Σ_τ̄ p(τ̄; θ) g(θ, τ̄) ∇_θ log p(τ̄; θ)ᵀ = Σ_τ̄ g(θ, τ̄) ∇_θ p(τ̄; θ)ᵀ`;
//! * the importance-weighted old-point term `g̃ = w_{θ_k→θ_{k+1}}(τ) g(θ_k, τ)` (math.md §4):
//!   `J̃_τ = ∂/∂θ_old [w_{θ_old→θ}(τ) g(θ_old, τ)]` at θ_old = θ, taken through the oracle's own
//!   [`IlProblem::weighted_estimate`], and its mean `Σ_τ̄ p(τ̄; θ) J̃_τ̄`;
//! * the Hessian ∇²F(θ) by X2 ([`forward`]) run in `Dual<S>`: the derivative of the exact ∇F,
//!   independent of the enumeration.
//!
//! Differentiating `∇F(θ) = Σ_τ̄ p(τ̄; θ) g(θ, τ̄)` under the finite sum gives the identity
//! `E[J] + C = ∇²F` (math.md §10.1), and the change of measure gives `E[J̃] = ∇²F` for both weightings.
//! Matrices are row-major: entry (i, j) is `∂(·)_i/∂θ_j`.

use super::ExactError;
use super::enumerate::for_each_prefix;
use super::forward::forward;
use crate::problem::{Cost, IlProblem, Weighting};
use crate::scalar::{Dual, Scalar};
use crate::toy::estimator::causal;
use crate::toy::{ToyProblem, ToyTrajectory};
use nalgebra::DVector;

/// A d × d matrix, row-major (`m[i][j]`).
pub type Matrix<S> = Vec<Vec<S>>;

/// The unweighted old-point term's mean linearisation at θ and the term that separates it from
/// ∇²F.
#[derive(Debug, Clone, PartialEq)]
pub struct Unweighted<S> {
    /// `E[J] = Σ_τ̄ p(τ̄; θ) ∂g(θ, τ̄)/∂θ` (states and actions held fixed).
    pub mean_jacobian: Matrix<S>,
    /// `C = Σ_τ̄ g(θ, τ̄) ∇_θ p(τ̄; θ)ᵀ = E[g ∇log pᵀ]`.
    pub covariance: Matrix<S>,
    /// `E[J ⊗ J] = Σ_τ̄ p(τ̄; θ) J_τ̄ ⊗ J_τ̄` (d² × d², Kronecker order: row `i·d + k`, column
    /// `j·d + l` holds `E[J_ij J_kl]`): what the second moment of the linearised recursion sees.
    pub second_moment: Matrix<S>,
}

/// A dual vector split into its values `x_i` and its Jacobian rows `m[i][j] = ∂x_i/∂θ_j`.
fn split<S: Scalar>(x: Vec<Dual<S>>, d: usize) -> (Vec<S>, Matrix<S>) {
    x.into_iter().map(|xi| xi.into_parts(d)).unzip()
}

/// A zero `rows × cols` matrix.
fn zeros<S: Scalar>(rows: usize, cols: usize) -> Matrix<S> {
    vec![vec![S::zero(); cols]; rows]
}

/// Complete a prefix (s_1..s_{T−1}, a_1..a_{T−2}) into the trajectory the oracle takes: the last
/// action and state do not enter the estimate.
fn trajectory_of(expert: &[usize], states: &[usize], actions: &[usize]) -> ToyTrajectory {
    let mut st = states.to_vec();
    st.push(states[states.len() - 1]);
    let mut ac = actions.to_vec();
    ac.push(0);
    ToyTrajectory {
        labels: states.iter().map(|s| expert[*s]).collect(),
        states: st,
        actions: ac,
    }
}

/// `E[J]`, `C` and `E[J ⊗ J]` at θ for the unweighted old-point term (math.md §10.1).
///
/// One enumeration in `Dual<S>`: each prefix's probability carries ∇p(τ̄; θ) and the oracle's
/// estimator [`causal`] on the dual table carries the rows of J_τ̄.
///
/// # Errors
/// If the tables cannot be built at θ, or the enumeration is too large.
pub fn unweighted<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<Unweighted<S>, ExactError> {
    let d = theta.len();
    let dual: ToyProblem<Dual<S>> = ToyProblem::new(problem.mdp());
    let table = dual.table(&Dual::variables(theta))?;
    let mut mean_jacobian = zeros(d, d);
    let mut covariance = zeros(d, d);
    let mut second_moment = zeros(d * d, d * d);
    for_each_prefix(&dual, &table, |states, actions, p| {
        let (p, grad_p) = p.clone().into_parts(d);
        let (g, jac) = split(
            causal(&table, states, dual.scored_actions(states, actions)),
            d,
        );
        for i in 0..d {
            for j in 0..d {
                mean_jacobian[i][j] += p.clone() * &jac[i][j];
                covariance[i][j] += g[i].clone() * &grad_p[j];
            }
        }
        for (i, row_i) in jac.iter().enumerate() {
            for (k, row_k) in jac.iter().enumerate() {
                for (j, x) in row_i.iter().enumerate() {
                    let px = p.clone() * x;
                    let out = &mut second_moment[i * d + k];
                    for (l, y) in row_k.iter().enumerate() {
                        out[j * d + l] += px.clone() * y;
                    }
                }
            }
        }
    })?;
    Ok(Unweighted {
        mean_jacobian,
        covariance,
        second_moment,
    })
}

/// `Σ_τ̄ p(τ̄; θ) J̃_τ̄` with `J̃_τ̄ = ∂/∂θ_old [w_{θ_old→θ}(τ̄) g(θ_old, τ̄)]` at θ_old = θ: the
/// importance-weighted old-point term's mean linearisation (math.md §10.1), through the oracle's
/// own [`IlProblem::weighted_estimate`] with θ_old seeded as dual variables and θ_new = θ constant.
/// Equals ∇²F(θ) for both weightings.
///
/// # Errors
/// If the tables cannot be built at θ, or the enumeration is too large.
pub fn weighted<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    weighting: Weighting,
) -> Result<Matrix<S>, ExactError> {
    let d = theta.len();
    let dual: ToyProblem<Dual<S>> = ToyProblem::new(problem.mdp());
    let old = DVector::from_vec(Dual::variables(theta));
    let new = DVector::from_iterator(d, theta.iter().cloned().map(Dual::constant));
    let table = dual.table(new.as_slice())?;
    let expert = &problem.mdp().expert;
    let mut mean = zeros(d, d);
    let mut failure = None;
    let mut cost = Cost::default();
    // The oracle is stateless; a copy is the `&mut` receiver while the enumeration reads `dual`.
    let mut oracle = dual.clone();
    for_each_prefix(&dual, &table, |states, actions, p| {
        if failure.is_some() {
            return;
        }
        let traj = trajectory_of(expert, states, actions);
        match oracle.weighted_estimate(&old, &new, &traj, weighting, &mut cost) {
            Ok(g) => {
                let p = p.value();
                let (_, jac) = split(g.iter().cloned().collect(), d);
                for (out, row) in mean.iter_mut().zip(&jac) {
                    for (o, x) in out.iter_mut().zip(row) {
                        *o += p.clone() * x;
                    }
                }
            }
            Err(e) => failure = Some(e),
        }
    })?;
    match failure {
        Some(e) => Err(e.into()),
        None => Ok(mean),
    }
}

/// ∇²F(θ): X2 ([`forward`]) run in `Dual<S>`, so entry (i, j) is `∂(∇F)_i/∂θ_j` of the exact
/// gradient of the forward dynamic programme — no enumeration, no estimator.
///
/// # Errors
/// If the tables cannot be built at θ.
pub fn hessian<S: Scalar>(problem: &ToyProblem<S>, theta: &[S]) -> Result<Matrix<S>, ExactError> {
    let dual: ToyProblem<Dual<S>> = ToyProblem::new(problem.mdp());
    let grad = forward(&dual, &Dual::variables(theta))?.gradient;
    Ok(split(grad, theta.len()).1)
}
