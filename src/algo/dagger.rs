//! DAgger (Ross, Gordon, Bagnell, AISTATS 2011; thesis Algorithm 2, eq. 3.30): at iteration i
//! roll out the β-mixture `π_i = β_i π* + (1 − β_i) π̂_i` (per step, the expert acts with
//! probability β_i), label the visited states with the expert, aggregate `D ← D ∪ D_i`, and
//! retrain on D (from θ₀ or warm-started). β schedules: constant, linear
//! `β_i = max(0, 1 − (i−1)/n)`, exponential `β_i = pⁱ⁻¹` (Ross et al.'s choice). With β ≡ 0 and
//! an exact argmin inner solver this is the map G_DA of eq. 3.30; without aggregation it is RRM
//! (eq. 3.29).

use super::dataset::{InnerConfig, Retrain, collect};
use super::learner::{DataSchedule, DatasetLearner, LearnerState};
use super::{AlgoError, ConfigNumber, StepContext, StepReport, in_range, invalid};
use crate::problem::{Behaviour, IlProblem};
use crate::scalar::{BigRational, Scalar};
use nalgebra::DVector;
use num_traits::{One, ToPrimitive, Zero};
use serde::{Deserialize, Serialize};

/// The β_i schedule (i = 1, 2, …).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum BetaSchedule {
    /// `β_i = beta` ∈ [0, 1].
    Constant {
        /// β.
        beta: ConfigNumber,
    },
    /// `β_i = max(0, 1 − (i−1)/iterations)`.
    Linear {
        /// Iterations to reach 0 (≥ 1).
        iterations: u64,
    },
    /// `β_i = p^{i−1}`, p ∈ [0, 1].
    Exponential {
        /// p.
        p: ConfigNumber,
    },
}

#[derive(Debug, Clone)]
enum Beta {
    Constant(BigRational),
    Linear(u64),
    Exponential(BigRational),
}

impl Beta {
    fn new(s: &BetaSchedule) -> Result<Self, AlgoError> {
        Ok(match s {
            BetaSchedule::Constant { beta } => {
                Beta::Constant(in_range(beta, "beta", (0, false), (1, false))?)
            }
            BetaSchedule::Linear { iterations } => {
                if *iterations == 0 {
                    return Err(invalid("beta.iterations", "must be at least 1"));
                }
                Beta::Linear(*iterations)
            }
            BetaSchedule::Exponential { p } => {
                Beta::Exponential(in_range(p, "beta.p", (0, false), (1, false))?)
            }
        })
    }
    /// β_i exactly.
    fn at(&self, i: u64) -> BigRational {
        match self {
            Beta::Constant(b) => b.clone(),
            Beta::Linear(n) => {
                let v = <BigRational as One>::one()
                    - BigRational::new((i as i64 - 1).into(), (*n as i64).into());
                if v < <BigRational as Zero>::zero() {
                    <BigRational as Zero>::zero()
                } else {
                    v
                }
            }
            Beta::Exponential(p) => num_traits::pow(p.clone(), (i - 1) as usize),
        }
    }
}

/// The behaviour `β π* + (1 − β) π_θ`.
pub(crate) fn beta_mixture<'a, S: Scalar>(
    beta: &BigRational,
    theta: &'a DVector<S>,
) -> Behaviour<'a, S> {
    if beta.is_zero() {
        Behaviour::Learner(theta)
    } else if beta.is_one() {
        Behaviour::Expert
    } else {
        let b = ToPrimitive::to_f64(beta).unwrap_or(0.0);
        Behaviour::Mixture {
            expert_weight: b,
            learners: vec![(1.0 - b, theta)],
        }
    }
}

/// DAgger configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DaggerConfig {
    /// Trajectories rolled out per iteration (≥ 1).
    pub trajectories_per_iteration: u64,
    /// The β_i schedule.
    pub beta: BetaSchedule,
    /// Aggregate the datasets (DAgger) or keep only the newest (RRM-like).
    pub aggregate: bool,
    /// Retrain from θ₀ or warm-start.
    pub retrain: Retrain,
    /// The supervised inner optimiser.
    pub inner: InnerConfig,
}

/// DAgger's schedule: the β_i mixture of expert and learner, the datasets aggregated or not.
#[derive(Debug, Clone)]
pub struct BetaMixing {
    beta: Beta,
    aggregate: bool,
    i: u64,
}

/// DAgger (Algorithm 2): a [`DatasetLearner`] with the [`BetaMixing`] schedule.
pub type Dagger<S, P> = DatasetLearner<S, P, BetaMixing>;

impl<S: Scalar, P: IlProblem<S> + ?Sized> DatasetLearner<S, P, BetaMixing> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &DaggerConfig) -> Result<Self, AlgoError> {
        Ok(DatasetLearner {
            state: LearnerState::build(&c.inner, c.trajectories_per_iteration, c.retrain)?,
            schedule: BetaMixing {
                beta: Beta::new(&c.beta)?,
                aggregate: c.aggregate,
                i: 0,
            },
        })
    }
    /// β_i of the next iteration, exactly.
    pub fn next_beta(&self) -> BigRational {
        self.schedule.beta.at(self.schedule.i + 1)
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> DataSchedule<S, P> for BetaMixing {
    const NAME: &'static str = "dagger";
    fn reset(&mut self) {
        self.i = 0;
    }
    /// Roll out `β_i π* + (1 − β_i) π_θ`, add (or, without aggregation, replace) the labelled
    /// states, retrain.
    fn step(
        &mut self,
        state: &mut LearnerState<S, P>,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        self.i += 1;
        let beta = self.beta.at(self.i);
        if !self.aggregate {
            state.data.clear();
        }
        collect(
            problem,
            &beta_mixture(&beta, &state.theta),
            state.trajectories,
            &mut state.data,
            ctx,
        )?;
        state.retrain_on_dataset(problem, ctx)
    }
}
