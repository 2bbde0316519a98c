//! Evaluating a learned θ: the Monte-Carlo objective `F̂(θ) = (1/n) Σ_j L(θ, τ_j)` over `n`
//! seeded roll-outs of the learner, `L` the problem's trajectory loss (for a task problem: the
//! summed imitation loss of one stream or episode, the absorbing tail included), with its
//! standard error; deterministic evaluation episodes ([`episodes`]), the success rates and
//! rewards chapter 4 reports; and the kit's built-in tasks paired with the thesis's learners,
//! their IL problems and their evaluation of θ ([`builtin`]), shared by `ilopt run` and the
//! appendix.

pub mod builtin;
pub mod episodes;
mod evaluation;

pub use evaluation::Evaluation;

use crate::problem::{Behaviour, Cost, IlProblem, KitRng, OracleError};
use nalgebra::DVector;
use rand::SeedableRng;

/// `F̂(θ)` with its standard error and the number of roll-outs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Objective {
    /// `(1/n) Σ_j L(θ, τ_j)`.
    pub mean: f64,
    /// `s/√n`, s the sample standard deviation (0 for n = 1).
    pub standard_error: f64,
    /// n.
    pub rollouts: usize,
}

/// `F̂(θ)` over `n ≥ 1` roll-outs of the learner at θ from one RNG seeded with `seed` (the same
/// seed gives the same roll-outs, so two θ compared with one seed share their random numbers).
///
/// # Errors
/// [`OracleError::Trajectory`] for `n = 0`; a roll-out's or the loss's error; a non-finite loss.
pub fn objective<P: IlProblem<f64> + ?Sized>(
    problem: &mut P,
    theta: &DVector<f64>,
    n: usize,
    seed: u64,
) -> Result<Objective, OracleError> {
    if n == 0 {
        return Err(OracleError::Trajectory(
            "evaluate with at least one roll-out".into(),
        ));
    }
    let mut rng = KitRng::seed_from_u64(seed);
    let mut losses = Vec::with_capacity(n);
    for _ in 0..n {
        let t = problem.rollout(&Behaviour::Learner(theta), &mut rng, &mut Cost::default())?;
        let l = problem.trajectory_loss(theta, &t)?;
        if !l.is_finite() {
            return Err(OracleError::NonFinite("a trajectory's loss"));
        }
        losses.push(l);
    }
    let mean = losses.iter().sum::<f64>() / n as f64;
    let standard_error = if n > 1 {
        let var = losses.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (var / n as f64).sqrt()
    } else {
        0.0
    };
    Ok(Objective {
        mean,
        standard_error,
        rollouts: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::BigRational;
    use crate::toy::{ToyMdp, ToyProblem};

    /// On a toy MDP the Monte-Carlo objective agrees with the exact F (X2) within 4 standard
    /// errors, and n = 0 is an error.
    #[test]
    fn the_monte_carlo_objective_agrees_with_the_exact_one() {
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/toy/m1-tied.json"),
        )
        .unwrap();
        let mdp = ToyMdp::from_json_str(&text).unwrap();
        let exact = crate::exact::forward::forward(
            &ToyProblem::<BigRational>::new(&mdp),
            &[BigRational::new(1.into(), 3.into())],
        )
        .unwrap()
        .objective;
        let exact = crate::scalar::Scalar::to_f64(&exact);
        let mut p = ToyProblem::<f64>::new(&mdp);
        let theta = DVector::from_vec(vec![1.0 / 3.0]);
        let f = objective(&mut p, &theta, 20_000, 3).unwrap();
        assert!(
            approx::abs_diff_eq!(f.mean, exact, epsilon = 4.0 * f.standard_error),
            "{f:?} vs {exact}"
        );
        assert_eq!(objective(&mut p, &theta, 20_000, 3).unwrap(), f);
        assert!(objective(&mut p, &theta, 0, 3).is_err());
    }
}
