//! The velocity-obstacle expert of thesis eq. 4.1 (§4.1.2), solved to **global** optimality in
//! closed form.
//!
//! # The problem (eq. 4.1)
//!
//! ```text
//! minimise   J(u) = ‖v_des − (v_r + u)‖² + λ‖u‖²          over u ∈ ℝ²
//! subject to c(u) = (rᵀv)²/‖v‖² − ‖r‖² + R² ≤ 0,  v = v_o − (v_r + u),  R = R_A + R_B,
//! ```
//!
//! where (thesis §4.1.2) `r` is the position of the obstacle seen by the agent (obstacle centre
//! minus agent centre), `v_o` the obstacle's velocity, `v_r` the agent's current velocity,
//! `v_des = v_max · g/‖g‖` the desired velocity (full speed towards the goal), `u` the change of
//! velocity, and `v` the velocity of the obstacle *relative to the agent* after the change.
//!
//! # Geometry of the constraint
//!
//! `(rᵀv)²/‖v‖²` is the squared length of the projection of `r` on the line `ℝv`, so
//! `‖r‖² − (rᵀv)²/‖v‖²` is the squared distance from the obstacle to the line through the agent
//! spanned by the relative velocity, and `c(u) ≤ 0` says: **that line stays at distance ≥ R from the
//! obstacle**. Because it is a *line* (the sign of `t` in `r + t v` is not restricted), the
//! constraint forbids relative motion both towards the obstacle and directly away from it: in the
//! new agent velocity `x = v_r + u` the infeasible set is the open **double** cone
//!
//! ```text
//! K = { x ≠ v_o : the angle between the line ℝ(x − v_o) and r is < α },   sin α = R/‖r‖,
//! ```
//!
//! with apex `v_o`, axis `r` and half-angle `α ∈ (0, π/2)` (for `‖r‖ > R`). The physically
//! meaningful collision cone — collision *in the future*, `min_{t ≥ 0} ‖r + t v‖ < R` — is only the
//! nappe around `+r` (the agent moving towards the obstacle, `rᵀ(x − v_o) > 0`). [`vo_expert`] solves
//! eq. 4.1 exactly as the thesis writes it ([`Cone::Double`]); [`vo_expert_cone`] with
//! [`Cone::Forward`] solves the same problem with only the forward nappe excluded, which does not
//! stop an agent that has already passed the obstacle from heading straight for the goal.
//!
//! **Convention at `v = 0`** (`x = v_o`, `‖v‖²` in a denominator): feasible. With no relative
//! motion the distance between the centres stays `‖r‖ > R`, so there is no collision; and with this
//! convention the feasible set `F = ℝ² \ K` is closed (the apex is a limit of boundary points), so
//! the minimum is attained. (Declaring the apex infeasible would make `F` not closed; it changes the
//! answer only when the unconstrained minimiser is exactly the apex, see below.)
//!
//! # Global solution
//!
//! For `λ ≥ 0`, `J` is a strictly convex quadratic with Hessian `2(1+λ)I`; completing the square,
//!
//! ```text
//! J(u) = (1+λ)‖u − u₀‖² + J(u₀),   u₀ = (v_des − v_r)/(1+λ),   J(u₀) = λ/(1+λ)·‖v_des − v_r‖²,
//! ```
//!
//! so minimising `J` over the feasible set is the **Euclidean projection** of `x₀ = v_r + u₀` onto
//! the closed set `F` (in `x`). If `x₀ ∈ F`, `u₀` is optimal. Otherwise `x₀` lies in the open set
//! `K`, and for any feasible `y` the segment `[x₀, y]` leaves `K` at a boundary point that is no
//! farther from `x₀` than `y` and is itself feasible (`∂K ⊆ F`, `F` closed): the minimum over `F` is
//! the minimum over `∂K`, and `∂K` is the two lines `{v_o + t d±}` (double cone) or the two rays `t ≥ 0` (forward cone), where
//! `d±` is `r/‖r‖` rotated by `±α`:
//!
//! ```text
//! d± = (k r₁ ∓ R r₂,  ±R r₁ + k r₂) / ‖r‖²,   k = √(‖r‖² − R²)   (‖d±‖ = 1, d±ᵀr/‖r‖ = cos α).
//! ```
//!
//! Every boundary point is feasible (`c = 0`, or the apex). The projection of `x₀` on each line is
//! `v_o + t± d±` with `t± = d±ᵀ(x₀ − v_o)` (for a ray, `max(t±, 0)`), and the optimum is the nearer of
//! the two — closed form, one square root, no iteration, no allocation. Ties (when `x₀ − v_o` is
//! exactly on the axis, e.g. an obstacle dead ahead) go to `d₊`, the boundary rotated
//! counter-clockwise from `r`. The apex is never optimal when `x₀ ≠ v_o`: on lines it would need
//! `t₊ = t₋ = 0`, i.e. `x₀ − v_o ⊥ d₊, d₋`, impossible as `d₊, d₋` are independent (`α < π/2`); on
//! rays it would need `t± ≤ 0`, i.e. `x₀ − v_o` at ≥ 90° from both, impossible in the forward nappe,
//! which lies between `d₊` and `d₋` (`2α < π` apart). So the convention at `v = 0` only decides the
//! case `x₀ = v_o`, which it makes feasible (and optimal).
//!
//! [`vo_expert_generic`] is the same closed form over any [`Sqrt`] scalar (intervals give rigorous
//! enclosures of `u*`, duals give its derivatives).
//!
//! The feasibility test multiplies through by `‖v‖²` (no division):
//! `x₀ ∈ K ⇔ (rᵀw)² > (‖r‖² − R²)‖w‖²` with `w = x₀ − v_o` (plus `rᵀw > 0` for the forward cone).
//!
//! # Degenerate inputs
//!
//! | input | result |
//! |---|---|
//! | `λ = 0` | fine: `u₀ = v_des − v_r` is still the unique unconstrained minimiser |
//! | `λ < 0` | [`VoError::NegativeLambda`] (`J` is then not convex, or unbounded below for `λ < −1`) |
//! | `R ≤ 0` | [`VoError::NonPositiveRadius`] |
//! | `‖r‖ ≤ R` | [`VoError::InsideObstacle`]: every direction (all but one line at `‖r‖ = R`) collides |
//! | NaN/∞ input | [`VoError::NonFinite`] |
//! | overflow of an intermediate (inputs ≳ 1e150) | [`VoError::Overflow`]; never a NaN output |
//! | tiny inputs (max of `‖r‖`, `R` or of the velocities below 2⁻⁶⁰) | rescaled by exact powers of two before solving ([`vo_expert_cone`]), so no product underflows; the answer is unchanged |
//!
//! # Reference
//! Thesis §4.1.2, eq. 4.1 (the thesis solves it with MATLAB's `fmincon`, a local method); the
//! velocity-obstacle formulation follows its reference \[41\].

use crate::scalar::{Scalar, Sqrt, Undecidable};
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use thiserror::Error;

/// Which collision cone the constraint excludes (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Cone {
    /// Eq. 4.1 as written: `c(u) ≤ 0`, the relative-velocity *line* misses the obstacle by `≥ R`.
    /// Excludes the open double cone with apex `v_o`.
    #[default]
    Double,
    /// Only future collisions: `rᵀv ≥ 0` (the obstacle is not approaching) or `c(u) ≤ 0`.
    /// Excludes the open single cone `{x = v_r + u : rᵀ(x − v_o) > 0, c(u) > 0}`.
    Forward,
}

/// The global minimiser of eq. 4.1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct VoSolution {
    /// The optimal change of velocity `u*`.
    pub u: [f64; 2],
    /// `J(u*) = ‖v_des − (v_r + u*)‖² + λ‖u*‖²`, evaluated directly at `u*`.
    pub j: f64,
    /// Whether the collision constraint is active (the unconstrained minimiser `u₀` was infeasible).
    pub active: bool,
}

/// Why eq. 4.1 has no solution for the given inputs.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum VoError {
    /// An input is NaN or infinite.
    #[error("non-finite input `{name}`")]
    NonFinite {
        /// The input's name (`r`, `v_o`, `v_r`, `v_des`, `lam`, `R`).
        name: &'static str,
    },
    /// `λ < 0`: the objective is not convex (unbounded below for `λ < −1`).
    #[error("λ must be ≥ 0, got {0}")]
    NegativeLambda(f64),
    /// `R ≤ 0`.
    #[error("the combined radius R = R_A + R_B must be > 0, got {0}")]
    NonPositiveRadius(f64),
    /// `‖r‖ ≤ R`: the agent is inside (or touching) the obstacle, every direction collides.
    #[error("inside the obstacle: distance between centres {distance} ≤ R = {radius}")]
    InsideObstacle {
        /// `‖r‖`.
        distance: f64,
        /// `R`.
        radius: f64,
    },
    /// An intermediate result overflowed (inputs too large, ≳ 1e150).
    #[error("numerical overflow: inputs too large")]
    Overflow,
    /// [`vo_expert_generic`] could not decide a branch (an interval straddles its threshold).
    #[error(transparent)]
    Undecidable(#[from] Undecidable),
}

#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The power of two `2^k` (`k ≥ 0`) that brings `m ∈ (0, 2⁻⁶⁰)` to at least `2⁻⁶⁰`; 1 otherwise.
/// At most `2^1014`, so it and its inverse are normal floats.
fn upscale(m: f64) -> f64 {
    const FLOOR: f64 = 8.673_617_379_884_035e-19; // 2^-60
    let (mut x, mut s) = (m, 1.0f64);
    while x > 0.0 && x < FLOOR {
        let step = if x < FLOOR * FLOOR {
            2f64.powi(60)
        } else {
            2.0
        };
        x *= step;
        s *= step;
    }
    s
}

#[inline]
fn check_finite(x: &[f64], name: &'static str) -> Result<(), VoError> {
    if x.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(VoError::NonFinite { name })
    }
}

/// The velocity-obstacle expert: the global minimiser of eq. 4.1 as the thesis writes it
/// (double cone, [`Cone::Double`]).
///
/// `J(u) = ‖v_des − (v_r + u)‖² + λ‖u‖²` subject to `(rᵀv)²/‖v‖² − ‖r‖² + R² ≤ 0`,
/// `v = v_o − (v_r + u)`, with `v = 0` feasible. Closed form (module docs), no allocation.
///
/// * `r`: obstacle centre minus agent centre; `v_o`: obstacle velocity; `v_r`: agent velocity;
///   `v_des`: desired agent velocity; `lam`: λ ≥ 0; `big_r`: `R = R_A + R_B > 0`.
///
/// # Errors
/// [`VoError`]: non-finite input, `λ < 0`, `R ≤ 0`, `‖r‖ ≤ R` (inside the obstacle), overflow.
/// The result, when `Ok`, is always finite.
#[inline]
pub fn vo_expert(
    r: [f64; 2],
    v_o: [f64; 2],
    v_r: [f64; 2],
    v_des: [f64; 2],
    lam: f64,
    big_r: f64,
) -> Result<VoSolution, VoError> {
    vo_expert_cone(Cone::Double, r, v_o, v_r, v_des, lam, big_r)
}

/// [`vo_expert`] with a choice of collision cone: eq. 4.1 ([`Cone::Double`]) or its future-only
/// variant ([`Cone::Forward`]: feasible iff `rᵀv ≥ 0` or `c(u) ≤ 0`). Globally optimal in both cases.
///
/// # Errors
/// As [`vo_expert`].
#[inline]
pub fn vo_expert_cone(
    cone: Cone,
    r: [f64; 2],
    v_o: [f64; 2],
    v_r: [f64; 2],
    v_des: [f64; 2],
    lam: f64,
    big_r: f64,
) -> Result<VoSolution, VoError> {
    check_finite(&r, "r")?;
    check_finite(&v_o, "v_o")?;
    check_finite(&v_r, "v_r")?;
    check_finite(&v_des, "v_des")?;
    check_finite(&[lam], "lam")?;
    check_finite(&[big_r], "R")?;
    if lam < 0.0 {
        return Err(VoError::NegativeLambda(lam));
    }
    if big_r <= 0.0 {
        return Err(VoError::NonPositiveRadius(big_r));
    }
    // Tiny inputs are rescaled by powers of two (exact) so that the squares and products below
    // cannot underflow: the geometry (r, R) and the velocities separately, as the cone depends only
    // on the direction of r and R/‖r‖ and the solution u* is linear in the velocities. Inputs at
    // or above 2⁻⁶⁰ are not rescaled, so for them the result is bit-identical to
    // [`vo_expert_generic`] at `f64`. (Found by the `vo_expert` fuzz target: with ‖r‖, R and the
    // velocities ≈ 6e−154 the products of the feasibility test underflowed to 0 and an infeasible
    // u₀ was returned.)
    let sr = upscale(r[0].abs().max(r[1].abs()).max(big_r));
    let velocities = [v_o[0], v_o[1], v_r[0], v_r[1], v_des[0], v_des[1]];
    let sv = upscale(velocities.iter().fold(0.0f64, |m, x| m.max(x.abs())));
    if sr != 1.0 || sv != 1.0 {
        let scale = |a: [f64; 2], s: f64| [a[0] * s, a[1] * s];
        let scaled = vo_expert_cone(
            cone,
            scale(r, sr),
            scale(v_o, sv),
            scale(v_r, sv),
            scale(v_des, sv),
            lam,
            big_r * sr,
        )
        .map_err(|e| match e {
            VoError::InsideObstacle { distance, .. } => VoError::InsideObstacle {
                distance: distance / sr,
                radius: big_r,
            },
            e => e,
        })?;
        let u = scale(scaled.u, 1.0 / sv);
        let j = objective(u, v_r, v_des, lam);
        if !(u[0].is_finite() && u[1].is_finite() && j.is_finite()) {
            return Err(VoError::Overflow);
        }
        return Ok(VoSolution {
            u,
            j,
            active: scaled.active,
        });
    }
    let rr = dot(r, r);
    let big_r2 = big_r * big_r;
    if !rr.is_finite() || !big_r2.is_finite() {
        return Err(VoError::Overflow);
    }
    if rr <= big_r2 {
        return Err(VoError::InsideObstacle {
            distance: rr.sqrt(),
            radius: big_r,
        });
    }
    let inv = 1.0 / (1.0 + lam);
    let u0 = [(v_des[0] - v_r[0]) * inv, (v_des[1] - v_r[1]) * inv];
    // Agent velocity relative to the obstacle at the unconstrained minimiser: w = x₀ − v_o = −v.
    let w = [v_r[0] + u0[0] - v_o[0], v_r[1] + u0[1] - v_o[1]];
    let rw = dot(r, w);
    let k2 = rr - big_r2;
    let (lhs, rhs) = (rw * rw, k2 * dot(w, w));
    if !(lhs.is_finite() && rhs.is_finite()) {
        return Err(VoError::Overflow);
    }
    let in_double = lhs > rhs;
    let inside = match cone {
        Cone::Double => in_double,
        Cone::Forward => in_double && rw > 0.0,
    };
    let (u, active) = if inside {
        let k = k2.sqrt();
        let d_plus = [
            (k * r[0] - big_r * r[1]) / rr,
            (big_r * r[0] + k * r[1]) / rr,
        ];
        let d_minus = [
            (k * r[0] + big_r * r[1]) / rr,
            (-big_r * r[0] + k * r[1]) / rr,
        ];
        let project = |d: [f64; 2]| {
            let mut t = dot(d, w);
            if cone == Cone::Forward && t < 0.0 {
                t = 0.0;
            }
            let e = [w[0] - t * d[0], w[1] - t * d[1]];
            (t, dot(e, e))
        };
        let (tp, ep) = project(d_plus);
        let (tm, em) = project(d_minus);
        let (t, d) = if ep <= em {
            (tp, d_plus)
        } else {
            (tm, d_minus)
        };
        (
            [v_o[0] + t * d[0] - v_r[0], v_o[1] + t * d[1] - v_r[1]],
            true,
        )
    } else {
        (u0, false)
    };
    let j = objective(u, v_r, v_des, lam);
    if !(u[0].is_finite() && u[1].is_finite() && j.is_finite()) {
        return Err(VoError::Overflow);
    }
    Ok(VoSolution { u, j, active })
}

/// The global minimiser of eq. 4.1 in a generic scalar type (see [`vo_expert_generic`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct VoSolutionOf<S> {
    /// The optimal change of velocity `u*`.
    pub u: [S; 2],
    /// `J(u*)`.
    pub j: S,
    /// Whether the collision constraint is active.
    pub active: bool,
}

fn dot_g<S: Sqrt>(a: &[S; 2], b: &[S; 2]) -> S {
    a[0].clone() * &b[0] + a[1].clone() * &b[1]
}

fn cmp_g<S: Scalar>(a: &S, b: &S, what: &'static str) -> Result<Ordering, VoError> {
    a.certain_cmp(b)
        .ok_or(VoError::Undecidable(Undecidable { what }))
}

/// [`vo_expert_cone`] generic over the scalar type (any [`Sqrt`] scalar: `f64`, `f32`,
/// [`crate::scalar::Interval`], [`crate::scalar::Dual`]): the same closed form, operation for
/// operation (for `f64` the result is bit-identical to [`vo_expert_cone`] when no input group
/// is below 2⁻⁶⁰; this generic form does not rescale tiny inputs).
///
/// With intervals the result *encloses* the exact minimiser for every point input in the argument
/// intervals, provided every branch was decided; with duals it carries the derivatives of `u*` and
/// `J*` with respect to the inputs (valid where the branch does not change).
///
/// # Errors
/// As [`vo_expert_cone`], plus [`VoError::Undecidable`] when a branch (sign of λ or R, inside the
/// obstacle, inside the cone, which boundary line is nearer, ray clamp) cannot be decided — e.g. an
/// interval input for which both boundary lines are equally near (an obstacle exactly dead ahead).
/// Error payloads that are numbers are reported through [`Scalar::to_f64`].
#[allow(clippy::too_many_arguments)]
pub fn vo_expert_generic<S: Sqrt>(
    cone: Cone,
    r: &[S; 2],
    v_o: &[S; 2],
    v_r: &[S; 2],
    v_des: &[S; 2],
    lam: &S,
    big_r: &S,
) -> Result<VoSolutionOf<S>, VoError> {
    let fin = |x: &[S], name: &'static str| {
        if x.iter().all(Scalar::is_finite) {
            Ok(())
        } else {
            Err(VoError::NonFinite { name })
        }
    };
    fin(r, "r")?;
    fin(v_o, "v_o")?;
    fin(v_r, "v_r")?;
    fin(v_des, "v_des")?;
    fin(std::slice::from_ref(lam), "lam")?;
    fin(std::slice::from_ref(big_r), "R")?;
    let zero = S::zero();
    if cmp_g(lam, &zero, "sign of λ")? == Ordering::Less {
        return Err(VoError::NegativeLambda(lam.to_f64()));
    }
    if cmp_g(big_r, &zero, "sign of R")? != Ordering::Greater {
        return Err(VoError::NonPositiveRadius(big_r.to_f64()));
    }
    let rr = dot_g(r, r);
    let big_r2 = big_r.clone() * big_r;
    if !rr.is_finite() || !big_r2.is_finite() {
        return Err(VoError::Overflow);
    }
    if cmp_g(&rr, &big_r2, "‖r‖ vs R")? != Ordering::Greater {
        return Err(VoError::InsideObstacle {
            distance: rr.sqrt().to_f64(),
            radius: big_r.to_f64(),
        });
    }
    let inv = S::one() / (S::one() + lam);
    let u0 = [
        (v_des[0].clone() - &v_r[0]) * &inv,
        (v_des[1].clone() - &v_r[1]) * &inv,
    ];
    let w = [
        v_r[0].clone() + &u0[0] - &v_o[0],
        v_r[1].clone() + &u0[1] - &v_o[1],
    ];
    let rw = dot_g(r, &w);
    let k2 = rr.clone() - &big_r2;
    let (lhs, rhs) = (rw.clone() * &rw, k2.clone() * dot_g(&w, &w));
    if !(lhs.is_finite() && rhs.is_finite()) {
        return Err(VoError::Overflow);
    }
    let in_double = cmp_g(&lhs, &rhs, "inside the collision cone")? == Ordering::Greater;
    let inside = match cone {
        Cone::Double => in_double,
        Cone::Forward => {
            in_double && cmp_g(&rw, &zero, "approaching the obstacle")? == Ordering::Greater
        }
    };
    let (u, active) = if inside {
        let k = k2.sqrt();
        let d_plus = [
            (k.clone() * &r[0] - big_r.clone() * &r[1]) / &rr,
            (big_r.clone() * &r[0] + k.clone() * &r[1]) / &rr,
        ];
        let d_minus = [
            (k.clone() * &r[0] + big_r.clone() * &r[1]) / &rr,
            (-(big_r.clone() * &r[0]) + k.clone() * &r[1]) / &rr,
        ];
        let project = |d: &[S; 2]| -> Result<(S, S), VoError> {
            let mut t = dot_g(d, &w);
            if cone == Cone::Forward && cmp_g(&t, &zero, "ray clamp")? == Ordering::Less {
                t = S::zero();
            }
            let e = [
                w[0].clone() - t.clone() * &d[0],
                w[1].clone() - t.clone() * &d[1],
            ];
            Ok((t, dot_g(&e, &e)))
        };
        let (tp, ep) = project(&d_plus)?;
        let (tm, em) = project(&d_minus)?;
        let (t, d) = if cmp_g(&ep, &em, "nearer boundary line")? != Ordering::Greater {
            (tp, d_plus)
        } else {
            (tm, d_minus)
        };
        (
            [
                v_o[0].clone() + t.clone() * &d[0] - &v_r[0],
                v_o[1].clone() + t * &d[1] - &v_r[1],
            ],
            true,
        )
    } else {
        (u0, false)
    };
    let e = [
        v_des[0].clone() - &v_r[0] - &u[0],
        v_des[1].clone() - &v_r[1] - &u[1],
    ];
    let j = dot_g(&e, &e) + lam.clone() * dot_g(&u, &u);
    if !(u[0].is_finite() && u[1].is_finite() && j.is_finite()) {
        return Err(VoError::Overflow);
    }
    Ok(VoSolutionOf { u, j, active })
}

/// The objective of eq. 4.1: `J(u) = ‖v_des − (v_r + u)‖² + λ‖u‖²`.
#[inline]
pub fn objective(u: [f64; 2], v_r: [f64; 2], v_des: [f64; 2], lam: f64) -> f64 {
    let e = [v_des[0] - v_r[0] - u[0], v_des[1] - v_r[1] - u[1]];
    dot(e, e) + lam * dot(u, u)
}

/// The constraint function of eq. 4.1: `c(u) = (rᵀv)²/‖v‖² − ‖r‖² + R²` with
/// `v = v_o − (v_r + u)`; at `v = 0` it returns `R² − ‖r‖²` (the module's convention: no relative
/// motion is feasible when `‖r‖ > R`, as if the line were perpendicular to `r`).
///
/// `c(u) ≤ 0` ⇔ the relative-velocity line misses the obstacle by at least `R`.
#[inline]
pub fn constraint(r: [f64; 2], v_o: [f64; 2], v_r: [f64; 2], u: [f64; 2], big_r: f64) -> f64 {
    let v = [v_o[0] - v_r[0] - u[0], v_o[1] - v_r[1] - u[1]];
    let vv = dot(v, v);
    let proj2 = if vv > 0.0 {
        let rv = dot(r, v);
        rv * rv / vv
    } else {
        0.0
    };
    proj2 - dot(r, r) + big_r * big_r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        approx::abs_diff_eq!(a, b, epsilon = tol)
    }

    /// Obstacle dead ahead: r = (1,0), R = 1/2 (α = 30°), v_o = v_r = 0, v_des = (1,0), λ = 0.
    /// x₀ = (1,0) is on the axis; its projection on the line at +30° is t = cos30° = √3/2,
    /// x* = (3/4, √3/4), and J* = sin²30° = 1/4.
    #[test]
    fn dead_ahead_by_hand() {
        let s = vo_expert([1.0, 0.0], [0.0; 2], [0.0; 2], [1.0, 0.0], 0.0, 0.5).unwrap();
        assert!(s.active);
        assert!(close(s.u[0], 0.75, 1e-15), "{s:?}");
        assert!(close(s.u[1], 3f64.sqrt() / 4.0, 1e-15), "{s:?}");
        assert!(close(s.j, 0.25, 1e-15), "{s:?}");
    }

    /// r = (0,2), R = 1 (α = 30°), v_o = v_r = (1,0), v_des = (1,3), λ = 1:
    /// u₀ = (0, 3/2), J(u₀) = λ/(1+λ)‖v_des − v_r‖² = 9/2, w = x₀ − v_o = (0, 3/2) on the axis;
    /// distance to the boundary line 3/2·sin30° = 3/4, so J* = 9/2 + 2·(3/4)² = 45/8;
    /// t = 3/2·cos30°, d₊ = (−1/2, √3/2), u* = t d₊ = (−3√3/8, 9/8).
    #[test]
    fn lambda_one_by_hand() {
        let s = vo_expert([0.0, 2.0], [1.0, 0.0], [1.0, 0.0], [1.0, 3.0], 1.0, 1.0).unwrap();
        assert!(close(s.j, 45.0 / 8.0, 1e-14), "{s:?}");
        assert!(close(s.u[0], -3.0 * 3f64.sqrt() / 8.0, 1e-14), "{s:?}");
        assert!(close(s.u[1], 9.0 / 8.0, 1e-14), "{s:?}");
    }

    /// Obstacle behind the agent, agent wants to move away from it: the double cone (eq. 4.1 as
    /// written) forbids it (J* = 1/4 as in the dead-ahead case, mirrored), the forward cone allows it.
    #[test]
    fn obstacle_behind_double_vs_forward() {
        let args = ([-1.0, 0.0], [0.0; 2], [0.0; 2], [1.0, 0.0], 0.0, 0.5);
        let d = vo_expert(args.0, args.1, args.2, args.3, args.4, args.5).unwrap();
        assert!(d.active && close(d.j, 0.25, 1e-15), "{d:?}");
        let f = vo_expert_cone(
            Cone::Forward,
            args.0,
            args.1,
            args.2,
            args.3,
            args.4,
            args.5,
        )
        .unwrap();
        assert!(!f.active && f.u == [1.0, 0.0] && f.j == 0.0, "{f:?}");
    }

    /// x₀ = v_o (no relative motion): feasible by convention, u = u₀, J = 0.
    #[test]
    fn apex_is_feasible() {
        let s = vo_expert([1.0, 0.0], [1.0, 0.0], [0.0; 2], [1.0, 0.0], 0.0, 0.5).unwrap();
        assert!(!s.active && s.u == [1.0, 0.0] && s.j == 0.0, "{s:?}");
    }

    #[test]
    fn unconstrained_when_clear() {
        // Obstacle far to the side: x₀ − v_o = (1,0) is at 90° from r = (0,3).
        let s = vo_expert([0.0, 3.0], [0.0; 2], [0.0; 2], [1.0, 0.0], 0.5, 1.0).unwrap();
        assert!(!s.active);
        assert!(close(s.u[0], 1.0 / 1.5, 1e-15) && s.u[1] == 0.0);
        assert!(close(s.j, 0.5 / 1.5, 1e-15));
    }

    #[test]
    fn errors() {
        let ok = ([1.0, 0.0], [0.0; 2], [0.0; 2], [1.0, 0.0]);
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, ok.3, -0.1, 0.5),
            Err(VoError::NegativeLambda(-0.1))
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, ok.3, 0.0, 0.0),
            Err(VoError::NonPositiveRadius(0.0))
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, ok.3, 0.0, -1.0),
            Err(VoError::NonPositiveRadius(-1.0))
        );
        assert!(matches!(
            vo_expert(ok.0, ok.1, ok.2, ok.3, 0.0, 1.0),
            Err(VoError::InsideObstacle { .. })
        ));
        assert!(matches!(
            vo_expert([0.3, 0.4], ok.1, ok.2, ok.3, 0.0, 0.6),
            Err(VoError::InsideObstacle { .. })
        ));
        assert_eq!(
            vo_expert([f64::NAN, 0.0], ok.1, ok.2, ok.3, 0.0, 0.5),
            Err(VoError::NonFinite { name: "r" })
        );
        assert_eq!(
            vo_expert(ok.0, [0.0, f64::INFINITY], ok.2, ok.3, 0.0, 0.5),
            Err(VoError::NonFinite { name: "v_o" })
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, [f64::NEG_INFINITY, 0.0], ok.3, 0.0, 0.5),
            Err(VoError::NonFinite { name: "v_r" })
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, [0.0, f64::NAN], 0.0, 0.5),
            Err(VoError::NonFinite { name: "v_des" })
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, ok.3, f64::NAN, 0.5),
            Err(VoError::NonFinite { name: "lam" })
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, ok.3, 0.0, f64::INFINITY),
            Err(VoError::NonFinite { name: "R" })
        );
        assert_eq!(
            vo_expert([1e200, 0.0], ok.1, ok.2, ok.3, 0.0, 0.5),
            Err(VoError::Overflow)
        );
        assert_eq!(
            vo_expert(ok.0, ok.1, ok.2, [1e308, 1e308], 0.0, 0.5),
            Err(VoError::Overflow)
        );
    }

    /// Intervals: the dead-ahead tie cannot be decided (both lines are equally near); a case off
    /// the axis is decided and encloses the f64 answer's exact value.
    #[test]
    fn generic_intervals_tie_is_undecidable() {
        use crate::scalar::Interval;
        let p = |x: f64| Interval::try_from((x, x)).unwrap();
        let z = [p(0.0), p(0.0)];
        let tie = vo_expert_generic(
            Cone::Double,
            &[p(1.0), p(0.0)],
            &z,
            &z,
            &[p(1.0), p(0.0)],
            &p(0.0),
            &p(0.5),
        );
        assert!(matches!(tie, Err(VoError::Undecidable(_))), "{tie:?}");
        let off = vo_expert_generic(
            Cone::Double,
            &[p(1.0), p(0.1)],
            &z,
            &z,
            &[p(1.0), p(0.0)],
            &p(0.0),
            &p(0.5),
        )
        .unwrap();
        let f = vo_expert([1.0, 0.1], [0.0; 2], [0.0; 2], [1.0, 0.0], 0.0, 0.5).unwrap();
        assert!(off.active && f.active);
        for (e, x) in off.u.iter().zip(f.u) {
            assert!(e.inf() - 1e-15 <= x && x <= e.sup() + 1e-15, "{e:?} vs {x}");
        }
    }

    #[test]
    fn constraint_at_hand_solution_is_zero() {
        let s = vo_expert([1.0, 0.0], [0.0; 2], [0.0; 2], [1.0, 0.0], 0.0, 0.5).unwrap();
        let c = constraint([1.0, 0.0], [0.0; 2], [0.0; 2], s.u, 0.5);
        assert!(c.abs() <= 1e-15, "{c}");
        // The unconstrained minimiser violates it: the line through (1,0) hits the obstacle centre.
        assert!(close(
            constraint([1.0, 0.0], [0.0; 2], [0.0; 2], [1.0, 0.0], 0.5),
            0.25,
            0.0
        ));
    }
}
