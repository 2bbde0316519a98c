//! The curvature of the importance-weighted variance `V_IS(θ, θ′)` of assumption (A4) in θ′,
//! `∂²V_IS/∂θ′²`, enclosed on a box of two chart coordinates (math.md §3.2, §7.1): the natural
//! interval extension and the tighter mean-value form the L̃ certificates use.

use crate::certify::charts::{
    SecondOrder, lift2, parts, prefix_terms_with, table_at, theta_second, var2,
};
use crate::record::certificate::Chart;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::toy::estimator::per_decision;
use ilopt::toy::{ToyMdp, ToyProblem};

/// `∂²V_IS/∂θ′²` at (θ in `charts[0]` at `b[0]`, θ′ in `charts[1]` at `b[1]`), where
/// `V_IS(θ, θ′) = Σ_τ̄ [p′ g′² − 2p g′ g + p²/p′ g²]` (p = p(τ̄; θ), g = g(θ, τ̄), primes at θ′)
/// is E_{τ∼θ′} (g(θ′, τ) − w g(θ, τ))² with the trajectory (prefix) weight w = p/p′.
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    v_is_second_with(mdp, pd, weighting, None, charts, b)
}

/// [`v_is_second`] for the estimator `g_b` with the constant `baseline` when one is given.
fn v_is_second_with(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    weighting: Weighting,
    baseline: Option<&BigRational>,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    let base = baseline.map(SecondOrder::from_rational);
    let total = v_is_total(
        mdp,
        pd,
        weighting,
        base.as_ref(),
        charts,
        &lift2(&b[0]),
        &var2(b[1]),
    )?;
    let (_, vx, vxx) = parts(&total);
    Ok(theta_second(charts[1], b[1], vx, vxx))
}

/// `V(θ, θ′) = Σ_τ̄ p(τ̄; θ′) (g(θ′, τ̄) − g̃(θ → θ′, τ̄))²` with θ at `x_old` in `charts[0]` and θ′
/// at `x_new` in `charts[1]`, in any scalar. The old-point term g̃ is `w g(θ, τ̄)` with the
/// prefix weight w = p(τ̄; θ)/p(τ̄; θ′) (trajectory), or the engine's per-decision form
/// ([`per_decision`]). With a `baseline` b the estimator is `g_b = g − b Σ_i ψ_i` at both points
/// and the trajectory weight multiplies `g_b(θ, τ̄)` (docs/math.md §9; trajectory weights only).
/// The factored square keeps enclosures tight near θ′ = θ, where an expanded form would cancel.
fn v_is_total<S: Scalar>(
    mdp: &ToyMdp,
    problem: &ToyProblem<S>,
    weighting: Weighting,
    baseline: Option<&S>,
    charts: &[Chart],
    x_old: &S,
    x_new: &S,
) -> Result<S, String> {
    let t_old = table_at(mdp, problem, charts[0], x_old)?;
    let t_new = table_at(mdp, problem, charts[1], x_new)?;
    if baseline.is_some() && weighting != Weighting::Trajectory {
        return Err("the baselined (A4) quantity is written for trajectory weights".into());
    }
    let at = prefix_terms_with(problem, &t_old, baseline)?;
    let prime = prefix_terms_with(problem, &t_new, baseline)?;
    if at.len() != prime.len() {
        return Err("prefix sets differ".into());
    }
    let mut total = S::zero();
    for (a, q) in at.iter().zip(&prime) {
        if a.states != q.states || a.actions != q.actions {
            return Err("prefix order differs".into());
        }
        let old = match weighting {
            Weighting::Trajectory => a.prob.clone() / &q.prob * &a.estimate,
            Weighting::PerDecision => {
                let ratios: Vec<S> = a
                    .states
                    .iter()
                    .zip(&a.actions)
                    .map(|(&s, &act)| t_old.prob(s, act).clone() / t_new.prob(s, act))
                    .collect();
                per_decision(&t_old, &a.states, &a.actions, &ratios).swap_remove(0)
            }
        };
        let e = q.estimate.clone() - old;
        total += q.prob.clone() * &e * &e;
    }
    Ok(total)
}

/// A third-order jet: [`SecondOrder`] differentiated once more, in both chart coordinates.
pub(crate) type ThirdOrder = Dual<SecondOrder>;

/// Enclosures of `h = ∂²V_IS/∂θ′²` and of its chart-coordinate derivatives `∂₁h`, `∂₂h` on a box
/// (see [`v_is_second_mean_value`]).
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second_jet(
    mdp: &ToyMdp,
    p3: &ToyProblem<ThirdOrder>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<[Interval; 3], String> {
    v_is_second_jet_with(mdp, p3, weighting, None, charts, b)
}

fn v_is_second_jet_with(
    mdp: &ToyMdp,
    p3: &ToyProblem<ThirdOrder>,
    weighting: Weighting,
    baseline: Option<&BigRational>,
    charts: &[Chart],
    b: &[Interval],
) -> Result<[Interval; 3], String> {
    let x1 = Dual::variable(lift2(&b[0]), 0, 2);
    let x2 = Dual::variable(var2(b[1]), 1, 2);
    let base = baseline.map(ThirdOrder::from_rational);
    let total = v_is_total(mdp, p3, weighting, base.as_ref(), charts, &x1, &x2)?;
    let (_, v2, v22) = parts(total.value());
    let grad = total.gradient_padded(2);
    let (_, v12, v122) = parts(&grad[0]);
    let (_, _, v222) = parts(&grad[1]);
    let natural = theta_second(charts[1], b[1], v2, v22);
    let (d1, d2) = match charts[1] {
        Chart::Core => (v122, v222),
        Chart::Tail => {
            let u = b[1];
            let (u2, six) = (u * u, Interval::from_i64(6));
            let u3 = u2 * u;
            (
                u2 * u2 * v122 + Interval::from_i64(2) * u3 * v12,
                u2 * u2 * v222 + six * u3 * v22 + six * u2 * v2,
            )
        }
    };
    Ok([natural, d1, d2])
}

/// A tighter enclosure of `∂²V_IS/∂θ′²` on a box, in chart coordinates (x₁, x₂): the natural
/// interval extension intersected with the mean-value form
/// `h(X) ⊆ h(m) + ∂₁h(X)(X₁ − m₁) + ∂₂h(X)(X₂ − m₂)`, whose overestimation shrinks
/// quadratically with the box. The derivatives of h come from third-order nested duals (outer level
/// in (x₁, x₂), the two inner levels in x₂); in the tail chart h = u⁴V_uu + 2u³V_u, so
/// `∂_u h = u⁴V_uuu + 6u³V_uu + 6u²V_u` and `∂₁h = u⁴∂₁V_uu + 2u³∂₁V_u`.
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second_mean_value(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    p3: &ToyProblem<ThirdOrder>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    v_is_second_mean_value_with(mdp, pd, p3, weighting, None, charts, b)
}

/// [`v_is_second_mean_value`] for the baselined estimator `g_b = g − b Σ_i ψ_i` with one constant
/// b for every decision and the trajectory weight on `g_b(θ, τ̄)` (docs/math.md §9): the curvature
/// of `V_b(θ, θ′) = E_{τ∼θ′}(g_b(θ′, τ) − w g_b(θ, τ))²`, the (A4) quantity of IS-STORM run on g_b.
///
/// # Errors
/// As [`v_is_second_mean_value`].
pub fn v_is_second_mean_value_baselined(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    p3: &ToyProblem<ThirdOrder>,
    baseline: &BigRational,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    v_is_second_mean_value_with(
        mdp,
        pd,
        p3,
        Weighting::Trajectory,
        Some(baseline),
        charts,
        b,
    )
}

fn v_is_second_mean_value_with(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    p3: &ToyProblem<ThirdOrder>,
    weighting: Weighting,
    baseline: Option<&BigRational>,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    let [natural, d1, d2] = v_is_second_jet_with(mdp, p3, weighting, baseline, charts, b)?;
    let point = |x: Interval| {
        let m = x.mid();
        Interval::try_from((m, m)).map_err(|e| format!("{e:?}"))
    };
    let m = [point(b[0])?, point(b[1])?];
    let at_mid = v_is_second_with(mdp, pd, weighting, baseline, charts, &m)?;
    let mv = at_mid + d1 * (b[0] - m[0]) + d2 * (b[1] - m[1]);
    let both = natural.intersection(mv);
    Ok(if both.is_empty() { natural } else { both })
}
