//! The [`Algorithm`] trait the runner drives, what a step reports ([`StepReport`]) and what it may
//! use ([`StepContext`]); and the oracle draw every gradient method starts from.

use super::error::{AlgoError, check_finite};
use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use crate::scalar::Scalar;
use nalgebra::DVector;

/// What one algorithm step hands to the runner.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct StepReport<S> {
    /// The direction the step used (the oracle estimate for SGD, `d_k` for STORM, …), for the
    /// per-iteration "estimate norm" metric.
    pub estimate: Option<DVector<S>>,
    /// A loss estimate at the new or current iterate when the step has one at no extra cost
    /// (e.g. `Σ_t l(s_t, θ)` on the sampled trajectory, or the dataset loss).
    pub loss: Option<S>,
    /// The algorithm has completed its own schedule (O2NC after `M = KT` steps, forward training
    /// after `T − 1` policies).
    pub finished: bool,
    /// Where the step's gradient was evaluated when that is not the iterate (O2NC's w_n).
    pub evaluated_at: Option<DVector<S>>,
}

impl<S> StepReport<S> {
    /// A report with an estimate and optional loss, not finished.
    pub fn new(estimate: Option<DVector<S>>, loss: Option<S>) -> Self {
        StepReport {
            estimate,
            loss,
            finished: false,
            evaluated_at: None,
        }
    }
    /// Record where the gradient was evaluated.
    pub fn evaluated_at(mut self, point: DVector<S>) -> Self {
        self.evaluated_at = Some(point);
        self
    }
    /// Mark the algorithm as finished.
    pub fn finished(mut self) -> Self {
        self.finished = true;
        self
    }
}

/// What a step may use and must account to: the run's RNG and the cumulative [`Cost`].
#[derive(Debug)]
pub struct StepContext<'a> {
    /// The run's seeded RNG (owned by the runner).
    pub rng: &'a mut KitRng,
    /// The cumulative cost of the run.
    pub cost: &'a mut Cost,
}

/// An algorithm: hyper-parameters + state, initialised once and stepped by the runner
/// (conventions.md 5). It drives the problem only through [`IlProblem`].
pub trait Algorithm<S: Scalar, P: IlProblem<S> + ?Sized> {
    /// A short stable name (`"sgd"`, `"is-storm"`, …).
    fn name(&self) -> &'static str;

    /// Reset the state and start from `theta0` (may already sample, e.g. STORM's `d_1`).
    ///
    /// # Errors
    /// [`AlgoError::Dimension`] for a θ of the wrong length; oracle failures.
    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        ctx: &mut StepContext<'_>,
    ) -> Result<(), AlgoError>;

    /// One iteration.
    ///
    /// # Errors
    /// Oracle failures, undecidable interval branches, non-finite values.
    fn step(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError>;

    /// The current iterate (what the runner reports and returns).
    fn theta(&self) -> &DVector<S>;

    /// Further outputs (O2NC's `w̄ᵏ`, forward training's per-step policies, SMILe's mixture
    /// components). Empty by default.
    fn outputs(&self) -> Vec<DVector<S>> {
        Vec::new()
    }
}

/// One oracle draw at `theta`: roll out π_θ, evaluate eq. 3.15 and the trajectory loss.
pub(crate) fn oracle_draw<S: Scalar, P: IlProblem<S> + ?Sized>(
    problem: &mut P,
    theta: &DVector<S>,
    form: EstimatorForm,
    ctx: &mut StepContext<'_>,
) -> Result<(P::Trajectory, DVector<S>, S), AlgoError> {
    let tau = problem.rollout(&Behaviour::Learner(theta), ctx.rng, ctx.cost)?;
    let (g, loss) = problem.estimate_with_loss(theta, &tau, form, ctx.cost)?;
    check_finite(&g, "the gradient estimate")?;
    Ok((tau, g, loss))
}
