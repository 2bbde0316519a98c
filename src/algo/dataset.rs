//! What the dataset learners of §2.4 share: the supervised inner optimiser (any first-order
//! [`UpdateRule`] on the dataset loss through [`IlProblem::supervised`]), the retraining policy,
//! and data collection — all accounted in the same [`crate::problem::Cost`] units as the
//! oracle-driven optimisers (every per-example ∇l is one gradient evaluation).
//!
//! The dataset loss is the mean `L_D(θ) = (1/|B|) Σ_{s∈B} l(s, θ)` over the full dataset or a
//! minibatch B drawn uniformly with replacement from the run's RNG (indices do not depend on the
//! scalar).

use super::adam::{AdamConfig, AdamRule};
use super::rmsprop::{RmsPropConfig, RmsPropRule};
use super::sgd::{SgdRule, SgdStep};
use super::{AlgoError, StepContext, UpdateRule, check_finite, invalid};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::Scalar;
use nalgebra::DVector;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// The update rule of the inner optimiser.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "rule", rename_all = "kebab-case")]
pub enum RuleConfig {
    /// Gradient descent with the given step sizes.
    Sgd {
        /// Step sizes.
        step: SgdStep,
    },
    /// Adam (needs square roots).
    Adam(AdamConfig),
    /// RMSProp (needs square roots).
    RmsProp(RmsPropConfig),
}

/// The supervised inner optimiser: `iterations` updates of `rule` on the dataset loss.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InnerConfig {
    /// The update rule.
    pub rule: RuleConfig,
    /// Number of updates per training call (≥ 1).
    pub iterations: u64,
    /// Minibatch size (≥ 1), or `None` for full-batch gradients.
    pub batch_size: Option<u64>,
}

impl InnerConfig {
    /// Full-batch gradient descent with constant step `eta`, `iterations` updates.
    pub fn gradient_descent(eta: impl Into<super::ConfigNumber>, iterations: u64) -> Self {
        InnerConfig {
            rule: RuleConfig::Sgd {
                step: SgdStep::constant(eta),
            },
            iterations,
            batch_size: None,
        }
    }
}

/// How each retraining starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Retrain {
    /// From the initial θ₀ every time.
    FromScratch,
    /// From the current θ.
    WarmStart,
}

/// A built inner optimiser.
#[derive(Debug)]
pub struct InnerOptimiser<S> {
    rule: Box<dyn UpdateRule<S>>,
    iterations: u64,
    batch_size: Option<u64>,
}

impl<S: Scalar> InnerOptimiser<S> {
    /// Validate and build; Adam and RMSProp need a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] (zero iterations or batch size, bad rule parameters);
    /// [`AlgoError::NeedsRoots`] for Adam/RMSProp, or SGD with η₀/√k, without square roots.
    pub fn new(c: &InnerConfig) -> Result<Self, AlgoError> {
        if c.iterations == 0 {
            return Err(invalid("inner.iterations", "must be at least 1"));
        }
        if c.batch_size == Some(0) {
            return Err(invalid("inner.batch_size", "must be at least 1"));
        }
        let rule: Box<dyn UpdateRule<S>> = match &c.rule {
            RuleConfig::Sgd { step } => Box::new(SgdRule::new(step)?),
            RuleConfig::Adam(a) => Box::new(AdamRule::new(a)?),
            RuleConfig::RmsProp(r) => Box::new(RmsPropRule::new(r)?),
        };
        Ok(InnerOptimiser {
            rule,
            iterations: c.iterations,
            batch_size: c.batch_size,
        })
    }

    /// Train from `start` on `data`; returns the final θ and the dataset (or last minibatch)
    /// loss at the start of the last update.
    ///
    /// # Errors
    /// [`AlgoError::EmptyDataset`]; oracle failures; non-finite iterates.
    pub fn train<P: IlProblem<S> + ?Sized>(
        &mut self,
        problem: &mut P,
        start: &DVector<S>,
        data: &[P::Labelled],
        ctx: &mut StepContext<'_>,
    ) -> Result<(DVector<S>, S), AlgoError> {
        if data.is_empty() {
            return Err(AlgoError::EmptyDataset);
        }
        self.rule.reset();
        let mut theta = start.clone();
        let mut loss = S::zero();
        let mut gi = vec![S::zero(); theta.len()];
        for _ in 0..self.iterations {
            let batch: Vec<&P::Labelled> = match self.batch_size {
                None => data.iter().collect(),
                Some(b) => (0..b)
                    .map(|_| {
                        let example = &data[ctx.rng.random_range(0..data.len())];
                        super::prefetch::prefetch(example);
                        example
                    })
                    .collect(),
            };
            let inv = S::one() / S::from_i64(batch.len() as i64);
            let mut g = DVector::from_element(theta.len(), S::zero());
            let mut l = S::zero();
            for ex in batch {
                l += problem.supervised(&theta, ex, &mut gi, ctx.cost)?;
                // On slices, not nalgebra's strided iterator: the loop then runs in vector lanes.
                for (x, y) in g.as_mut_slice().iter_mut().zip(&gi) {
                    *x += y;
                }
            }
            let g = g.map(|x| x * &inv);
            loss = l * &inv;
            self.rule.apply(&mut theta, &g)?;
            check_finite(&theta, "θ (inner optimiser)")?;
        }
        Ok((theta, loss))
    }
}

/// Roll out `behaviour` `n` times and append the labelled states to `data`.
pub(crate) fn collect<S: Scalar, P: IlProblem<S> + ?Sized>(
    problem: &mut P,
    behaviour: &Behaviour<'_, S>,
    n: u64,
    data: &mut Vec<P::Labelled>,
    ctx: &mut StepContext<'_>,
) -> Result<(), AlgoError> {
    for _ in 0..n {
        let tau = problem.rollout(behaviour, ctx.rng, ctx.cost)?;
        data.extend(problem.labelled_states(&tau));
    }
    Ok(())
}

/// Validate a trajectory count.
pub(crate) fn trajectories(n: u64) -> Result<u64, AlgoError> {
    if n == 0 {
        Err(invalid("trajectories_per_iteration", "must be at least 1"))
    } else {
        Ok(n)
    }
}
