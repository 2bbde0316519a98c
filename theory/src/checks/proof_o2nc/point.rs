//! The exact quantities of the proof at one point of a run: F, ∇F and the conditional moments of
//! the oracle g(w, τ), τ ∼ p(·; w), of eq. 3.15 (through [`TableInputs::estimate`]), by the
//! prefix enumeration (X1) and the forward DP (X2) in ℚ.

use crate::inputs::TableInputs;
use ilopt::exact::enumerate::prefixes;
use ilopt::exact::forward::forward;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::ToyProblem;

type Q = BigRational;

/// The oracle's conditional moments at a point w, with X = ∇F(w) − g(w, τ), τ ∼ p(·; w).
#[derive(Debug, Clone, PartialEq)]
pub struct Moments {
    /// ∇F(w) (X2).
    pub grad: Q,
    /// E[g | w].
    pub mean: Q,
    /// E[‖g‖² | w] (the quantity G² bounds).
    pub second: Q,
    /// E[‖X‖² | w] (the quantity σ² bounds in (3.69)).
    pub centred: Q,
    /// E[‖X‖ | w] (the summand of the printed (3.69)).
    pub abs_dev: Q,
}

/// [`Moments`] at the one-parameter point `w`.
///
/// # Errors
/// If the engine cannot evaluate the problem at `w`.
pub fn moments(problem: &ToyProblem<Q>, inputs: &TableInputs, w: &Q) -> Result<Moments, String> {
    let at = std::slice::from_ref(w);
    let grad = forward(problem, at).map_err(|e| e.to_string())?.gradient[0].clone();
    // Each prefix's probability-weighted estimate p·g is formed once; the centred moments follow
    // from the raw ones: E X² = ∇F² Σp − 2∇F E g + E g², E|X| = Σ_i σ_i p_i g_i − ∇F Σ_i σ_i p_i
    // with σ_i = sign(g_i − ∇F) (fewer operations on the large rationals).
    let (mut mass, mut mean, mut second) = (Q::zero(), Q::zero(), Q::zero());
    let (mut signed_pg, mut signed_p) = (Q::zero(), Q::zero());
    for p in prefixes(problem, at).map_err(|e| e.to_string())? {
        let g = inputs.estimate(p.estimate).swap_remove(0);
        let pg = p.prob.clone() * &g;
        if g > grad {
            signed_pg += &pg;
            signed_p += &p.prob;
        } else if g < grad {
            signed_pg -= &pg;
            signed_p -= &p.prob;
        }
        second += pg.clone() * &g;
        mean += pg;
        mass += p.prob;
    }
    let centred =
        grad.clone() * &grad * &mass - Q::from_integer(2.into()) * &grad * &mean + &second;
    let abs_dev = signed_pg - grad.clone() * &signed_p;
    Ok(Moments {
        grad,
        mean,
        second,
        centred,
        abs_dev,
    })
}

/// F(θ) at the one-parameter point `theta` (X2).
///
/// # Errors
/// If the engine cannot evaluate the problem at `theta`.
pub fn objective(problem: &ToyProblem<Q>, theta: &Q) -> Result<Q, String> {
    Ok(forward(problem, std::slice::from_ref(theta))
        .map_err(|e| e.to_string())?
        .objective)
}
