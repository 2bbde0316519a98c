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
use crate::scalar::{Scalar, powi};
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

/// The Adam update as an [`UpdateRule`], also usable on plain slices with a per-step step size
/// ([`AdamRule::update`]; the PPO expert's trainer anneals it).
///
/// In floating point the order of operations is fixed: `v ← β₂v + ((1 − β₂)·g)·g`, the bias
/// corrections `1 − βᵗ` with `βᵗ` by [`powi`] (binary powering, `f64::powi`'s order), and
/// `θ ← θ − (α·m̂)/(√v̂ + ε)`.
#[derive(Debug, Clone)]
pub struct AdamRule<S> {
    alpha: S,
    beta1: S,
    beta2: S,
    epsilon: S,
    steps: u32,
    m: Vec<S>,
    v: Vec<S>,
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
            steps: 0,
            m: Vec::new(),
            v: Vec::new(),
        };
        require_roots::<S>(ADAM, "square roots")?;
        Ok(rule)
    }

    /// The moments `(m, v)` after the last update (empty before the first).
    pub fn moments(&self) -> (&[S], &[S]) {
        (&self.m, &self.v)
    }

    /// One Adam step of `theta` along `g` with step size `alpha` in place of the configured α
    /// (the module's update, t counting the updates since the last reset).
    ///
    /// # Errors
    /// [`AlgoError::Dimension`] if `g` and `theta` (or the moments of earlier steps)
    /// differ in length; [`AlgoError::NonFinite`] for a zero denominator √v̂ + ε;
    /// [`AlgoError::NeedsRoots`] if a square root is not available.
    pub fn update(&mut self, theta: &mut [S], g: &[S], alpha: &S) -> Result<(), AlgoError> {
        if self.steps == 0 {
            self.m = vec![S::zero(); g.len()];
            self.v = vec![S::zero(); g.len()];
        }
        if theta.len() != g.len() || self.m.len() != g.len() {
            return Err(AlgoError::Dimension {
                expected: self.m.len(),
                got: if theta.len() != self.m.len() {
                    theta.len()
                } else {
                    g.len()
                },
            });
        }
        self.steps = self.steps.saturating_add(1);
        let one = S::one();
        let (d1, d2) = (one.clone() - &self.beta1, one.clone() - &self.beta2);
        let c1 = one.clone() - powi(&self.beta1, self.steps);
        let c2 = one - powi(&self.beta2, self.steps);
        for (((t, gi), m), v) in theta.iter_mut().zip(g).zip(&mut self.m).zip(&mut self.v) {
            *m = self.beta1.clone() * &*m + d1.clone() * gi;
            *v = self.beta2.clone() * &*v + d2.clone() * gi * gi;
            let mhat = m.clone() / &c1;
            let vhat = v.clone() / &c2;
            let den = sqrt(&vhat, ADAM)? + &self.epsilon;
            if !den.is_certainly_positive() {
                return Err(AlgoError::NonFinite("Adam's denominator √v̂ + ε (zero)"));
            }
            *t -= alpha.clone() * mhat / den;
        }
        Ok(())
    }
}

impl<S: Scalar> UpdateRule<S> for AdamRule<S> {
    fn reset(&mut self) {
        self.steps = 0;
        self.m.clear();
        self.v.clear();
    }
    fn apply(&mut self, theta: &mut DVector<S>, g: &DVector<S>) -> Result<(), AlgoError> {
        let alpha = self.alpha.clone();
        self.update(theta.as_mut_slice(), g.as_slice(), &alpha)
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
