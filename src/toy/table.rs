//! Everything the oracle and the exact engine need at one θ, computed once: π(·|o), ∇π, the scores
//! ψ = ∇π/π, and per state the Brier loss l(s, θ) and ∇l(s, θ) (math.md §§1.2–1.3); an absorbing
//! state (math.md §8) carries its constant loss and a zero gradient instead.
//!
//! Gradients are stored per group block (length `block`); [`PolicyTable::add_block`] scatters a
//! block into a full d-vector at the state's offset.

use super::ToyMdp;
use super::policy::brier;
use crate::problem::OracleError;
use crate::scalar::Scalar;

/// The policy and loss tables at one θ.
#[derive(Debug, Clone)]
pub struct PolicyTable<S> {
    /// π(a|o) as `probs[o][a]`.
    pub probs: Vec<Vec<S>>,
    /// ∂π(a|o)/∂θ_{o,j} as `jacobian[o][a][j]`.
    pub jacobian: Vec<Vec<Vec<S>>>,
    /// ψ(a|o) = ∇log π(a|o) as `score[o][a][j]`.
    pub score: Vec<Vec<Vec<S>>>,
    /// l(s, θ) per state: the Brier loss, or at an absorbing state (math.md §8) its stated loss
    /// per step, which does not depend on θ.
    pub loss: Vec<S>,
    /// ∇l(s, θ) per state, in the block of o(s) (zero at an absorbing state).
    pub loss_grad: Vec<Vec<S>>,
    /// o(s).
    pub groups: Vec<usize>,
    /// Parameters per group.
    pub block: usize,
    /// d.
    pub dim: usize,
}

impl<S: Scalar> PolicyTable<S> {
    /// Build the table at θ.
    ///
    /// # Errors
    /// [`OracleError::Dimension`] for a θ of the wrong length; [`OracleError::NonFinite`] for a
    /// non-finite θ; the policy's domain errors; [`OracleError::ZeroProbability`] when a
    /// probability is not certainly positive (its score would divide by zero).
    pub fn new(mdp: &ToyMdp, c: &S, theta: &[S]) -> Result<Self, OracleError> {
        let spec = &mdp.policy;
        let (block, dim) = (spec.block(), spec.dim());
        if theta.len() != dim {
            return Err(OracleError::Dimension {
                expected: dim,
                got: theta.len(),
            });
        }
        if !theta.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("θ"));
        }
        let (mut probs, mut jacobian, mut score) = (Vec::new(), Vec::new(), Vec::new());
        for o in 0..spec.group_count() {
            let th = &theta[o * block..(o + 1) * block];
            let p = spec.group_probs(th, c)?;
            if !p.iter().all(Scalar::is_finite) {
                return Err(OracleError::NonFinite(
                    "π_θ(a|s) (the arithmetic overflowed at this θ)",
                ));
            }
            let j = spec.group_jacobian(th, c, &p);
            let mut sc = Vec::with_capacity(p.len());
            for (pa, ja) in p.iter().zip(&j) {
                if !pa.is_certainly_positive() {
                    return Err(OracleError::ZeroProbability("π(a|s) in a score"));
                }
                sc.push(ja.iter().map(|x| x.clone() / pa).collect());
            }
            probs.push(p);
            jacobian.push(j);
            score.push(sc);
        }
        let (mut loss, mut loss_grad) = (Vec::new(), Vec::new());
        for (s, &o) in spec.groups.iter().enumerate() {
            if let Some(c) = mdp.termination.absorbing_loss(s) {
                // An absorbing state pays its stated loss, a constant in θ (math.md §8).
                loss.push(S::from_rational(c));
                loss_grad.push(vec![S::zero(); block]);
                continue;
            }
            let (l, g) = brier(&probs[o], &jacobian[o], mdp.expert[s]);
            loss.push(l);
            loss_grad.push(g);
        }
        Ok(Self {
            probs,
            jacobian,
            score,
            loss,
            loss_grad,
            groups: spec.groups.clone(),
            block,
            dim,
        })
    }

    /// π(a|s).
    pub fn prob(&self, s: usize, a: usize) -> &S {
        &self.probs[self.groups[s]][a]
    }
    /// ψ(a|s) (block of o(s)).
    pub fn score(&self, s: usize, a: usize) -> &[S] {
        &self.score[self.groups[s]][a]
    }
    /// ∇π(a|s) (block of o(s)).
    pub fn prob_grad(&self, s: usize, a: usize) -> &[S] {
        &self.jacobian[self.groups[s]][a]
    }
    /// `full[o(s) block] += scale · local`.
    pub fn add_block(&self, full: &mut [S], s: usize, local: &[S], scale: &S) {
        let off = self.groups[s] * self.block;
        for (f, x) in full[off..off + self.block].iter_mut().zip(local) {
            *f += scale.product(x);
        }
    }
    /// `full[o(s) block] += local`.
    pub fn add_block_unscaled(&self, full: &mut [S], s: usize, local: &[S]) {
        let off = self.groups[s] * self.block;
        for (f, x) in full[off..off + self.block].iter_mut().zip(local) {
            *f += x;
        }
    }
}
