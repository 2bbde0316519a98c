//! An LQR expert for CartPole: the discrete-time linear-quadratic regulator of the linearised
//! dynamics at the upright equilibrium, applied as a bang-bang controller (CartPole's actions are
//! the two forces ±10 N).
//!
//! # Linearisation (from Gymnasium's equations, see [`crate::env::cartpole`])
//! At `s = 0` (cart centred, pole upright, at rest) with force `F`, to first order
//! `sin θ ≈ θ`, `cos θ ≈ 1`, `θ̇² ≈ 0`, so with `M = total_mass`, `mₚl = polemass_length`,
//! `d = length · (4/3 − masspole / M)`:
//!
//! ```text
//! temp = F / M,   θ̈ = (g θ − F / M) / d,   ẍ = F / M − mₚl θ̈ / M
//!
//!       ⎡0 1      0      0⎤         ⎡        0         ⎤
//! A_c = ⎢0 0 −mₚl g/(M d) 0⎥,  b_c = ⎢1/M + mₚl/(M² d)  ⎥
//!       ⎢0 0      0      1⎥         ⎢        0         ⎥
//!       ⎣0 0     g/d     0⎦         ⎣    −1/(M d)      ⎦
//! ```
//!
//! and Gymnasium's euler step (`τ = 0.02`) discretises it as `A = I + τ A_c`, `b = τ b_c`
//! ([`linearised_cartpole`]; `tests` check it against exact derivatives of the real step, computed
//! with dual numbers).
//!
//! # Riccati equation
//! The gain minimises `Σ_t sₜᵀ Q sₜ + r uₜ²` for `sₜ₊₁ = A sₜ + b uₜ`: `K = (r + bᵀPb)⁻¹ bᵀPA` with
//! `P` the stabilising solution of the discrete algebraic Riccati equation (DARE)
//! `P = Q + AᵀPA − AᵀPb (r + bᵀPb)⁻¹ bᵀPA`, computed by the structure-preserving doubling algorithm
//! (SDA; Chu, Fan & Lin 2005, "A structure-preserving doubling algorithm for discrete-time algebraic
//! Riccati equations", with `G₀ = b r⁻¹ bᵀ`, `H₀ = Q`, `A₀ = A`):
//!
//! ```text
//! W = I + Gₖ Hₖ,  Aₖ₊₁ = Aₖ W⁻¹ Aₖ,  Gₖ₊₁ = Gₖ + Aₖ W⁻¹ Gₖ Aₖᵀ,  Hₖ₊₁ = Hₖ + Aₖᵀ Hₖ W⁻¹ Aₖ,
//! ```
//!
//! `Hₖ → P` quadratically. The solver stops when `‖Hₖ₊₁ − Hₖ‖_F ≤ tol · max(1, ‖Hₖ₊₁‖_F)`, then
//! checks the DARE residual and that `A − bK` is Schur stable; otherwise it returns an [`LqrError`].
//!
//! # Action (bang-bang = one-step cost-to-go)
//! The action is `1` (push right, `u = +10`) if `−K s > 0`, else `0`. This is also the action that
//! minimises the one-step LQR cost-to-go `V(u) = (As + bu)ᵀ P (As + bu) + r u²` over
//! `u ∈ {−10, +10}`: `V(+10) − V(−10) = 40 bᵀPAs`, which has the sign of `K s` because
//! `r + bᵀPb > 0`. Ties (`K s = 0`) go to action 0.

use crate::env::cartpole::CartPoleParams;
use crate::scalar::{Scalar, Undecidable};
use nalgebra::{Matrix4, RowVector4, Vector4};

/// Default stopping tolerance of the doubling algorithm (relative change of `Hₖ`, Frobenius).
pub const DARE_TOLERANCE: f64 = 1e-12;
/// Default iteration cap of the doubling algorithm (it converges quadratically: a few tens at most).
pub const DARE_MAX_ITERATIONS: usize = 100;
/// Accepted relative DARE residual `‖R(P)‖_F / max(1, ‖P‖_F)` of the returned solution.
pub const DARE_RESIDUAL_TOLERANCE: f64 = 1e-8;

/// Why an LQR controller could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LqrError {
    /// The weights are not admissible (`Q` symmetric positive semi-definite with finite entries,
    /// `r > 0` finite).
    #[error("invalid LQR weights: {0}")]
    InvalidWeights(&'static str),
    /// `I + Gₖ Hₖ` was singular in the doubling algorithm.
    #[error("singular matrix at iteration {iteration} of the doubling algorithm")]
    Singular {
        /// The iteration (1-based).
        iteration: usize,
    },
    /// The doubling algorithm did not meet its tolerance, or its result fails the residual check.
    #[error(
        "the Riccati solver did not converge: {iterations} iterations, relative change {change:e}, relative residual {residual:e}"
    )]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Last relative change of `Hₖ`.
        change: f64,
        /// Relative DARE residual of the last iterate.
        residual: f64,
    },
    /// The closed loop `A − bK` is not Schur stable (spectral radius ≥ 1).
    #[error("the closed loop is not stable: spectral radius {spectral_radius}")]
    NotStabilising {
        /// Spectral radius of `A − bK`.
        spectral_radius: f64,
    },
}

/// The euler-discretised linearisation `(A, b)` of CartPole-v1 at the upright equilibrium, for the
/// force `u` in newtons (module docs): `s' ≈ A s + b u`.
pub fn linearised_cartpole() -> (Matrix4<f64>, Vector4<f64>) {
    let p = CartPoleParams::<f64>::gymnasium();
    let m = p.total_mass;
    let d = p.length * (p.four_thirds - p.masspole / m);
    let a_c = Matrix4::new(
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        -p.polemass_length * p.gravity / (m * d),
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        p.gravity / d,
        0.0,
    );
    let b_c = Vector4::new(
        0.0,
        1.0 / m + p.polemass_length / (m * m * d),
        0.0,
        -1.0 / (m * d),
    );
    (Matrix4::identity() + a_c * p.tau, b_c * p.tau)
}

/// The relative DARE residual `‖Q + AᵀPA − AᵀPb (r + bᵀPb)⁻¹ bᵀPA − P‖_F / max(1, ‖P‖_F)`.
pub fn dare_residual(
    a: &Matrix4<f64>,
    b: &Vector4<f64>,
    q: &Matrix4<f64>,
    r: f64,
    p: &Matrix4<f64>,
) -> f64 {
    let pa = p * a;
    let bpa = b.transpose() * pa; // 1×4
    let s = r + (b.transpose() * p * b)[(0, 0)];
    let res = q + a.transpose() * pa - bpa.transpose() * bpa / s - p;
    res.norm() / p.norm().max(1.0)
}

/// The stabilising solution `P` of the DARE for `(A, b, Q, r)` by the doubling algorithm (module
/// docs), and the number of iterations it took.
///
/// # Errors
/// [`LqrError::InvalidWeights`] for a non-symmetric, non-finite or indefinite `Q` or `r ≤ 0`;
/// [`LqrError::Singular`]; [`LqrError::NotConverged`] if the change does not fall below `tol` within
/// `max_iterations` or the relative residual exceeds [`DARE_RESIDUAL_TOLERANCE`].
pub fn solve_dare(
    a: &Matrix4<f64>,
    b: &Vector4<f64>,
    q: &Matrix4<f64>,
    r: f64,
    tol: f64,
    max_iterations: usize,
) -> Result<(Matrix4<f64>, usize), LqrError> {
    if !(r.is_finite() && r > 0.0) {
        return Err(LqrError::InvalidWeights("r must be finite and positive"));
    }
    if q.iter().any(|v| !v.is_finite()) || *q != q.transpose() {
        return Err(LqrError::InvalidWeights("Q must be finite and symmetric"));
    }
    if q.symmetric_eigenvalues().iter().any(|&e| e < 0.0) {
        return Err(LqrError::InvalidWeights("Q must be positive semi-definite"));
    }
    let id = Matrix4::<f64>::identity();
    let mut ak = *a;
    let mut gk = b * b.transpose() / r;
    let mut hk = *q;
    let mut change = f64::INFINITY;
    for iteration in 1..=max_iterations {
        let w_inv = (id + gk * hk)
            .try_inverse()
            .ok_or(LqrError::Singular { iteration })?;
        let a_next = ak * w_inv * ak;
        let g_next = gk + ak * w_inv * gk * ak.transpose();
        let h_next = hk + ak.transpose() * hk * w_inv * ak;
        // Keep the iterates exactly symmetric.
        let g_next = (g_next + g_next.transpose()) / 2.0;
        let h_next = (h_next + h_next.transpose()) / 2.0;
        change = (h_next - hk).norm() / h_next.norm().max(1.0);
        ak = a_next;
        gk = g_next;
        hk = h_next;
        if !change.is_finite() {
            break;
        }
        if change <= tol {
            let residual = dare_residual(a, b, q, r, &hk);
            if residual <= DARE_RESIDUAL_TOLERANCE {
                return Ok((hk, iteration));
            }
            return Err(LqrError::NotConverged {
                iterations: iteration,
                change,
                residual,
            });
        }
    }
    Err(LqrError::NotConverged {
        iterations: max_iterations,
        change,
        residual: dare_residual(a, b, q, r, &hk),
    })
}

/// The LQR expert for CartPole (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LqrExpert {
    a: Matrix4<f64>,
    b: Vector4<f64>,
    p: Matrix4<f64>,
    k: RowVector4<f64>,
    iterations: usize,
}

impl LqrExpert {
    /// The state weights of [`LqrExpert::cartpole`]: `Q = diag(1, 1, 10, 1)` (the pole angle
    /// weighted most; the thesis does not fix an LQR, so these are the kit's choice).
    pub fn default_q() -> Matrix4<f64> {
        Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, 10.0, 1.0))
    }

    /// The control weight of [`LqrExpert::cartpole`]: `r = 1`.
    pub const DEFAULT_R: f64 = 1.0;

    /// The LQR expert with the default weights ([`LqrExpert::default_q`], [`LqrExpert::DEFAULT_R`]).
    ///
    /// # Errors
    /// As [`LqrExpert::new`] (not expected for these weights).
    pub fn cartpole() -> Result<Self, LqrError> {
        Self::new(&Self::default_q(), Self::DEFAULT_R)
    }

    /// The LQR expert for the weights `Q` (4×4, on `(x, ẋ, θ, θ̇)`) and `r` (on the force in N).
    ///
    /// # Errors
    /// [`solve_dare`]'s errors (tolerance [`DARE_TOLERANCE`], at most [`DARE_MAX_ITERATIONS`]), and
    /// [`LqrError::NotStabilising`] if the closed loop `A − bK` has spectral radius ≥ 1.
    pub fn new(q: &Matrix4<f64>, r: f64) -> Result<Self, LqrError> {
        let (a, b) = linearised_cartpole();
        let (p, iterations) = solve_dare(&a, &b, q, r, DARE_TOLERANCE, DARE_MAX_ITERATIONS)?;
        let s = r + (b.transpose() * p * b)[(0, 0)];
        let k: RowVector4<f64> = b.transpose() * p * a / s;
        let spectral_radius = (a - b * k)
            .complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);
        if spectral_radius.is_nan() || spectral_radius >= 1.0 || k.iter().any(|v| !v.is_finite()) {
            return Err(LqrError::NotStabilising { spectral_radius });
        }
        Ok(LqrExpert {
            a,
            b,
            p,
            k,
            iterations,
        })
    }

    /// The gain `K` (the LQR force is `u = −K s`).
    pub fn gain(&self) -> &RowVector4<f64> {
        &self.k
    }

    /// The Riccati solution `P` (the LQR cost-to-go is `sᵀ P s`).
    pub fn riccati_solution(&self) -> &Matrix4<f64> {
        &self.p
    }

    /// The linearised dynamics `(A, b)` the controller was designed for.
    pub fn model(&self) -> (&Matrix4<f64>, &Vector4<f64>) {
        (&self.a, &self.b)
    }

    /// Doubling iterations the Riccati solver took.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The expert's action in `state`: `1` if `−K s > 0`, else `0` (module docs). The product is
    /// evaluated in `S` with `K`'s float entries taken exactly.
    ///
    /// # Errors
    /// [`Undecidable`] when the sign of `−K s` cannot be decided (an interval around 0, or NaN).
    #[inline]
    pub fn action<S: Scalar>(&self, state: &[S; 4]) -> Result<usize, Undecidable> {
        self.gain_in::<S>().action(state)
    }

    /// The gain `K` converted to `S` once, for many actions (a roll-out's labels).
    pub fn gain_in<S: Scalar>(&self) -> LqrGain<S> {
        // Each gain is a finite f64 (checked at construction), so `from_binary64` is exact: the
        // exact value of the f64 gain in every scalar, without a rational round trip.
        LqrGain {
            k: std::array::from_fn(|i| S::from_binary64(self.k[i]).expect("finite gain")),
        }
    }
}

/// An LQR gain `K` in the scalar `S` ([`LqrExpert::gain_in`]): the expert's action without
/// converting `K` at every call.
#[derive(Debug, Clone, PartialEq)]
pub struct LqrGain<S> {
    k: [S; 4],
}

impl<S: Scalar> LqrGain<S> {
    /// [`LqrExpert::action`]: `1` if `−K s > 0`, else `0`, with `−K s = 0 − k₀s₀ − k₁s₁ − k₂s₂ − k₃s₃`
    /// evaluated left to right.
    ///
    /// # Errors
    /// [`Undecidable`] when the sign of `−K s` cannot be decided (an interval around 0, or NaN).
    #[inline]
    pub fn action(&self, state: &[S; 4]) -> Result<usize, Undecidable> {
        let u = self
            .k
            .iter()
            .zip(state)
            .fold(S::zero(), |acc, (k, s)| acc - k.clone() * s);
        match u.positive_when_certain() {
            Some(positive) => Ok(usize::from(positive)),
            None => Err(Undecidable {
                what: "LQR expert: sign of -K s",
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::cartpole::cartpole_step;
    use crate::scalar::Dual;

    /// `(A, b)` against exact derivatives of the real step: the step is affine in the force, so the
    /// mean of the two actions is the step with `F = 0`, and their difference is `2·10·b`.
    #[test]
    fn linearisation_matches_dual_derivatives_of_the_step() {
        let (a, b) = linearised_cartpole();
        let s: [Dual<f64>; 4] = std::array::from_fn(|i| Dual::variable(0.0, i, 4));
        let (right, _) = cartpole_step(&s, 1).unwrap();
        let (left, _) = cartpole_step(&s, 0).unwrap();
        for i in 0..4 {
            let mean = (right[i].clone() + left[i].clone()) / Dual::from_ratio(2, 1);
            let grad = mean.gradient_padded(4);
            for j in 0..4 {
                assert!(
                    approx::abs_diff_eq!(
                        grad[j],
                        a[(i, j)],
                        epsilon = 1e-15 * (1.0 + a[(i, j)].abs())
                    ),
                    "A[{i},{j}]: {} vs {}",
                    grad[j],
                    a[(i, j)]
                );
            }
            let db = (right[i].value() - left[i].value()) / 20.0;
            approx::assert_abs_diff_eq!(db, b[i], epsilon = 1e-15);
        }
    }

    #[test]
    fn riccati_solution_satisfies_the_dare_and_stabilises() {
        let e = LqrExpert::cartpole().unwrap();
        let (a, b) = e.model();
        let residual = dare_residual(a, b, &LqrExpert::default_q(), LqrExpert::DEFAULT_R, &e.p);
        assert!(residual <= 1e-10, "residual {residual}");
        assert!(e.iterations() < 40, "{} iterations", e.iterations());
        // P is symmetric positive definite (Q is).
        assert!(e.riccati_solution().symmetric_eigenvalues().min() > 0.0);
        // Pushing right when the pole leans right (θ > 0) is what keeps it up.
        assert_eq!(e.action(&[0.0, 0.0, 0.05, 0.0]).unwrap(), 1);
        assert_eq!(e.action(&[0.0, 0.0, -0.05, 0.0]).unwrap(), 0);
    }

    #[test]
    fn bad_weights_are_errors() {
        let q = LqrExpert::default_q();
        assert!(matches!(
            LqrExpert::new(&q, 0.0),
            Err(LqrError::InvalidWeights(_))
        ));
        assert!(matches!(
            LqrExpert::new(&q, f64::NAN),
            Err(LqrError::InvalidWeights(_))
        ));
        assert!(matches!(
            LqrExpert::new(&-q, 1.0),
            Err(LqrError::InvalidWeights(_))
        ));
        let (a, b) = linearised_cartpole();
        assert!(matches!(
            solve_dare(&a, &b, &q, 1.0, 1e-12, 1),
            Err(LqrError::NotConverged { .. })
        ));
    }

    #[test]
    fn nan_state_is_undecidable() {
        let e = LqrExpert::cartpole().unwrap();
        assert!(e.action(&[f64::NAN, 0.0, 0.0, 0.0]).is_err());
    }
}
