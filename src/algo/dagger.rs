//! DAgger (Ross, Gordon, Bagnell, AISTATS 2011; thesis Algorithm 2, eq. 3.30): at iteration i
//! roll out the β-mixture `π_i = β_i π* + (1 − β_i) π̂_i` (per step, the expert acts with
//! probability β_i), label the visited states with the expert, aggregate `D ← D ∪ D_i`, and
//! retrain on D (from θ₀ or warm-started). β schedules: constant, linear
//! `β_i = max(0, 1 − (i−1)/n)`, exponential `β_i = pⁱ⁻¹` (Ross et al.'s choice). With β ≡ 0 and
//! an exact argmin inner solver this is the map G_DA of eq. 3.30; without aggregation it is RRM
//! (eq. 3.29).

use super::dataset::{Inner, InnerConfig, Retrain, collect, trajectories};
use super::{AlgoError, Algorithm, Ctx, Num, StepReport, check_dim, in_range, invalid};
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
        beta: Num,
    },
    /// `β_i = max(0, 1 − (i−1)/iterations)`.
    Linear {
        /// Iterations to reach 0 (≥ 1).
        iterations: u64,
    },
    /// `β_i = p^{i−1}`, p ∈ [0, 1].
    Exponential {
        /// p.
        p: Num,
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

/// DAgger.
#[derive(Debug)]
pub struct Dagger<S: Scalar, P: IlProblem<S> + ?Sized> {
    n: u64,
    beta: Beta,
    aggregate: bool,
    retrain: Retrain,
    inner: Inner<S>,
    data: Vec<P::Labelled>,
    i: u64,
    theta0: DVector<S>,
    theta: DVector<S>,
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Dagger<S, P> {
    /// Validate and build; an Adam or RMSProp inner optimiser needs a scalar with roots.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`].
    pub fn new(c: &DaggerConfig) -> Result<Self, AlgoError> {
        Self::with_inner(c, Inner::new(&c.inner)?)
    }
    /// Build with an already-built inner optimiser.
    ///
    /// # Errors
    /// As [`Dagger::new`].
    pub fn with_inner(c: &DaggerConfig, inner: Inner<S>) -> Result<Self, AlgoError> {
        Ok(Dagger {
            n: trajectories(c.trajectories_per_iteration)?,
            beta: Beta::new(&c.beta)?,
            aggregate: c.aggregate,
            retrain: c.retrain,
            inner,
            data: Vec::new(),
            i: 0,
            theta0: DVector::from_vec(Vec::new()),
            theta: DVector::from_vec(Vec::new()),
        })
    }
    /// β_i of the next iteration, exactly.
    pub fn next_beta(&self) -> BigRational {
        self.beta.at(self.i + 1)
    }
    /// The (aggregated) dataset.
    pub fn dataset(&self) -> &[P::Labelled] {
        &self.data
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for Dagger<S, P> {
    fn name(&self) -> &'static str {
        "dagger"
    }
    fn init(&mut self, problem: &P, theta0: DVector<S>, _: &mut Ctx<'_>) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.data.clear();
        self.i = 0;
        self.theta0 = theta0.clone();
        self.theta = theta0;
        Ok(())
    }
    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError> {
        self.i += 1;
        let beta = self.beta.at(self.i);
        if !self.aggregate {
            self.data.clear();
        }
        collect(
            problem,
            &beta_mixture(&beta, &self.theta),
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
