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
        let mut p = Vec::with_capacity(self.actions);
        self.group_probs_into(block, c, &mut p)?;
        Ok(p)
    }

    /// [`PolicySpec::group_probs`] into `out` (cleared first; its storage reused).
    ///
    /// # Errors
    /// As [`PolicySpec::group_probs`].
    pub fn group_probs_into<T: Scalar>(
        &self,
        block: &[T],
        c: &T,
        out: &mut Vec<T>,
    ) -> Result<(), OracleError> {
        match self.kind {
            PolicyKind::Direct => {
                out.clear();
                out.extend_from_slice(block);
                let rest = block.iter().fold(T::one(), |acc, x| acc - x);
                out.push(rest);
                if let Some(a) = out.iter().position(|x| !x.is_certainly_positive()) {
                    return Err(OracleError::Domain(format!(
                        "direct parameterisation: π(a={a}) = {:?} is not certainly > 0 (θ must lie in the open simplex)",
                        out[a].to_f64()
                    )));
                }
                Ok(())
            }
            PolicyKind::RationalSoftmax => softmax_into(block, c, out),
            PolicyKind::TiedSoftmax => {
                let t = &block[0];
                softmax_into(&[T::one() - t, t.clone()], c, out)
            }
        }
    }

    /// The analytic Jacobian `∂π_a/∂θ_j` (rows a, columns the group's block), given the
    /// probabilities from [`PolicySpec::group_probs`].
    pub fn group_jacobian<S: Scalar>(&self, block: &[S], c: &S, probs: &[S]) -> Vec<Vec<S>> {
        let mut j = Vec::with_capacity(self.actions);
        self.group_jacobian_into(block, c, probs, &mut j);
        j
    }

    /// [`PolicySpec::group_jacobian`] into `out` (one row per action; the rows' storage reused).
    pub fn group_jacobian_into<S: Scalar>(
        &self,
        block: &[S],
        c: &S,
        probs: &[S],
        out: &mut Vec<Vec<S>>,
    ) {
        let n = self.actions;
        match self.kind {
            PolicyKind::Direct => {
                out.resize_with(n, Vec::new);
                for (a, row) in out.iter_mut().enumerate() {
                    row.clear();
                    row.extend((0..n - 1).map(|b| {
                        if a == n - 1 {
                            -S::one()
                        } else if a == b {
                            S::one()
                        } else {
                            S::zero()
                        }
                    }));
                }
            }
            PolicyKind::RationalSoftmax => softmax_jacobian_into(block, c, probs, out),
            PolicyKind::TiedSoftmax => {
                // θ_0 = 1 − θ, θ_1 = θ: dπ_a/dθ = ∂π_a/∂θ_1 − ∂π_a/∂θ_0, each entry as
                // [`softmax_jacobian_entry`] forms it.
                let t = &block[0];
                let theta = [S::one() - t, t.clone()];
                let two_over_s = softmax_two_over_s(&theta, c);
                out.resize_with(probs.len(), Vec::new);
                for (a, row) in out.iter_mut().enumerate() {
                    let entry = |b: usize| softmax_jacobian_entry(&two_over_s, &theta, probs, a, b);
                    let d = entry(1) - &entry(0);
                    row.clear();
                    row.push(d);
                }
            }
        }
    }
}

/// The rational softmax `u_a / Σ u`, `u_a = θ_a² + c`, into `out` (cleared first).
fn softmax_into<T: Scalar>(theta: &[T], c: &T, out: &mut Vec<T>) -> Result<(), OracleError> {
    out.clear();
    out.extend(theta.iter().map(|t| t.square() + c));
    let s = out.iter().fold(T::zero(), |acc, x| acc + x);
    if !s.is_certainly_positive() {
        return Err(OracleError::ZeroProbability("rational softmax denominator"));
    }
    for x in out.iter_mut() {
        let u = std::mem::replace(x, T::zero());
        *x = u / &s;
    }
    Ok(())
}

/// `2/S`, S = Σ_b(θ_b² + c), of [`softmax_jacobian_into`].
fn softmax_two_over_s<S: Scalar>(theta: &[S], c: &S) -> S {
    let s = theta.iter().fold(S::zero(), |acc, t| acc + t.square() + c);
    S::from_i64(2) / &s
}

/// ∂π_a/∂θ_b = 2θ_b/S (δ_ab − π_a).
fn softmax_jacobian_entry<S: Scalar>(
    two_over_s: &S,
    theta: &[S],
    probs: &[S],
    a: usize,
    b: usize,
) -> S {
    let delta = if a == b { S::one() } else { S::zero() };
    two_over_s.product(&theta[b]).product(&(delta - &probs[a]))
}

/// ∂π_a/∂θ_b = 2θ_b/S (δ_ab − π_a), S = Σ_b(θ_b² + c), into `out` (rows a; storage reused).
fn softmax_jacobian_into<S: Scalar>(theta: &[S], c: &S, probs: &[S], out: &mut Vec<Vec<S>>) {
    let two_over_s = softmax_two_over_s(theta, c);
    out.resize_with(theta.len(), Vec::new);
    for (a, row) in out.iter_mut().enumerate() {
        row.clear();
        row.extend(
            (0..theta.len()).map(|b| softmax_jacobian_entry(&two_over_s, theta, probs, a, b)),
        );
    }
}

/// The Brier loss of math.md §1.2 (L-Brier): `l = Σ_a (π_a − 1[a = a*])²`, and its gradient
/// `∇l = 2 Σ_a (π_a − 1[a = a*]) ∇π_a` in the group's block.
pub fn brier<S: Scalar>(probs: &[S], jacobian: &[Vec<S>], expert: usize) -> (S, Vec<S>) {
    let mut grad = Vec::with_capacity(jacobian.first().map_or(0, Vec::len));
    let loss = brier_into(probs, jacobian, expert, &mut grad);
    (loss, grad)
}

/// [`brier`] with the gradient into `grad` (its storage reused); returns the loss.
pub fn brier_into<S: Scalar>(
    probs: &[S],
    jacobian: &[Vec<S>],
    expert: usize,
    grad: &mut Vec<S>,
) -> S {
    let block = jacobian.first().map_or(0, Vec::len);
    let mut loss = S::zero();
    grad.clear();
    grad.resize(block, S::zero());
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
    loss
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
