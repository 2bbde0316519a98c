//! Random velocity-obstacle problems of eq. 4.1, shared by the expert's tests
//! (`tests/environments/vo_expert.rs`) and the command's (`cli/tests/commands/expert.rs`).

use ilopt::problem::KitRng;
use rand::Rng;
use std::f64::consts::PI;

/// One velocity-obstacle problem of eq. 4.1.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    pub r: [f64; 2],
    pub v_o: [f64; 2],
    pub v_r: [f64; 2],
    pub v_des: [f64; 2],
    pub lam: f64,
    pub big_r: f64,
}

/// A random case: outside the obstacle, sometimes very close to it, a
/// quarter aimed at it (active constraint).
pub fn random_case(rng: &mut KitRng) -> Case {
    let big_r = rng.random_range(0.05..1.0);
    // Mostly moderate distances, sometimes very close to the obstacle (half-angle α near 90°).
    let ratio = if rng.random_bool(0.1) {
        1.0 + rng.random_range(1e-9..1e-3)
    } else {
        rng.random_range(1.0001..5.0)
    };
    let th = rng.random_range(0.0..2.0 * PI);
    let r = [big_r * ratio * th.cos(), big_r * ratio * th.sin()];
    let mut vec = |s: f64| [rng.random_range(-s..s), rng.random_range(-s..s)];
    let v_o = vec(0.5);
    let v_r = vec(1.0);
    let mut v_des = vec(1.0);
    let lam = if rng.random_bool(0.2) {
        0.0
    } else {
        rng.random_range(0.0..3.0)
    };
    // A quarter of the cases aim the unconstrained minimiser at the obstacle (active constraint).
    if rng.random_bool(0.25) {
        let s = rng.random_range(0.1..2.0);
        // x₀ = v_o + s r̂ + noise  ⇒  v_des = (1+λ)x₀ − λ v_r.
        let x0 = [
            v_o[0] + s * th.cos() + rng.random_range(-0.05..0.05),
            v_o[1] + s * th.sin() + rng.random_range(-0.05..0.05),
        ];
        v_des = [
            (1.0 + lam) * x0[0] - lam * v_r[0],
            (1.0 + lam) * x0[1] - lam * v_r[1],
        ];
    }
    Case {
        r,
        v_o,
        v_r,
        v_des,
        lam,
        big_r,
    }
}
