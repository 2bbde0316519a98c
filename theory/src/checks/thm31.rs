//! Check 5: Theorem 3.1 on the M-family of math.md §6 (direct parameterisation P1, θ = π(0|·),
//! p = π(1|·) = 1 − θ), exactly in rationals:
//! θ_PS ≠ θ_PO, F(θ_PO) < F(θ_PS), F′(θ_PS) ≠ 0, G(θ_PS) = θ_PS, F′(θ_PO) = 0, and RRM contracts to
//! θ_PS with the exact modulus κ = (T−2)Δ/(T−1), DAgger's averaged recursion converges to θ_PS.
//!
//! Every quantity is computed by the kit's engine (F and ∇F by X2, G by the exact RRM map), and
//! compared with math.md's closed forms (A₂, A₁, A₀, p_PS, κ), an independent route.

use crate::check::{Check, Measured, Method, Role, Verdict};
use ilopt::exact::forward::forward;
use ilopt::exact::rrm::rrm_map;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp, ToyProblem};

type Q = BigRational;

/// An instance M(μ_A, p₀, p₁, T).
#[derive(Debug, Clone)]
pub struct Instance {
    /// μ_A.
    pub mu_a: Q,
    /// P(A | action 0).
    pub p0: Q,
    /// P(A | action 1).
    pub p1: Q,
    /// Horizon.
    pub t: usize,
}

/// Everything the engine says about an instance, exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct Findings {
    /// p_PO from the engine (vertex of the quadratic F fitted exactly through three points).
    pub p_po: Q,
    /// p_PS from the engine (fixed point of the affine map G, from two evaluations).
    pub p_ps: Q,
    /// Slope of G (the RRM contraction modulus).
    pub kappa: Q,
    /// F(p_PO), F(p_PS).
    pub f_po: Q,
    /// F(p_PS).
    pub f_ps: Q,
    /// dF/dp at p_PS and p_PO.
    pub df_ps: Q,
    /// dF/dp at p_PO.
    pub df_po: Q,
    /// G(p_PS) − p_PS.
    pub fixed_point_residual: Q,
    /// |p_{k+1} − p_PS| / |p_k − p_PS| for RRM from p₁ = 1/2, k = 1..10.
    pub rrm_ratios: Vec<Q>,
    /// |p_k − p_PS| of DAgger's recursion p_{k+1} = (1/k)Σ_{i≤k} G(p_i) at k = 10, 30, 100.
    pub dagger_errors: Vec<Q>,
    /// Whether the engine's F agrees with math.md's closed form A₂p² + A₁p + A₀ at 7 points.
    pub closed_form_agrees: bool,
    /// Whether p_PS, κ agree with math.md's closed forms.
    pub ps_closed_form_agrees: bool,
}

fn q(n: i64, d: i64) -> Q {
    Q::new(n.into(), d.into())
}

fn abs(x: Q) -> Q {
    if x < Q::zero() { -x } else { x }
}

/// Run the engine on an instance.
///
/// # Errors
/// If the instance is invalid or the engine fails.
pub fn analyse(m: &Instance) -> Result<Findings, String> {
    let mdp = ToyMdp::m_family(
        m.mu_a.clone(),
        m.p0.clone(),
        m.p1.clone(),
        m.t,
        PolicyKind::Direct,
        None,
    )
    .map_err(|e| e.to_string())?;
    let prob = ToyProblem::<Q>::new(&mdp);
    let one = Q::one();
    // θ = 1 − p; F as a function of p, dF/dp = −dF/dθ.
    let f = |p: &Q| -> Result<(Q, Q), String> {
        let x = forward(&prob, &[one.clone() - p]).map_err(|e| e.to_string())?;
        Ok((x.objective, -x.gradient[0].clone()))
    };
    let g = |p: &Q| -> Result<Q, String> {
        Ok(one.clone() - rrm_map(&prob, &[one.clone() - p]).map_err(|e| e.to_string())?[0].clone())
    };
    // Quadratic through p = 1/4, 1/2, 3/4 (exact: F is a quadratic in p by math.md §6 — verified below).
    let (xs, ys): (Vec<Q>, Vec<Q>) = [q(1, 4), q(1, 2), q(3, 4)]
        .into_iter()
        .map(|p| {
            let v = f(&p).map(|r| r.0);
            (p, v)
        })
        .map(|(p, v)| v.map(|v| (p, v)))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    let h = q(1, 4);
    let a2 = (ys[2].clone() - q(2, 1) * &ys[1] + &ys[0]) / (q(2, 1) * &h * &h);
    let a1 = (ys[2].clone() - &ys[0]) / (q(2, 1) * &h) - q(2, 1) * &a2 * &xs[1];
    let a0 = ys[1].clone() - a2.clone() * &xs[1] * &xs[1] - a1.clone() * &xs[1];
    let p_po = -a1.clone() / (q(2, 1) * &a2);
    // G affine: two evaluations give slope and intercept.
    let (g1, g2) = (g(&q(1, 4))?, g(&q(3, 4))?);
    let kappa = (g2.clone() - &g1) / q(1, 2);
    let icpt = g1 - kappa.clone() * q(1, 4);
    let p_ps = icpt / (one.clone() - &kappa);
    let (f_po, df_po) = f(&p_po)?;
    let (f_ps, df_ps) = f(&p_ps)?;
    let fixed_point_residual = g(&p_ps)? - &p_ps;
    // Closed forms of math.md §6.
    let tq = Q::from_i64(m.t as i64);
    let delta = m.p1.clone() - &m.p0;
    let c2 = q(2, 1) * (tq.clone() - one.clone()) - q(4, 1) * (tq.clone() - q(2, 1)) * &delta;
    let c1 = q(2, 1) * (tq.clone() - q(2, 1)) * &delta
        - q(4, 1) * (m.mu_a.clone() + (tq.clone() - q(2, 1)) * &m.p0);
    let c0 = q(2, 1) * (m.mu_a.clone() + (tq.clone() - q(2, 1)) * &m.p0);
    let mut closed_form_agrees = a2 == c2 && a1 == c1 && a0 == c0;
    for k in 1..8 {
        let p = q(k, 8);
        let want = c2.clone() * &p * &p + c1.clone() * &p + &c0;
        closed_form_agrees &= f(&p)?.0 == want;
    }
    let ps_formula = (m.mu_a.clone() + (tq.clone() - q(2, 1)) * &m.p0)
        / ((tq.clone() - one.clone()) - (tq.clone() - q(2, 1)) * &delta);
    let kappa_formula = (tq.clone() - q(2, 1)) * &delta / (tq - one.clone());
    let ps_closed_form_agrees = ps_formula == p_ps && kappa_formula == kappa;
    // RRM from p₁ = 1/2.
    let mut p = q(1, 2);
    let mut rrm_ratios = vec![];
    for _ in 0..10 {
        let next = g(&p)?;
        if p != p_ps {
            rrm_ratios.push(abs(next.clone() - &p_ps) / abs(p.clone() - &p_ps));
        }
        p = next;
    }
    // DAgger (3.30): p_{k+1} = (1/k) Σ_{i≤k} G(p_i), from p₁ = 1/2; G is affine, so the running
    // mean of G(p_i) is G(mean p_i).
    let mut p = q(1, 2);
    let mut sum_g = Q::zero();
    let mut dagger_errors = vec![];
    for k in 1..=100u32 {
        sum_g += g(&p)?;
        p = sum_g.clone() / Q::from_i64(i64::from(k));
        if matches!(k, 10 | 30 | 100) {
            dagger_errors.push(abs(p.clone() - &p_ps));
        }
    }
    Ok(Findings {
        p_po,
        p_ps,
        kappa,
        f_po,
        f_ps,
        df_ps,
        df_po,
        fixed_point_residual,
        rrm_ratios,
        dagger_errors,
        closed_form_agrees,
        ps_closed_form_agrees,
    })
}

/// The rows for one instance.
pub fn rows(m: &Instance) -> Vec<Check> {
    let name = format!("M({}, {}, {}, {})", m.mu_a, m.p0, m.p1, m.t);
    let fd = match analyse(m) {
        Ok(f) => f,
        Err(e) => {
            return vec![Check {
                id: "5".into(),
                result: "Theorem 3.1".into(),
                claim: format!("{name}: analysis"),
                assumptions: vec![],
                constants: vec![],
                bound: None,
                measured: None,
                tightness: None,
                method: Method::Exact,
                verdict: Verdict::Inconclusive,
                erratum: Some("E15".into()),
                role: Role::Corrected,
                details: e,
            }];
        }
    };
    let base = |id: &str,
                claim: String,
                ok: bool,
                role: Role,
                details: String,
                measured: Option<Measured>| Check {
        id: id.into(),
        result: "Theorem 3.1 (DAgger → stable point)".into(),
        claim,
        assumptions: vec![format!(
            "{name}, direct parameterisation P1, Brier loss, aliased states"
        )],
        constants: vec![],
        bound: None,
        measured,
        tightness: None,
        method: Method::Exact,
        verdict: Verdict::from_bool(ok),
        erratum: Some("E15".into()),
        role,
        details,
    };
    let rrm_exact = fd.rrm_ratios.iter().all(|r| *r == fd.kappa);
    let dagger_decreasing = fd.dagger_errors.windows(2).all(|w| w[1] < w[0]);
    vec![
        base(
            "5a",
            format!("{name}: p_PS ≠ p_PO and F(p_PO) < F(p_PS) (stable ≠ optimal)"),
            fd.p_ps != fd.p_po
                && fd.f_po < fd.f_ps
                && fd.df_ps != Q::zero()
                && fd.df_po == Q::zero(),
            Role::Corrected,
            format!(
                "p_PO = {}, F = {}; p_PS = {}, F = {}; F′(p_PS) = {}, F′(p_PO) = {}; closed forms agree: {}",
                fd.p_po,
                fd.f_po,
                fd.p_ps,
                fd.f_ps,
                fd.df_ps,
                fd.df_po,
                fd.closed_form_agrees && fd.ps_closed_form_agrees
            ),
            None,
        ),
        base(
            "5b",
            format!("{name}: RRM contracts to p_PS with modulus exactly κ = (T−2)Δ/(T−1)"),
            rrm_exact && fd.fixed_point_residual == Q::zero() && fd.ps_closed_form_agrees,
            Role::Corrected,
            format!(
                "κ = {}; ratios |p_{{k+1}} − p_PS|/|p_k − p_PS| over 10 steps all = κ: {rrm_exact}",
                fd.kappa
            ),
            Some(Measured::exact(Scalar::to_f64(&fd.kappa))),
        ),
        base(
            "5c",
            format!("{name}: DAgger's averaged recursion (3.30) converges to p_PS (κ < 1)"),
            fd.kappa < Q::one() && dagger_decreasing,
            Role::Corrected,
            format!(
                "|p_k − p_PS| at k = 10, 30, 100: {}",
                fd.dagger_errors
                    .iter()
                    .map(|e| format!("{:.3e}", Scalar::to_f64(e)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None,
        ),
    ]
}

/// The instances of math.md §6's table.
pub fn instances() -> Vec<Instance> {
    vec![
        Instance {
            mu_a: q(1, 2),
            p0: q(1, 2),
            p1: q(1, 1),
            t: 3,
        },
        Instance {
            mu_a: q(1, 2),
            p0: q(1, 4),
            p1: q(1, 2),
            t: 4,
        },
        Instance {
            mu_a: q(1, 2),
            p0: q(1, 4),
            p1: q(1, 2),
            t: 5,
        },
    ]
}
