//! (P3) The linear-Gaussian policy of math.md §1.3: `π_W(a|s) = N(a; Wφ(s), σ_π² I_m)`.
//!
//! | quantity | formula | scalar layer |
//! |---|---|---|
//! | output (mean) | `m_W(s) = Wφ` | [`Scalar`] |
//! | loss (E1: on the output) | `l = ‖Wφ − π*(s)‖²`, `∇_W l = 2(Wφ − π*)φᵀ` | [`Scalar`] |
//! | score | `∇_W log π(a\|s) = (a − Wφ)φᵀ/σ_π²` | [`Scalar`] |
//! | log-density ratio | `log π_W(a\|s) − log π_{W'}(a\|s) = (‖a − W'φ‖² − ‖a − Wφ‖²)/(2σ_π²)` | [`Scalar`] |
//! | log-density (up to `−(m/2) ln 2π`) | `−‖a − Wφ‖²/(2σ_π²) − m ln σ_π` | [`Real`] |
//! | sampling | `a = Wφ + σ_π ε`, `ε ∼ N(0, I_m)` | [`Scalar`] |
//!
//! The loss and the score are polynomial (affine, for the score) in W, so with rational data they
//! are exact in `BigRational`; only the density itself needs `exp`/`ln`.
//!
//! **Layout of θ**: W ∈ S^{m×n} row-major, `θ[i·n + j] = W_ij` (row i = action coordinate i,
//! column j = feature j). Gradients use the same layout.

use super::{Policy, PolicyError, check_size, check_vec, mat_vec, outer, standard_normal};
use crate::problem::KitRng;
use crate::scalar::{Real, Scalar};

/// The linear-Gaussian policy (P3) with `m` action coordinates, `n` features and exploration
/// standard deviation σ_π > 0.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearGaussian<S> {
    actions: usize,
    features: usize,
    sigma: S,
    sigma_sq: S,
}

impl<S: Scalar> LinearGaussian<S> {
    /// A validated policy: `actions = m ≥ 1`, `features = n ≥ 1`, σ_π finite and certainly > 0.
    ///
    /// # Errors
    /// [`PolicyError::TooSmall`] for `m = 0` or `n = 0`, [`PolicyError::NonFinite`] or
    /// [`PolicyError::NotPositive`] for a bad `sigma`.
    pub fn new(actions: usize, features: usize, sigma: S) -> Result<Self, PolicyError> {
        check_size("actions", actions, 1)?;
        check_size("features", features, 1)?;
        if !sigma.is_finite() {
            return Err(PolicyError::NonFinite { param: "sigma" });
        }
        if !sigma.is_certainly_positive() {
            return Err(PolicyError::NotPositive {
                param: "sigma",
                value: sigma.to_f64(),
            });
        }
        Ok(Self {
            actions,
            features,
            sigma_sq: sigma.square(),
            sigma,
        })
    }

    /// m, the dimension of an action.
    pub fn actions(&self) -> usize {
        self.actions
    }
    /// σ_π.
    pub fn sigma(&self) -> &S {
        &self.sigma
    }
    /// σ_π².
    pub fn sigma_sq(&self) -> &S {
        &self.sigma_sq
    }

    fn check(&self, theta: &[S], phi: &[S]) -> Result<(), PolicyError> {
        check_vec("theta", theta, self.actions * self.features)?;
        check_vec("phi", phi, self.features)
    }

    /// The deterministic output `m_W(s) = Wφ` (math.md §1.3, P3).
    ///
    /// # Errors
    /// [`PolicyError::Shape`] / [`PolicyError::NonFinite`] for a bad θ or φ.
    pub fn mean(&self, theta: &[S], phi: &[S]) -> Result<Vec<S>, PolicyError> {
        self.check(theta, phi)?;
        Ok(mat_vec(theta, phi, self.actions))
    }

    /// The log-density ratio `log π_W(a|s) − log π_{W'}(a|s) = (‖a − W'φ‖² − ‖a − Wφ‖²)/(2σ_π²)`,
    /// exact in rationals (the factor of an importance weight, math.md §4; the weight itself is
    /// its exponential, [`LinearGaussian::density_ratio`]).
    ///
    /// # Errors
    /// As [`LinearGaussian::mean`], and [`PolicyError::Shape`] for an action of the wrong length.
    pub fn log_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &[S],
    ) -> Result<S, PolicyError> {
        check_vec("action", action, self.actions)?;
        let r = residual(action, &self.mean(theta, phi)?);
        let r_other = residual(action, &self.mean(theta_other, phi)?);
        Ok(
            (crate::scalar::norm_sq(&r_other) - crate::scalar::norm_sq(&r))
                / (S::from_i64(2) * &self.sigma_sq),
        )
    }
}

impl<S: Real> LinearGaussian<S> {
    /// The log-density without its constant: `log π_W(a|s) + (m/2) ln 2π
    /// = −‖a − Wφ‖²/(2σ_π²) − m ln σ_π`.
    ///
    /// The omitted term `−(m/2) ln 2π` depends on neither W nor σ_π, so it cancels in every
    /// likelihood ratio; it is left out because π is not constructible in the [`Real`] layer
    /// without rounding, and an interval result must stay a rigorous enclosure.
    ///
    /// # Errors
    /// As [`LinearGaussian::log_ratio`].
    pub fn log_prob_unnormalised(
        &self,
        theta: &[S],
        phi: &[S],
        action: &[S],
    ) -> Result<S, PolicyError> {
        check_vec("action", action, self.actions)?;
        let r = residual(action, &self.mean(theta, phi)?);
        let m = S::from_i64(self.actions as i64);
        Ok(-(crate::scalar::norm_sq(&r) / (S::from_i64(2) * &self.sigma_sq)) - m * self.sigma.ln())
    }

    /// The importance weight `π_W(a|s)/π_{W'}(a|s) = exp(log_ratio)` of one decision (math.md §4;
    /// the trajectory weight is the product over decisions).
    ///
    /// # Errors
    /// As [`LinearGaussian::log_ratio`].
    pub fn density_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &[S],
    ) -> Result<S, PolicyError> {
        Ok(self.log_ratio(theta, theta_other, phi, action)?.exp())
    }
}

fn residual<S: Scalar>(a: &[S], b: &[S]) -> Vec<S> {
    a.iter().zip(b).map(|(x, y)| x.clone() - y).collect()
}

impl<S: Scalar> Policy<S> for LinearGaussian<S> {
    type Action = Vec<S>;
    type Label = [S];

    fn param_dim(&self) -> usize {
        self.actions * self.features
    }
    fn feature_dim(&self) -> usize {
        self.features
    }

    /// `l = ‖Wφ − π*(s)‖²`, `∇_W l = 2(Wφ − π*)φᵀ` (math.md §1.3, P3); `label` is π*(s) ∈ Sᵐ.
    fn loss(&self, theta: &[S], phi: &[S], label: &[S]) -> Result<(S, Vec<S>), PolicyError> {
        check_vec("label", label, self.actions)?;
        let r = residual(&self.mean(theta, phi)?, label);
        let two_r: Vec<S> = r.iter().map(|x| S::from_i64(2) * x).collect();
        Ok((crate::scalar::norm_sq(&r), outer(&two_r, phi)))
    }

    /// `∇_W log π(a|s) = (a − Wφ)φᵀ/σ_π²` (math.md §1.3, P3).
    fn score(&self, theta: &[S], phi: &[S], action: &Vec<S>) -> Result<Vec<S>, PolicyError> {
        check_vec("action", action, self.actions)?;
        let r: Vec<S> = residual(action, &self.mean(theta, phi)?)
            .into_iter()
            .map(|x| x / &self.sigma_sq)
            .collect();
        Ok(outer(&r, phi))
    }

    /// `a = Wφ + σ_π ε` with ε drawn as `m` f64 standard normals, converted exactly.
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<Vec<S>, PolicyError> {
        let mean = self.mean(theta, phi)?;
        Ok(mean
            .into_iter()
            .map(|mu| mu + self.sigma.clone() * standard_normal::<S>(rng))
            .collect())
    }
}
