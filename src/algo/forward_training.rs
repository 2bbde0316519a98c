//! Forward training (Ross & Bagnell 2010; thesis §2.4.3): a non-stationary policy π₁, …, π_{T−1},
//! one per time step at which a loss is paid. At iteration t, roll out π₁..π_{t−1} for the first
//! t − 1 steps and the expert afterwards, label the state s_t of each trajectory, and train π_t on
//! those states (from θ₀). The horizon is learnt from the first roll-out
//! ([`IlProblem::labelled_states`]); the run finishes after T − 1 iterations.
//! [`Algorithm::theta`] is the newest π_t; [`Algorithm::outputs`] is the whole sequence.

use super::dataset::{Inner, InnerConfig, trajectories};
use super::{AlgoError, Algorithm, Ctx, StepReport, check_dim};
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

/// Forward training.
#[derive(Debug)]
pub struct ForwardTraining<S: Scalar> {
    n: u64,
    inner: Inner<S>,
    policies: Vec<DVector<S>>,
    horizon: Option<usize>,
    theta0: DVector<S>,
    theta: DVector<S>,
}

impl<S: Scalar> ForwardTraining<S> {
    /// The current iterate (as [`Algorithm::theta`], without naming the problem type).
    pub fn theta(&self) -> &DVector<S> {
        &self.theta
    }

    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &ForwardTrainingConfig) -> Result<Self, AlgoError> {
        Self::with_inner(c, Inner::new(&c.inner)?)
    }
    /// Build with an already-built inner optimiser.
    ///
    /// # Errors
    /// As [`ForwardTraining::new`].
    pub fn with_inner(c: &ForwardTrainingConfig, inner: Inner<S>) -> Result<Self, AlgoError> {
        Ok(ForwardTraining {
            n: trajectories(c.trajectories_per_iteration)?,
            inner,
            policies: Vec::new(),
            horizon: None,
            theta0: DVector::from_vec(Vec::new()),
            theta: DVector::from_vec(Vec::new()),
        })
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for ForwardTraining<S> {
    fn name(&self) -> &'static str {
        "forward-training"
    }
    fn init(&mut self, problem: &P, theta0: DVector<S>, _: &mut Ctx<'_>) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.policies.clear();
        self.horizon = None;
        self.theta0 = theta0.clone();
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
        let t = self.policies.len(); // 0-based index of the step being trained
        if self.horizon.is_some_and(|h| t >= h) {
            return Err(AlgoError::State("forward training has trained every step"));
        }
        let behaviour = Behaviour::NonStationary(self.policies.iter().map(Some).collect());
        let mut data = Vec::new();
        for _ in 0..self.n {
            let tau = problem.rollout(&behaviour, ctx.rng, ctx.cost)?;
            let states = problem.labelled_states(&tau);
            self.horizon.get_or_insert(states.len());
            if let Some(s) = states.into_iter().nth(t) {
                data.push(s);
            }
        }
        let (theta, loss) = self.inner.train(problem, &self.theta0, &data, ctx)?;
        self.policies.push(theta.clone());
        self.theta = theta;
        let report = StepReport::new(None, Some(loss));
        Ok(if self.horizon.is_some_and(|h| self.policies.len() >= h) {
            report.finished()
        } else {
            report
        })
    }
    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
    fn outputs(&self) -> Vec<DVector<S>> {
        self.policies.clone()
    }
}
