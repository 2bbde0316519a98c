//! The exact engine (math.md §1.4): F, ∇F, E[∇f], E[∇f_full], E‖∇f‖² and Var on toy MDPs, by
//! three independent routes, generic over the scalar (exact in `BigRational`).
//!
//! | route | module | computes |
//! |---|---|---|
//! | X1 enumeration of prefixes | [`enumerate`] | F, E\[g\], E\[g_full\], E‖g‖², and ∇F = Σ ∇\[p·L\] by dual numbers (no score formula) |
//! | X2 forward DP | [`forward`] | F, ∇F from differentiated state distributions, and d_t |
//! | X3 backward DP | [`backward`] | F, ∇F in the adjoint (performative policy-gradient) form |
//! | baselines | [`baseline`] | E\[g_b\], E‖g_b‖² of the baselined estimator, the optimal b*_i, b*_const (math.md §9) |
//! | importance sampling | [`importance`] | Σ p(τ̄;θ′) w g(θ, τ̄) (identity I3) and the bias b(θ, θ′) (I4) |
//! | STORM's mean linearisation | [`storm_jacobian`] | E\[J\], C = E\[g ∇log pᵀ\], the IS term's E\[J̃\] and ∇²F (math.md §10) |
//! | at one θ, as `ilopt toy eval` reports | [`evaluation`] | F, ∇F (X2), E\[g\] or E\[g_b\] and their second moment (X1), optionally the optimal baselines |
//!
//! The identities (I1) F_X1 = F_X2 = F_X3 and (I2) ∇F_X2 = ∇F_X3 = ∇F_enum = E\[g\] = E\[g_full\] are
//! the thesis's unbiasedness claim (eqs. 3.16/3.18) proved exactly.
//!
//! With termination (math.md §8) every route runs on the augmented chain P′ of
//! [`crate::toy::ToyMdp::chain_transition`] (reset: terminal transitions redirected to the reset
//! law; absorb: terminal states absorbing, with their constant loss in the policy table), so the
//! same identities state the unbiasedness of the fixed-horizon estimators.

pub mod backward;
pub mod baseline;
pub mod enumerate;
pub mod evaluation;
pub mod forward;
pub mod importance;
pub mod rrm;
pub mod storm_jacobian;

use crate::problem::OracleError;

/// Largest number of prefixes the enumeration visits before giving up.
pub const MAX_PREFIXES: u64 = 20_000_000;

/// Why an exact computation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExactError {
    /// The policy/loss tables could not be built at θ.
    #[error(transparent)]
    Oracle(#[from] OracleError),
    /// Enumeration would visit too many prefixes.
    #[error(
        "the MDP has {}{prefixes:.3e} trajectory prefixes of positive probability at this θ, more than the limit of {limit}; enumeration is infeasible (use a shorter horizon or fewer states)",
        if *at_least { "at least " } else { "" }
    )]
    TooLarge {
        /// The number of prefixes.
        prefixes: f64,
        /// Whether `prefixes` is only a lower bound (counting stopped past the limit).
        at_least: bool,
        /// The limit.
        limit: u64,
    },
    /// The computation does not apply to this policy class.
    #[error("{0}")]
    NotApplicable(String),
}
