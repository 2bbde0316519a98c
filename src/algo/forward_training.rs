//! Forward training (Ross & Bagnell 2010; thesis §2.4.3): a non-stationary policy π₁, …, π_{T−1},
//! one per time step at which a loss is paid. At iteration t, roll out π₁..π_{t−1} for the first
//! t − 1 steps and the expert afterwards, label the state s_t of each trajectory, and train π_t on
//! those states (from θ₀). The horizon is learnt from the first roll-out
//! ([`IlProblem::labelled_states`]); the run finishes after T − 1 iterations.
//! [`crate::algo::Algorithm::theta`] is the newest π_t; [`crate::algo::Algorithm::outputs`] is the whole sequence.

use super::dataset::{InnerConfig, Retrain};
use super::learner::{DataSchedule, DatasetLearner, LearnerState};
use super::{AlgoError, StepContext, StepReport};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// Forward-training configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForwardTrainingConfig {
    /// Trajectories per time step (≥ 1).
    pub trajectories_per_iteration: u64,
    /// The supervised inner optimiser.
    pub inner: InnerConfig,
}

/// Forward training's schedule: the per-step policies trained so far and the horizon.
#[derive(Debug, Clone)]
pub struct PerStepPolicies<S> {
    policies: Vec<DVector<S>>,
    horizon: Option<usize>,
}

/// Forward training: a [`DatasetLearner`] with the [`PerStepPolicies`] schedule.
pub type ForwardTraining<S, P> = DatasetLearner<S, P, PerStepPolicies<S>>;

impl<S: Scalar, P: IlProblem<S> + ?Sized> DatasetLearner<S, P, PerStepPolicies<S>> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &ForwardTrainingConfig) -> Result<Self, AlgoError> {
        Ok(DatasetLearner {
            state: LearnerState::build(
                &c.inner,
                c.trajectories_per_iteration,
                Retrain::FromScratch,
            )?,
            schedule: PerStepPolicies {
                policies: Vec::new(),
                horizon: None,
            },
        })
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> DataSchedule<S, P> for PerStepPolicies<S> {
    const NAME: &'static str = "forward-training";
    fn reset(&mut self) {
        self.policies.clear();
        self.horizon = None;
    }
    /// Roll out π₁..π_{t−1} then the expert, keep the labelled state s_t of each trajectory, train
    /// π_t on them from θ₀; finished once every step of the horizon has a policy.
    fn step(
        &mut self,
        state: &mut LearnerState<S, P>,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        let t = self.policies.len(); // 0-based index of the step being trained
        if self.horizon.is_some_and(|h| t >= h) {
            return Err(AlgoError::State("forward training has trained every step"));
        }
        let behaviour = Behaviour::NonStationary(self.policies.iter().map(Some).collect());
        state.data.clear();
        for _ in 0..state.trajectories {
            let tau = problem.rollout(&behaviour, ctx.rng, ctx.cost)?;
            let states = problem.labelled_states(&tau);
            self.horizon.get_or_insert(states.len());
            if let Some(s) = states.into_iter().nth(t) {
                state.data.push(s);
            }
        }
        let report = state.retrain_on_dataset(problem, ctx)?;
        self.policies.push(state.theta.clone());
        Ok(if self.horizon.is_some_and(|h| self.policies.len() >= h) {
            report.finished()
        } else {
            report
        })
    }
    fn outputs(&self) -> Vec<DVector<S>> {
        self.policies.clone()
    }
}
