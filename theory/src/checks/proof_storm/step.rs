//! One STORM step k → k + 1 at a visited state, exactly: conditionally on F_k the next point
//! θ_{k+1} = θ_k − η_k d_k is fixed and τ_{k+1} ∼ p(·; θ_{k+1}) ranges over the finitely many
//! prefixes of [`step_samples`], so every conditional expectation of the corrected proof
//! (math.md §3.2, step 1) is a finite sum in ℚ.
//!
//! With ε_k = d_k − ∇F(θ_k), the IS-STORM update
//! d_{k+1} = g(θ_{k+1}, τ) + (1 − a_{k+1})(d_k − w g(θ_k, τ)) gives
//! ε_{k+1} = (1 − a)ε_k + aW + (1 − a)Z with W = g(θ_{k+1}, τ) − ∇F(θ_{k+1}) and
//! Z = g(θ_{k+1}, τ) − w g(θ_k, τ) − ∇F(θ_{k+1}) + ∇F(θ_k). Every estimate is read through
//! [`TableInputs::estimate`], so a biased oracle shows in these means.

use super::states::State;
use crate::inputs::TableInputs;
use ilopt::exact::forward::forward;
use ilopt::exact::importance::step_samples;
use ilopt::scalar::{BigRational, Scalar, dot, norm_sq};
use ilopt::toy::ToyProblem;

type Q = BigRational;

/// The exact quantities of one step at a visited state, conditionally on F_k.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// η_k (the run's `f64`, exactly).
    pub eta: Q,
    /// a_{k+1}.
    pub a_next: Q,
    /// η_{k−1}.
    pub eta_prev: Q,
    /// a_k.
    pub a: Q,
    /// d_k.
    pub d: Vec<Q>,
    /// ∇F(θ_k).
    pub grad: Vec<Q>,
    /// F(θ_k).
    pub f: Q,
    /// F(θ_{k+1}), θ_{k+1} = θ_k − η_k d_k exactly.
    pub f_next: Q,
    /// ε_k = d_k − ∇F(θ_k).
    pub eps: Vec<Q>,
    /// E[W | F_k].
    pub mean_w: Vec<Q>,
    /// E[Z | F_k] (importance-weighted old-point term).
    pub mean_z: Vec<Q>,
    /// E[Z_u | F_k] for the unweighted old-point term g(θ_k, τ) of eq. 3.40 verbatim (E10).
    pub mean_z_unweighted: Vec<Q>,
    /// E[u | F_k] for the printed Algorithm 4 (E9), u = ε_{k+1} − (1 − a)ε_k with
    /// d_{k+1} = g(θ_{k+1}, τ) + (1 − a) g(θ_k, τ).
    pub mean_u_printed: Vec<Q>,
    /// E[‖W‖² | F_k].
    pub w2: Q,
    /// E[‖Z‖² | F_k].
    pub z2: Q,
    /// E[‖ε_{k+1}‖² | F_k] with d_{k+1} from the IS-STORM update.
    pub eps_next2: Q,
}

fn exact(x: f64, what: &str) -> Result<Q, String> {
    Q::from_float(x).ok_or_else(|| format!("{what} = {x} is not finite"))
}

fn exact_vec(x: &[f64], what: &str) -> Result<Vec<Q>, String> {
    x.iter().map(|v| exact(*v, what)).collect()
}

fn sub(x: &[Q], y: &[Q]) -> Vec<Q> {
    x.iter().zip(y).map(|(a, b)| a - b).collect()
}

fn axpy(a: &Q, x: &[Q], y: &[Q]) -> Vec<Q> {
    x.iter().zip(y).map(|(xi, yi)| a * xi + yi).collect()
}

fn add_scaled(acc: &mut [Q], p: &Q, x: &[Q]) {
    for (a, v) in acc.iter_mut().zip(x) {
        *a += p * v;
    }
}

impl Step {
    /// The step at `state` (of a run with the state's own weights), exactly.
    ///
    /// # Errors
    /// A message naming the state if a value is not finite or the exact engine fails.
    pub fn at(
        problem: &ToyProblem<Q>,
        state: &State,
        inputs: &TableInputs,
    ) -> Result<Step, String> {
        let at = |e: &dyn std::fmt::Display| format!("{}: {e}", state.label());
        let theta = exact_vec(&state.theta, "θ_k").map_err(|e| at(&e))?;
        let d = exact_vec(&state.d, "d_k").map_err(|e| at(&e))?;
        let eta = exact(state.eta, "η_k").map_err(|e| at(&e))?;
        let a_next = exact(state.a_next, "a_{k+1}").map_err(|e| at(&e))?;
        let theta_next = axpy(&-eta.clone(), &d, &theta);
        let here = forward(problem, &theta).map_err(|e| at(&e))?;
        let next = forward(problem, &theta_next).map_err(|e| at(&e))?;
        let samples =
            step_samples(problem, &theta, &theta_next, state.weighting).map_err(|e| at(&e))?;
        let (g0, g1) = (&here.gradient, &next.gradient);
        let eps = sub(&d, g0);
        let one_minus_a = Q::one() - &a_next;
        let n = d.len();
        let (mut mean_w, mut mean_z, mut mean_zu, mut mean_up) = (
            vec![Q::zero(); n],
            vec![Q::zero(); n],
            vec![Q::zero(); n],
            vec![Q::zero(); n],
        );
        let (mut w2, mut z2, mut eps_next2) = (Q::zero(), Q::zero(), Q::zero());
        // ∇F(θ_k) − ∇F(θ_{k+1}), the deterministic part of Z.
        let drift = sub(g0, g1);
        for s in &samples {
            let new = inputs.estimate(s.new.clone());
            let weighted = inputs.estimate(s.weighted.clone());
            let unweighted = inputs.estimate(s.unweighted.clone());
            let w = sub(&new, g1);
            let z = axpy(&Q::one(), &drift, &sub(&new, &weighted));
            let zu = axpy(&Q::one(), &drift, &sub(&new, &unweighted));
            // The IS-STORM update, as the algorithm computes it.
            let d_next = axpy(&one_minus_a, &sub(&d, &weighted), &new);
            let eps_next = sub(&d_next, g1);
            // The printed Algorithm 4: d_{k+1} = g(θ_{k+1}, τ) + (1 − a) g(θ_k, τ).
            let d_printed = axpy(&one_minus_a, &unweighted, &new);
            let u_printed = axpy(&-one_minus_a.clone(), &eps, &sub(&d_printed, g1));
            let p = &s.prob;
            add_scaled(&mut mean_w, p, &w);
            add_scaled(&mut mean_z, p, &z);
            add_scaled(&mut mean_zu, p, &zu);
            add_scaled(&mut mean_up, p, &u_printed);
            w2 += p * norm_sq(&w);
            z2 += p * norm_sq(&z);
            eps_next2 += p * norm_sq(&eps_next);
        }
        Ok(Step {
            eta,
            a_next,
            eta_prev: exact(state.eta_prev, "η_{k−1}").map_err(|e| at(&e))?,
            a: exact(state.a, "a_k").map_err(|e| at(&e))?,
            grad: here.gradient.clone(),
            f: here.objective,
            f_next: next.objective,
            d,
            eps,
            mean_w,
            mean_z,
            mean_z_unweighted: mean_zu,
            mean_u_printed: mean_up,
            w2,
            z2,
            eps_next2,
        })
    }

    /// ‖∇F(θ_k)‖².
    pub fn grad2(&self) -> Q {
        norm_sq(&self.grad)
    }

    /// ‖ε_k‖².
    pub fn eps2(&self) -> Q {
        norm_sq(&self.eps)
    }

    /// ‖d_k‖².
    pub fn d2(&self) -> Q {
        norm_sq(&self.d)
    }

    /// ⟨∇F(θ_k), d_k⟩.
    pub fn grad_dot_d(&self) -> Q {
        dot(&self.grad, &self.d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checks::proof_storm::states::run;
    use crate::protocol::m1_tied;
    use ilopt::problem::Weighting;

    /// The decomposition ε_{k+1} = (1 − a)ε_k + aW + (1 − a)Z holds in mean and in second
    /// moment: E‖ε_{k+1}‖² = (1 − a)²‖ε_k‖² + E‖aW + (1 − a)Z‖² when E W = E Z = 0.
    #[test]
    fn the_error_decomposes_as_the_proof_says() {
        let m1 = m1_tied();
        let p = ToyProblem::<Q>::new(&m1);
        for w in [Weighting::Trajectory, Weighting::PerDecision] {
            let (states, _) = run(&m1, w, 3.0, 0.0, 1, 4, &[1, 4]).unwrap();
            for s in &states {
                let st = Step::at(&p, s, &TableInputs::thesis()).unwrap();
                assert!(st.mean_w.iter().all(|x| *x == Q::zero()));
                assert!(st.mean_z.iter().all(|x| *x == Q::zero()));
                let oma = Q::one() - &st.a_next;
                // E‖aW + (1−a)Z‖² ≤ 2a²E‖W‖² + 2(1−a)²E‖Z‖², and E‖ε_{k+1}‖² exceeds (1−a)²‖ε‖².
                let cross = st.eps_next2.clone() - oma.clone() * &oma * st.eps2();
                assert!(cross >= Q::zero());
                let two = Q::from_integer(2.into());
                assert!(
                    cross
                        <= two.clone() * &st.a_next * &st.a_next * &st.w2
                            + two * &oma * &oma * &st.z2
                );
            }
        }
    }
}
