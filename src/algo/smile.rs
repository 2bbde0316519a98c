//! SMILe (Ross & Bagnell, *Efficient Reductions for Imitation Learning*, AISTATS 2010; thesis
//! Algorithm 1). Start from π⁰ = π*. At iteration i:
//!
//! 1. roll out the current stochastic mixture
//!    `π^{i−1} = (1−α)^{i−1} π* + α Σ_{j<i} (1−α)^{j−1} π̂^j` (a per-step mixture: the policy used at
//!    each step is drawn with these probabilities) and label the states with the expert;
//! 2. train a new component π̂^i on these data (the inner optimiser, from θ₀ or warm-started from
//!    π̂^{i−1});
//! 3. as the thesis's Algorithm 1 adds, aggregate D and train one policy θ on the whole D — this
//!    is the iterate the runner reports ([`Algorithm::theta`]).
//!
//! The components π̂^j are [`Algorithm::outputs`]; [`Smile::mixture_weights`] gives the final
//! mixture with the expert removed, `α(1−α)^{j−1}/(1 − (1−α)^N)`.

use super::dagger::beta_mixture;
use super::dataset::{Inner, InnerConfig, Retrain, collect, trajectories};
use super::{AlgoError, Algorithm, Ctx, Num, StepReport, check_dim, in_range};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::{BigRational, Scalar};
use nalgebra::DVector;
use num_traits::{One, ToPrimitive};
use serde::{Deserialize, Serialize};

/// SMILe configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SmileConfig {
    /// Mixing rate α ∈ (0, 1].
    pub alpha: Num,
    /// Trajectories per iteration (≥ 1).
    pub trajectories_per_iteration: u64,
    /// Retrain components (and the distilled policy) from θ₀ or warm-start.
    pub retrain: Retrain,
    /// The supervised inner optimiser.
    pub inner: InnerConfig,
}

/// SMILe.
#[derive(Debug)]
pub struct Smile<S: Scalar, P: IlProblem<S> + ?Sized> {
    alpha: BigRational,
    n: u64,
    retrain: Retrain,
    inner: Inner<S>,
    data: Vec<P::Labelled>,
    components: Vec<DVector<S>>,
    theta0: DVector<S>,
    theta: DVector<S>,
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Smile<S, P> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &SmileConfig) -> Result<Self, AlgoError> {
        Self::with_inner(c, Inner::new(&c.inner)?)
    }
    /// Build with an already-built inner optimiser.
    ///
    /// # Errors
    /// As [`Smile::new`].
    pub fn with_inner(c: &SmileConfig, inner: Inner<S>) -> Result<Self, AlgoError> {
        Ok(Smile {
            alpha: in_range(&c.alpha, "alpha", (0, true), (1, false))?,
            n: trajectories(c.trajectories_per_iteration)?,
            retrain: c.retrain,
            inner,
            data: Vec::new(),
            components: Vec::new(),
            theta0: DVector::from_vec(Vec::new()),
            theta: DVector::from_vec(Vec::new()),
        })
    }

    /// The mixture over the learned components with the expert removed (exact):
    /// `α(1−α)^{j−1} / (1 − (1−α)^N)`, j = 1..N. Empty before the first iteration.
    pub fn mixture_weights(&self) -> Vec<BigRational> {
        let n = self.components.len();
        let keep = <BigRational as One>::one() - &self.alpha;
        let norm = <BigRational as One>::one() - num_traits::pow(keep.clone(), n);
        (0..n)
            .map(|j| &self.alpha * num_traits::pow(keep.clone(), j) / &norm)
            .collect()
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for Smile<S, P> {
    fn name(&self) -> &'static str {
        "smile"
    }
    fn init(&mut self, problem: &P, theta0: DVector<S>, _: &mut Ctx<'_>) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.data.clear();
        self.components.clear();
        self.theta0 = theta0.clone();
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
        let i = self.components.len(); // components so far = i − 1 in 1-based terms
        let keep = <BigRational as One>::one() - &self.alpha;
        let expert = num_traits::pow(keep.clone(), i);
        let behaviour = if i == 0 {
            Behaviour::Expert
        } else if i == 1 {
            beta_mixture(&expert, &self.components[0])
        } else {
            Behaviour::Mixture {
                expert_weight: ToPrimitive::to_f64(&expert).unwrap_or(0.0),
                learners: self
                    .components
                    .iter()
                    .enumerate()
                    .map(|(j, th)| {
                        let w = &self.alpha * num_traits::pow(keep.clone(), j);
                        (ToPrimitive::to_f64(&w).unwrap_or(0.0), th)
                    })
                    .collect(),
            }
        };
        let mut fresh = Vec::new();
        collect(problem, &behaviour, self.n, &mut fresh, ctx)?;
        let start = match (self.retrain, self.components.last()) {
            (Retrain::WarmStart, Some(last)) => last.clone(),
            _ => self.theta0.clone(),
        };
        let (component, _) = self.inner.train(problem, &start, &fresh, ctx)?;
        self.components.push(component);
        self.data.extend(fresh);
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
    fn outputs(&self) -> Vec<DVector<S>> {
        self.components.clone()
    }
}
