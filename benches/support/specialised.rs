//! A hand-specialised `f64` CartPole + LQR-labels + logistic-policy oracle: plain arrays, no
//! traits, no error paths — the yardstick for the generic `TaskProblem<CartPoleTask<f64>,
//! Logistic>`: generic code must cost nothing in f64.
//!
//! It follows the generic code operation by operation (same RNG draws, same order of floating-point
//! operations), so the gradients are bit-for-bit the same; `tests/estimators/specialised.rs` checks that on
//! seeded trajectories, and `benches/oracle.rs` times both.

#![allow(clippy::needless_range_loop)] // index loops mirror the generic code

use ilopt::problem::KitRng;
use rand::{Rng, RngCore};

/// Features per state: (x, ẋ, θ, θ̇, 1).
pub const D: usize = 5;

/// A CartPole trajectory in flat arrays: features row after row, actions, LQR labels.
#[derive(Debug, Clone, Default)]
pub struct Trajectory {
    /// φ(s_t), `D` per decision.
    pub features: Vec<[f64; D]>,
    /// a_t ∈ {0, 1}.
    pub actions: Vec<u8>,
    /// The LQR expert's action at s_t.
    pub labels: Vec<u8>,
}

/// CartPole-v1 (Gymnasium's constants, as `f64`) with the LQR expert's gain `k`.
#[derive(Debug, Clone)]
pub struct Specialised {
    /// The LQR gain: the expert pushes right iff `−k·s > 0`.
    pub k: [f64; 4],
    /// Time limit (500 in CartPole-v1).
    pub max_steps: usize,
}

const GRAVITY: f64 = 49.0 / 5.0;
const MASSPOLE: f64 = 1.0 / 10.0;
const MASSCART: f64 = 1.0;
const LENGTH: f64 = 1.0 / 2.0;
const FORCE_MAG: f64 = 10.0;
const TAU: f64 = 1.0 / 50.0;
const FOUR_THIRDS: f64 = 4.0 / 3.0;
const X_THRESHOLD: f64 = 12.0 / 5.0;

#[inline(always)]
fn dot(theta: &[f64; D], phi: &[f64; D]) -> f64 {
    let mut z = 0.0;
    for j in 0..D {
        z += theta[j] * phi[j];
    }
    z
}

#[inline(always)]
fn sigmoid(z: f64) -> f64 {
    if z >= 0.0 {
        1.0 / (1.0 + (-z).exp())
    } else {
        let e = z.exp();
        e / (1.0 + e)
    }
}

impl Specialised {
    /// Roll out the logistic policy θ from a seeded reset into `t` (cleared first).
    ///
    /// A function of its own (`#[inline(never)]`), as the generic roll-out loop
    /// (`TaskProblem::rollout_into`) is, so that both benchmarks compile and call the same code.
    /// (Measured: inlined into criterion's closure it runs no faster, once the closure
    /// uses the whole gradient; a variant compiled through an `#[inline(always)]` helper was
    /// vectorised differently and ran 11–12 % slower.)
    #[inline(never)]
    pub fn rollout(&self, theta: &[f64; D], rng: &mut KitRng, t: &mut Trajectory) {
        t.features.clear();
        t.actions.clear();
        t.labels.clear();
        let total_mass = MASSPOLE + MASSCART;
        let polemass_length = MASSPOLE * LENGTH;
        let theta_threshold = 12.0 * 2.0 * std::f64::consts::PI / 360.0;
        let mut s: [f64; 4] = std::array::from_fn(|_| {
            let u: f64 = rng.random();
            -0.05 + (0.05 - -0.05) * u
        });
        let mut steps = 0;
        loop {
            let phi = [s[0], s[1], s[2], s[3], 1.0];
            let mut u = 0.0;
            for i in 0..4 {
                u -= self.k[i] * s[i];
            }
            let label = u8::from(u > 0.0);
            let p = sigmoid(dot(theta, &phi));
            let draw = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let q = 1.0 - p;
            let a = if p == 0.0 || (q != 0.0 && draw < q) {
                0
            } else {
                1
            };
            let force = if a == 1 { FORCE_MAG } else { -FORCE_MAG };
            let [x, x_dot, th, th_dot] = s;
            let (costheta, sintheta) = (th.cos(), th.sin());
            let temp = (force + polemass_length * (th_dot * th_dot) * sintheta) / total_mass;
            let thetaacc = (GRAVITY * sintheta - costheta * temp)
                / (LENGTH * (FOUR_THIRDS - MASSPOLE * (costheta * costheta) / total_mass));
            let xacc = temp - polemass_length * thetaacc * costheta / total_mass;
            s = [
                x + TAU * x_dot,
                x_dot + TAU * xacc,
                th + TAU * th_dot,
                th_dot + TAU * thetaacc,
            ];
            steps += 1;
            t.features.push(phi);
            t.actions.push(a);
            t.labels.push(label);
            let terminated = s[0] < -X_THRESHOLD
                || s[0] > X_THRESHOLD
                || s[2] < -theta_threshold
                || s[2] > theta_threshold;
            if terminated || steps >= self.max_steps {
                break;
            }
        }
    }

    /// The causal estimator of eq. 3.15 with the Brier loss `2(p − y)²` and the score `(a − p)φ`;
    /// a function of its own, as the generic estimate's fixed-length pass is. Callers that use
    /// only part of the result must still pass all of it through `black_box`: inlined, the
    /// arithmetic of unused entries is dropped (measured: only `g[0]` was computed).
    #[inline(never)]
    pub fn estimate(theta: &[f64; D], t: &Trajectory) -> [f64; D] {
        let mut g = [0.0; D];
        let mut score_sum = [0.0; D];
        for ((phi, &a), &y) in t.features.iter().zip(&t.actions).zip(&t.labels) {
            let p = sigmoid(dot(theta, phi));
            let r = if y == 1 { p - 1.0 } else { p };
            let dz = 4.0 * r * p * (1.0 - p);
            let l = 2.0 * (r * r);
            let c = if a == 1 { 1.0 - p } else { -p };
            for j in 0..D {
                g[j] += dz * phi[j] + l * score_sum[j];
                score_sum[j] += c * phi[j];
            }
        }
        g
    }
}
