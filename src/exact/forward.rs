//! (X2) Forward dynamic programming over state distributions, differentiated (math.md §1.4):
//!
//! `d_1 = μ`, `J_1 = 0`, and for t = 1..T−2
//! `d_{t+1}(s′) = Σ_{s,a} d_t(s) π(a|s) P(s′|s,a)`,
//! `J_{t+1}(s′) = Σ_{s,a} P(s′|s,a) [J_t(s) π(a|s) + d_t(s) ∇π(a|s)]`;
//! then `F = Σ_{t=1}^{T−1} Σ_s d_t(s) l(s)` and `∇F = Σ_t Σ_s [J_t(s) l(s) + d_t(s) ∇l(s)]`.

use super::ExactError;
use crate::scalar::Scalar;
use crate::toy::{PolicyTable, ToyProblem};

/// The X2 results at θ.
#[derive(Debug, Clone, PartialEq)]
pub struct Forward<S> {
    /// F(θ).
    pub objective: S,
    /// ∇F(θ).
    pub gradient: Vec<S>,
    /// d_t(s) for t = 1..T−1 (`visitation[t−1][s]`).
    pub visitation: Vec<Vec<S>>,
}

/// The state distributions d_1..d_{T−1} under π_θ (values only).
pub fn visitation<S: Scalar>(problem: &ToyProblem<S>, table: &PolicyTable<S>) -> Vec<Vec<S>> {
    let m = problem.mdp();
    let mut d = vec![problem.initial().to_vec()];
    for _ in 1..m.horizon - 1 {
        let cur = d.last().expect("non-empty");
        let mut next = vec![S::zero(); m.states];
        for (s, ds) in cur.iter().enumerate() {
            if ds.is_certainly_zero() {
                continue;
            }
            for a in 0..m.actions {
                let w = ds.product(table.prob(s, a));
                for (n, p) in next.iter_mut().zip(problem.transition(s, a)) {
                    *n += w.product(p);
                }
            }
        }
        d.push(next);
    }
    d
}

/// (X2) F, ∇F and d_t at θ.
///
/// # Errors
/// If the tables cannot be built at θ.
pub fn forward<S: Scalar>(problem: &ToyProblem<S>, theta: &[S]) -> Result<Forward<S>, ExactError> {
    let table = problem.table(theta)?;
    let m = problem.mdp();
    let dim = table.dim;
    let mut d = problem.initial().to_vec();
    // J_t(s) as the rows of a states × dim matrix; the next step's d and J are built in buffers
    // allocated once and swapped in (every entry is reset to zero before it is summed).
    let mut jac = vec![S::zero(); m.states * dim];
    let mut d2 = vec![S::zero(); m.states];
    let mut j2 = vec![S::zero(); m.states * dim];
    let mut dj = vec![S::zero(); dim];
    let mut objective = S::zero();
    let mut gradient = vec![S::zero(); dim];
    let mut visits = Vec::with_capacity(m.horizon - 1);
    for t in 1..m.horizon {
        for s in 0..m.states {
            objective += d[s].product(&table.loss[s]);
            for (g, j) in gradient.iter_mut().zip(&jac[s * dim..(s + 1) * dim]) {
                *g += j.product(&table.loss[s]);
            }
            table.add_block(&mut gradient, s, &table.loss_grad[s], &d[s]);
        }
        visits.push(d.clone());
        if t == m.horizon - 1 {
            break;
        }
        d2.fill(S::zero());
        j2.fill(S::zero());
        for s in 0..m.states {
            for a in 0..m.actions {
                let pi = table.prob(s, a);
                let w = d[s].product(pi);
                // J_t(s) π(a|s) + d_t(s) ∇π(a|s), scattered into the full vector.
                for (x, j) in dj.iter_mut().zip(&jac[s * dim..(s + 1) * dim]) {
                    *x = j.product(pi);
                }
                table.add_block(&mut dj, s, table.prob_grad(s, a), &d[s]);
                for (s2, p) in problem.transition(s, a).iter().enumerate() {
                    if p.is_certainly_zero() {
                        continue;
                    }
                    d2[s2] += w.product(p);
                    for (x, y) in j2[s2 * dim..(s2 + 1) * dim].iter_mut().zip(&dj) {
                        *x += p.product(y);
                    }
                }
            }
        }
        std::mem::swap(&mut d, &mut d2);
        std::mem::swap(&mut jac, &mut j2);
    }
    Ok(Forward {
        objective,
        gradient,
        visitation: visits,
    })
}
