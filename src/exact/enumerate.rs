//! (X1) Enumeration of trajectory prefixes τ̄ = (s_1, a_1, …, a_{T−2}, s_{T−1}) (math.md §1.4).
//!
//! `p(τ̄; θ) = μ(s_1) Π_{t=1}^{T−2} π_θ(a_t|s_t) P(s_{t+1}|s_t, a_t)`; zero-probability branches are
//! dropped. For every prefix the engine evaluates the oracle's own estimator code
//! ([`crate::toy::estimator`]), so E\[g\] = ∇F checks the oracle itself.
//!
//! With termination (math.md §8) the enumeration runs on the augmented chain P′
//! ([`ToyProblem::transition`]): under a reset, P′ already carries the reset law; at an absorbing
//! state no decision is taken, so the prefix continues in one branch (the state repeated, the
//! placeholder action 0, probability factor 1) and the estimator takes the scores of
//! [`ToyProblem::scored_actions`] only.

use super::{ExactError, MAX_PREFIXES};
use crate::scalar::{Dual, Scalar, norm_sq};
use crate::toy::estimator::{causal, full, prefix_loss};
use crate::toy::{PolicyTable, ToyProblem};

/// The callback of [`for_each_prefix`]: (states, actions, probability).
pub type Visitor<'a, S> = dyn FnMut(&[usize], &[usize], &S) + 'a;

/// One prefix with its probability, loss and estimates.
#[derive(Debug, Clone, PartialEq)]
pub struct Prefix<S> {
    /// s_1..s_{T−1}.
    pub states: Vec<usize>,
    /// a_1..a_{T−2} (the placeholder 0 at absorbing steps).
    pub actions: Vec<usize>,
    /// p(τ̄; θ).
    pub prob: S,
    /// L(τ̄) = Σ_t l(s_t, θ).
    pub loss: S,
    /// g(θ, τ̄), causal form (eq. 3.15).
    pub estimate: Vec<S>,
    /// g_full(θ, τ̄).
    pub estimate_full: Vec<S>,
}

/// The X1 moments at θ.
#[derive(Debug, Clone, PartialEq)]
pub struct Enumeration<S> {
    /// F(θ) = Σ p L.
    pub objective: S,
    /// E\[g\] = Σ p g.
    pub expected_estimate: Vec<S>,
    /// E\[g_full\] = Σ p g_full.
    pub expected_full: Vec<S>,
    /// E‖g‖² = Σ p ‖g‖².
    pub second_moment: S,
    /// Var = E‖g‖² − ‖E g‖².
    pub variance: S,
    /// Number of prefixes with positive probability.
    pub prefixes: u64,
}

/// Visit every positive-probability prefix at θ, in lexicographic order of (s_1, a_1, s_2, …),
/// calling `visit(states, actions, probability)`.
///
/// # Errors
/// [`ExactError::TooLarge`] beyond [`MAX_PREFIXES`].
pub fn for_each_prefix<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    mut visit: impl FnMut(&[usize], &[usize], &S),
) -> Result<u64, ExactError> {
    let h = problem.mdp().horizon;
    let mut states = Vec::with_capacity(h - 1);
    let mut actions = Vec::with_capacity(h - 2);
    let mut count = 0u64;
    #[allow(clippy::too_many_arguments)]
    fn rec<S: Scalar>(
        problem: &ToyProblem<S>,
        table: &PolicyTable<S>,
        len: usize,
        states: &mut Vec<usize>,
        actions: &mut Vec<usize>,
        prob: S,
        count: &mut u64,
        visit: &mut Visitor<'_, S>,
    ) -> Result<(), ExactError> {
        if states.len() == len {
            *count += 1;
            if *count > MAX_PREFIXES {
                return Err(ExactError::TooLarge {
                    limit: MAX_PREFIXES,
                });
            }
            visit(states, actions, &prob);
            return Ok(());
        }
        let s = *states.last().expect("non-empty");
        if problem.is_absorbing(s) {
            // No decision at an absorbing state: one branch, the state repeats.
            states.push(s);
            actions.push(0);
            rec(problem, table, len, states, actions, prob, count, visit)?;
            states.pop();
            actions.pop();
            return Ok(());
        }
        for a in 0..problem.mdp().actions {
            let pa = prob.clone() * table.prob(s, a);
            if pa.is_certainly_zero() {
                continue;
            }
            for (s2, pt) in problem.transition(s, a).iter().enumerate() {
                if pt.is_certainly_zero() {
                    continue;
                }
                states.push(s2);
                actions.push(a);
                rec(
                    problem,
                    table,
                    len,
                    states,
                    actions,
                    pa.clone() * pt,
                    count,
                    visit,
                )?;
                states.pop();
                actions.pop();
            }
        }
        Ok(())
    }
    for (s1, mu) in problem.initial().iter().enumerate() {
        if mu.is_certainly_zero() {
            continue;
        }
        states.push(s1);
        rec(
            problem,
            table,
            h - 1,
            &mut states,
            &mut actions,
            mu.clone(),
            &mut count,
            &mut visit,
        )?;
        states.pop();
    }
    Ok(count)
}

/// Every positive-probability prefix with its probability, loss and estimates.
///
/// # Errors
/// As [`for_each_prefix`], or if the tables cannot be built at θ.
pub fn prefixes<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<Vec<Prefix<S>>, ExactError> {
    let table = problem.table(theta)?;
    let mut out = Vec::new();
    for_each_prefix(problem, &table, |states, actions, prob| {
        out.push(Prefix {
            states: states.to_vec(),
            actions: actions.to_vec(),
            prob: prob.clone(),
            loss: prefix_loss(&table, states),
            estimate: causal(&table, states, problem.scored_actions(states, actions)),
            estimate_full: full(&table, states, problem.scored_actions(states, actions)),
        });
    })?;
    Ok(out)
}

/// (X1) F, E\[g\], E\[g_full\], E‖g‖², Var at θ.
///
/// # Errors
/// As [`prefixes`].
pub fn moments<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<Enumeration<S>, ExactError> {
    let table = problem.table(theta)?;
    let d = table.dim;
    let mut objective = S::zero();
    let mut eg = vec![S::zero(); d];
    let mut ef = vec![S::zero(); d];
    let mut m2 = S::zero();
    let n = for_each_prefix(problem, &table, |states, actions, p| {
        objective += p.clone() * prefix_loss(&table, states);
        let actions = problem.scored_actions(states, actions);
        let g = causal(&table, states, actions);
        m2 += p.clone() * norm_sq(&g);
        for (e, x) in eg.iter_mut().zip(&g) {
            *e += p.clone() * x;
        }
        for (e, x) in ef.iter_mut().zip(&full(&table, states, actions)) {
            *e += p.clone() * x;
        }
    })?;
    let variance = m2.clone() - norm_sq(&eg);
    Ok(Enumeration {
        objective,
        expected_estimate: eg,
        expected_full: ef,
        second_moment: m2,
        variance,
        prefixes: n,
    })
}

/// (X1, independent route) `∇F = Σ_τ̄ ∇\[p(τ̄; θ) L(τ̄; θ)\]`, evaluated in `Dual<S>` over the same
/// enumeration. It uses only π_θ and l in dual arithmetic — no score formula, no analytic Jacobian.
/// Returns (F, ∇F).
///
/// # Errors
/// As [`prefixes`].
pub fn gradient_by_duals<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<(S, Vec<S>), ExactError> {
    let dual: ToyProblem<Dual<S>> = ToyProblem::new(problem.mdp());
    let vars = Dual::variables(theta);
    let table = dual.table(&vars)?;
    let mut total = Dual::<S>::zero();
    for_each_prefix(&dual, &table, |states, _actions, p| {
        total += p.clone() * prefix_loss(&table, states);
    })?;
    Ok(total.into_parts(theta.len()))
}
