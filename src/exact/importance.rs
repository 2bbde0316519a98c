//! The importance-sampling identity (I3) and the bias of the unweighted old-point estimate (I4),
//! math.md §§1.4 and 4.
//!
//! (I3) `Σ_τ̄ p(τ̄; θ′) w_{θ→θ′}(τ̄) g(θ, τ̄) = ∇F(θ)` with `w = Π_{i≤T−2} π_θ(a_i|s_i)/π_θ′(a_i|s_i)`
//! (whole-trajectory) or the per-decision weights. (I4) `b(θ, θ′) = Σ p(τ̄; θ′) g(θ, τ̄) − ∇F(θ)`:
//! what the thesis's Algorithm 4 (E10) and Algorithm 5 (E11) actually estimate, minus ∇F.

use super::ExactError;
use super::baseline::prefix_trajectory;
use super::enumerate::for_each_prefix;
use super::forward::forward;
use crate::problem::{Cost, IlProblem, Weighting};
use crate::scalar::Scalar;
use crate::toy::ToyProblem;
use crate::toy::estimator::{causal, weighted};
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
    // The oracle is stateless; a copy is the `&mut` receiver while the enumeration reads `problem`.
    let mut oracle = problem.clone();
    for_each_prefix(problem, &table_new, |states, actions, p| {
        if failure.is_some() {
            return;
        }
        let traj = prefix_trajectory(problem, states, actions);
        match oracle.weighted_estimate(&old, &new, &traj, weighting, &mut cost) {
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

/// One trajectory prefix τ̄ drawn at θ_new, with the three estimates a STORM step from θ_old to
/// θ_new takes on it (math.md §§3.2, 4).
#[derive(Debug, Clone, PartialEq)]
pub struct StepSample<S> {
    /// p(τ̄; θ_new).
    pub prob: S,
    /// g(θ_new, τ̄), the causal form of eq. 3.15.
    pub new: Vec<S>,
    /// The importance-weighted old-point term w g(θ_old, τ̄) (the estimator code of the oracle's
    /// [`IlProblem::weighted_estimate`], [`weighted`]); its mean is ∇F(θ_old) by (I3).
    pub weighted: Vec<S>,
    /// The unweighted old-point term g(θ_old, τ̄) of eq. 3.40 verbatim (causal form); its mean is
    /// ∇F(θ_old) + b(θ_old, θ_new) by (I4).
    pub unweighted: Vec<S>,
}

/// Every positive-probability prefix at θ_new with the estimates of [`StepSample`]: the law of
/// one STORM step's randomness given the past, so that every conditional expectation of the
/// step is a finite sum over this list. The two policy tables are built once for all prefixes.
///
/// # Errors
/// As [`weighted_expectation`].
pub fn step_samples<S: Scalar>(
    problem: &ToyProblem<S>,
    theta_old: &[S],
    theta_new: &[S],
    weighting: Weighting,
) -> Result<Vec<StepSample<S>>, ExactError> {
    let table_new = problem.table(theta_new)?;
    let table_old = problem.table(theta_old)?;
    let mut out = Vec::new();
    for_each_prefix(problem, &table_new, |states, actions, p| {
        let scored = problem.scored_actions(states, actions);
        out.push(StepSample {
            prob: p.clone(),
            new: causal(&table_new, states, scored),
            weighted: weighted(&table_old, &table_new, states, scored, weighting),
            unweighted: causal(&table_old, states, scored),
        });
    })?;
    Ok(out)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{BigRational, parse_exact};
    use crate::toy::ToyMdp;

    /// The step's samples reproduce the three means exactly on M1 (math.md §1.4's reference
    /// values at θ = 0, θ′ = 1: −1/2 with the weight, −1/12 without), with either weighting.
    #[test]
    fn step_samples_carry_the_three_means() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/toy/m1-tied.json");
        let mdp = ToyMdp::load(&path).expect("M1");
        let p = ToyProblem::<BigRational>::new(&mdp);
        let q = |s: &str| parse_exact(s).unwrap();
        let (old, new) = ([q("0")], [q("1")]);
        for weighting in [Weighting::Trajectory, Weighting::PerDecision] {
            let samples = step_samples(&p, &old, &new, weighting).expect("small");
            let mean = |f: &dyn Fn(&StepSample<BigRational>) -> &Vec<BigRational>| {
                samples
                    .iter()
                    .fold(q("0"), |acc, s| acc + s.prob.clone() * &f(s)[0])
            };
            assert_eq!(samples.iter().fold(q("0"), |a, s| a + &s.prob), q("1"));
            assert_eq!(mean(&|s| &s.weighted), q("-1/2"));
            assert_eq!(mean(&|s| &s.unweighted), q("-1/12"));
            assert_eq!(mean(&|s| &s.new), forward(&p, &new).unwrap().gradient[0]);
            assert_eq!(
                vec![mean(&|s| &s.weighted)],
                weighted_expectation(&p, &old, &new, weighting).unwrap()
            );
        }
    }
}
