//! Behavioural cloning (§2.4.2, eq. 2.10): supervised learning on states visited by the expert,
//! `π̂_sup = argmin_π E_{s∼d_{π*}}[l(s, π)]`. One runner step rolls out the expert
//! `trajectories_per_iteration` times, adds the labelled states to the dataset and retrains with
//! the inner optimiser (so one step with enough trajectories is classic BC, and more steps show
//! BC's learning curve in the same cost units as the other learners).

use super::dataset::{Inner, InnerConfig, Retrain, collect, trajectories};
use super::{AlgoError, Algorithm, Ctx, StepReport, check_dim};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::Scalar;
use nalgebra::DVector;
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

/// Behavioural cloning.
#[derive(Debug)]
pub struct Bc<S: Scalar, P: IlProblem<S> + ?Sized> {
    n: u64,
    retrain: Retrain,
    inner: Inner<S>,
    data: Vec<P::Labelled>,
    theta0: DVector<S>,
    theta: DVector<S>,
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Bc<S, P> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &BcConfig) -> Result<Self, AlgoError> {
        Self::with_inner(c, Inner::new(&c.inner)?)
    }
    /// Build with an already-built inner optimiser.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] for zero trajectories per iteration.
    pub fn with_inner(c: &BcConfig, inner: Inner<S>) -> Result<Self, AlgoError> {
        Ok(Bc {
            n: trajectories(c.trajectories_per_iteration)?,
            retrain: c.retrain,
            inner,
            data: Vec::new(),
            theta0: DVector::from_vec(Vec::new()),
            theta: DVector::from_vec(Vec::new()),
        })
    }
    /// The aggregated dataset.
    pub fn dataset(&self) -> &[P::Labelled] {
        &self.data
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for Bc<S, P> {
    fn name(&self) -> &'static str {
        "bc"
    }
    fn init(&mut self, problem: &P, theta0: DVector<S>, _: &mut Ctx<'_>) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.data.clear();
        self.theta0 = theta0.clone();
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
        collect(problem, &Behaviour::Expert, self.n, &mut self.data, ctx)?;
        let start = match self.retrain {
            Retrain::FromScratch => &self.theta0,
            Retrain::WarmStart => &self.theta,
        };
        let (theta, loss) = self.inner.train(problem, start, &self.data, ctx)?;
        self.theta = theta;
        Ok(StepReport::new(None, Some(loss)))
    }
    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
