//! Step 2 of the corrected STORM proof (math.md §3.2), the descent lemma, pathwise at every
//! visited state (θ_{k+1} = θ_k − η_k d_k exactly); and the thesis's printed quadratic bound
//! (3.54) with L²/2 (E5), with L = L_F, the smoothness constant of F the bound is about.
//!
//! (3.58) as printed (E6) is not a row: pathwise it reads −(½ − ηL/4)‖∇F‖² − (1 − ηL)⟨∇F, ε⟩ −
//! ‖ε‖² ≤ 0 after the worst remainder (L/2)η²‖d‖² is inserted, a quadratic form that is negative
//! definite for ηL < (1 + √5)/2. With L = L_F and the schedule's L_Fη_k ≤ 1/4 no state can
//! refute it: E6 is an error of its derivation, not of its truth at these steps, and a row
//! checking it could not fail.

use super::{Ctx, Inequality};
use crate::record::check::{Check, Role};
use ilopt::scalar::{BigRational, Scalar};

type Q = BigRational;

/// The rows of step 2: 2c.s2 (polarisation descent) and 2c.s2.e5 ((3.54) as printed).
pub fn rows(ctx: &Ctx<'_>) -> Vec<Check> {
    let l_f = &ctx.c.l_f;
    let half = Q::from_ratio(1, 2);
    vec![
        ctx.check(
            Inequality::new(
                "2c.s2",
                "F(θ_{k+1}) ≤ F(θ_k) − (η_k/2)‖∇F(θ_k)‖² + (η_k/2)‖ε_k‖² − (η_k/2)(1 − L_Fη_k)‖d_k‖²",
                Role::Corrected,
            )
            .assumptions(["(A1) F is L_F-smooth on ℝ"]),
            &["L_F"],
            |s, _| {
                let h = half.clone() * &s.eta;
                let rhs = s.f.clone() - h.clone() * s.grad2() + h.clone() * s.eps2()
                    - h * (Q::one() - l_f.clone() * &s.eta) * s.d2();
                (s.f_next.clone(), rhs)
            },
        ),
        ctx.check(
            Inequality::new(
                "2c.s2.e5",
                "(3.54) as printed: F(θ_{k+1}) ≤ F(θ_k) + ⟨∇F(θ_k), θ_{k+1} − θ_k⟩ + (L_F²/2)‖θ_{k+1} − θ_k‖²",
                Role::Thesis,
            )
            .erratum("E5"),
            &["L_F"],
            |s, _| {
                let rhs = s.f.clone() - s.eta.clone() * s.grad_dot_d()
                    + half.clone() * l_f.square() * s.eta.square() * s.d2();
                (s.f_next.clone(), rhs)
            },
        ),
    ]
}
