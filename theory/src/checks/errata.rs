//! Errata without a row of their own elsewhere, each checked as printed (it must fail) and as
//! corrected (it must hold), exactly in ℚ on the toy MDPs.
//!
//! * **E1** (math.md §1.2): eq. 3.15 is unbiased only if l_t is a function of (s_t, θ). With the
//!   *sampled* 0-1 loss λ(s_t, a_t) = 1[a_t ≠ a*(s_t)] in place of l_t — an action-dependent loss,
//!   whose score sum would have to run to i ≤ t — the estimator's mean is not the gradient of
//!   F₀₁(θ) = E Σ_{t=1}^{T−1} λ(s_t, a_t). Written on the policy's output, l_t = 1 − π_θ(a*(s_t)|s_t)
//!   (L-01), the same F₀₁ is estimated without bias.
//! * **E2** (math.md §1.1): g(·, τ) is not the gradient of a function f(·, τ): its Jacobian
//!   contains ∇l_t (Σ_{i<t} ψ_i)ᵀ and is not symmetric (on the second toy, two parameters). Its
//!   mean E_θ g(θ, τ) = ∇F(θ) is a gradient: the Jacobian of ∇F, the Hessian of F, is symmetric.
//! * **E18**: (3.29)/(3.30) sum the loss to T, (3.1) to T − 1: the two objectives differ by
//!   E l(s_T, θ), which is > 0 wherever the learner is not the expert.
//!
//! Every expectation is a finite sum over trajectory prefixes (`ilopt::exact::enumerate`); the
//! gradients the printed and corrected estimators are compared with come from an independent
//! route, forward-mode dual numbers over the objective itself.

use crate::inputs::TableInputs;
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use ilopt::exact::enumerate::{for_each_prefix, gradient_by_duals};
use ilopt::scalar::{BigRational, Dual, Scalar};
use ilopt::toy::{PolicyTable, ToyMdp, ToyProblem};

/// `F₀₁(θ) = E Σ_{t=1}^{T−1} 1[a_t ≠ a*(s_t)]`: the prefix's sampled 0-1 losses at t ≤ T − 2 and,
/// for the last decision a_{T−1} (not in the prefix), its conditional mean 1 − π(a*|s_{T−1}).
fn objective_01<S: Scalar>(problem: &ToyProblem<S>, table: &PolicyTable<S>) -> Result<S, String> {
    let mdp = problem.mdp();
    let mut total = S::zero();
    for_each_prefix(problem, table, |states, actions, p| {
        let mut l = S::zero();
        for (&s, &a) in states.iter().zip(actions) {
            if a != mdp.expert[s] {
                l += S::one();
            }
        }
        let last = *states.last().expect("T ≥ 2");
        l += S::one() - table.prob(last, mdp.expert[last]).clone();
        total += p.clone() * l;
    })
    .map_err(|e| e.to_string())?;
    Ok(total)
}

/// The means at θ of eq. 3.15 with the sampled loss λ(s_t, a_t) (printed, E1) and with the
/// policy-output loss l_t = 1 − π_θ(a*|s_t) (corrected), each estimate passed through
/// [`TableInputs::estimate`]. Both use the thesis's score sum over i < t.
fn e1_means<S: Scalar>(
    inputs: &TableInputs,
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<(Vec<S>, Vec<S>), String> {
    let mdp = problem.mdp();
    let table = problem.table(theta).map_err(|e| e.to_string())?;
    let d = table.dim;
    let (mut printed, mut corrected) = (vec![S::zero(); d], vec![S::zero(); d]);
    for_each_prefix(problem, &table, |states, actions, p| {
        let mut g_printed = vec![S::zero(); d];
        let mut g_corrected = vec![S::zero(); d];
        // Σ_{i<t} ψ_i, accumulated in the full parameter vector.
        let mut scores = vec![S::zero(); d];
        for (t, &s) in states.iter().enumerate() {
            let star = mdp.expert[s];
            // λ(s_t, a_t): sampled in the prefix; for the last step, its mean over a_{T−1}.
            let lambda = match actions.get(t) {
                Some(&a) if a != star => S::one(),
                Some(_) => S::zero(),
                None => S::one() - table.prob(s, star).clone(),
            };
            let l_out = S::one() - table.prob(s, star).clone();
            for j in 0..d {
                g_printed[j] += lambda.clone() * &scores[j];
                g_corrected[j] += l_out.clone() * &scores[j];
            }
            // ∇l_t = −∇π(a*|s_t) (the sampled λ has no θ-dependence of its own).
            let mut grad = vec![S::zero(); d];
            table.add_block_unscaled(&mut grad, s, table.prob_grad(s, star));
            for j in 0..d {
                g_corrected[j] -= &grad[j];
            }
            if let Some(&a) = actions.get(t) {
                table.add_block_unscaled(&mut scores, s, table.score(s, a));
            }
        }
        let g_printed = inputs.estimate(g_printed);
        let g_corrected = inputs.estimate(g_corrected);
        for j in 0..d {
            printed[j] += p.clone() * &g_printed[j];
            corrected[j] += p.clone() * &g_corrected[j];
        }
    })
    .map_err(|e| e.to_string())?;
    Ok((printed, corrected))
}

/// ∇F₀₁(θ) by dual numbers over [`objective_01`] (no score formula).
fn e1_gradient(mdp: &ToyMdp, theta: &[BigRational]) -> Result<Vec<BigRational>, String> {
    let dual: ToyProblem<Dual<BigRational>> = ToyProblem::new(mdp);
    let vars = Dual::variables(theta);
    let table = dual.table(&vars).map_err(|e| e.to_string())?;
    Ok(objective_01(&dual, &table)?.into_parts(theta.len()).1)
}

fn max_abs_diff(a: &[BigRational], b: &[BigRational]) -> BigRational {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let d = x - y;
            if d < BigRational::zero() { -d } else { d }
        })
        .fold(BigRational::zero(), |m, d| if d > m { d } else { m })
}

/// Rows E1 (corrected: the policy-output loss is unbiased) and E1.printed (the sampled
/// action-dependent loss is biased) at each `(mdp, θ)` case; the mdp must not terminate early.
///
/// # Errors
/// A message if a case cannot be enumerated.
pub fn e1_rows(
    inputs: &TableInputs,
    cases: &[(ToyMdp, Vec<BigRational>)],
) -> Result<Vec<Check>, String> {
    let (mut worst_printed, mut worst_corrected) = (BigRational::zero(), BigRational::zero());
    for (mdp, theta) in cases {
        let problem = ToyProblem::<BigRational>::new(mdp);
        let grad = e1_gradient(mdp, theta)?;
        let (printed, corrected) = e1_means(inputs, &problem, theta)?;
        let (p, c) = (
            max_abs_diff(&printed, &grad),
            max_abs_diff(&corrected, &grad),
        );
        if p > worst_printed {
            worst_printed = p;
        }
        if c > worst_corrected {
            worst_corrected = c;
        }
    }
    let result = "Unbiasedness with an action-dependent loss, eqs. 3.2/3.5/3.15";
    let n = cases.len();
    let corrected = Check::builder(
        "E1",
        result,
        format!(
            "l_t on the policy output, l_t = 1 − π_θ(a*|s_t): E[g] = ∇F₀₁ exactly, F₀₁ = E Σ_t 1[a_t ≠ a*(s_t)], at {n} (MDP, θ) points"
        ),
        Role::Corrected,
    )
    .measured(Measured::exact(worst_corrected.to_f64()))
    .bound(0.0)
    .erratum("E1")
    .details(format!(
        "max_j |E g_j − ∂_j F₀₁| over the points = {} (∇F₀₁ by dual numbers over the objective)",
        worst_corrected
    ))
    .decided(Method::Exact, Verdict::from_bool(worst_corrected == BigRational::zero()));
    let printed = Check::builder(
        "E1.printed",
        result,
        format!(
            "the sampled loss l_t = 1[a_t ≠ a*(s_t)] in eq. 3.15 (scores over i < t): E[g] = ∇F₀₁, at {n} (MDP, θ) points"
        ),
        Role::Thesis,
    )
    .measured(Measured::exact(worst_printed.to_f64()))
    .bound(0.0)
    .erratum("E1")
        .refuted_by_erratum()
    .details(format!(
        "max_j |E g_j − ∂_j F₀₁| over the points = {worst_printed}: the term E[λ_t ψ_t] the score sum over i < t omits"
    ))
    .decided(Method::Exact, Verdict::from_bool(worst_printed == BigRational::zero()));
    Ok(vec![corrected, printed])
}

/// The Jacobian ∂_k g_j(θ, τ̄) of the estimate on every prefix at θ (by dual numbers), with the
/// prefix's probability; and the Jacobian of E_θ[g(θ, τ)] = ∇F(θ), i.e. F's Hessian, by dual
/// numbers over [`gradient_by_duals`]'s route.
type Jacobian = Vec<Vec<BigRational>>;

fn asymmetry(j: &Jacobian) -> BigRational {
    let mut worst = BigRational::zero();
    for (a, row) in j.iter().enumerate() {
        for (b, x) in row.iter().enumerate() {
            let d = x - &j[b][a];
            let d = if d < BigRational::zero() { -d } else { d };
            if d > worst {
                worst = d;
            }
        }
    }
    worst
}

fn per_trajectory_jacobians(mdp: &ToyMdp, theta: &[BigRational]) -> Result<Vec<Jacobian>, String> {
    let dual: ToyProblem<Dual<BigRational>> = ToyProblem::new(mdp);
    let vars = Dual::variables(theta);
    let table = dual.table(&vars).map_err(|e| e.to_string())?;
    let d = theta.len();
    let mut out = vec![];
    for_each_prefix(&dual, &table, |states, actions, _p| {
        let actions = dual.scored_actions(states, actions);
        let g = ilopt::toy::estimator::causal(&table, states, actions);
        out.push(g.iter().map(|gj| gj.gradient_padded(d)).collect());
    })
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// F's Hessian at θ: the Jacobian of ∇F = Σ_τ̄ ∇[p L], by nested dual numbers.
fn hessian(mdp: &ToyMdp, theta: &[BigRational]) -> Result<Jacobian, String> {
    let outer: ToyProblem<Dual<BigRational>> = ToyProblem::new(mdp);
    let vars = Dual::variables(theta);
    let (_, grad) = gradient_by_duals(&outer, &vars).map_err(|e| e.to_string())?;
    Ok(grad
        .iter()
        .map(|g| g.gradient_padded(theta.len()))
        .collect())
}

/// Rows E2.printed (g(·, τ) is a gradient field: every per-trajectory Jacobian symmetric) and E2
/// (its mean ∇F is: F's Hessian symmetric) at the given points of a multi-parameter toy.
///
/// # Errors
/// A message if a point cannot be enumerated.
pub fn e2_rows(mdp: &ToyMdp, thetas: &[Vec<BigRational>]) -> Result<Vec<Check>, String> {
    let (mut worst_g, mut worst_h) = (BigRational::zero(), BigRational::zero());
    let mut trajectories = 0usize;
    for theta in thetas {
        for j in per_trajectory_jacobians(mdp, theta)? {
            trajectories += 1;
            let a = asymmetry(&j);
            if a > worst_g {
                worst_g = a;
            }
        }
        let a = asymmetry(&hessian(mdp, theta)?);
        if a > worst_h {
            worst_h = a;
        }
    }
    let result = "Smoothness of f and F, eq. 3.41";
    let n = thetas.len();
    let printed = Check::builder(
        "E2.printed",
        result,
        format!(
            "g(·, τ) = ∇f(·, τ) for a function f(·, τ): its Jacobian is symmetric on every trajectory, at {n} points ({trajectories} (θ, τ) pairs)"
        ),
        Role::Thesis,
    )
    .measured(Measured::exact(worst_g.to_f64()))
    .bound(0.0)
    .erratum("E2")
        .refuted_by_erratum()
    .details(format!(
        "max |∂_k g_j − ∂_j g_k| over the pairs = {worst_g} (∇l_t (Σ_{{i<t}} ψ_i)ᵀ is not symmetric)"
    ))
    .decided(Method::Exact, Verdict::from_bool(worst_g == BigRational::zero()));
    let corrected = Check::builder(
        "E2",
        result,
        format!("E_θ g(θ, τ) = ∇F(θ) is a gradient field: F's Hessian is symmetric, at {n} points"),
        Role::Corrected,
    )
    .measured(Measured::exact(worst_h.to_f64()))
    .bound(0.0)
    .erratum("E2")
    .details(format!(
        "max |∂_k∂_j F − ∂_j∂_k F| = {worst_h} (nested dual numbers); the smoothness the proofs need is assumed of F directly, (A1)"
    ))
    .decided(Method::Exact, Verdict::from_bool(worst_h == BigRational::zero()));
    Ok(vec![corrected, printed])
}

/// `E Σ_{t=1}^{n} l(s_t, θ)` for n = T − 1 (eq. 3.1) and n = T ((3.29)/(3.30)): the prefix's
/// losses, plus for n = T the mean of l(s_T) over a_{T−1} and s_T.
fn objectives_to_t(
    mdp: &ToyMdp,
    theta: &[BigRational],
) -> Result<(BigRational, BigRational), String> {
    let problem = ToyProblem::<BigRational>::new(mdp);
    let table = problem.table(theta).map_err(|e| e.to_string())?;
    let (mut f_t1, mut extra) = (BigRational::zero(), BigRational::zero());
    for_each_prefix(&problem, &table, |states, _actions, p| {
        f_t1 += p.clone() * ilopt::toy::estimator::prefix_loss(&table, states);
        let last = *states.last().expect("T ≥ 2");
        for a in 0..mdp.actions {
            for (s2, pt) in problem.transition(last, a).iter().enumerate() {
                extra += p.clone() * table.prob(last, a) * pt * &table.loss[s2];
            }
        }
    })
    .map_err(|e| e.to_string())?;
    Ok((f_t1.clone(), f_t1 + extra))
}

/// Row E18.printed: DAgger's objective (3.29)/(3.30), summed to T, is the thesis's objective
/// (3.1), summed to T − 1 — at the given points; it fails wherever E l(s_T, θ) > 0.
///
/// # Errors
/// A message if a point cannot be enumerated.
pub fn e18_row(mdp: &ToyMdp, thetas: &[Vec<BigRational>]) -> Result<Check, String> {
    let mut worst = BigRational::zero();
    for theta in thetas {
        let (f1, ft) = objectives_to_t(mdp, theta)?;
        let d = ft - f1;
        if d > worst {
            worst = d;
        }
    }
    Ok(Check::builder(
        "E18.printed",
        "DAgger's objective, eqs. 3.29/3.30 against 3.1",
        format!(
            "E Σ_{{t=1}}^{{T}} l_t (3.29/3.30) = E Σ_{{t=1}}^{{T−1}} l_t (3.1), at {} points",
            thetas.len()
        ),
        Role::Thesis,
    )
    .measured(Measured::exact(worst.to_f64()))
    .bound(0.0)
    .erratum("E18")
    .refuted_by_erratum()
    .details(format!(
        "max over the points of E l(s_T, θ) = {worst}; the kit sums to T − 1 throughout"
    ))
    .decided(
        Method::Exact,
        Verdict::from_bool(worst == BigRational::zero()),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checks::second_toy::m2_two_groups;
    use crate::protocol::m1_tied;
    use ilopt::scalar::parse_exact;

    fn q(s: &str) -> BigRational {
        parse_exact(s).unwrap()
    }

    /// E1: the policy-output loss is unbiased and the sampled loss is not, on M1; an oracle bias
    /// of 10⁻³ turns the corrected row.
    #[test]
    fn e1_holds_corrected_and_fails_printed() {
        let m1 = m1_tied();
        let cases: Vec<_> = ["0", "1/3", "-2"]
            .iter()
            .map(|t| (m1.clone(), vec![q(t)]))
            .collect();
        let rows = e1_rows(&TableInputs::thesis(), &cases).unwrap();
        assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
        assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
        let biased = TableInputs {
            oracle_bias: Some(q("1/1000")),
            ..TableInputs::thesis()
        };
        assert_eq!(e1_rows(&biased, &cases).unwrap()[0].verdict, Verdict::Fails);
    }

    /// E2: per-trajectory Jacobians are not symmetric on the two-parameter toy; F's Hessian is.
    #[test]
    fn e2_holds_corrected_and_fails_printed() {
        let mdp = m2_two_groups();
        let rows = e2_rows(&mdp, &[vec![q("0"), q("0")], vec![q("1/2"), q("-1")]]).unwrap();
        assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
        assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
    }

    /// E18: summing to T adds E l(s_T) > 0 away from the expert.
    #[test]
    fn e18_fails_printed() {
        let row = e18_row(&m1_tied(), &[vec![q("0")]]).unwrap();
        assert_eq!(row.verdict, Verdict::Fails, "{}", row.details);
        assert!(row.measured.unwrap().value > 0.0);
    }
}
