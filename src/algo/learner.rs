//! [`DatasetLearner`]: the one shell of the dataset learners of §2.4 (BC, DAgger, RRM, SMILe,
//! forward training). The shell holds what they share — the supervised inner optimiser, the
//! dataset, θ₀ and the iterate ([`LearnerState`]); a [`DataSchedule`] holds what differs: which
//! behaviour is rolled out, which data are kept, and what is trained on them.

use super::dataset::{InnerConfig, InnerOptimiser, Retrain, trajectories};
use super::{AlgoError, Algorithm, StepContext, StepReport, check_dim};
use crate::problem::IlProblem;
use crate::scalar::Scalar;
use nalgebra::DVector;

/// What every dataset learner holds.
#[derive(Debug)]
pub struct LearnerState<S: Scalar, P: IlProblem<S> + ?Sized> {
    /// Trajectories rolled out per iteration (validated ≥ 1).
    pub(crate) trajectories: u64,
    /// Where each retraining starts.
    pub(crate) retrain: Retrain,
    /// The supervised inner optimiser.
    pub(crate) inner: InnerOptimiser<S>,
    /// The dataset the learner trains on.
    pub(crate) data: Vec<P::Labelled>,
    /// The initial parameter.
    pub(crate) theta0: DVector<S>,
    /// The current iterate.
    pub(crate) theta: DVector<S>,
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> LearnerState<S, P> {
    /// A state with validated parts; θ₀ and θ are set by [`Algorithm::init`].
    pub(crate) fn new(trajectories: u64, retrain: Retrain, inner: InnerOptimiser<S>) -> Self {
        LearnerState {
            trajectories,
            retrain,
            inner,
            data: Vec::new(),
            theta0: DVector::from_vec(Vec::new()),
            theta: DVector::from_vec(Vec::new()),
        }
    }

    /// Validate and build the inner optimiser, then the trajectory count.
    ///
    /// # Errors
    /// As [`InnerOptimiser::new`]; [`AlgoError::InvalidParameter`] for zero trajectories.
    pub(crate) fn build(
        inner: &InnerConfig,
        trajectories_per_iteration: u64,
        retrain: Retrain,
    ) -> Result<Self, AlgoError> {
        let inner = InnerOptimiser::new(inner)?;
        Ok(Self::new(
            trajectories(trajectories_per_iteration)?,
            retrain,
            inner,
        ))
    }

    /// Train on the whole dataset from θ₀ or θ (by [`Retrain`]), make the result the iterate and
    /// report the dataset loss.
    ///
    /// # Errors
    /// As [`InnerOptimiser::train`].
    pub(crate) fn retrain_on_dataset(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        let start = match self.retrain {
            Retrain::FromScratch => &self.theta0,
            Retrain::WarmStart => &self.theta,
        };
        let (theta, loss) = self.inner.train(problem, start, &self.data, ctx)?;
        self.theta = theta;
        Ok(StepReport::new(None, Some(loss)))
    }
}

/// The per-algorithm part of a dataset learner: one iteration on the shared [`LearnerState`].
pub trait DataSchedule<S: Scalar, P: IlProblem<S> + ?Sized>: std::fmt::Debug {
    /// The algorithm's short stable name (`"bc"`, `"dagger"`, …).
    const NAME: &'static str;
    /// Clear the schedule's own state (iteration counter, components) at [`Algorithm::init`].
    fn reset(&mut self);
    /// One iteration: collect data, train, update the iterate.
    ///
    /// # Errors
    /// Oracle failures, an empty dataset, non-finite iterates.
    fn step(
        &mut self,
        state: &mut LearnerState<S, P>,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError>;
    /// Further outputs (SMILe's components, forward training's per-step policies).
    fn outputs(&self) -> Vec<DVector<S>> {
        Vec::new()
    }
}

/// A dataset learner: the shared [`LearnerState`] driven by the schedule `D`.
#[derive(Debug)]
pub struct DatasetLearner<S: Scalar, P: IlProblem<S> + ?Sized, D> {
    pub(crate) state: LearnerState<S, P>,
    pub(crate) schedule: D,
}

impl<S: Scalar, P: IlProblem<S> + ?Sized, D: DataSchedule<S, P>> DatasetLearner<S, P, D> {
    /// The current iterate (as [`Algorithm::theta`], without naming the problem type).
    pub fn theta(&self) -> &DVector<S> {
        &self.state.theta
    }
    /// The dataset the learner trains on (aggregated or the newest, by algorithm).
    pub fn dataset(&self) -> &[P::Labelled] {
        &self.state.data
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized, D: DataSchedule<S, P>> Algorithm<S, P>
    for DatasetLearner<S, P, D>
{
    fn name(&self) -> &'static str {
        D::NAME
    }
    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        _: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.state.data.clear();
        self.schedule.reset();
        self.state.theta0 = theta0.clone();
        self.state.theta = theta0;
        Ok(())
    }
    fn step(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        self.schedule.step(&mut self.state, problem, ctx)
    }
    fn theta(&self) -> &DVector<S> {
        &self.state.theta
    }
    fn outputs(&self) -> Vec<DVector<S>> {
        self.schedule.outputs()
    }
}
