//! Behavioural cloning (§2.4.2, eq. 2.10): supervised learning on states visited by the expert,
//! `π̂_sup = argmin_π E_{s∼d_{π*}}[l(s, π)]`. One runner step rolls out the expert
//! `trajectories_per_iteration` times, adds the labelled states to the dataset and retrains with
//! the inner optimiser (so one step with enough trajectories is classic BC, and more steps show
//! BC's learning curve in the same cost units as the other learners).

use super::dataset::{InnerConfig, Retrain, collect};
use super::learner::{DataSchedule, DatasetLearner, LearnerState};
use super::{AlgoError, StepContext, StepReport};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::Scalar;
use serde::{Deserialize, Serialize};

/// Behavioural-cloning configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BcConfig {
    /// Expert trajectories per step (≥ 1).
    pub trajectories_per_iteration: u64,
    /// The supervised inner optimiser.
    pub inner: InnerConfig,
    /// Retrain from θ₀ or warm-start.
    pub retrain: Retrain,
}

/// BC's schedule: every iteration adds expert roll-outs to the dataset.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExpertData;

/// Behavioural cloning: a [`DatasetLearner`] with the [`ExpertData`] schedule.
pub type Bc<S, P> = DatasetLearner<S, P, ExpertData>;

impl<S: Scalar, P: IlProblem<S> + ?Sized> DatasetLearner<S, P, ExpertData> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &BcConfig) -> Result<Self, AlgoError> {
        Ok(DatasetLearner {
            state: LearnerState::build(&c.inner, c.trajectories_per_iteration, c.retrain)?,
            schedule: ExpertData,
        })
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> DataSchedule<S, P> for ExpertData {
    const NAME: &'static str = "bc";
    fn reset(&mut self) {}
    /// Roll out the expert, add the labelled states to the dataset (eq. 2.10's `d_{π*}`), retrain.
    fn step(
        &mut self,
        state: &mut LearnerState<S, P>,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        collect(
            problem,
            &Behaviour::Expert,
            state.trajectories,
            &mut state.data,
            ctx,
        )?;
        state.retrain_on_dataset(problem, ctx)
    }
}
