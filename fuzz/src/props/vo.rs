//! The velocity-obstacle expert's property: its answer is feasible (checked in exact arithmetic)
//! and no feasible point it could have missed is better.

use ilopt::expert::vo::{VoError, objective, vo_expert};
use ilopt::scalar::Scalar;
use num_bigint::BigInt;
use num_traits::Zero;

/// One geometry for [`vo_expert`] (any bit patterns: NaN, ±∞, subnormals, huge values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoInput {
    /// Obstacle centre minus agent centre.
    pub r: [f64; 2],
    /// Obstacle velocity.
    pub v_o: [f64; 2],
    /// Agent velocity.
    pub v_r: [f64; 2],
    /// Desired velocity.
    pub v_des: [f64; 2],
    /// λ.
    pub lam: f64,
    /// R.
    pub big_r: f64,
    /// Offsets along the perpendicular of `r` for extra feasible candidate points.
    pub probes: [f64; 2],
}

const EPS: f64 = f64::EPSILON;

fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

/// Exact test of the constraint of eq. 4.1 at a float point `u`, with a slack relative to the
/// scale of `c`: `(rᵀv)² − (‖r‖² − R²)‖v‖² ≤ rel·(‖r‖² + R²)‖v‖²`, `v = v_o − v_r − u` (all in
/// rationals), i.e. `c(u) ≤ rel·(‖r‖² + R²)` for `v ≠ 0`; `v = 0` is feasible by the module's
/// convention.
/// The finite float `x` times 2¹⁰⁷⁵, an exact integer (`integer_decode` reports subnormals with
/// exponent −1075).
fn z(x: f64) -> BigInt {
    let (m, e, sign) = num_traits::Float::integer_decode(x);
    let n = BigInt::from(m) << usize::try_from(i32::from(e) + 1075).expect("e ≥ −1075");
    if sign < 0 { -n } else { n }
}

fn constraint_exact_le(inp: &VoInput, u: [f64; 2], rel: f64) -> bool {
    if !rel.is_finite() {
        return true; // the tolerance itself overflowed (∞ or ∞/∞): no information
    }
    // Every float is an integer multiple of 2⁻¹⁰⁷⁵ (`integer_decode` reports subnormals with exponent −1075): compute with the integers x·2¹⁰⁷⁵ (exact, and
    // much faster than rationals, which reduce by a gcd after every operation). Both sides of
    // the inequality are homogeneous of degree 2 in (r, R) and in v, so the scale cancels; `rel`
    // is scaled too, so the left side is multiplied by 2¹⁰⁷⁵ once more.
    let v: Vec<BigInt> = (0..2)
        .map(|k| z(inp.v_o[k]) - z(inp.v_r[k]) - z(u[k]))
        .collect();
    let r: Vec<BigInt> = inp.r.iter().map(|&x| z(x)).collect();
    let vv = &v[0] * &v[0] + &v[1] * &v[1];
    if vv.is_zero() {
        return true;
    }
    let rv = &r[0] * &v[0] + &r[1] * &v[1];
    let rr = &r[0] * &r[0] + &r[1] * &r[1];
    let rr2 = z(inp.big_r) * z(inp.big_r);
    ((&rv * &rv - (&rr - &rr2) * &vv) << 1075usize) <= z(rel) * (rr + rr2) * vv
}

/// The documented rounding tolerance of the feasibility check (fuzz/README.md), relative to the
/// scale `‖r‖² + R²` of `c`: with `M = ‖v_o‖ + ‖v_r‖ + ‖v_des‖ + ‖u‖`,
/// `c(u*) ≤ 64·(‖r‖² + R²)·(ε + (εM + η)/‖v‖)`, `η = 2⁻¹⁰⁷⁴` (the subnormal spacing). The
/// returned `u*` is the rounded image of a point on the cone's boundary; an error
/// `e ≲ 8(εM + η)` in its position turns the line's direction by `e/‖v‖`,
/// which moves `c` by at most `‖r‖²·e/‖v‖`; computing the boundary direction `d±` (one square
/// root of `‖r‖² − R²`) costs another few `ε(‖r‖² + R²)`. Both are invariant under rescaling r
/// and R, so the bound is stated relative to `‖r‖² + R²`.
pub fn vo_feasibility_slack(inp: &VoInput, u: [f64; 2]) -> f64 {
    let v = [
        inp.v_o[0] - inp.v_r[0] - u[0],
        inp.v_o[1] - inp.v_r[1] - u[1],
    ];
    let m = norm(inp.v_o) + norm(inp.v_r) + norm(inp.v_des) + norm(u);
    let nv = norm(v);
    // Position error of u*: a few ulps of M, but never less than the spacing of subnormals
    // (2⁻¹⁰⁷⁴): a u* in the subnormal range has only a few significant bits.
    let e = EPS * m + f64::from_bits(1);
    let ratio = if nv > 0.0 { e / nv } else { f64::INFINITY };
    64.0 * (EPS + ratio)
}

/// Target `vo_expert`: a finite, feasible (within [`vo_feasibility_slack`]) global optimum that is
/// no worse than a few known feasible points, or a clear error; never NaN, never a panic.
pub fn check_vo(inp: &VoInput) {
    let res = vo_expert(inp.r, inp.v_o, inp.v_r, inp.v_des, inp.lam, inp.big_r);
    let all = [
        inp.r[0],
        inp.r[1],
        inp.v_o[0],
        inp.v_o[1],
        inp.v_r[0],
        inp.v_r[1],
        inp.v_des[0],
        inp.v_des[1],
        inp.lam,
        inp.big_r,
    ];
    let sol = match res {
        Err(e) => {
            assert!(!e.to_string().is_empty());
            assert!(!e.to_string().contains("NaN"), "error prints NaN: {e}");
            if all.iter().any(|x| !x.is_finite()) {
                assert!(
                    matches!(e, VoError::NonFinite { .. }),
                    "non-finite input gave {e:?}"
                );
            }
            return;
        }
        Ok(sol) => sol,
    };
    assert!(
        all.iter().all(|x| x.is_finite()),
        "Ok for a non-finite input"
    );
    assert!(inp.lam >= 0.0 && inp.big_r > 0.0, "Ok for λ < 0 or R ≤ 0");
    // ‖r‖ > R, decided exactly (‖r‖ may exceed R by less than an ulp).
    let (r0, r1, big) = (z(inp.r[0]), z(inp.r[1]), z(inp.big_r));
    assert!(
        &r0 * &r0 + &r1 * &r1 > &big * &big,
        "Ok inside the obstacle"
    );
    let u = sol.u;
    assert!(
        u[0].is_finite() && u[1].is_finite() && sol.j.is_finite(),
        "non-finite Ok: {sol:?}"
    );
    let j_u = objective(u, inp.v_r, inp.v_des, inp.lam);
    // The scale of J's terms; everything below is relative to it.
    let m = norm(inp.v_o) + norm(inp.v_r) + norm(inp.v_des) + norm(u);
    let j_scale = (1.0 + inp.lam) * (1.0 + m) * (1.0 + m);
    if !j_scale.is_finite() || !j_u.is_finite() {
        return; // the f64 checks below would overflow; finiteness was checked above
    }
    let j_tol = 1e-9 * j_scale;
    assert!(sol.j >= -j_tol, "J* < 0: {sol:?}");
    assert!(
        (sol.j - j_u).abs() <= j_tol,
        "J* = {} but J(u*) = {j_u}",
        sol.j
    );
    let slack = vo_feasibility_slack(inp, u);
    assert!(
        constraint_exact_le(inp, u, slack),
        "u* = {u:?} infeasible beyond the slack {slack:e}"
    );
    // Known feasible points: the apex (v = 0), and points of the line through v_o perpendicular
    // to r (rᵀv = 0 there, so c = R² − ‖r‖² < 0); plus u = 0 and u₀ when exactly feasible.
    let apex = [inp.v_o[0] - inp.v_r[0], inp.v_o[1] - inp.v_r[1]];
    let nr = norm(inp.r);
    let perp = [-inp.r[1] / nr, inp.r[0] / nr];
    let mut candidates = vec![apex, [0.0, 0.0]];
    let u0 = [
        (inp.v_des[0] - inp.v_r[0]) / (1.0 + inp.lam),
        (inp.v_des[1] - inp.v_r[1]) / (1.0 + inp.lam),
    ];
    candidates.push(u0);
    for &s in &inp.probes {
        if s.is_finite() && s.abs() < 1e6 * (1.0 + m) {
            candidates.push([apex[0] + s * perp[0], apex[1] + s * perp[1]]);
        }
    }
    for c in candidates {
        if !(c[0].is_finite() && c[1].is_finite()) {
            continue;
        }
        // Only points that are feasible exactly (no slack) count.
        if !constraint_exact_le(inp, c, 0.0) {
            continue;
        }
        let j_c = objective(c, inp.v_r, inp.v_des, inp.lam);
        if !j_c.is_finite() {
            continue;
        }
        let tol = 1e-9 * (j_scale + (1.0 + inp.lam) * (norm(c) + 1.0).powi(2));
        assert!(
            sol.j <= j_c + tol,
            "J* = {} > J({c:?}) = {j_c} at a feasible point",
            sol.j
        );
    }
}
