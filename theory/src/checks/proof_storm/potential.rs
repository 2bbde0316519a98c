//! Step 3 of the corrected STORM proof (math.md §3.2): the potential Φ_k = F(θ_k) + λ_{k−1}‖ε_k‖²
//! with λ_k = 1/(8L²η_k) decreases in conditional mean up to the noise term, at every visited
//! state; the conditions (C1), (C2) for the run's own η_k, a_{k+1}; and the thesis's potential
//! after (3.58)/(3.59) (multiplier η_k/(2a_{k+1}), erratum E7) at the same states.

use super::states::{RunSchedule, weighting_name};
use super::{Ctx, Inequality};
use crate::checks::proof_step::StepSlack;
use crate::record::check::{Check, Method, Role, Verdict};
use ilopt::scalar::{BigRational, Interval, Scalar, enclose_rational};

type Q = BigRational;

/// λ_k = 1/(8L²η_k), the potential's weight on ‖ε_{k+1}‖² (math.md §3.2, step 3).
pub fn lambda(l: &Q, eta: &Q) -> Q {
    Q::one() / (Q::from_integer(8.into()) * l.square() * eta)
}

/// The noise term 2λ_k a_{k+1}²σ² on the right of step 3, from the product λ_k a_{k+1}².
pub fn noise(lambda_a2: &Q, sigma2: &Q) -> Q {
    Q::from_integer(2.into()) * lambda_a2 * sigma2
}

/// The rows of step 3 at the visited states: 2c.s3 (corrected potential) and 2c.s3.e7 (the
/// thesis's potential).
pub fn rows(ctx: &Ctx<'_>) -> Vec<Check> {
    let half = Q::from_ratio(1, 2);
    vec![
        ctx.check(
            Inequality::new(
                "2c.s3",
                "E[Φ_{k+1} | F_k] − Φ_k ≤ −(η_k/2)‖∇F(θ_k)‖² + 2λ_k a_{k+1}²σ², Φ_k = F(θ_k) + λ_{k−1}‖ε_k‖², λ_k = 1/(8L²η_k), L = max(L_F, L̃)",
                Role::Corrected,
            )
            .assumptions(["(A1)–(A4); (C1), (C2) for the run's η_k, a_{k+1} (row 2c.s3c)"]),
            &["σ²", "L_F", "L̃", "L̃_PD"],
            |s, w| {
                let l = ctx.c.l(w);
                let (lam, lam_prev) = (lambda(&l, &s.eta), lambda(&l, &s.eta_prev));
                let lhs = s.f_next.clone() + lam.clone() * &s.eps_next2
                    - (s.f.clone() + lam_prev * s.eps2());
                let rhs = -(half.clone() * &s.eta * s.grad2())
                    + noise(&(lam * s.a_next.square()), &ctx.c.sigma2);
                (lhs, rhs)
            },
        ),
        ctx.check(
            Inequality::new(
                "2c.s3.e7",
                "the thesis's potential after (3.59): F(θ_{k+1}) − F(θ_k) + (η_k/(2a_{k+1}))E[‖ε_{k+1}‖² | F_k] − (η_{k−1}/(2a_k))‖ε_k‖² ≤ −(η_k/8)‖∇F(θ_k)‖² + η_k a_{k+1}σ²",
                Role::Thesis,
            )
            .erratum("E7"),
            &["σ²"],
            |s, _| {
                let m = s.eta.clone() / (Q::from_integer(2.into()) * &s.a_next);
                let m_prev = s.eta_prev.clone() / (Q::from_integer(2.into()) * &s.a);
                let lhs = s.f_next.clone() - &s.f + m * &s.eps_next2 - m_prev * s.eps2();
                let rhs = -(Q::from_ratio(1, 8) * &s.eta * s.grad2())
                    + s.eta.clone() * &s.a_next * &ctx.c.sigma2;
                (lhs, rhs)
            },
        ),
    ]
}

/// Row 2c.s3c: (C1) Lη_k ≤ 1/2 and (C2) 4L²η_k² + (1 − a_{k+1})² ≤ η_k/η_{k−1} for every step
/// k = 1..K of each run's schedule (the run's `f64` values, η₀ the virtual 1/(4L)), with
/// L = max(L_F, L̃) of the rows' inputs; decided in interval arithmetic (outward rounding), which
/// is rigorous and, at K = 3·10⁴ steps per schedule, far faster than ℚ.
pub fn conditions(ctx: &Ctx<'_>, schedules: &[RunSchedule]) -> Check {
    let point = |x: f64| Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE);
    let (mut c1, mut c2) = (StepSlack::new(), StepSlack::new());
    let mut worst = String::new();
    for sch in schedules {
        let l = enclose_rational(&ctx.c.l(sch.weighting));
        let mut prev = point(sch.eta0);
        for (k, &(eta, a)) in sch.steps.iter().enumerate() {
            let (eta, a) = (point(eta), point(a));
            c1.enclosed(l * eta, point(0.5));
            let before = c2.points;
            let lhs = point(4.0) * l * l * eta * eta + (point(1.0) - a) * (point(1.0) - a);
            c2.enclosed(lhs, eta / prev);
            if c2.argmin == before {
                worst = format!("{} weights, k = {}", weighting_name(sch.weighting), k + 1);
            }
            prev = eta;
        }
    }
    let verdict = match (c1.verdict(), c2.verdict()) {
        (Verdict::Fails, _) | (_, Verdict::Fails) => Verdict::Fails,
        (Verdict::Holds, Verdict::Holds) => Verdict::Holds,
        _ => Verdict::Inconclusive,
    };
    let steps: Vec<String> = schedules
        .iter()
        .map(|s| {
            format!(
                "{} weights: K = {}",
                weighting_name(s.weighting),
                s.steps.len()
            )
        })
        .collect();
    c2.row(
        "2c.s3c",
        super::RESULT,
        "(C1) Lη_k ≤ 1/2 and (C2) 4L²η_k² + (1 − a_{k+1})² ≤ η_k/η_{k−1} (the e_k coefficient of step 3 is ≤ 0) for the η_k, a_{k+1} the runs used, L = max(L_F, L̃)",
        Role::Corrected,
    )
    .constants(ctx.constants(&["L_F", "L̃", "L̃_PD"]))
    .details(format!(
        "C1: {}; C2: {} (smallest at {worst}); {}; {}",
        c1.summary(),
        c2.summary(),
        steps.join(", "),
        ctx.c.describe()
    ))
    .decided(Method::Rigorous, verdict)
}
