//! RMSProp (Tieleman & Hinton 2012) as the thesis prints it, eqs. 2.14–2.15:
//!
//! ```text
//! v_t = β v_{t−1} + (1 − β) g_t⊙g_t                  (2.14)
//! θ_t = θ_{t−1} − η g_t / (√v_t + ε)   (entrywise)   (2.15, with ε)
//! ```
//!
//! The thesis's eq. 2.15 has no ε (ε = 0 here reproduces it literally); a zero denominator then
//! stops the run with [`AlgoError::NonFinite`] rather than producing NaN. `v₀ = 0`.

use super::first_order::{FirstOrder, UpdateRule};
use super::{AlgoError, ConfigNumber, in_range, positive, require_roots, sqrt};
use crate::problem::EstimatorForm;
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// RMSProp, as named in [`AlgoError::NeedsRoots`].
const RMSPROP: &str = "RMSProp";

/// RMSProp's hyper-parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RmsPropConfig {
    /// Step size η > 0.
    pub eta: ConfigNumber,
    /// Decay β ∈ [0, 1).
    pub beta: ConfigNumber,
    /// ε ≥ 0 added to √v (0 = eq. 2.15 as printed).
    pub epsilon: ConfigNumber,
}

impl RmsPropConfig {
    /// Step size `eta` with β = 0.9, ε = 10⁻⁸.
    pub fn with_eta(eta: impl Into<ConfigNumber>) -> Self {
        RmsPropConfig {
            eta: eta.into(),
            beta: ConfigNumber::ratio(9, 10),
            epsilon: ConfigNumber::ratio(1, 100_000_000),
        }
    }
}

/// The RMSProp update as an [`UpdateRule`].
#[derive(Debug, Clone)]
pub struct RmsPropRule<S> {
    eta: S,
    beta: S,
    epsilon: S,
    v: Option<DVector<S>>,
}

impl<S: Scalar> RmsPropRule<S> {
    /// Validate and build.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming `eta`, `beta` or `epsilon`;
    /// [`AlgoError::NeedsRoots`] for a scalar without square roots.
    pub fn new(c: &RmsPropConfig) -> Result<Self, AlgoError> {
        let rule = RmsPropRule {
            eta: S::from_rational(&positive(&c.eta, "eta", true)?),
            beta: S::from_rational(&in_range(&c.beta, "beta", (0, false), (1, true))?),
            epsilon: S::from_rational(&positive(&c.epsilon, "epsilon", false)?),
            v: None,
        };
        require_roots::<S>(RMSPROP, "square roots")?;
        Ok(rule)
    }
}

impl<S: Scalar> UpdateRule<S> for RmsPropRule<S> {
    fn reset(&mut self) {
        self.v = None;
    }
    fn apply(&mut self, theta: &mut DVector<S>, g: &DVector<S>) -> Result<(), AlgoError> {
        let v = self
            .v
            .take()
            .unwrap_or_else(|| DVector::from_element(g.len(), S::zero()));
        let v = v.zip_map(g, |vi, gi| {
            self.beta.clone() * vi + (S::one() - &self.beta) * gi.square()
        });
        for i in 0..theta.len() {
            let den = sqrt(&v[i], RMSPROP)? + &self.epsilon;
            if !den.is_certainly_positive() {
                return Err(AlgoError::NonFinite("RMSProp's denominator √v + ε (zero)"));
            }
            theta[i] -= self.eta.clone() * &g[i] / den;
        }
        self.v = Some(v);
        Ok(())
    }
}

/// RMSProp configuration on the IL objective.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RmsPropOptimizerConfig {
    /// RMSProp's hyper-parameters.
    #[serde(flatten)]
    pub rmsprop: RmsPropConfig,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

/// RMSProp on the IL objective, driven by the eq. 3.15 oracle: [`FirstOrder`] with the [`RmsPropRule`].
pub type RmsProp<S> = FirstOrder<S, RmsPropRule<S>>;

impl<S: Scalar> FirstOrder<S, RmsPropRule<S>> {
    /// Validate and build.
    ///
    /// # Errors
    /// As [`RmsPropRule::new`].
    pub fn new(config: &RmsPropOptimizerConfig) -> Result<Self, AlgoError> {
        Ok(FirstOrder::with_rule(
            "rmsprop",
            RmsPropRule::new(&config.rmsprop)?,
            config.form,
        ))
    }
}
