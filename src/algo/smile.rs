//! SMILe (Ross & Bagnell, *Efficient Reductions for Imitation Learning*, AISTATS 2010; thesis
//! Algorithm 1). Start from π⁰ = π*. At iteration i:
//!
//! 1. roll out the current stochastic mixture
//!    `π^{i−1} = (1−α)^{i−1} π* + α Σ_{j<i} (1−α)^{j−1} π̂^j` (a per-step mixture: the policy used at
//!    each step is drawn with these probabilities) and label the states with the expert;
//! 2. train a new component π̂^i on these data (the inner optimiser, from θ₀ or warm-started from
//!    π̂^{i−1});
//! 3. as the thesis's Algorithm 1 adds, aggregate D and train one policy θ on the whole D — this
//!    is the iterate the runner reports ([`crate::algo::Algorithm::theta`]).
//!
//! The components π̂^j are [`crate::algo::Algorithm::outputs`]; [`DatasetLearner::mixture_weights`] gives the final
//! mixture with the expert removed, `α(1−α)^{j−1}/(1 − (1−α)^N)`.

use super::dagger::beta_mixture;
use super::dataset::{InnerConfig, InnerOptimiser, Retrain, collect, trajectories};
use super::learner::{DataSchedule, DatasetLearner, LearnerState};
use super::{AlgoError, ConfigNumber, StepContext, StepReport, in_range};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::{BigRational, Scalar};
use nalgebra::DVector;
use num_traits::{One, ToPrimitive};
use serde::{Deserialize, Serialize};

/// SMILe configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SmileConfig {
    /// Mixing rate α ∈ (0, 1].
    pub alpha: ConfigNumber,
    /// Trajectories per iteration (≥ 1).
    pub trajectories_per_iteration: u64,
    /// Retrain components (and the distilled policy) from θ₀ or warm-start.
    pub retrain: Retrain,
    /// The supervised inner optimiser.
    pub inner: InnerConfig,
}

/// SMILe's schedule: the geometric mixture rate α and the components trained so far.
#[derive(Debug, Clone)]
pub struct SmileMixture<S> {
    alpha: BigRational,
    components: Vec<DVector<S>>,
}

/// SMILe (Algorithm 1): a [`DatasetLearner`] with the [`SmileMixture`] schedule.
pub type Smile<S, P> = DatasetLearner<S, P, SmileMixture<S>>;

impl<S: Scalar, P: IlProblem<S> + ?Sized> DatasetLearner<S, P, SmileMixture<S>> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &SmileConfig) -> Result<Self, AlgoError> {
        let inner = InnerOptimiser::new(&c.inner)?;
        let alpha = in_range(&c.alpha, "alpha", (0, true), (1, false))?;
        let n = trajectories(c.trajectories_per_iteration)?;
        Ok(DatasetLearner {
            state: LearnerState::new(n, c.retrain, inner),
            schedule: SmileMixture {
                alpha,
                components: Vec::new(),
            },
        })
    }

    /// The mixture over the learned components with the expert removed (exact):
    /// `α(1−α)^{j−1} / (1 − (1−α)^N)`, j = 1..N. Empty before the first iteration.
    pub fn mixture_weights(&self) -> Vec<BigRational> {
        let n = self.schedule.components.len();
        let keep = <BigRational as One>::one() - &self.schedule.alpha;
        let norm = <BigRational as One>::one() - num_traits::pow(keep.clone(), n);
        (0..n)
            .map(|j| &self.schedule.alpha * num_traits::pow(keep.clone(), j) / &norm)
            .collect()
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> DataSchedule<S, P> for SmileMixture<S> {
    const NAME: &'static str = "smile";
    fn reset(&mut self) {
        self.components.clear();
    }
    /// Roll out the current mixture, train a new component on the fresh data, aggregate, and
    /// train the reported policy on the whole dataset.
    fn step(
        &mut self,
        state: &mut LearnerState<S, P>,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
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
        collect(problem, &behaviour, state.trajectories, &mut fresh, ctx)?;
        let start = match (state.retrain, self.components.last()) {
            (Retrain::WarmStart, Some(last)) => last.clone(),
            _ => state.theta0.clone(),
        };
        let (component, _) = state.inner.train(problem, &start, &fresh, ctx)?;
        self.components.push(component);
        state.data.extend(fresh);
        state.retrain_on_dataset(problem, ctx)
    }
    fn outputs(&self) -> Vec<DVector<S>> {
        self.components.clone()
    }
}
