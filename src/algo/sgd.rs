//! SGD on the IL objective: Algorithm 3, `θ_{k+1} = θ_k − η_k ∇f(θ_k, τ_k)` with
//! `τ_k ∼ p(·; θ_k)` and the eq. 3.15 estimator.
//!
//! Step sizes: constant (the setting of eqs. 3.23–3.28), inverse-time `η_k = η₀k₀/(k₀ + k − 1)`
//! (field operations only) and inverse-square-root `η_k = η₀/√k` (needs a scalar with
//! [`crate::scalar::Roots`]).
//! Per erratum E17, the guarantees are for a random or best iterate, not θ_K; the runner's
//! history has every iterate.

use super::first_order::{FirstOrder, UpdateRule};
use super::{AlgoError, ConfigNumber, axpy, positive, require_roots, sqrt};
use crate::problem::EstimatorForm;
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// Step-size schedule η_k (k = 1, 2, …).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum SgdStep {
    /// `η_k = eta` (eq. 3.23 ff.).
    Constant {
        /// η > 0.
        eta: ConfigNumber,
    },
    /// `η_k = eta0 · k0 / (k0 + k − 1)` (so η₁ = η₀); field operations only.
    InverseTime {
        /// η₀ > 0.
        eta0: ConfigNumber,
        /// k₀ > 0.
        k0: ConfigNumber,
    },
    /// `η_k = eta0 / √k` (needs square roots).
    InverseSqrt {
        /// η₀ > 0.
        eta0: ConfigNumber,
    },
}

impl SgdStep {
    /// Constant step size `eta`.
    pub fn constant(eta: impl Into<ConfigNumber>) -> Self {
        SgdStep::Constant { eta: eta.into() }
    }
}

/// SGD configuration (Algorithm 3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SgdConfig {
    /// The step-size schedule.
    pub step: SgdStep,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

/// The inverse-square-root schedule, as named in [`AlgoError::NeedsRoots`].
const INVERSE_SQRT: &str = "SGD with η₀/√k";

#[derive(Debug, Clone)]
enum Schedule<S> {
    Constant(S),
    InverseTime(S, S),
    InverseSqrt(S),
}

/// The plain gradient step `θ ← θ − η_k g` as an [`UpdateRule`].
#[derive(Debug, Clone)]
pub struct SgdRule<S> {
    schedule: Schedule<S>,
    k: u64,
}

impl<S: Scalar> SgdRule<S> {
    /// Validate the schedule (η > 0, k₀ > 0) and build it in `S`.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`] for
    /// `inverse-sqrt` without square roots.
    pub fn new(step: &SgdStep) -> Result<Self, AlgoError> {
        let schedule = match step {
            SgdStep::Constant { eta } => {
                Schedule::Constant(S::from_rational(&positive(eta, "eta", true)?))
            }
            SgdStep::InverseTime { eta0, k0 } => Schedule::InverseTime(
                S::from_rational(&positive(eta0, "eta0", true)?),
                S::from_rational(&positive(k0, "k0", true)?),
            ),
            SgdStep::InverseSqrt { eta0 } => {
                let eta0 = S::from_rational(&positive(eta0, "eta0", true)?);
                require_roots::<S>(INVERSE_SQRT, "square roots")?;
                Schedule::InverseSqrt(eta0)
            }
        };
        Ok(SgdRule { schedule, k: 0 })
    }

    /// η_k for the next update (k is 1-based).
    fn eta(&self, k: u64) -> Result<S, AlgoError> {
        Ok(match &self.schedule {
            Schedule::Constant(e) => e.clone(),
            Schedule::InverseTime(e, k0) => {
                e.clone() * k0 / (k0.clone() + S::from_i64(k as i64 - 1))
            }
            Schedule::InverseSqrt(e) => e.clone() / sqrt(&S::from_i64(k as i64), INVERSE_SQRT)?,
        })
    }
}

impl<S: Scalar> UpdateRule<S> for SgdRule<S> {
    fn reset(&mut self) {
        self.k = 0;
    }
    fn apply(&mut self, theta: &mut DVector<S>, g: &DVector<S>) -> Result<(), AlgoError> {
        self.k += 1;
        let eta = self.eta(self.k)?;
        *theta = axpy(&-eta, g, theta);
        Ok(())
    }
}

/// SGD for IL (Algorithm 3): [`FirstOrder`] with the [`SgdRule`].
pub type Sgd<S> = FirstOrder<S, SgdRule<S>>;

impl<S: Scalar> FirstOrder<S, SgdRule<S>> {
    /// SGD with the configured schedule; `inverse-sqrt` needs a scalar with roots.
    ///
    /// # Errors
    /// As [`SgdRule::new`].
    pub fn new(config: &SgdConfig) -> Result<Self, AlgoError> {
        Ok(FirstOrder::with_rule(
            "sgd",
            SgdRule::new(&config.step)?,
            config.form,
        ))
    }
}
