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
//! With `a₀ = 1, b₀ = 0, c = 1, s = 1` this is, to the best of my recollection, the paper's
//! Algorithm 1: `a_{t+1} = 1/(1 + Σ‖∇f(x_i, ξ_i)‖²)^{2/3}`, `η_t = 1/(Σ‖d_i‖²/a_{i+1})^{1/3}`.
//! **Uncertainty:** the paper was not available while this was written. Its theory allows (and
//! the authors' released optimiser uses) initial accumulator values and a scale on the step size;
//! these are exposed as `a0`, `b0`, `c`, `eta_scale` (the released PyTorch code initialises both
//! accumulators at 1, i.e. `b₀ = 1`). The exponents −2/3 and −1/3 and the order of the updates
//! (a_{t+1} from gradients up to t, η_t from d_i/a_{i+1} up to t) are the parts I am confident
//! of; the clip `a ≤ 1` is a no-op for `a₀ ≥ c^{3/2}`.
//!
//! **Checked against released code** (a public PyTorch `STORMplus` optimiser, read while this
//! was reviewed): it keeps `grad_accumulator` and `estimator_accumulator`, both initialised to
//! `init_accumulator = 1`, sets `a = c / grad_accumulator^{2/3}` after adding ‖g_t‖², then
//! `estimator_accumulator += ‖d_t‖²/a` and `η = lr / estimator_accumulator^{1/3}`, and forms
//! `d_{t+1} = g_{t+1} + (1 − a)(d_t − g(θ_t; ξ_{t+1}))` — the same exponents, update order and
//! recursion as above, with `b₀ = 1` ([`StormPlusConfig::released_code`]). The paper's own
//! statement of the constants was not available; cite [`StormPlusConfig::released_code`] as
//! "STORM+ (released code)".

use super::{
    AlgoError, Algorithm, Ctx, Num, StepReport, axpy, cbrt, check_dim, check_finite, min_one,
    norm_sq, oracle_draw, positive, require_roots,
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
    pub a0: Num,
    /// Initial value of the step-size accumulator, b₀ ≥ 0 (paper: 0).
    pub b0: Num,
    /// Momentum scale c > 0 (paper: 1).
    pub c: Num,
    /// Step-size scale s > 0 (paper: 1).
    pub eta_scale: Num,
    /// The old-point term.
    pub correction: Correction,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

impl StormPlusConfig {
    /// The paper's constants (a₀ = 1, b₀ = 0, c = 1, s = 1) with the given correction.
    pub fn paper(correction: Correction, form: EstimatorForm) -> Self {
        StormPlusConfig {
            a0: Num::ratio(1, 1),
            b0: Num::ratio(0, 1),
            c: Num::ratio(1, 1),
            eta_scale: Num::ratio(1, 1),
            correction,
            form,
        }
    }
}

impl StormPlusConfig {
    /// The constants of the authors' released optimiser: both accumulators start at 1
    /// (a₀ = b₀ = 1), c = 1, and the step-size scale `lr` (s).
    pub fn released_code(lr: Num, correction: Correction, form: EstimatorForm) -> Self {
        StormPlusConfig {
            b0: Num::ratio(1, 1),
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
        problem: &P,
        theta0: DVector<S>,
        ctx: &mut Ctx<'_>,
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

    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
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
        let g_new = problem.estimate(&new, &tau, self.form, ctx.cost)?;
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
        let loss = problem.trajectory_loss(&new, &tau)?;
        self.theta = new;
        self.d = Some(d_next.clone());
        Ok(StepReport::new(Some(d_next), Some(loss)))
    }

    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
