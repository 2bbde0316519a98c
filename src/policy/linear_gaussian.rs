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
//!
//! **Action type.** An action is a `Vec<S>` by default (any m). With a fixed m known at compile
//! time, `LinearGaussian<S, [S; M]>` ([`LinearGaussian::with_actions`]) stores actions inline, so
//! that sampling (and a roll-out storing the actions) allocates nothing; the numbers are the same.

use super::{
    LikelihoodRatio, Policy, PolicyError, check_out, check_positive, check_size, check_vec, mat_vec,
};
use crate::problem::KitRng;
use crate::sampling::standard_normal;
use crate::scalar::{Real, Scalar};
use std::borrow::Borrow;
use std::marker::PhantomData;

/// The storage of an action (or a target output) of the linear-Gaussian policy: `Vec<S>` for any
/// number of coordinates, `[S; M]` for exactly `M` (inline, no allocation).
pub trait ActionVector<S>: Clone + std::fmt::Debug + Borrow<[S]> {
    /// Whether this type can hold an action of `m` coordinates.
    fn holds(m: usize) -> bool;
    /// The action `(f(0), …, f(m − 1))`, calling `f` in order. `m` must be accepted by
    /// [`ActionVector::holds`].
    fn build(m: usize, f: impl FnMut(usize) -> S) -> Self;
}

impl<S: Clone + std::fmt::Debug> ActionVector<S> for Vec<S> {
    fn holds(_: usize) -> bool {
        true
    }
    fn build(m: usize, f: impl FnMut(usize) -> S) -> Self {
        (0..m).map(f).collect()
    }
}

impl<S: Clone + std::fmt::Debug, const M: usize> ActionVector<S> for [S; M] {
    fn holds(m: usize) -> bool {
        m == M
    }
    fn build(m: usize, f: impl FnMut(usize) -> S) -> Self {
        debug_assert_eq!(m, M, "an action of {m} coordinates in [S; {M}]");
        std::array::from_fn(f)
    }
}

/// The linear-Gaussian policy (P3) with `m` action coordinates, `n` features and exploration
/// standard deviation σ_π > 0; actions are stored as `A` (module docs: `Vec<S>`, or `[S; m]`).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearGaussian<S, A = Vec<S>> {
    actions: usize,
    features: usize,
    sigma: S,
    sigma_sq: S,
    action_type: PhantomData<fn() -> A>,
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
        check_positive("sigma", &sigma)?;
        Ok(Self {
            actions,
            features,
            sigma_sq: sigma.square(),
            sigma,
            action_type: PhantomData,
        })
    }
}

impl<S: Scalar, A> LinearGaussian<S, A> {
    /// The loss `‖Wφ − π*(s)‖²` of [`Policy::loss_into`], the same operations without the
    /// gradient and without checking θ and φ (validated by the caller).
    ///
    /// # Errors
    /// [`PolicyError::Shape`] / [`PolicyError::NonFinite`] for a bad label.
    pub(crate) fn loss_only_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
    ) -> Result<S, PolicyError> {
        check_vec("label", label, self.actions)?;
        let n = self.features;
        let mut loss = S::zero();
        for (i, y) in label.iter().enumerate() {
            let r = crate::scalar::dot(&theta[i * n..(i + 1) * n], phi) - y;
            loss += r.square();
        }
        Ok(loss)
    }

    /// The same policy with actions stored as `B` (e.g. `[S; 2]` for the obstacle task: sampling
    /// then allocates nothing).
    ///
    /// # Errors
    /// [`PolicyError::Shape`] if `B` cannot hold `m` coordinates.
    pub fn with_actions<B: ActionVector<S>>(self) -> Result<LinearGaussian<S, B>, PolicyError> {
        if !B::holds(self.actions) {
            return Err(PolicyError::Shape {
                param: "action type",
                expected: self.actions,
                got: std::mem::size_of::<B>() / std::mem::size_of::<S>().max(1),
            });
        }
        Ok(LinearGaussian {
            actions: self.actions,
            features: self.features,
            sigma: self.sigma,
            sigma_sq: self.sigma_sq,
            action_type: PhantomData,
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
        self.check(theta, phi)?;
        self.check(theta_other, phi)?;
        // ‖a − Wφ‖² row by row (the operations of `norm_sq(residual(a, mean))`, no temporaries).
        let n = self.features;
        let residual_sq = |w: &[S]| {
            action.iter().enumerate().fold(S::zero(), |acc, (i, a)| {
                acc + (a.clone() - crate::scalar::dot(&w[i * n..(i + 1) * n], phi)).square()
            })
        };
        Ok((residual_sq(theta_other) - residual_sq(theta)) / (S::from_i64(2) * &self.sigma_sq))
    }
}

impl<S: Real, A> LinearGaussian<S, A> {
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

impl<S: Scalar, A: ActionVector<S>> Policy<S> for LinearGaussian<S, A> {
    type Action = A;
    type Label = [S];

    fn param_dim(&self) -> usize {
        self.actions * self.features
    }
    fn feature_dim(&self) -> usize {
        self.features
    }

    /// `l = ‖Wφ − π*(s)‖²`, `∇_W l = 2(Wφ − π*)φᵀ` into `grad` (math.md §1.3, P3); `label` is
    /// π*(s) ∈ Sᵐ. Row by row of W, without a temporary for the mean.
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        check_vec("label", label, self.actions)?;
        self.check(theta, phi)?;
        check_out("grad", grad, self.actions * self.features)?;
        let n = self.features;
        let mut loss = S::zero();
        for (i, y) in label.iter().enumerate() {
            let r = crate::scalar::dot(&theta[i * n..(i + 1) * n], phi) - y;
            loss += r.square();
            let two_r = S::from_i64(2) * &r;
            for (g, x) in grad[i * n..(i + 1) * n].iter_mut().zip(phi) {
                *g = two_r.clone() * x;
            }
        }
        Ok(loss)
    }

    /// `∇_W log π(a|s) = (a − Wφ)φᵀ/σ_π²` into `score` (math.md §1.3, P3), row by row of W
    /// without a temporary for the mean.
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &A,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        let action: &[S] = action.borrow();
        check_vec("action", action, self.actions)?;
        self.check(theta, phi)?;
        check_out("score", score, self.actions * self.features)?;
        let n = self.features;
        for (i, a) in action.iter().enumerate() {
            let r =
                (a.clone() - crate::scalar::dot(&theta[i * n..(i + 1) * n], phi)) / &self.sigma_sq;
            for (s, x) in score[i * n..(i + 1) * n].iter_mut().zip(phi) {
                *s = r.clone() * x;
            }
        }
        Ok(())
    }

    /// Loss, gradient and score with each output `(Wφ)_i` computed once (the same numbers as
    /// [`Policy::loss_into`] then [`Policy::score_into`]).
    fn loss_score_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        action: &A,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        check_vec("label", label, self.actions)?;
        self.check(theta, phi)?;
        self.loss_score_validated(theta, phi, label, action, grad, score)
    }

    /// `a = Wφ + σ_π ε` with ε drawn as `m` f64 standard normals (coordinate by coordinate),
    /// converted exactly.
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<A, PolicyError> {
        check_vec("theta", theta, self.actions * self.features)?;
        self.sample_validated_theta(theta, phi, rng)
    }
}

impl<S: Scalar, A: ActionVector<S>> LinearGaussian<S, A> {
    /// [`Policy::loss_score_into`] for a θ and φ the caller has checked (lengths and
    /// finiteness): the same operations after those checks, so the same values and, for such
    /// inputs, the same errors in the same order.
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`].
    #[inline]
    pub(crate) fn loss_score_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        action: &A,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        let action: &[S] = action.borrow();
        check_vec("label", label, self.actions)?;
        check_out("grad", grad, self.actions * self.features)?;
        check_vec("action", action, self.actions)?;
        check_out("score", score, self.actions * self.features)?;
        let n = self.features;
        let mut loss = S::zero();
        for (i, (y, a)) in label.iter().zip(action).enumerate() {
            let mean = crate::scalar::dot(&theta[i * n..(i + 1) * n], phi);
            let r = mean.clone() - y;
            loss += r.square();
            let two_r = S::from_i64(2) * &r;
            let s = (a.clone() - mean) / &self.sigma_sq;
            let rows = grad[i * n..(i + 1) * n]
                .iter_mut()
                .zip(&mut score[i * n..(i + 1) * n]);
            for ((g, sc), x) in rows.zip(phi) {
                *g = two_r.clone() * x;
                *sc = s.clone() * x;
            }
        }
        Ok(loss)
    }

    /// [`Policy::sample`] for a θ the caller has checked (length and finiteness); φ is checked
    /// as [`Policy::sample`] checks it. For such a θ the same action, the same draws and the
    /// same errors.
    ///
    /// # Errors
    /// As [`Policy::sample`].
    #[inline]
    pub(crate) fn sample_validated_theta(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<A, PolicyError> {
        check_vec("phi", phi, self.features)?;
        let n = self.features;
        Ok(A::build(self.actions, |i| {
            crate::scalar::dot(&theta[i * n..(i + 1) * n], phi)
                + self.sigma.clone() * standard_normal::<S>(rng)
        }))
    }
}

impl<S: Scalar, A: ActionVector<S>> LikelihoodRatio<S> for LinearGaussian<S, A> {
    /// `−‖a − Wφ‖²/(2σ²)`: the log-density without its normaliser `−m ln σ − (m/2) ln 2π`, which
    /// does not depend on W (and needs a logarithm, which [`Scalar`] does not have).
    fn log_prob(&self, theta: &[S], phi: &[S], action: &A) -> Result<S, PolicyError> {
        let action: &[S] = action.borrow();
        check_vec("action", action, self.actions)?;
        let r = residual(action, &self.mean(theta, phi)?);
        Ok(-(crate::scalar::norm_sq(&r) / (S::from_i64(2) * &self.sigma_sq)))
    }

    /// Exact: [`LinearGaussian::log_ratio`].
    fn log_likelihood_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &A,
    ) -> Result<S, PolicyError> {
        self.log_ratio(theta, theta_other, phi, action.borrow())
    }
}
