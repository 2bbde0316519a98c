//! The stochastic gradient of eq. 3.15 on one trajectory prefix, in its three forms (math.md §§1.1, 4).
//!
//! Only the prefix τ̄ = (s_1, a_1, …, a_{T−2}, s_{T−1}) matters: losses are paid at t = 1..T−1 and
//! the score of a_{T−1} multiplies no later loss. `states` holds s_1..s_{T−1} and `actions` holds
//! the actions whose scores count, a_1..a_n (0-based arrays):
//!
//! * without absorption n = T − 2, every decision but the last;
//! * when the chain absorbs (math.md §8) at s_{n+1}, n is the number of decisions taken: the
//!   decision a_n that caused the termination is included, and the absorbing steps s_{n+1}..s_{T−1}
//!   take none. Their losses (the table's constant absorbing loss, with zero gradient) stay in
//!   `states`, so they enter the loss-to-go Σ_{t>i} l_t of every earlier decision.
//!
//! Dropping the scores of absorbing steps is exact: at an absorbing s_i the later losses are a
//! function of s_i alone, so E[ψ_i Σ_{t>i} l_t] = E[E[ψ_i | s_i] Σ_{t>i} l_t] = 0.

use super::table::PolicyTable;
use crate::oracle::DecisionTerms;
use crate::problem::Weighting;
use crate::scalar::Scalar;

/// Causal form (eq. 3.15): `g = Σ_t ∇l_t + Σ_{i=1}^{n} ψ_i Σ_{t=i+1}^{T−1} l_t` with n = `actions.len()`
/// (T − 2 without absorption), which equals `Σ_t [∇l_t + l_t Σ_{i<t, i≤n} ψ_i]`.
pub fn causal<S: Scalar>(table: &PolicyTable<S>, states: &[usize], actions: &[usize]) -> Vec<S> {
    debug_assert!(actions.len() <= states.len());
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

/// Full (non-causal) form: `g_full = Σ_t ∇l_t + (Σ_t l_t) Σ_{i=1}^{n} ψ_i`; same mean as
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

/// Σ_{t=1}^{T−1} l(s_t): the prefix's loss (absorbing steps included).
pub fn prefix_loss<S: Scalar>(table: &PolicyTable<S>, states: &[usize]) -> S {
    states
        .iter()
        .fold(S::zero(), |acc, &s| acc + &table.loss[s])
}

/// The per-decision importance-weighted causal form (math.md §4):
/// `g̃ = Σ_t w_{1:t−1} [∇l_t(θ) + l_t(θ) Σ_{i<t} ψ_θ(a_i|s_i)]`,
/// `w_{1:t−1} = Π_{i<t} π_θ(a_i|s_i)/π_θ′(a_i|s_i)`, where the prefix was sampled at θ′.
/// `ratios[i]` must hold π_θ(a_i|s_i)/π_θ′(a_i|s_i) for the decisions i < n = `actions.len()`
/// (absorbing steps take no decision, so their ratio is 1).
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

/// IS-STORM's importance-weighted old-point estimate (math.md §4) on a prefix sampled at θ′, from
/// the tables `old` at θ and `new` at θ′: the whole-trajectory weight
/// `w = Π_{i≤n} π_θ(a_i|s_i)/π_θ′(a_i|s_i)` times the causal form at θ, or the per-decision form
/// [`per_decision`]. `states` and `actions` as in [`causal`].
pub fn weighted<S: Scalar>(
    old: &PolicyTable<S>,
    new: &PolicyTable<S>,
    states: &[usize],
    actions: &[usize],
    weighting: Weighting,
) -> Vec<S> {
    let ratios: Vec<S> = states
        .iter()
        .zip(actions)
        .map(|(&s, &a)| old.prob(s, a).clone() / new.prob(s, a))
        .collect();
    match weighting {
        Weighting::Trajectory => {
            let w = ratios.iter().fold(S::one(), |acc, r| acc * r);
            causal(old, states, actions)
                .into_iter()
                .map(|x| x * &w)
                .collect()
        }
        Weighting::PerDecision => per_decision(old, states, actions, &ratios),
    }
}

/// The causal form's per-decision terms ([`DecisionTerms`]) on a prefix, for the baselined
/// estimator `g_b = g − Σ_i b_i ψ_i` ([`crate::baseline`]): the direct part `Σ_t w_{1:t−1} ∇l_t`,
/// per step the loss `w_{1:t−1} l_t`, per scored decision i ≤ n = `actions.len()` its score ψ_i
/// (absorbing steps take none). `ratios` as in [`per_decision`]: `None` gives eq. 3.15's terms;
/// with `per_decision` the prefix weights `w_{1:t−1}` and `w_{1:i}` enter as there, otherwise the
/// whole product `Π_i ratios[i]` is the estimate's scale (math.md §4). Calls
/// [`DecisionTerms::finish`].
pub fn decision_terms<S: Scalar>(
    table: &PolicyTable<S>,
    states: &[usize],
    actions: &[usize],
    ratios: Option<&[S]>,
    per_decision: bool,
    out: &mut DecisionTerms<S>,
) {
    out.begin(table.dim, states.len());
    let mut w = S::one();
    for (t, &s) in states.iter().enumerate() {
        let weighted = ratios.is_some() && per_decision;
        if weighted {
            table.add_block(out.direct_mut(), s, &table.loss_grad[s], &w);
            out.push_loss(w.clone() * &table.loss[s]);
        } else {
            table.add_block_unscaled(out.direct_mut(), s, &table.loss_grad[s]);
            out.push_loss(table.loss[s].clone());
        }
        if t < actions.len() {
            if let Some(r) = ratios {
                w *= &r[t];
            }
            let row = out.push_score(weighted.then(|| w.clone()));
            table.add_block_unscaled(row, s, table.score(s, actions[t]));
        }
    }
    if ratios.is_some() && !per_decision {
        out.set_scale(w);
    }
    out.finish();
}
