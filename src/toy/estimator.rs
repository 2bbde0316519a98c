//! The stochastic gradient of eq. 3.15 on one trajectory prefix, in its three forms (math.md §§1.1, 4).
//!
//! Only the prefix τ̄ = (s_1, a_1, …, a_{T−2}, s_{T−1}) matters: losses are paid at t = 1..T−1 and
//! the score of a_{T−1} multiplies no later loss. `states` holds s_1..s_{T−1} and `actions` holds
//! a_1..a_{T−2} (0-based arrays).

use super::table::PolicyTable;
use crate::scalar::Scalar;

/// Causal form (eq. 3.15): `g = Σ_t ∇l_t + Σ_{i=1}^{T−2} ψ_i Σ_{t=i+1}^{T−1} l_t`, which equals
/// `Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`.
pub fn causal<S: Scalar>(table: &PolicyTable<S>, states: &[usize], actions: &[usize]) -> Vec<S> {
    debug_assert_eq!(states.len(), actions.len() + 1);
    let mut g = vec![S::zero(); table.dim];
    let mut tail = S::zero(); // Σ_{t>i} l_t, built backwards
    for i in (0..states.len()).rev() {
        let s = states[i];
        table.add_block_unscaled(&mut g, s, &table.loss_grad[s]);
        if i < actions.len() {
            table.add_block(&mut g, s, table.score(s, actions[i]), &tail);
        }
        tail += &table.loss[s];
    }
    g
}

/// Full (non-causal) form: `g_full = Σ_t ∇l_t + (Σ_t l_t) Σ_{i=1}^{T−2} ψ_i`; same mean as
/// [`causal`] because E[l_t ψ_i] = 0 for i ≥ t.
pub fn full<S: Scalar>(table: &PolicyTable<S>, states: &[usize], actions: &[usize]) -> Vec<S> {
    let total = states
        .iter()
        .fold(S::zero(), |acc, &s| acc + &table.loss[s]);
    let mut g = vec![S::zero(); table.dim];
    for (i, &s) in states.iter().enumerate() {
        table.add_block_unscaled(&mut g, s, &table.loss_grad[s]);
        if i < actions.len() {
            table.add_block(&mut g, s, table.score(s, actions[i]), &total);
        }
    }
    g
}

/// Σ_{t=1}^{T−1} l(s_t): the prefix's loss.
pub fn prefix_loss<S: Scalar>(table: &PolicyTable<S>, states: &[usize]) -> S {
    states
        .iter()
        .fold(S::zero(), |acc, &s| acc + &table.loss[s])
}

/// The per-decision importance-weighted causal form (math.md §4):
/// `g̃ = Σ_t w_{1:t−1} [∇l_t(θ) + l_t(θ) Σ_{i<t} ψ_θ(a_i|s_i)]`,
/// `w_{1:t−1} = Π_{i<t} π_θ(a_i|s_i)/π_θ′(a_i|s_i)`, where the prefix was sampled at θ′.
/// `ratios[i]` must hold π_θ(a_i|s_i)/π_θ′(a_i|s_i).
pub fn per_decision<S: Scalar>(
    table: &PolicyTable<S>,
    states: &[usize],
    actions: &[usize],
    ratios: &[S],
) -> Vec<S> {
    let mut g = vec![S::zero(); table.dim];
    let mut score_sum = vec![S::zero(); table.dim];
    let mut w = S::one();
    for (t, &s) in states.iter().enumerate() {
        // term t: w_{1:t−1} [∇l_t + l_t Σ_{i<t} ψ_i]
        table.add_block(&mut g, s, &table.loss_grad[s], &w);
        let wl = w.clone() * &table.loss[s];
        for (gj, sj) in g.iter_mut().zip(&score_sum) {
            *gj += wl.clone() * sj;
        }
        if t < actions.len() {
            table.add_block_unscaled(&mut score_sum, s, table.score(s, actions[t]));
            w *= &ratios[t];
        }
    }
    g
}
