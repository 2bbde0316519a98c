//! Adam (Kingma & Ba, *Adam: A Method for Stochastic Optimization*, ICLR 2015, Algorithm 1), as
//! the thesis uses it (§2.6.2, described in words; the thesis prints no update for Adam — its
//! eqs. 2.14–2.15 are RMSProp's). With `g` the eq. 3.15 estimate and t = 1, 2, …:
//!
//! ```text
//! m_t = β₁ m_{t−1} + (1 − β₁) g          v_t = β₂ v_{t−1} + (1 − β₂) g⊙g
//! m̂_t = m_t / (1 − β₁ᵗ)                  v̂_t = v_t / (1 − β₂ᵗ)
//! θ_t = θ_{t−1} − α m̂_t / (√v̂_t + ε)     (entrywise)
//! ```

use super::first_order::{FirstOrder, UpdateRule};
use super::{AlgoError, ConfigNumber, in_range, positive, require_roots, sqrt};
use crate::problem::EstimatorForm;
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// Adam, as named in [`AlgoError::NeedsRoots`].
const ADAM: &str = "Adam";

/// Adam's hyper-parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdamConfig {
    /// Step size α > 0.
    pub alpha: ConfigNumber,
    /// First-moment decay β₁ ∈ [0, 1).
    pub beta1: ConfigNumber,
    /// Second-moment decay β₂ ∈ [0, 1).
    pub beta2: ConfigNumber,
    /// ε ≥ 0 added to √v̂.
    pub epsilon: ConfigNumber,
}

impl AdamConfig {
    /// Kingma & Ba's defaults with step size `alpha`: β₁ = 0.9, β₂ = 0.999, ε = 10⁻⁸.
    pub fn with_alpha(alpha: impl Into<ConfigNumber>) -> Self {
        AdamConfig {
            alpha: alpha.into(),
            beta1: ConfigNumber::ratio(9, 10),
            beta2: ConfigNumber::ratio(999, 1000),
            epsilon: ConfigNumber::ratio(1, 100_000_000),
        }
    }
}

/// The Adam update as an [`UpdateRule`].
#[derive(Debug, Clone)]
pub struct AdamRule<S> {
    alpha: S,
    beta1: S,
    beta2: S,
    epsilon: S,
    beta1_t: S,
    beta2_t: S,
    m: Option<DVector<S>>,
    v: Option<DVector<S>>,
}

impl<S: Scalar> AdamRule<S> {
    /// Validate and build.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming `alpha`, `beta1`, `beta2` or `epsilon`;
    /// [`AlgoError::NeedsRoots`] for a scalar without square roots.
    pub fn new(c: &AdamConfig) -> Result<Self, AlgoError> {
        let rule = AdamRule {
            alpha: S::from_rational(&positive(&c.alpha, "alpha", true)?),
            beta1: S::from_rational(&in_range(&c.beta1, "beta1", (0, false), (1, true))?),
            beta2: S::from_rational(&in_range(&c.beta2, "beta2", (0, false), (1, true))?),
            epsilon: S::from_rational(&positive(&c.epsilon, "epsilon", false)?),
            beta1_t: S::one(),
            beta2_t: S::one(),
            m: None,
            v: None,
        };
        require_roots::<S>(ADAM, "square roots")?;
        Ok(rule)
    }
}

impl<S: Scalar> UpdateRule<S> for AdamRule<S> {
    fn reset(&mut self) {
        self.beta1_t = S::one();
        self.beta2_t = S::one();
        self.m = None;
        self.v = None;
    }
    fn apply(&mut self, theta: &mut DVector<S>, g: &DVector<S>) -> Result<(), AlgoError> {
        let zeros = || DVector::from_element(g.len(), S::zero());
        let m = self.m.take().unwrap_or_else(zeros);
        let v = self.v.take().unwrap_or_else(zeros);
        let one = S::one();
        let m = m.zip_map(g, |mi, gi| {
            self.beta1.clone() * mi + (one.clone() - &self.beta1) * gi
        });
        let v = v.zip_map(g, |vi, gi| {
            self.beta2.clone() * vi + (one.clone() - &self.beta2) * gi.square()
        });
        self.beta1_t *= &self.beta1;
        self.beta2_t *= &self.beta2;
        let c1 = one.clone() - &self.beta1_t;
        let c2 = one - &self.beta2_t;
        for i in 0..theta.len() {
            let mhat = m[i].clone() / &c1;
            let vhat = v[i].clone() / &c2;
            let den = sqrt(&vhat, ADAM)? + &self.epsilon;
            if !den.is_certainly_positive() {
                return Err(AlgoError::NonFinite("Adam's denominator √v̂ + ε (zero)"));
            }
            theta[i] -= self.alpha.clone() * mhat / den;
        }
        self.m = Some(m);
        self.v = Some(v);
        Ok(())
    }
}

/// Adam configuration on the IL objective.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdamOptimizerConfig {
    /// Adam's hyper-parameters.
    #[serde(flatten)]
    pub adam: AdamConfig,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

/// Adam on the IL objective, driven by the eq. 3.15 oracle: [`FirstOrder`] with the [`AdamRule`].
pub type Adam<S> = FirstOrder<S, AdamRule<S>>;

impl<S: Scalar> FirstOrder<S, AdamRule<S>> {
    /// Validate and build.
    ///
    /// # Errors
    /// As [`AdamRule::new`].
    pub fn new(config: &AdamOptimizerConfig) -> Result<Self, AlgoError> {
        Ok(FirstOrder::with_rule(
            "adam",
            AdamRule::new(&config.adam)?,
            config.form,
        ))
    }
}
