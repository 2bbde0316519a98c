//! The gradient oracle of eq. 3.15 (math.md §1.1) on a recorded trajectory: the estimator passes
//! and the per-decision kernel they run on.
//!
//! On a trajectory with decisions t = 1..n, losses `l_t = l(s_t, θ)` and scores
//! `ψ_t = ∇_θ log π_θ(a_t|s_t)`:
//!
//! * the causal estimator of eq. 3.15, `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`
//!   ([`EstimatorKernel::causal_sum_trusted`], and the weighted pass below);
//! * the full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i` (eq. 3.16);
//! * the importance-weighted old-point estimates of math.md §4, with per-decision ratios
//!   `π_old(a_i|s_i)/π_new(a_i|s_i) = exp(log π_old − log π_new)`;
//! * the per-decision terms from which a baseline `b_i` is subtracted, `g − Σ_i b_i ψ_i`
//!   ([`crate::baseline`]), also folded into the causal pass as loss shifts.
//!
//! Every pass accumulates one decision with the same update, [`kernel`]'s `accumulate`:
//! `g += w ∇l_t + w l_t Σ_{i<t} ψ_i`, then `Σ_{i<t} ψ_i += ψ_t`.

pub mod kernel;
mod logistic;

pub use kernel::EstimatorKernel;
