//! Step 1 of the corrected STORM proof (math.md §3.2), the error recursion, at every visited
//! state; and the thesis's printed steps it replaces: the unweighted old-point term (E10), the
//! printed Algorithm 4 update (E9) and Lemma 3.3's recursion (3.44) as printed (E3).

use super::{Ctx, Inequality};
use crate::record::check::{Check, Role};
use ilopt::scalar::{BigRational, Scalar, norm_sq};

type Q = BigRational;

fn two() -> Q {
    Q::from_integer(2.into())
}

fn four() -> Q {
    Q::from_integer(4.into())
}

/// The rows of step 1: 2c.s1a (E[W | F_k] = E[Z | F_k] = 0), its controls 2c.s1a.e10 and
/// 2c.s1a.e9, 2c.s1b (A3), 2c.s1c (A4), 2c.s1d (the recursion), 2c.s1e ((3.44) with E3
/// corrected) and 2c.s1e.printed ((3.44) as printed).
pub fn rows(ctx: &Ctx<'_>) -> Vec<Check> {
    let zero = Q::zero();
    vec![
        ctx.check(
            Inequality::new(
                "2c.s1a",
                "E[W | F_k] = 0 and E[Z | F_k] = 0, i.e. ‖E[W | F_k]‖² + ‖E[Z | F_k]‖² ≤ 0, with W = g(θ_{k+1}, τ) − ∇F(θ_{k+1}), Z = g(θ_{k+1}, τ) − w g(θ_k, τ) − ∇F(θ_{k+1}) + ∇F(θ_k), τ ∼ p(·; θ_{k+1})",
                Role::Corrected,
            )
            .erratum("E10")
            .assumptions(["(A2): E g = ∇F and, by the importance weight, E[w g(θ_k, τ) | F_k] = ∇F(θ_k) (identity I3)"]),
            &[],
            |s, _| (norm_sq(&s.mean_w) + norm_sq(&s.mean_z), zero.clone()),
        ),
        ctx.check(
            Inequality::new(
                "2c.s1a.e10",
                "E[Z_u | F_k] = 0 with the unweighted old-point term of eq. 3.40 verbatim: Z_u = g(θ_{k+1}, τ) − g(θ_k, τ) − ∇F(θ_{k+1}) + ∇F(θ_k), τ ∼ p(·; θ_{k+1})",
                Role::Thesis,
            )
            .erratum("E10")
            .refuted_by_erratum()
            .assumptions(["Lemma 3.3's step \"E_{k+1} B = 0\" (3.46), read in IL, where τ_{k+1} is drawn at θ_{k+1}"]),
            &[],
            |s, _| (norm_sq(&s.mean_z_unweighted), zero.clone()),
        ),
        ctx.check(
            Inequality::new(
                "2c.s1a.e9",
                "E[ε_{k+1} − (1 − a_{k+1})ε_k | F_k] = 0 for the printed Algorithm 4 update d_{k+1} = g(θ_{k+1}, τ) + (1 − a_{k+1}) g(θ_k, τ)",
                Role::Thesis,
            )
            .erratum("E9, E10")
            .refuted_by_erratum()
            .assumptions(["Algorithm 4 as printed, at the states of IS-STORM's runs"]),
            &[],
            |s, _| (norm_sq(&s.mean_u_printed), zero.clone()),
        ),
        ctx.check(
            Inequality::new(
                "2c.s1b",
                "E[‖W‖² | F_k] ≤ σ² (A3)",
                Role::Corrected,
            )
            .tightness(),
            &["σ²"],
            |s, _| (s.w2.clone(), ctx.c.sigma2.clone()),
        ),
        ctx.check(
            Inequality::new(
                "2c.s1c",
                "E[‖Z‖² | F_k] ≤ L̃²η_k²‖d_k‖² (A4), L̃ of the run's weights",
                Role::Corrected,
            )
            .tightness(),
            &["L̃", "L̃_PD"],
            |s, w| {
                let lt = ctx.c.l_tilde(w);
                (s.z2.clone(), lt.clone() * lt * &s.eta * &s.eta * s.d2())
            },
        ),
        ctx.check(
            Inequality::new(
                "2c.s1d",
                "E[‖ε_{k+1}‖² | F_k] ≤ (1 − a_{k+1})²‖ε_k‖² + 2a_{k+1}²σ² + 2(1 − a_{k+1})²L̃²η_k²‖d_k‖²",
                Role::Corrected,
            )
            .tightness(),
            &["σ²", "L̃", "L̃_PD"],
            |s, w| {
                let lt = ctx.c.l_tilde(w);
                let oma2 = (Q::one() - &s.a_next).square();
                let rhs = oma2.clone() * s.eps2()
                    + two() * s.a_next.square() * &ctx.c.sigma2
                    + two() * oma2 * lt.square() * s.eta.square() * s.d2();
                (s.eps_next2.clone(), rhs)
            },
        ),
        ctx.check(
            Inequality::new(
                "2c.s1e",
                "Lemma 3.3 with E3 corrected: E[‖ε_{k+1}‖² | F_k] ≤ (1 − a_{k+1})²(1 + 4L²η_k²)‖ε_k‖² + 4(1 − a_{k+1})²L²η_k²‖∇F(θ_k)‖² + 2a_{k+1}²σ², L = max(L_F, L̃)",
                Role::Corrected,
            )
            .tightness()
            .erratum("E3"),
            &["σ²", "L_F", "L̃", "L̃_PD"],
            |s, w| (s.eps_next2.clone(), lemma_3_3(ctx, s, w, true)),
        ),
        ctx.check(
            Inequality::new(
                "2c.s1e.printed",
                "Lemma 3.3 as printed (3.44): E[‖ε_{k+1}‖² | F_k] ≤ (1 − a_{k+1})²(1 + 4L²η_k²)‖ε_k‖² + 4(1 − a_{k+1})²L²‖∇F(θ_k)‖² + 2a_{k+1}²σ² (the Δ_k term without η_k²), L = max(L_F, L̃)",
                Role::Thesis,
            )
            .tightness()
            .erratum("E3"),
            &["σ²", "L_F", "L̃", "L̃_PD"],
            |s, w| (s.eps_next2.clone(), lemma_3_3(ctx, s, w, false)),
        ),
    ]
}

/// The right side of (3.44) at a state: with the η_k² of the Δ_k term (E3 corrected) or as
/// printed.
fn lemma_3_3(
    ctx: &Ctx<'_>,
    s: &super::step::Step,
    w: ilopt::problem::Weighting,
    corrected: bool,
) -> Q {
    let l2 = ctx.c.l(w).square();
    let oma2 = (Q::one() - &s.a_next).square();
    let eta2 = s.eta.square();
    let delta_factor = if corrected { eta2.clone() } else { Q::one() };
    oma2.clone() * (Q::one() + four() * &l2 * &eta2) * s.eps2()
        + four() * oma2 * l2 * delta_factor * s.grad2()
        + two() * s.a_next.square() * &ctx.c.sigma2
}
