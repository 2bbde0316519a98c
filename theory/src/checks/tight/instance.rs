//! A point of the search space of the tight rows: an instance of the M family of math.md §6 with
//! the tied rational softmax P2' (`ToyMdp::m_family`), a start θ₁ and a horizon K of the run.

use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp};

/// M(μ_A, p₀, p₁, T) with P2' (parameter c), started at θ₁ and run for K steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Instance {
    /// μ(A), the probability of starting in A.
    pub mu_a: BigRational,
    /// P(A | action 0).
    pub p0: BigRational,
    /// P(A | action 1).
    pub p1: BigRational,
    /// The MDP's horizon T (losses at t = 1..T−1).
    pub horizon: usize,
    /// c > 0 of the rational softmax P2'.
    pub c: BigRational,
    /// The start θ₁.
    pub theta1: BigRational,
    /// Iterations K of the run.
    pub k: u64,
}

impl Instance {
    /// The toy MDP of this instance.
    ///
    /// # Errors
    /// A message if the numbers are not probabilities or c is not positive.
    pub fn mdp(&self) -> Result<ToyMdp, String> {
        ToyMdp::m_family(
            self.mu_a.clone(),
            self.p0.clone(),
            self.p1.clone(),
            self.horizon,
            PolicyKind::TiedSoftmax,
            Some(self.c.clone()),
        )
        .map_err(|e| e.to_string())
    }

    /// θ₁ in `S`.
    pub fn theta1_in<S: Scalar>(&self) -> Vec<S> {
        vec![S::from_rational(&self.theta1)]
    }

    /// `M(μ_A, p₀, p₁, T), c, θ₁, K` as the rows print it.
    pub fn describe(&self) -> String {
        format!(
            "M({}, {}, {}, {}) with P2′ (c = {}), θ₁ = {}, K = {}",
            self.mu_a, self.p0, self.p1, self.horizon, self.c, self.theta1, self.k
        )
    }
}

/// The rational equal to a finite `f64` (every `f64` is a dyadic rational).
///
/// # Panics
/// Never for the finite values the search draws.
pub fn exact(x: f64) -> BigRational {
    BigRational::from_float(x).expect("a finite f64")
}
