//! (X3) Backward dynamic programming, the adjoint / performative policy-gradient form
//! (math.md §1.4): `V_T ≡ 0`, and for t = T−1..1
//! `Q_t(s,a) = Σ_{s′} P(s′|s,a) V_{t+1}(s′)`, `V_t(s) = l(s) + Σ_a π(a|s) Q_t(s,a)`;
//! then `F = Σ_s μ(s) V_1(s)` and `∇F = Σ_t Σ_s d_t(s) [∇l(s) + Σ_a ∇π(a|s) Q_t(s,a)]`.

use super::ExactError;
use super::forward::visitation;
use crate::scalar::Scalar;
use crate::toy::ToyProblem;

/// (X3) (F, ∇F) at θ.
///
/// # Errors
/// If the tables cannot be built at θ.
pub fn backward<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<(S, Vec<S>), ExactError> {
    let table = problem.table(theta)?;
    let m = problem.mdp();
    let d = visitation(problem, &table);
    let mut v = vec![S::zero(); m.states]; // V_{t+1}
    let mut gradient = vec![S::zero(); table.dim];
    for t in (1..m.horizon).rev() {
        let mut v_t = Vec::with_capacity(m.states);
        for s in 0..m.states {
            let mut local = table.loss_grad[s].clone();
            let mut value = table.loss[s].clone();
            for a in 0..m.actions {
                let q = problem
                    .transition(s, a)
                    .iter()
                    .zip(&v)
                    .fold(S::zero(), |acc, (p, x)| acc + p.clone() * x);
                value += table.prob(s, a).clone() * &q;
                for (l, g) in local.iter_mut().zip(table.prob_grad(s, a)) {
                    *l += g.clone() * &q;
                }
            }
            table.add_block(&mut gradient, s, &local, &d[t - 1][s]);
            v_t.push(value);
        }
        v = v_t;
    }
    let objective = problem
        .initial()
        .iter()
        .zip(&v)
        .fold(S::zero(), |acc, (mu, x)| acc + mu.clone() * x);
    Ok((objective, gradient))
}
