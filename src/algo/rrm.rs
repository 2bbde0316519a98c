//! Repeated risk minimisation, eq. 3.29 (Perdomo, Zrnic, Mendler-Dünner, Hardt, *Performative
//! Prediction*, ICML 2020): `θ_{k+1} = G(θ_k) = argmin_θ E_{τ∼p(·;θ_k)} Σ_t l(s_t, θ)`.
//!
//! * [`Rrm`]: the sampled map — roll out π_{θ_k} `trajectories_per_iteration` times and minimise
//!   the empirical loss on those states only (no aggregation) with the inner optimiser.
//! * [`ExactRrm`]: iterate a given population map G exactly (e.g. the toy engine's exact RRM map
//!   for the direct parameterisation, or [`crate::algo::fixture::AliasedTwoState::rrm_map`]); it
//!   uses no samples and costs nothing. Its map is a closure, so it is not part of
//!   [`crate::algo::AlgorithmConfig`] and cannot be replayed from JSON.
//!
//! Convergence to θ_PS needs the contraction modulus εβ/γ < 1 (erratum E15); on the M-family it is
//! exactly κ = (T−2)Δ/(T−1) (math.md §6).

use super::dataset::{Inner, InnerConfig, Retrain, collect, trajectories};
use super::{AlgoError, Algorithm, Ctx, StepReport, check_dim, check_finite};
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

/// Sampled RRM (eq. 3.29 with an empirical risk).
#[derive(Debug)]
pub struct Rrm<S: Scalar, P: IlProblem<S> + ?Sized> {
    n: u64,
    retrain: Retrain,
    inner: Inner<S>,
    data: Vec<P::Labelled>,
    theta0: DVector<S>,
    theta: DVector<S>,
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Rrm<S, P> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &RrmConfig) -> Result<Self, AlgoError> {
        Self::with_inner(c, Inner::new(&c.inner)?)
    }
    /// Build with an already-built inner optimiser.
    ///
    /// # Errors
    /// As [`Rrm::new`].
    pub fn with_inner(c: &RrmConfig, inner: Inner<S>) -> Result<Self, AlgoError> {
        Ok(Rrm {
            n: trajectories(c.trajectories_per_iteration)?,
            retrain: c.retrain,
            inner,
            data: Vec::new(),
            theta0: DVector::from_vec(Vec::new()),
            theta: DVector::from_vec(Vec::new()),
        })
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for Rrm<S, P> {
    fn name(&self) -> &'static str {
        "rrm"
    }
    fn init(&mut self, problem: &P, theta0: DVector<S>, _: &mut Ctx<'_>) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.theta0 = theta0.clone();
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
        self.data.clear();
        collect(
            problem,
            &Behaviour::Learner(&self.theta),
            self.n,
            &mut self.data,
            ctx,
        )?;
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
    fn init(&mut self, problem: &P, theta0: DVector<S>, _: &mut Ctx<'_>) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, _: &P, _: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
        let next = (self.map)(&self.theta)?;
        check_finite(&next, "θ")?;
        self.theta = next;
        Ok(StepReport::new(None, None))
    }
    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
