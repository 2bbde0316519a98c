//! Everything the oracle and the exact engine need at one θ, computed once: π(·|o), ∇π, the scores
//! ψ = ∇π/π, and per state the Brier loss l(s, θ) and ∇l(s, θ) (math.md §§1.2–1.3); an absorbing
//! state (math.md §8) carries its constant loss and a zero gradient instead.
//!
//! Gradients are stored per group block (length `block`); [`PolicyTable::add_block`] scatters a
//! block into a full d-vector at the state's offset.

use super::ToyMdp;
use super::policy::brier_into;
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
        let mut table = Self {
            probs: Vec::new(),
            jacobian: Vec::new(),
            score: Vec::new(),
            loss: Vec::new(),
            loss_grad: Vec::new(),
            groups: Vec::new(),
            block: 0,
            dim: 0,
        };
        table.rebuild(mdp, c, theta)?;
        Ok(table)
    }

    /// The table at θ in place of this one, its storage reused: [`PolicyTable::new`]'s values,
    /// with no allocation when the table was built for the same MDP before.
    ///
    /// # Errors
    /// As [`PolicyTable::new`]; the table's contents are then unspecified.
    pub fn rebuild(&mut self, mdp: &ToyMdp, c: &S, theta: &[S]) -> Result<(), OracleError> {
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
        let groups = spec.group_count();
        self.probs.resize_with(groups, Vec::new);
        self.jacobian.resize_with(groups, Vec::new);
        self.score.resize_with(groups, Vec::new);
        for o in 0..groups {
            let th = &theta[o * block..(o + 1) * block];
            let p = &mut self.probs[o];
            spec.group_probs_into(th, c, p)?;
            if !p.iter().all(Scalar::is_finite) {
                return Err(OracleError::NonFinite(
                    "π_θ(a|s) (the arithmetic overflowed at this θ)",
                ));
            }
            let j = &mut self.jacobian[o];
            spec.group_jacobian_into(th, c, p, j);
            let sc = &mut self.score[o];
            sc.resize_with(p.len(), Vec::new);
            for ((pa, ja), row) in p.iter().zip(j.iter()).zip(sc.iter_mut()) {
                if !pa.is_certainly_positive() {
                    return Err(OracleError::ZeroProbability("π(a|s) in a score"));
                }
                row.clear();
                row.extend(ja.iter().map(|x| x.clone() / pa));
            }
        }
        self.loss.clear();
        self.loss_grad.resize_with(spec.groups.len(), Vec::new);
        for ((s, &o), grad) in spec.groups.iter().enumerate().zip(&mut self.loss_grad) {
            if let Some(c) = mdp.termination.absorbing_loss(s) {
                // An absorbing state pays its stated loss, a constant in θ (math.md §8).
                self.loss.push(S::from_rational(c));
                grad.clear();
                grad.resize(block, S::zero());
                continue;
            }
            let l = brier_into(&self.probs[o], &self.jacobian[o], mdp.expert[s], grad);
            self.loss.push(l);
        }
        self.groups.clone_from(&spec.groups);
        self.block = block;
        self.dim = dim;
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{BigRational, Dual, Interval};
    use crate::toy::PolicyKind;

    /// Every committed example MDP: the three parameterisations, two groups, both terminations.
    fn examples() -> Vec<ToyMdp> {
        [
            include_str!("../../examples/toy/m1-direct.json"),
            include_str!("../../examples/toy/m1-softmax.json"),
            include_str!("../../examples/toy/m1-tied.json"),
            include_str!("../../examples/toy/m2-tied-two-groups.json"),
            include_str!("../../examples/toy/terminal-absorb.json"),
            include_str!("../../examples/toy/terminal-reset.json"),
            include_str!("../../examples/toy/three-state.json"),
        ]
        .iter()
        .map(|s| ToyMdp::from_json_str(s).expect("valid toy file"))
        .collect()
    }

    /// A θ in the policy's domain, different for each `k` (the direct parameterisation's blocks
    /// inside the open simplex).
    fn theta<S: Scalar>(mdp: &ToyMdp, k: i64) -> Vec<S> {
        let spec = &mdp.policy;
        (0..spec.dim() as i64)
            .map(|i| match spec.kind {
                PolicyKind::Direct => S::from_ratio(1, 2 * spec.actions() as i64 + i % 3 + k),
                _ => S::from_ratio((i + 1) * (k + 2) * if i % 2 == 0 { 1 } else { -1 }, 7),
            })
            .collect()
    }

    /// Everything a table holds, to compare two tables entry by entry (`Debug` tells apart
    /// every two different values of each scalar type, −0 and 0 included).
    fn contents<S: Scalar>(t: &PolicyTable<S>) -> String {
        format!(
            "{:?} {:?} {:?} {:?} {:?} {:?} {} {}",
            t.probs, t.jacobian, t.score, t.loss, t.loss_grad, t.groups, t.block, t.dim
        )
    }

    /// A table rebuilt in place equals the one built afresh at the same θ, whatever the table
    /// was built for before (another θ, another MDP, or a failed rebuild), and a rebuild at a θ
    /// outside the domain fails as `new` does.
    fn rebuild_equals_new<S: Scalar>() {
        let mdps = examples();
        let c = |m: &ToyMdp| m.policy.c.as_ref().map_or_else(S::zero, S::from_rational);
        let mut rebuilt = 0;
        for (i, mdp) in mdps.iter().enumerate() {
            let other = &mdps[(i + 3) % mdps.len()];
            let mut t = PolicyTable::new(other, &c(other), &theta::<S>(other, 1)).unwrap();
            for k in 0..3 {
                let th = theta::<S>(mdp, k);
                t.rebuild(mdp, &c(mdp), &th).unwrap();
                let fresh = PolicyTable::new(mdp, &c(mdp), &th).unwrap();
                assert_eq!(contents(&t), contents(&fresh), "example {i}, θ #{k}");
                rebuilt += 1;
            }
            let mut bad = theta::<S>(mdp, 0);
            bad.push(S::one());
            let want = PolicyTable::new(mdp, &c(mdp), &bad).unwrap_err();
            let got = t.rebuild(mdp, &c(mdp), &bad).unwrap_err();
            assert_eq!(format!("{got:?}"), format!("{want:?}"));
            let th = theta::<S>(mdp, 2);
            t.rebuild(mdp, &c(mdp), &th).unwrap();
            let fresh = PolicyTable::new(mdp, &c(mdp), &th).unwrap();
            assert_eq!(
                contents(&t),
                contents(&fresh),
                "example {i} after a failure"
            );
        }
        assert_eq!(rebuilt, 3 * mdps.len());
    }

    #[test]
    fn a_rebuilt_table_is_the_new_one_in_every_scalar() {
        rebuild_equals_new::<f64>();
        rebuild_equals_new::<f32>();
        rebuild_equals_new::<BigRational>();
        rebuild_equals_new::<Interval>();
        rebuild_equals_new::<Dual<f64>>();
    }
}
