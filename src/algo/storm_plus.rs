//! STORM+ (Levy, Kavis, Cevher, *STORM+: Fully Adaptive SGD with Recursive Momentum for
//! Nonconvex Optimization*, NeurIPS 2021, Algorithm 1): STORM with step sizes and momenta that
//! need neither L nor G nor σ.
//!
//! # The form implemented
//! With `g_i = g(θ_i, τ_i)` (eq. 3.15, τ_i ∼ p(·; θ_i)), `d₁ = g₁` and for t = 1, 2, …:
//!
//! ```text
//! a_{t+1} = min(1, c · (a₀ + Σ_{i≤t} ‖g_i‖²)^{−2/3})
//! η_t     = s · (b₀ + Σ_{i≤t} ‖d_i‖² / a_{i+1})^{−1/3}
//! θ_{t+1} = θ_t − η_t d_t
//! d_{t+1} = g(θ_{t+1}, τ_{t+1}) + (1 − a_{t+1}) (d_t − g̃_t)
//! ```
//!
//! with `g̃_t` unweighted or importance-weighted as in [`crate::algo::storm`] (IS-STORM+).
//!
//! # Constants
//! `a0`, `b0`, `c` and `eta_scale` (= s) are the initial accumulators, the momentum constant and
//! the step-size scale. [`StormPlusConfig::paper`] takes `a₀ = 1, b₀ = 0, c = 1, s = 1`:
//! `a_{t+1} = 1/(1 + Σ‖g_i‖²)^{2/3}`, `η_t = 1/(Σ‖d_i‖²/a_{i+1})^{1/3}`.
//! [`StormPlusConfig::released_code`] takes `a₀ = b₀ = 1, c = 1` and a given scale, as the
//! authors' released PyTorch `STORMplus` optimiser does: it keeps a gradient and an estimator
//! accumulator, both starting at 1, sets `a = c / grad_accumulator^{2/3}` after adding ‖g_t‖²,
//! then adds ‖d_t‖²/a to the estimator accumulator and steps with
//! `η = lr / estimator_accumulator^{1/3}` — the exponents, update order and recursion above. The
//! clip `a ≤ 1` is inactive for `a₀ ≥ c^{3/2}`.

use super::{
    AlgoError, Algorithm, ConfigNumber, StepContext, StepReport, axpy, cbrt, check_dim,
    check_finite, min_one, norm_sq, oracle_draw, positive, require_roots,
};
use crate::algo::storm::Correction;
use crate::problem::{Behaviour, EstimatorForm, IlProblem, Weighting};
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// STORM+, as named in [`AlgoError::NeedsRoots`].
const STORM_PLUS: &str = "STORM+";

/// STORM+ configuration (see the module docs for the exact form).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StormPlusConfig {
    /// Initial value of the gradient accumulator, a₀ > 0 (paper: 1).
    pub a0: ConfigNumber,
    /// Initial value of the step-size accumulator, b₀ ≥ 0 (paper: 0).
    pub b0: ConfigNumber,
    /// Momentum scale c > 0 (paper: 1).
    pub c: ConfigNumber,
    /// Step-size scale s > 0 (paper: 1).
    pub eta_scale: ConfigNumber,
    /// The old-point term.
    pub correction: Correction,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

impl StormPlusConfig {
    /// The paper's constants (a₀ = 1, b₀ = 0, c = 1, s = 1) with the given correction.
    pub fn paper(correction: Correction, form: EstimatorForm) -> Self {
        StormPlusConfig {
            a0: ConfigNumber::ratio(1, 1),
            b0: ConfigNumber::ratio(0, 1),
            c: ConfigNumber::ratio(1, 1),
            eta_scale: ConfigNumber::ratio(1, 1),
            correction,
            form,
        }
    }
}

impl StormPlusConfig {
    /// The constants of the authors' released optimiser: both accumulators start at 1
    /// (a₀ = b₀ = 1), c = 1, and the step-size scale `lr` (s).
    pub fn released_code(lr: ConfigNumber, correction: Correction, form: EstimatorForm) -> Self {
        StormPlusConfig {
            b0: ConfigNumber::ratio(1, 1),
            eta_scale: lr,
            ..StormPlusConfig::paper(correction, form)
        }
    }
}

/// STORM+ (and IS-STORM+).
#[derive(Debug, Clone)]
pub struct StormPlus<S> {
    a0: S,
    b0: S,
    c: S,
    scale: S,
    correction: Correction,
    form: EstimatorForm,
    grad_acc: S,
    est_acc: S,
    a_next: S,
    theta: DVector<S>,
    d: Option<DVector<S>>,
}

impl<S: Scalar> StormPlus<S> {
    /// The current iterate (as [`Algorithm::theta`], without naming the problem type).
    pub fn theta(&self) -> &DVector<S> {
        &self.theta
    }

    /// Validate and build.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming `a0`, `b0`, `c` or `eta_scale`;
    /// [`AlgoError::NeedsRoots`] for a scalar without cube roots.
    pub fn new(config: &StormPlusConfig) -> Result<Self, AlgoError> {
        let a0 = S::from_rational(&positive(&config.a0, "a0", true)?);
        let b0 = S::from_rational(&positive(&config.b0, "b0", false)?);
        let c = S::from_rational(&positive(&config.c, "c", true)?);
        let scale = S::from_rational(&positive(&config.eta_scale, "eta_scale", true)?);
        require_roots::<S>(STORM_PLUS, "cube roots")?;
        Ok(StormPlus {
            grad_acc: a0.clone(),
            est_acc: b0.clone(),
            a0,
            b0,
            c,
            scale,
            correction: config.correction,
            form: config.form,
            a_next: S::one(),
            theta: DVector::from_vec(Vec::new()),
            d: None,
        })
    }

    /// Fold in `‖g_t‖²` and `‖d_t‖²`: update a_{t+1} and the step-size accumulator.
    fn accumulate(&mut self, g: &DVector<S>, d: &DVector<S>) -> Result<(), AlgoError> {
        self.grad_acc += norm_sq(g);
        let r = cbrt(&self.grad_acc, STORM_PLUS)?;
        self.a_next = min_one(self.c.clone() / r.square(), "a = min(1, c·acc^(−2/3))")?;
        self.est_acc += norm_sq(d) / &self.a_next;
        if !self.a_next.is_finite() || !self.est_acc.is_finite() {
            return Err(AlgoError::NonFinite("the STORM+ accumulators"));
        }
        Ok(())
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for StormPlus<S> {
    fn name(&self) -> &'static str {
        if self.correction == Correction::Unweighted {
            "storm-plus"
        } else {
            "is-storm-plus"
        }
    }

    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        ctx: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.grad_acc = self.a0.clone();
        self.est_acc = self.b0.clone();
        let (_, g, _) = oracle_draw(problem, &theta0, self.form, ctx)?;
        self.accumulate(&g, &g)?;
        self.d = Some(g);
        self.theta = theta0;
        Ok(())
    }

    fn step(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        let d = self
            .d
            .take()
            .ok_or(AlgoError::State("STORM+ stepped before init"))?;
        if !self.est_acc.is_certainly_positive() {
            return Err(AlgoError::NonFinite(
                "η = (b₀ + Σ‖d‖²/a)^(−1/3) with a zero sum",
            ));
        }
        let eta = self.scale.clone() / cbrt(&self.est_acc, STORM_PLUS)?;
        let a = self.a_next.clone();
        let new = axpy(&-eta, &d, &self.theta);
        check_finite(&new, "θ")?;
        let tau = problem.rollout(&Behaviour::Learner(&new), ctx.rng, ctx.cost)?;
        let (g_new, loss) = problem.estimate_with_loss(&new, &tau, self.form, ctx.cost)?;
        let weighting: Option<Weighting> = match self.correction {
            Correction::Unweighted => None,
            Correction::Trajectory => Some(Weighting::Trajectory),
            Correction::PerDecision => Some(Weighting::PerDecision),
        };
        let g_old = match weighting {
            Some(w) => problem.weighted_estimate(&self.theta, &new, &tau, w, ctx.cost)?,
            None => problem.estimate(&self.theta, &tau, self.form, ctx.cost)?,
        };
        let d_next = axpy(&(S::one() - a), &(d - g_old), &g_new);
        check_finite(&d_next, "the STORM+ direction d")?;
        self.accumulate(&g_new, &d_next)?;
        self.theta = new;
        self.d = Some(d_next.clone());
        Ok(StepReport::new(Some(d_next), Some(loss)))
    }

    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
