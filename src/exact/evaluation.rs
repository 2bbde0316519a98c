//! The exact engine at one θ of a toy MDP, as `ilopt toy eval` reports it: F(θ) and ∇F(θ) by the
//! forward DP (X2), E\[∇f(θ, τ)\] (eq. 3.15) and E‖∇f‖² by enumeration (X1) — of the baselined
//! estimator `g_b = g − Σ_i b_i ψ_i` when baselines are given (math.md §9) — and, on request, the
//! variance-minimising baselines of [`super::baseline`].

use super::ExactError;
use super::baseline::{
    OptimalBaselines, OptimalStateBaseline, baselined_moments, optimal_baselines,
    optimal_state_baseline,
};
use super::enumerate::moments;
use super::forward::forward;
use crate::scalar::{BigRational, Scalar};
use crate::toy::{ToyMdp, ToyProblem};

/// What [`evaluate`] adds to the four quantities.
#[derive(Debug, Clone, Default)]
pub struct EvaluationOptions<'a> {
    /// Baselines, one number b for every decision or T − 2 numbers b_1..b_{T−2}: the estimator's
    /// moments become those of g_b.
    pub baseline: Option<&'a [BigRational]>,
    /// Also compute the exact optimal baselines (time-indexed, constant and per state).
    pub optimal_baseline: bool,
}

/// The exact quantities at θ in scalar `S`.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation<S> {
    /// F(θ) (X2).
    pub objective: S,
    /// ∇F(θ) (X2).
    pub gradient: Vec<S>,
    /// E\[g\] of the estimator (eq. 3.15), or E\[g_b\] with baselines (X1).
    pub expected_estimate: Vec<S>,
    /// E‖g‖², or E‖g_b‖² with baselines (X1).
    pub second_moment: S,
    /// The baselines as given, in `S`.
    pub baseline: Option<Vec<S>>,
    /// The variance-minimising baselines b*_i and b*_const with the moments they reach.
    pub optimal_baseline: Option<OptimalBaselines<S>>,
    /// The variance-minimising baseline per state, `b_i = w*_{s_i}`.
    pub optimal_state_baseline: Option<OptimalStateBaseline<S>>,
}

/// Why [`evaluate`] failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EvaluationError {
    /// The exact engine, a baseline list of the wrong length included.
    #[error("at θ: {0}")]
    Engine(#[from] ExactError),
    /// A result is not a finite number in the scalar type (e.g. f64 overflow); it names the
    /// quantity.
    #[error("`{0}` is not finite in the chosen arithmetic")]
    NonFinite(&'static str),
}

/// F(θ), ∇F(θ), E\[g\] and E‖g‖² of `mdp` at the exact `theta`, computed in scalar `S`, with what
/// `options` adds.
///
/// # Errors
/// [`EvaluationError::Engine`] if the exact engine fails at θ or the baseline list has the wrong
/// length ([`baselined_moments`]), [`EvaluationError::NonFinite`] if one of the four quantities is
/// not finite in `S`.
pub fn evaluate<S: Scalar>(
    mdp: &ToyMdp,
    theta: &[BigRational],
    options: &EvaluationOptions<'_>,
) -> Result<Evaluation<S>, EvaluationError> {
    let p = ToyProblem::<S>::new(mdp);
    let th: Vec<S> = theta.iter().map(S::from_rational).collect();
    let x2 = forward(&p, &th)?;
    let x1 = moments(&p, &th)?;
    let baseline: Option<Vec<S>> = options
        .baseline
        .map(|b| b.iter().map(S::from_rational).collect());
    let (expected_estimate, second_moment) = match &baseline {
        None => (x1.expected_estimate, x1.second_moment),
        Some(b) => {
            let m = baselined_moments(&p, &th, b)?;
            (m.expected_estimate, m.second_moment)
        }
    };
    let finite = |name: &'static str, xs: &[S]| {
        if xs.iter().all(Scalar::is_finite) {
            Ok(())
        } else {
            Err(EvaluationError::NonFinite(name))
        }
    };
    finite("objective", std::slice::from_ref(&x2.objective))?;
    finite("gradient", &x2.gradient)?;
    finite("expected_estimate", &expected_estimate)?;
    finite("second_moment", std::slice::from_ref(&second_moment))?;
    let (optimal_baseline, optimal_state_baseline) = if options.optimal_baseline {
        (
            Some(optimal_baselines(&p, &th)?),
            Some(optimal_state_baseline(&p, &th)?),
        )
    } else {
        (None, None)
    };
    Ok(Evaluation {
        objective: x2.objective,
        gradient: x2.gradient,
        expected_estimate,
        second_moment,
        baseline,
        optimal_baseline,
        optimal_state_baseline,
    })
}
