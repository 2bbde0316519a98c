//! The oracle-driven first-order methods on the IL objective (SGD, Adam, RMSProp): one shell,
//! [`FirstOrder`], around an [`UpdateRule`]. One step samples `τ ∼ p(·; θ)`, evaluates the
//! eq. 3.15 estimate `g(θ, τ)` and applies the rule `θ ← U(θ, g)`.

use super::{AlgoError, Algorithm, StepContext, StepReport, check_dim, check_finite, oracle_draw};
use crate::problem::{EstimatorForm, IlProblem};
use crate::scalar::Scalar;
use nalgebra::DVector;

/// A first-order update rule `θ ← U(θ, g)` with its own buffers (SGD, Adam, RMSProp). The outer
/// optimisers apply it to the eq. 3.15 estimate; the dataset learners apply it to the gradient of
/// the dataset loss (the supervised inner optimiser).
pub trait UpdateRule<S: Scalar>: std::fmt::Debug {
    /// Clear the buffers (step counter, moments).
    fn reset(&mut self);
    /// One update of `theta` along the gradient (estimate) `g`.
    ///
    /// # Errors
    /// [`AlgoError::NonFinite`] if the update is not finite (e.g. a zero RMSProp denominator).
    fn apply(&mut self, theta: &mut DVector<S>, g: &DVector<S>) -> Result<(), AlgoError>;
}

/// A first-order method on the IL objective: the update rule `R` applied to the eq. 3.15
/// estimate at the current iterate. [`crate::algo::sgd::Sgd`], [`crate::algo::adam::Adam`] and
/// [`crate::algo::rmsprop::RmsProp`] are this type with their rules.
#[derive(Debug, Clone)]
pub struct FirstOrder<S, R> {
    name: &'static str,
    rule: R,
    form: EstimatorForm,
    theta: DVector<S>,
}

impl<S: Scalar, R: UpdateRule<S>> FirstOrder<S, R> {
    /// The method `name` with a built rule and the estimator form of eq. 3.15; the iterate is
    /// set by [`Algorithm::init`].
    pub fn with_rule(name: &'static str, rule: R, form: EstimatorForm) -> Self {
        FirstOrder {
            name,
            rule,
            form,
            theta: DVector::from_vec(Vec::new()),
        }
    }

    /// The current iterate (as [`Algorithm::theta`], without naming the problem type).
    pub fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}

impl<S: Scalar, R: UpdateRule<S>, P: IlProblem<S> + ?Sized> Algorithm<S, P> for FirstOrder<S, R> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        _: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.rule.reset();
        self.theta = theta0;
        Ok(())
    }
    /// Sample τ ∼ p(·; θ), estimate g(θ, τ) (eq. 3.15), update θ with the rule.
    fn step(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        let (_, g, loss) = oracle_draw(problem, &self.theta, self.form, ctx)?;
        self.rule.apply(&mut self.theta, &g)?;
        check_finite(&self.theta, "θ")?;
        Ok(StepReport::new(Some(g), Some(loss)))
    }
    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
