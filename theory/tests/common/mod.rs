//! Exact helpers shared by the theory tests.

use ilopt::exact::enumerate::prefixes;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::ToyProblem;

/// V_IS(θ, θ′) = Σ_τ̄ p(τ̄; θ′) ‖g(θ′, τ̄) − w g(θ, τ̄)‖² with the trajectory weight
/// w = p(τ̄; θ)/p(τ̄; θ′), exactly, from the prefix enumeration (independent of the engine's
/// importance-weighted estimator).
pub fn v_is_trajectory(
    p: &ToyProblem<BigRational>,
    theta: &BigRational,
    prime: &BigRational,
) -> BigRational {
    let a = prefixes(p, std::slice::from_ref(theta)).unwrap();
    let b = prefixes(p, std::slice::from_ref(prime)).unwrap();
    a.iter().zip(&b).fold(BigRational::zero(), |acc, (x, y)| {
        assert_eq!((&x.states, &x.actions), (&y.states, &y.actions));
        let w = x.prob.clone() / &y.prob;
        let d = y.estimate[0].clone() - w * &x.estimate[0];
        acc + y.prob.clone() * &d * &d
    })
}
