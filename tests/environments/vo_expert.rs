//! The velocity-obstacle expert of eq. 4.1 against independent oracles: a dense grid search, a
//! general local (log-barrier Newton) solver started from many points, feasibility of the answer,
//! the degenerate inputs, and hand-computed cases.
//!
//! Tolerance policy (floats): feasibility is judged on `c(u)`, a difference of terms of size
//! `‖r‖²`, whose evaluation error is a few ulps of `‖r‖²` plus the error of the direction of
//! `v = v_o − v_r − u` (absolute error ≈ 4ε(|v_o|+|v_r|+|u|), turning the line by that over `‖v‖`);
//! objective values are compared with a relative `1e-12` (a handful of roundings in a quadratic).

use approx::abs_diff_eq;
use ilopt::expert::vo::{
    Cone, VoError, VoSolution, constraint, objective, vo_expert, vo_expert_cone, vo_expert_generic,
};
use ilopt::problem::KitRng;
use ilopt::scalar::{Dual, Interval};
use rand::{Rng, SeedableRng};

#[path = "../common/vo_cases.rs"]
mod vo_cases;
use vo_cases::{Case, random_case};

impl Case {
    fn solve(&self, cone: Cone) -> Result<VoSolution, VoError> {
        vo_expert_cone(
            cone, self.r, self.v_o, self.v_r, self.v_des, self.lam, self.big_r,
        )
    }
    fn j(&self, u: [f64; 2]) -> f64 {
        objective(u, self.v_r, self.v_des, self.lam)
    }
    fn c(&self, u: [f64; 2]) -> f64 {
        constraint(self.r, self.v_o, self.v_r, u, self.big_r)
    }
    fn v(&self, u: [f64; 2]) -> [f64; 2] {
        [
            self.v_o[0] - self.v_r[0] - u[0],
            self.v_o[1] - self.v_r[1] - u[1],
        ]
    }
    fn rr(&self) -> f64 {
        self.r[0] * self.r[0] + self.r[1] * self.r[1]
    }
    /// Rounding allowance for `c(u)` (module docs).
    fn c_tol(&self, u: [f64; 2]) -> f64 {
        let v = self.v(u);
        let vn = v[0].hypot(v[1]);
        let mag =
            self.v_o[0].hypot(self.v_o[1]) + self.v_r[0].hypot(self.v_r[1]) + u[0].hypot(u[1]);
        let dir = if vn > 0.0 {
            8.0 * f64::EPSILON * mag / vn
        } else {
            0.0
        };
        self.rr() * (1e-13 + dir)
    }
    /// Feasible *with margin* `m ≥ 0` (so that rounding cannot misclassify an infeasible point).
    fn feasible_with_margin(&self, cone: Cone, u: [f64; 2], m: f64) -> bool {
        let v = self.v(u);
        let rv = self.r[0] * v[0] + self.r[1] * v[1];
        let vn = v[0].hypot(v[1]);
        let c_ok = self.c(u) <= -m;
        match cone {
            Cone::Double => c_ok,
            _ => c_ok || rv >= m.sqrt() * vn * self.rr().sqrt(),
        }
    }
}

fn u0(c: &Case) -> [f64; 2] {
    [
        (c.v_des[0] - c.v_r[0]) / (1.0 + c.lam),
        (c.v_des[1] - c.v_r[1]) / (1.0 + c.lam),
    ]
}

/// (a) Grid search: on an `n × n` grid over the square of half-width `1.02‖u* − u₀‖` around `u₀` —
/// which contains the whole sublevel set `{J ≤ J*}` (a disc of that radius around `u₀`, since
/// `J = (1+λ)‖u − u₀‖² + J(u₀)`), so no feasible point outside the grid can beat `J*` — every grid
/// point that is feasible (with a rounding margin) has `J ≥ J* − 1e-12(1 + J*)`.
/// Returns (cases with an active constraint, the largest `(best grid J − J*)/(1+J*)`).
fn grid_check(cone: Cone, cases: usize, n: usize, seed: u64) -> (usize, f64) {
    let mut rng = KitRng::seed_from_u64(seed);
    let mut active = 0;
    let mut worst_gap: f64 = 0.0;
    for k in 0..cases {
        let c = random_case(&mut rng);
        let s = c.solve(cone).unwrap();
        let base = u0(&c);
        let rho = (s.u[0] - base[0]).hypot(s.u[1] - base[1]);
        if !s.active {
            let err = (s.u[0] - base[0]).hypot(s.u[1] - base[1]);
            let tol = 4.0 * f64::EPSILON * (1.0 + base[0].hypot(base[1]));
            assert!(err <= tol, "case {k}: inactive but u ≠ u₀: {c:?} {s:?}");
            continue;
        }
        active += 1;
        let half = 1.02 * rho;
        let h = 2.0 * half / (n - 1) as f64;
        let tol = 1e-12 * (1.0 + s.j);
        let mut best = f64::INFINITY;
        for i in 0..n {
            for l in 0..n {
                let g = [base[0] - half + i as f64 * h, base[1] - half + l as f64 * h];
                if !c.feasible_with_margin(cone, g, c.c_tol(g)) {
                    continue;
                }
                let jg = c.j(g);
                assert!(
                    jg >= s.j - tol,
                    "case {k} ({cone:?}): grid point {g:?} feasible with J = {jg} < J* = {} ({c:?}, {s:?})",
                    s.j
                );
                best = best.min(jg);
            }
        }
        if best.is_finite() {
            worst_gap = worst_gap.max((best - s.j) / (1.0 + s.j));
        }
    }
    (active, worst_gap)
}

#[test]
fn never_beaten_by_a_fine_grid() {
    for cone in [Cone::Double, Cone::Forward] {
        let (active, gap) = grid_check(cone, 300, 401, 11);
        println!(
            "{cone:?}: 401×401 grid, {active}/300 active, worst (best grid − J*)/(1+J*) = {gap:.3e}"
        );
        assert!(
            active >= 100,
            "too few active cases to test anything: {active}"
        );
    }
}

#[test]
#[ignore = "slow (≈ 1 min in release): 401×401 grid on 5000 cases per cone; run with --release --ignored"]
fn never_beaten_by_a_fine_grid_on_many_cases() {
    for cone in [Cone::Double, Cone::Forward] {
        let (active, gap) = grid_check(cone, 5000, 401, 13);
        println!(
            "{cone:?}: 401×401 grid, {active}/5000 active, worst (best grid − J*)/(1+J*) = {gap:.3e}"
        );
        assert!(
            active >= 1500,
            "too few active cases to test anything: {active}"
        );
    }
}

#[test]
fn never_beaten_by_a_coarse_grid_on_many_cases() {
    for cone in [Cone::Double, Cone::Forward] {
        let (active, gap) = grid_check(cone, 4000, 61, 12);
        println!(
            "{cone:?}: 61×61 grid, {active}/4000 active, worst (best grid − J*)/(1+J*) = {gap:.3e}"
        );
        assert!(
            active >= 1000,
            "too few active cases to test anything: {active}"
        );
    }
}

/// (b) The returned `u` is feasible, `J` is `J(u)` and finite, and the unconstrained minimiser is
/// returned exactly when it is feasible.
#[test]
fn solutions_are_feasible() {
    let mut rng = KitRng::seed_from_u64(21);
    let mut worst: f64 = 0.0;
    for k in 0..100_000 {
        let c = random_case(&mut rng);
        for cone in [Cone::Double, Cone::Forward] {
            let s = c.solve(cone).unwrap();
            assert!(s.j.is_finite() && s.u.iter().all(|x| x.is_finite()));
            assert_eq!(s.j, c.j(s.u));
            let cu = c.c(s.u);
            let v = c.v(s.u);
            let forward_ok = cone == Cone::Forward && c.r[0] * v[0] + c.r[1] * v[1] >= 0.0;
            assert!(
                forward_ok || cu <= c.c_tol(s.u),
                "case {k} ({cone:?}): c(u*) = {cu} > {} ({c:?}, {s:?})",
                c.c_tol(s.u)
            );
            if cone == Cone::Double {
                worst = worst.max(cu / c.rr());
            }
            // J* never exceeds J at the unconstrained minimiser's feasible alternatives: at least
            // J(u₀), and equal to it iff inactive.
            let j0 = c.j(u0(&c));
            assert!(s.j >= j0 - 1e-12 * (1.0 + j0));
        }
    }
    println!("worst c(u*)/‖r‖² over 100000 double-cone solves: {worst:.3e}");
}

/// A general local method for eq. 4.1 that knows nothing of the cone geometry: log-barrier
/// `φ_μ(u) = J(u) − μ ln(−c(u))`, damped Newton (finite-difference Hessian of the analytic gradient,
/// backtracking that keeps `c < 0` and decreases `φ`), `μ` from `1e-2(1 + J(u₀))` down by 10 per
/// stage to `1e-14(1+J(u₀))`. Every iterate is strictly feasible, so its `J` bounds `J*` above.
fn barrier_local(c: &Case, start: [f64; 2]) -> Option<[f64; 2]> {
    let grad_j = |u: [f64; 2]| {
        let e = [c.v_des[0] - c.v_r[0] - u[0], c.v_des[1] - c.v_r[1] - u[1]];
        [
            -2.0 * e[0] + 2.0 * c.lam * u[0],
            -2.0 * e[1] + 2.0 * c.lam * u[1],
        ]
    };
    let grad_c = |u: [f64; 2]| {
        let v = c.v(u);
        let vv = v[0] * v[0] + v[1] * v[1];
        let rv = c.r[0] * v[0] + c.r[1] * v[1];
        // ∂c/∂v = 2(rᵀv) r/‖v‖² − 2(rᵀv)² v/‖v‖⁴; ∂v/∂u = −I.
        [
            -(2.0 * rv * c.r[0] / vv - 2.0 * rv * rv * v[0] / (vv * vv)),
            -(2.0 * rv * c.r[1] / vv - 2.0 * rv * rv * v[1] / (vv * vv)),
        ]
    };
    let j0 = c.j(u0(c));
    let mut u = start;
    if c.c(u) >= 0.0 {
        return None;
    }
    let mut mu = 1e-2 * (1.0 + j0);
    while mu >= 1e-14 * (1.0 + j0) {
        let phi = |u: [f64; 2]| {
            let cu = c.c(u);
            if cu < 0.0 {
                c.j(u) - mu * (-cu).ln()
            } else {
                f64::INFINITY
            }
        };
        let grad = |u: [f64; 2]| {
            let (gj, gc, cu) = (grad_j(u), grad_c(u), c.c(u));
            [gj[0] - mu * gc[0] / cu, gj[1] - mu * gc[1] / cu]
        };
        for _ in 0..60 {
            let g = grad(u);
            let scale = 1e-7 * (1.0 + u[0].abs().max(u[1].abs()));
            let mut hess = [[0.0; 2]; 2];
            for (i, row) in hess.iter_mut().enumerate() {
                let mut up = u;
                let mut dn = u;
                up[i] += scale;
                dn[i] -= scale;
                let (gp, gm) = (grad(up), grad(dn));
                row[0] = (gp[0] - gm[0]) / (2.0 * scale);
                row[1] = (gp[1] - gm[1]) / (2.0 * scale);
            }
            let (a, b, d) = (hess[0][0], 0.5 * (hess[0][1] + hess[1][0]), hess[1][1]);
            let det = a * d - b * b;
            let mut step = if a > 0.0 && det > 0.0 && det.is_finite() {
                [-(d * g[0] - b * g[1]) / det, -(-b * g[0] + a * g[1]) / det]
            } else {
                let gn = g[0].hypot(g[1]).max(1e-300);
                let len = 0.1 * (1.0 + u[0].hypot(u[1]));
                [-g[0] / gn * len, -g[1] / gn * len]
            };
            let f = phi(u);
            let slope = g[0] * step[0] + g[1] * step[1];
            let mut moved = false;
            for _ in 0..60 {
                let cand = [u[0] + step[0], u[1] + step[1]];
                let fc = phi(cand);
                if fc.is_finite() && fc <= f + 1e-4 * slope.min(0.0) {
                    moved = cand != u;
                    u = cand;
                    break;
                }
                step = [0.5 * step[0], 0.5 * step[1]];
            }
            if !moved || g[0].hypot(g[1]) < 1e-15 * (1.0 + j0) {
                break;
            }
        }
        mu *= 0.1;
    }
    (c.c(u) < 0.0).then_some(u)
}

/// (c) The closed form is never worse than the best of a general local solver started from 16
/// random strictly feasible points (on the double cone, eq. 4.1 as the thesis states it and solves
/// it with a local method), and on almost all cases the local solver finds the same optimum.
#[test]
fn never_worse_than_a_multistart_local_solver() {
    let mut rng = KitRng::seed_from_u64(31);
    let cases = 400;
    let (mut compared, mut agree) = (0, 0);
    let mut worst_local_minus_star: f64 = 0.0;
    let mut best_local_minus_star = f64::INFINITY;
    for k in 0..cases {
        let c = random_case(&mut rng);
        let s = c.solve(Cone::Double).unwrap();
        let base = u0(&c);
        let half = 2.0 * (s.u[0] - base[0]).hypot(s.u[1] - base[1]) + 0.1;
        let mut best = f64::INFINITY;
        let mut starts = 0;
        for _ in 0..20_000 {
            if starts == 16 {
                break;
            }
            let p = [
                base[0] + rng.random_range(-half..half),
                base[1] + rng.random_range(-half..half),
            ];
            if c.c(p) >= 0.0 {
                continue;
            }
            starts += 1;
            if let Some(u) = barrier_local(&c, p) {
                best = best.min(c.j(u));
            }
        }
        if !best.is_finite() {
            continue;
        }
        compared += 1;
        let rel = (best - s.j) / (1.0 + s.j);
        assert!(
            rel >= -1e-12,
            "case {k}: a local solution has J = {best} < J* = {} ({c:?}, {s:?})",
            s.j
        );
        worst_local_minus_star = worst_local_minus_star.max(rel);
        best_local_minus_star = best_local_minus_star.min(rel);
        if rel <= 1e-6 {
            agree += 1;
        }
    }
    println!(
        "local solver: {compared}/{cases} cases compared, {agree} within 1e-6 relative of J*, \
         (best local − J*)/(1+J*) in [{best_local_minus_star:.3e}, {worst_local_minus_star:.3e}]"
    );
    assert!(
        compared >= cases * 9 / 10,
        "too few comparisons: {compared}"
    );
    assert!(
        agree * 100 >= compared * 95,
        "local solver rarely reaches J*: {agree}/{compared}"
    );
}

/// (d) Degenerate inputs give their errors (through the public API).
#[test]
fn degenerate_inputs() {
    let (r, z, d) = ([1.0, 0.0], [0.0; 2], [1.0, 0.0]);
    assert_eq!(
        vo_expert(r, z, z, d, -1e-300, 0.5),
        Err(VoError::NegativeLambda(-1e-300))
    );
    assert!(matches!(
        vo_expert(r, z, z, d, 0.0, 0.0),
        Err(VoError::NonPositiveRadius(_))
    ));
    assert!(matches!(
        vo_expert(r, z, z, d, 0.0, 1.0),
        Err(VoError::InsideObstacle { .. })
    ));
    assert!(matches!(
        vo_expert(z, z, z, d, 0.0, 1e-9),
        Err(VoError::InsideObstacle { .. })
    ));
    assert!(matches!(
        vo_expert(r, z, z, [f64::NAN; 2], 0.0, 0.5),
        Err(VoError::NonFinite { name: "v_des" })
    ));
    // λ = 0 is fine.
    assert!(vo_expert([0.0, 3.0], z, z, d, 0.0, 1.0).is_ok());
    // Just outside: a very narrow feasible set (α → 90°), still a finite, feasible answer.
    let big_r = 0.5;
    let r_close = [big_r * (1.0 + 1e-12), 0.0];
    let s = vo_expert(r_close, z, z, d, 0.0, big_r).unwrap();
    assert!(s.active && s.j.is_finite());
    assert!(constraint(r_close, z, z, s.u, big_r) <= 1e-12);
}

/// (e) Hand-computed: obstacle dead ahead and moving towards the agent.
/// r = (2, 0), R = 1 (sin α = 1/2, α = 30°), v_o = (−1, 0), v_r = (0, 0), v_des = (1, 0), λ = 0:
/// x₀ = (1, 0), w = x₀ − v_o = (2, 0) on the axis; the nearest boundary point is at distance
/// 2·sin 30° = 1, J* = 1, x* = v_o + 2cos30°·(cos30°, sin30°) = (−1 + 3/2, √3/2) = (1/2, √3/2).
#[test]
fn hand_computed_head_on() {
    let s = vo_expert([2.0, 0.0], [-1.0, 0.0], [0.0; 2], [1.0, 0.0], 0.0, 1.0).unwrap();
    assert!(abs_diff_eq!(s.j, 1.0, epsilon = 1e-15), "{s:?}");
    assert!(
        abs_diff_eq!(s.u[0], 0.5, epsilon = 1e-15)
            && abs_diff_eq!(s.u[1], 3f64.sqrt() / 2.0, epsilon = 1e-15),
        "{s:?}"
    );
    // The forward cone gives the same answer here (the obstacle approaches).
    let f = vo_expert_cone(
        Cone::Forward,
        [2.0, 0.0],
        [-1.0, 0.0],
        [0.0; 2],
        [1.0, 0.0],
        0.0,
        1.0,
    )
    .unwrap();
    assert_eq!(f.u, s.u);
}

/// The generic closed form, instantiated at `f64`, is bit-identical to the `f64` one.
#[test]
fn generic_f64_is_bit_identical() {
    let mut rng = KitRng::seed_from_u64(41);
    for k in 0..20_000 {
        let c = random_case(&mut rng);
        for cone in [Cone::Double, Cone::Forward] {
            let s = c.solve(cone).unwrap();
            let g =
                vo_expert_generic(cone, &c.r, &c.v_o, &c.v_r, &c.v_des, &c.lam, &c.big_r).unwrap();
            assert_eq!(
                (g.u, g.j, g.active),
                (s.u, s.j, s.active),
                "case {k} {cone:?}"
            );
        }
    }
    // Errors agree too.
    let z = [0.0; 2];
    assert_eq!(
        vo_expert_generic(Cone::Double, &[1.0, 0.0], &z, &z, &z, &-1.0, &0.5),
        Err(VoError::NegativeLambda(-1.0))
    );
}

/// Rigorous accuracy of the `f64` closed form: with point-interval inputs the generic solver
/// encloses the exact minimiser (of the exact problem with the `f64` inputs); the distance from the
/// `f64` answer to that enclosure plus the enclosure's width bounds the `f64` error. Most cases
/// must be decidable, and the `f64` error must be at the level of rounding (≤ 1e-9 relative to the
/// inputs' scale; a bound, not a measurement, since the enclosure may be wide near α → 90°).
#[test]
fn f64_answer_lies_in_the_interval_enclosure() {
    let point = |x: f64| Interval::try_from((x, x)).unwrap();
    let pv = |v: [f64; 2]| [point(v[0]), point(v[1])];
    let mut rng = KitRng::seed_from_u64(51);
    let (mut decided, mut worst): (usize, f64) = (0, 0.0);
    let cases = 20_000;
    for k in 0..cases {
        let c = random_case(&mut rng);
        let s = c.solve(Cone::Double).unwrap();
        let Ok(g) = vo_expert_generic(
            Cone::Double,
            &pv(c.r),
            &pv(c.v_o),
            &pv(c.v_r),
            &pv(c.v_des),
            &point(c.lam),
            &point(c.big_r),
        ) else {
            continue;
        };
        decided += 1;
        assert_eq!(g.active, s.active, "case {k}");
        let scale = 1.0
            + c.v_o[0].hypot(c.v_o[1])
            + c.v_r[0].hypot(c.v_r[1])
            + c.v_des[0].hypot(c.v_des[1]);
        for (x, e) in s.u.iter().zip(&g.u) {
            let outside = (e.inf() - x).max(x - e.sup()).max(0.0);
            let bound = (outside + e.wid()) / scale;
            worst = worst.max(bound);
            assert!(
                bound <= 1e-9,
                "case {k}: f64 u* {x} vs enclosure {e:?} ({c:?})"
            );
        }
    }
    println!(
        "interval enclosure: {decided}/{cases} decided, worst rigorous f64 error bound / scale = {worst:.3e}"
    );
    assert!(
        decided * 10 >= cases * 9,
        "only {decided}/{cases} decidable"
    );
}

/// Dual numbers through the generic solver give `∂J*/∂v_des`, which by the envelope theorem (the
/// constraint does not involve `v_des`) equals `∂J/∂v_des` at fixed `u*`: `2(v_des − v_r − u*)`.
#[test]
fn dual_gradient_matches_the_envelope_theorem() {
    let mut rng = KitRng::seed_from_u64(61);
    let cst = |v: [f64; 2]| [Dual::constant(v[0]), Dual::constant(v[1])];
    for k in 0..2000 {
        let c = random_case(&mut rng);
        let v_des = [
            Dual::variable(c.v_des[0], 0, 2),
            Dual::variable(c.v_des[1], 1, 2),
        ];
        let g = vo_expert_generic(
            Cone::Double,
            &cst(c.r),
            &cst(c.v_o),
            &cst(c.v_r),
            &v_des,
            &Dual::constant(c.lam),
            &Dual::constant(c.big_r),
        )
        .unwrap();
        let u = [*g.u[0].value(), *g.u[1].value()];
        let grad = g.j.gradient_padded(2);
        for i in 0..2 {
            let expect = 2.0 * (c.v_des[i] - c.v_r[i] - u[i]);
            assert!(
                abs_diff_eq!(grad[i], expect, epsilon = 1e-9 * (1.0 + expect.abs())),
                "case {k}: ∂J*/∂v_des[{i}] = {} vs envelope {expect} ({c:?})",
                grad[i]
            );
        }
    }
}
