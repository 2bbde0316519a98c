//! A point of the search space of the tight rows: an instance of the M family of math.md §6 with
//! the tied rational softmax P2' (`ToyMdp::m_family`), a start θ₁ and a horizon K of the run.
//! With a two-coordinate θ₁ the learner sees the state and has one parameter per state, θ =
//! (θ_A, θ_B): the family of the second toy (`checks::second_toy`, M(1/2, 1/4, 1/2, 4), c = 1/2).

use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp};
use serde_json::{Value, json};

/// M(μ_A, p₀, p₁, T) with P2' (parameter c), started at θ₁ and run for K steps; one parameter
/// for both states if θ₁ has one coordinate, one per state if it has two.
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
    /// The start θ₁: (θ) with one parameter, (θ_A, θ_B) with one per state.
    pub theta1: Vec<BigRational>,
    /// Iterations K of the run.
    pub k: u64,
}

impl Instance {
    /// The toy MDP of this instance.
    ///
    /// # Errors
    /// A message if the numbers are not probabilities, c is not positive, or θ₁ has neither one
    /// nor two coordinates.
    pub fn mdp(&self) -> Result<ToyMdp, String> {
        let tied = ToyMdp::m_family(
            self.mu_a.clone(),
            self.p0.clone(),
            self.p1.clone(),
            self.horizon,
            PolicyKind::TiedSoftmax,
            Some(self.c.clone()),
        )
        .map_err(|e| e.to_string())?;
        match self.theta1.len() {
            1 => Ok(tied),
            2 => per_state(&tied, &self.c),
            n => Err(format!(
                "θ₁ has {n} coordinates; the M family has one parameter or one per state (two)"
            )),
        }
    }

    /// θ₁ in `S`.
    pub fn theta1_in<S: Scalar>(&self) -> Vec<S> {
        self.theta1.iter().map(S::from_rational).collect()
    }

    /// `M(μ_A, p₀, p₁, T), c, θ₁, K` as the rows print it.
    pub fn describe(&self) -> String {
        let (policy, theta1) = match self.theta1.as_slice() {
            [t] => ("P2′", t.to_string()),
            ts => (
                "P2′ per state",
                format!(
                    "({})",
                    ts.iter()
                        .map(|t| t.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ),
        };
        format!(
            "M({}, {}, {}, {}) with {policy} (c = {}), θ₁ = {theta1}, K = {}",
            self.mu_a, self.p0, self.p1, self.horizon, self.c, self.k
        )
    }
}

/// The MDP `tied` (an M-family instance, its two states in one group) with one parameter per
/// state instead: the same chain, expert and P2' with parameter c, groups o(A) = 0, o(B) = 1.
fn per_state(tied: &ToyMdp, c: &BigRational) -> Result<ToyMdp, String> {
    let s = |q: &BigRational| Value::String(q.to_string());
    let row = |r: &[BigRational]| Value::Array(r.iter().map(s).collect());
    let v = json!({
        "states": tied.states,
        "actions": tied.actions,
        "horizon": tied.horizon,
        "initial": row(&tied.initial),
        "transition": tied
            .transition
            .iter()
            .map(|by_action| Value::Array(by_action.iter().map(|p| row(p)).collect()))
            .collect::<Vec<_>>(),
        "expert": tied.expert,
        "policy": { "kind": "tied-softmax", "c": s(c), "groups": [0, 1] },
    });
    ToyMdp::from_json(&v).map_err(|e| e.to_string())
}

/// The rational equal to a finite `f64` (every `f64` is a dyadic rational).
///
/// # Panics
/// Never for the finite values the search draws.
pub fn exact(x: f64) -> BigRational {
    BigRational::from_float(x).expect("a finite f64")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checks::second_toy::m2_two_groups;

    /// With θ₁ in 2-D the instance M(1/2, 1/4, 1/2, 4), c = 1/2, is the second toy itself; with
    /// three coordinates it is refused.
    #[test]
    fn a_two_coordinate_start_gives_the_second_toy() {
        let q = |n, d| BigRational::from_ratio(n, d);
        let mut inst = Instance {
            mu_a: q(1, 2),
            p0: q(1, 4),
            p1: q(1, 2),
            horizon: 4,
            c: q(1, 2),
            theta1: vec![q(0, 1), q(1, 2)],
            k: 2,
        };
        assert_eq!(inst.mdp().unwrap(), m2_two_groups());
        assert!(
            inst.describe()
                .contains("P2′ per state (c = 1/2), θ₁ = (0, 1/2)")
        );
        inst.theta1.push(q(0, 1));
        assert!(inst.mdp().unwrap_err().contains("3 coordinates"));
    }
}
