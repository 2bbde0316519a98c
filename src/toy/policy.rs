//! Rational policy parameterisations of math.md §1.3 and the Brier loss of §1.2.
//!
//! States are mapped to groups o(s) (aliasing); each group owns a block of parameters:
//!
//! | kind | block | π(a \| s), with θ the block of o(s) | ∂π_a/∂θ_b |
//! |---|---|---|---|
//! | P1 `direct` | A − 1 | θ_a (a < A−1), 1 − Σ_b θ_b (a = A−1) | δ_ab − δ_{a,A−1} |
//! | P2 `rational-softmax` | A | u_a/Σ u, u_a = θ_a² + c | 2θ_b/S (δ_ab − π_a) |
//! | P2' `tied-softmax` (A = 2) | 1 | P2 with θ_1 = θ, θ_0 = 1 − θ | chain rule through the tie |
//!
//! The probabilities are generic over any [`Scalar`] (so they run in `Dual<S>` for the independent
//! derivative checks); the Jacobians are the analytic formulas above.

use crate::problem::OracleError;
use crate::scalar::{BigRational, Scalar};

/// The parameterisation (math.md §1.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PolicyKind {
    /// P2: π(a|s) = (θ_{o,a}² + c)/Σ_b(θ_{o,b}² + c).
    RationalSoftmax,
    /// P1: the open simplex, last action gets the remainder.
    Direct,
    /// P2': two actions, θ_{o,1} = θ, θ_{o,0} = 1 − θ in P2.
    TiedSoftmax,
}

/// A policy class for a toy MDP: kind, parameter c, and the state → group map.
#[derive(Debug, Clone, PartialEq)]
pub struct PolicySpec {
    /// The parameterisation.
    pub kind: PolicyKind,
    /// c > 0 for the softmax kinds.
    pub c: Option<BigRational>,
    /// o(s) for every state; groups are 0..G.
    pub groups: Vec<usize>,
    actions: usize,
    group_count: usize,
}

impl PolicySpec {
    /// A validated spec (validation happens in the file reader; this only assembles it).
    pub(crate) fn new(
        kind: PolicyKind,
        c: Option<BigRational>,
        groups: Vec<usize>,
        actions: usize,
    ) -> Self {
        let group_count = groups.iter().max().map_or(0, |m| m + 1);
        Self {
            kind,
            c,
            groups,
            actions,
            group_count,
        }
    }
    /// Number of groups G.
    pub fn group_count(&self) -> usize {
        self.group_count
    }
    /// Number of actions A.
    pub fn actions(&self) -> usize {
        self.actions
    }
    /// Parameters per group.
    pub fn block(&self) -> usize {
        match self.kind {
            PolicyKind::RationalSoftmax => self.actions,
            PolicyKind::Direct => self.actions - 1,
            PolicyKind::TiedSoftmax => 1,
        }
    }
    /// d = G · block.
    pub fn dim(&self) -> usize {
        self.group_count * self.block()
    }

    /// π(·|group) from the group's parameter block, in any scalar (math.md §1.3).
    ///
    /// # Errors
    /// [`OracleError::Domain`] when a direct-parameterisation probability is not certainly positive
    /// (θ off the open simplex), [`OracleError::ZeroProbability`] if a softmax denominator vanishes.
    pub fn group_probs<T: Scalar>(&self, block: &[T], c: &T) -> Result<Vec<T>, OracleError> {
        match self.kind {
            PolicyKind::Direct => {
                let mut p: Vec<T> = block.to_vec();
                let rest = block.iter().fold(T::one(), |acc, x| acc - x);
                p.push(rest);
                if let Some(a) = p.iter().position(|x| !x.is_certainly_positive()) {
                    return Err(OracleError::Domain(format!(
                        "direct parameterisation: π(a={a}) = {:?} is not certainly > 0 (θ must lie in the open simplex)",
                        p[a].to_f64()
                    )));
                }
                Ok(p)
            }
            PolicyKind::RationalSoftmax => softmax(block, c),
            PolicyKind::TiedSoftmax => {
                let t = &block[0];
                softmax(&[T::one() - t, t.clone()], c)
            }
        }
    }

    /// The analytic Jacobian `∂π_a/∂θ_j` (rows a, columns the group's block), given the
    /// probabilities from [`PolicySpec::group_probs`].
    pub fn group_jacobian<S: Scalar>(&self, block: &[S], c: &S, probs: &[S]) -> Vec<Vec<S>> {
        let n = self.actions;
        match self.kind {
            PolicyKind::Direct => (0..n)
                .map(|a| {
                    (0..n - 1)
                        .map(|b| {
                            if a == n - 1 {
                                -S::one()
                            } else if a == b {
                                S::one()
                            } else {
                                S::zero()
                            }
                        })
                        .collect()
                })
                .collect(),
            PolicyKind::RationalSoftmax => softmax_jacobian(block, c, probs),
            PolicyKind::TiedSoftmax => {
                // θ_0 = 1 − θ, θ_1 = θ: dπ_a/dθ = ∂π_a/∂θ_1 − ∂π_a/∂θ_0.
                let t = &block[0];
                let j = softmax_jacobian(&[S::one() - t, t.clone()], c, probs);
                j.into_iter()
                    .map(|row| vec![row[1].clone() - &row[0]])
                    .collect()
            }
        }
    }
}

fn softmax<T: Scalar>(theta: &[T], c: &T) -> Result<Vec<T>, OracleError> {
    let u: Vec<T> = theta.iter().map(|t| t.square() + c).collect();
    let s = u.iter().fold(T::zero(), |acc, x| acc + x);
    if !s.is_certainly_positive() {
        return Err(OracleError::ZeroProbability("rational softmax denominator"));
    }
    Ok(u.into_iter().map(|x| x / &s).collect())
}

/// ∂π_a/∂θ_b = 2θ_b/S (δ_ab − π_a), S = Σ_b(θ_b² + c).
fn softmax_jacobian<S: Scalar>(theta: &[S], c: &S, probs: &[S]) -> Vec<Vec<S>> {
    let s = theta.iter().fold(S::zero(), |acc, t| acc + t.square() + c);
    let two_over_s = S::from_i64(2) / &s;
    (0..theta.len())
        .map(|a| {
            (0..theta.len())
                .map(|b| {
                    let delta = if a == b { S::one() } else { S::zero() };
                    two_over_s.product(&theta[b]).product(&(delta - &probs[a]))
                })
                .collect()
        })
        .collect()
}

/// The Brier loss of math.md §1.2 (L-Brier): `l = Σ_a (π_a − 1[a = a*])²`, and its gradient
/// `∇l = 2 Σ_a (π_a − 1[a = a*]) ∇π_a` in the group's block.
pub fn brier<S: Scalar>(probs: &[S], jacobian: &[Vec<S>], expert: usize) -> (S, Vec<S>) {
    let block = jacobian.first().map_or(0, Vec::len);
    let mut loss = S::zero();
    let mut grad = vec![S::zero(); block];
    for (a, p) in probs.iter().enumerate() {
        let r = if a == expert {
            p.clone() - S::one()
        } else {
            p.clone()
        };
        loss += r.square();
        let two_r = S::from_i64(2) * &r;
        for (g, j) in grad.iter_mut().zip(&jacobian[a]) {
            *g += two_r.product(j);
        }
    }
    (loss, grad)
}

/// The Brier loss alone, in any scalar (for the dual-number checks).
pub fn brier_value<T: Scalar>(probs: &[T], expert: usize) -> T {
    probs.iter().enumerate().fold(T::zero(), |acc, (a, p)| {
        let r = if a == expert {
            p.clone() - T::one()
        } else {
            p.clone()
        };
        acc + r.square()
    })
}
