//! Baselines (control variates) for the causal estimator of eq. 3.15 that keep it exactly
//! unbiased.
//!
//! With per-decision baselines b_i (i = 1..T−2, the scored decisions),
//!
//! `g_b(θ, τ) = Σ_{t=1}^{T−1} ∇l_t + Σ_{i=1}^{T−2} ψ_i (Σ_{t=i+1}^{T−1} l_t − b_i) = g − Σ_i b_i ψ_i`,
//!
//! ψ_i = ∇log π_θ(a_i|s_i). **Why it stays unbiased.** If b_i is a function of the history
//! h_i = (s_1, a_1, …, s_i) and of data independent of the current trajectory (earlier
//! iterations, the other trajectories of a minibatch), but not of a_i or anything later, then
//! `E[b_i ψ_i] = E[b_i E[ψ_i | h_i]] = 0`, because `E[ψ_i | h_i] = Σ_a π_θ(a|s_i) ∇log π_θ(a|s_i)
//! = ∇ Σ_a π_θ(a|s_i) = 0`. So `E[g_b] = E[g] = ∇F(θ)` (eqs. 3.16/3.18). A baseline that looks
//! at a_i breaks this (e.g. `b_i = 1[a_i = 0]` gives `E[b_i ψ_i] = E[∇π_θ(0|s_i)] ≠ 0`).
//!
//! **Variance.** `E[ψ_i·ψ_j] = 0` for i ≠ j (condition on the later one's history), so
//! `E‖g_b‖² = E‖g‖² − 2 Σ_i b_i E[g·ψ_i] + Σ_i b_i² E‖ψ_i‖²` for constants b_i, minimised by
//! `b*_i = E[g·ψ_i] / E‖ψ_i‖²` (time-indexed) and `b*_const = Σ_i E[g·ψ_i] / Σ_i E‖ψ_i‖²` (one
//! constant). [`crate::exact::baseline`] computes all of these exactly on toy MDPs.
//!
//! **Importance-weighted old-point estimate** (IS-STORM, math.md §4), τ ∼ p(·; θ′):
//!
//! * whole-trajectory weight `w = p(τ; θ)/p(τ; θ′)` multiplies the baselined estimate:
//!   `E_θ′[w g_b(θ, τ)] = E_θ[g_b(θ, τ)] = ∇F(θ)`, since `w b_i ψ_i` has θ′-mean `E_θ[b_i ψ_i] = 0`;
//! * per-decision weights: term t of eq. 3.15 carries `w_{1:t−1}` and the baseline term of
//!   decision i carries the prefix weight `w_{1:i} = Π_{k≤i} π_θ(a_k|s_k)/π_θ′(a_k|s_k)`.
//!   `w_{1:i} b_i ψ_i` is a function of the prefix up to a_i, so its θ′-mean is the θ-mean of
//!   `b_i ψ_i`, which is 0.
//!
//! **Kinds** ([`Baseline`]): none (the plain estimator, bit for bit), one constant, constants per
//! decision index, the variance-minimising constant(s) estimated from earlier iterations only
//! ([`RunningOptimum`]), leave-one-out across the m trajectories of one gradient (trajectory
//! j's b_i is the mean loss-to-go at decision i of the other m − 1, independent of trajectory j;
//! exact for m ≥ 2), and a linear function of the decision's state, `b_i = w·φ_b(s_i)`, with
//! the variance-minimising weights estimated from earlier iterations ([`RunningRegression`]; a
//! function of s_i, which is part of the history h_i, so the argument above applies). [`Baselined`] is the oracle that applies them, to any problem that exposes
//! its [`DecisionTerms`](crate::oracle::DecisionTerms) ([`PerDecisionTerms::decision_terms`]); every oracle method
//! (SGD, STORM, IS-STORM, Adam, RMSProp, O2NC) run on it uses the baseline. Leave-one-out
//! estimates take each trajectory's plain pass with its losses and scores recorded
//! ([`RecordedPass`](crate::oracle::RecordedPass)) and subtract `Σ_i b_i ψ_i` once every trajectory's losses are known.

mod decisions;
mod oracle;
mod regression;
mod running;

pub use decisions::{PerDecisionTerms, baselined_estimate};
pub(crate) use decisions::{leading_features, record_by_terms, shifted_by_given};
pub use oracle::Baselined;
pub use regression::{RunningRegression, solve_symmetric};
pub use running::RunningOptimum;

use crate::scalar::ConfigNumber;
use serde::{Deserialize, Serialize};

/// The state-dependent baseline's default share of trajectories whose statistics enter its
/// weights: one in this many ([`Baseline::StateDependent`]'s `fit_every`). The statistics take
/// k(k + 3)/2 products per decision, about as much as the plain estimate itself; one trajectory
/// in eight pays them, and the weights still rest on enough data (with m = 16 trajectories per
/// gradient and a decay of 0.99, about 200 trajectories in the memory for k weights).
pub const DEFAULT_FIT_EVERY: u64 = 8;

/// Which baseline the oracle subtracts (JSON: `{"kind": "constant", "value": "1/2"}`).
///
/// Indices: b_1 is the baseline of the first decision (index 0 in code).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Baseline {
    /// No baseline: eq. 3.15 as it is (results bit-identical to the plain oracle).
    #[default]
    None,
    /// One number b for every decision: `g_b = g − b Σ_i ψ_i`.
    Constant {
        /// b.
        value: ConfigNumber,
    },
    /// b_1, b_2, … per decision index: `g_b = g − Σ_i b_i ψ_i`. A decision beyond the list is an
    /// error.
    TimeIndexed {
        /// b_1, b_2, ….
        values: Vec<ConfigNumber>,
    },
    /// The variance-minimising constant(s) `E[g·ψ_i]/E‖ψ_i‖²` estimated from earlier iterations'
    /// trajectories ([`RunningOptimum`]).
    Estimated {
        /// Per decision index (`true`) or one constant (`false`).
        time_indexed: bool,
        /// Factor in [0, 1] applied to the past statistics at every iteration (absent: 1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        decay: Option<ConfigNumber>,
    },
    /// Leave-one-out across the m ≥ 2 trajectories of one gradient.
    LeaveOneOut,
    /// A function of the decision's state, `b_i = w·φ_b(s_i)`: φ_b the problem's state
    /// features ([`PerDecisionTerms::state_features`]: a task's learner features, a toy MDP's
    /// one-hot state), w the variance-minimising weights `A⁻¹c` estimated from earlier
    /// iterations' trajectories only ([`RunningRegression`]).
    StateDependent {
        /// Use only the first this many state features (absent: all of them).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        features: Option<usize>,
        /// Append the decision's index i and a constant 1 to the state features, so that the
        /// baseline can follow the loss-to-go's decline along the horizon (i is part of the
        /// history, so the baseline stays unbiased).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        time: bool,
        /// Factor in [0, 1] applied to the past statistics at every iteration (absent: 1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        decay: Option<ConfigNumber>,
        /// λ ≥ 0 added to the diagonal of A before the solve (absent: 0).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ridge: Option<ConfigNumber>,
        /// The weights' statistics from every this-many-th trajectory only, e ≥ 1 (absent:
        /// [`DEFAULT_FIT_EVERY`]; 1: every trajectory). Which trajectories enter depends only
        /// on their count, so the estimate stays unbiased for every e
        /// ([`RunningRegression::takes_next`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        fit_every: Option<u64>,
    },
}
