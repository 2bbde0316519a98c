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

/// The number of positive-probability prefixes at θ, counted on the support graph without any
/// arithmetic in `S` (a dynamic programme over states; each step costs the number of support
/// edges). Returns `(count, complete)`: once the count has passed `limit` (it never decreases
/// with the length, since every prefix has a continuation) the programme stops after a bounded
/// amount of work, and `count` is then a lower bound (`complete = false`).
pub fn count_prefixes<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    limit: u64,
) -> (f64, bool) {
    const WORK: usize = 50_000_000;
    let (n, h) = (problem.mdp().states, problem.mdp().horizon);
    // succ[s] = (s′, number of actions a with π(a|s) > 0 and P′(s′|s, a) > 0).
    let succ: Vec<Vec<(usize, f64)>> = (0..n)
        .map(|s| {
            if problem.is_absorbing(s) {
                return vec![(s, 1.0)];
            }
            let mut m = vec![0.0f64; n];
            for a in 0..problem.mdp().actions {
                if table.prob(s, a).is_certainly_zero() {
                    continue;
                }
                for (s2, pt) in problem.transition(s, a).iter().enumerate() {
                    if !pt.is_certainly_zero() {
                        m[s2] += 1.0;
                    }
                }
            }
            m.into_iter()
                .enumerate()
                .filter(|(_, k)| *k > 0.0)
                .collect()
        })
        .collect();
    let edges: usize = succ.iter().map(Vec::len).sum::<usize>() + n;
    let mut count: Vec<f64> = problem
        .initial()
        .iter()
        .map(|mu| if mu.is_certainly_zero() { 0.0 } else { 1.0 })
        .collect();
    let mut total: f64 = count.iter().sum();
    let mut work = 0usize;
    for _ in 1..h.saturating_sub(1) {
        if total > limit as f64 && work > WORK {
            return (total, false);
        }
        let mut next = vec![0.0f64; n];
        for (s, c) in count.iter().enumerate() {
            if *c > 0.0 {
                for &(s2, k) in &succ[s] {
                    next[s2] += c * k;
                }
            }
        }
        count = next;
        total = count.iter().sum();
        work += edges;
    }
    (total, true)
}

/// Visit every positive-probability prefix at θ, in lexicographic order of (s_1, a_1, s_2, …),
/// calling `visit(states, actions, probability)`.
///
/// # Errors
/// [`ExactError::TooLarge`] beyond [`MAX_PREFIXES`], decided by [`count_prefixes`] before any
/// prefix is visited.
pub fn for_each_prefix<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    mut visit: impl FnMut(&[usize], &[usize], &S),
) -> Result<u64, ExactError> {
    let (expected, complete) = count_prefixes(problem, table, MAX_PREFIXES);
    if expected > MAX_PREFIXES as f64 {
        return Err(ExactError::TooLarge {
            prefixes: expected,
            at_least: !complete,
            limit: MAX_PREFIXES,
        });
    }
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
                    prefixes: *count as f64,
                    at_least: true,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::BigRational;
    use crate::toy::ToyMdp;

    /// The support count agrees with the prefixes the enumeration visits, on every example MDP
    /// (with and without termination) at several θ, and refuses before visiting anything.
    #[test]
    fn the_prefix_count_is_the_number_visited() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/toy");
        let mut checked = 0;
        for entry in std::fs::read_dir(&dir).expect("the examples") {
            let mdp = ToyMdp::load(&entry.expect("an entry").path()).expect("a valid example");
            let p = ToyProblem::<BigRational>::new(&mdp);
            for x in [0i64, 1, -2] {
                let theta = vec![BigRational::from_integer(x.into()); mdp.policy.dim()];
                let Ok(table) = p.table(&theta) else {
                    continue;
                };
                let visited = for_each_prefix(&p, &table, |_, _, _| {}).expect("small");
                assert_eq!(
                    count_prefixes(&p, &table, MAX_PREFIXES),
                    (visited as f64, true)
                );
                checked += 1;
                let limit = visited.saturating_sub(1);
                if limit > 0 {
                    assert!(count_prefixes(&p, &table, limit).0 > limit as f64);
                }
            }
        }
        assert!(checked >= 10, "{checked}");
    }

    /// Beyond the limit the enumeration is refused before a single prefix is visited: M1 at
    /// T = 20 has 2 · 3¹⁸ prefixes (two initial states; action 0 branches to 2 states, action 1
    /// to one).
    #[test]
    fn an_infeasible_enumeration_visits_nothing() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/toy/m1-tied.json");
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).expect("M1")).expect("JSON");
        v["horizon"] = serde_json::json!(20);
        let mdp = ToyMdp::from_json_str(&v.to_string()).expect("valid");
        let p = ToyProblem::<BigRational>::new(&mdp);
        let table = p
            .table(&[BigRational::from_integer(0.into())])
            .expect("θ = 0");
        let mut visited = 0u64;
        let err = for_each_prefix(&p, &table, |_, _, _| visited += 1).expect_err("too large");
        assert_eq!(visited, 0);
        assert_eq!(
            err,
            ExactError::TooLarge {
                prefixes: 2.0 * 3f64.powi(18),
                at_least: false,
                limit: MAX_PREFIXES
            }
        );
    }
}
