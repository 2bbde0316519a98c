//! Repeated risk minimisation, eq. 3.29 (Perdomo, Zrnic, Mendler-Dünner, Hardt, *Performative
//! Prediction*, ICML 2020): `θ_{k+1} = G(θ_k) = argmin_θ E_{τ∼p(·;θ_k)} Σ_t l(s_t, θ)`.
//!
//! * [`Rrm`]: the sampled map — roll out π_{θ_k} `trajectories_per_iteration` times and minimise
//!   the empirical loss on those states only (no aggregation) with the inner optimiser.
//! * [`ExactRrm`]: iterate a given population map G exactly (e.g. the toy engine's exact RRM map
//!   for the direct parameterisation, or the aliased two-state fixture of the algorithm tests); it
//!   uses no samples and costs nothing. Its map is a closure, so it is not part of
//!   [`crate::algo::AlgorithmConfig`] and cannot be replayed from JSON.
//!
//! Convergence to θ_PS needs the contraction modulus εβ/γ < 1 (erratum E15); on the M-family it is
//! exactly κ = (T−2)Δ/(T−1) (math.md §6).

use super::dataset::{InnerConfig, Retrain, collect};
use super::learner::{DataSchedule, DatasetLearner, LearnerState};
use super::{AlgoError, Algorithm, StepContext, StepReport, check_dim, check_finite};
use crate::problem::{Behaviour, IlProblem, OracleError};
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// Sampled RRM configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RrmConfig {
    /// Trajectories rolled out at θ_k per iteration (≥ 1).
    pub trajectories_per_iteration: u64,
    /// Retrain from θ₀ or warm-start from θ_k.
    pub retrain: Retrain,
    /// The supervised inner optimiser (the argmin of eq. 3.29).
    pub inner: InnerConfig,
}

/// Sampled RRM's schedule: every iteration replaces the dataset by roll-outs of the current
/// learner.
#[derive(Debug, Clone, Copy, Default)]
pub struct OnPolicyData;

/// Sampled RRM (eq. 3.29 with an empirical risk): a [`DatasetLearner`] with the
/// [`OnPolicyData`] schedule.
pub type Rrm<S, P> = DatasetLearner<S, P, OnPolicyData>;

impl<S: Scalar, P: IlProblem<S> + ?Sized> DatasetLearner<S, P, OnPolicyData> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &RrmConfig) -> Result<Self, AlgoError> {
        Ok(DatasetLearner {
            state: LearnerState::build(&c.inner, c.trajectories_per_iteration, c.retrain)?,
            schedule: OnPolicyData,
        })
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> DataSchedule<S, P> for OnPolicyData {
    const NAME: &'static str = "rrm";
    fn reset(&mut self) {}
    /// Roll out π_{θ_k}, keep only those labelled states, minimise the empirical risk on them.
    fn step(
        &mut self,
        state: &mut LearnerState<S, P>,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        state.data.clear();
        collect(
            problem,
            &Behaviour::Learner(&state.theta),
            state.trajectories,
            &mut state.data,
            ctx,
        )?;
        state.retrain_on_dataset(problem, ctx)
    }
}

/// RRM with an exact population map `G` (eq. 3.29 without sampling).
pub struct ExactRrm<S, G> {
    map: G,
    theta: DVector<S>,
}

impl<S, G> std::fmt::Debug for ExactRrm<S, G>
where
    S: std::fmt::Debug,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExactRrm")
            .field("theta", &self.theta)
            .finish()
    }
}

impl<S: Scalar, G> ExactRrm<S, G>
where
    G: Fn(&DVector<S>) -> Result<DVector<S>, OracleError>,
{
    /// Iterate the population map `map`.
    pub fn new(map: G) -> Self {
        ExactRrm {
            map,
            theta: DVector::from_vec(Vec::new()),
        }
    }
}

impl<S: Scalar, G, P: IlProblem<S> + ?Sized> Algorithm<S, P> for ExactRrm<S, G>
where
    G: Fn(&DVector<S>) -> Result<DVector<S>, OracleError>,
{
    fn name(&self) -> &'static str {
        "exact-rrm"
    }
    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        _: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, _: &mut P, _: &mut StepContext<'_>) -> Result<StepReport<S>, AlgoError> {
        let next = (self.map)(&self.theta)?;
        check_finite(&next, "θ")?;
        self.theta = next;
        Ok(StepReport::new(None, None))
    }
    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
