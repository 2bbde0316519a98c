//! The contract between an imitation-learning problem and the algorithms: the gradient oracle of
//! eq. 3.15 and what it costs.
//!
//! An [`IlProblem`] knows how to roll out a behaviour (the learner π_θ, the expert π*, or a mixture
//! of them), label the visited states with the expert, and evaluate on a sampled trajectory
//!
//! * the estimator of eq. 3.15 (causal form, math.md §1.1)
//!   `g(θ, τ) = Σ_{t=1}^{T−1} [∇l(s_t, θ) + l(s_t, θ) Σ_{i<t} ∇log π_θ(a_i|s_i)]`,
//!   or its full (non-causal) form, both unbiased for ∇F(θ) when τ ∼ p(·; θ) (eqs. 3.16/3.18);
//! * the importance-weighted "old point" estimate `w·g(θ_old, τ)` with τ ∼ p(·; θ_new) used by
//!   IS-STORM (math.md §4), with whole-trajectory or per-decision weights;
//! * the supervised loss `l(s, θ)` and `∇l(s, θ)` on labelled states, for the dataset learners.
//!
//! Every call adds what it cost to a [`Cost`], so "gradient calls" (Tables 4.1, 4.3) mean one thing
//! across algorithms.

use crate::scalar::{Scalar, Undecidable};
use nalgebra::DVector;
use serde::{Deserialize, Serialize};
use std::ops::{Add, AddAssign};

/// The kit's RNG: ChaCha8, seeded and serialisable so that every run can be replayed.
pub type KitRng = rand_chacha::ChaCha8Rng;

/// What an oracle call consumed. The units are the same for every algorithm.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Cost {
    /// Trajectories rolled out in the environment.
    pub trajectories: u64,
    /// Environment steps taken (states visited) during those roll-outs.
    pub env_steps: u64,
    /// Per-state gradient evaluations (∇l or ∇log π at one state): the "gradient calls" of the
    /// thesis's Tables 4.1 and 4.3.
    pub gradient_evaluations: u64,
    /// States labelled by the expert.
    pub expert_queries: u64,
}

impl Add for Cost {
    type Output = Cost;
    fn add(self, o: Cost) -> Cost {
        Cost {
            trajectories: self.trajectories + o.trajectories,
            env_steps: self.env_steps + o.env_steps,
            gradient_evaluations: self.gradient_evaluations + o.gradient_evaluations,
            expert_queries: self.expert_queries + o.expert_queries,
        }
    }
}

impl AddAssign for Cost {
    fn add_assign(&mut self, o: Cost) {
        *self = *self + o;
    }
}

/// Which form of the eq. 3.15 estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EstimatorForm {
    /// `Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]` (eq. 3.15 as derived; lower variance).
    Causal,
    /// `Σ_t ∇l_t + (Σ_t l_t) Σ_{i≤T−2} ψ_i` (same mean, math.md §1.1).
    Full,
}

/// Importance weights of the IS-STORM correction (math.md §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Weighting {
    /// `w = Π_{i=1}^{T−2} π_old(a_i|s_i)/π_new(a_i|s_i)` on the whole estimate.
    Trajectory,
    /// Term t weighted by `w_{1:t−1}` only (lower variance, also exactly unbiased).
    PerDecision,
}

/// Who acts during a roll-out.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Behaviour<'a, S> {
    /// The learner π_θ.
    Learner(&'a DVector<S>),
    /// The expert π* (behavioural cloning's data).
    Expert,
    /// At every step, the expert acts with probability `expert_weight`, otherwise learner `j` with
    /// probability `learners[j].0` (weights sum to 1). DAgger's β-mixture is
    /// `Mixture { expert_weight: β, learners: [(1 − β, θ)] }`; SMILe's policy is a longer mixture.
    Mixture {
        /// Probability that the expert acts.
        expert_weight: f64,
        /// Learner policies with their probabilities.
        learners: Vec<(f64, &'a DVector<S>)>,
    },
    /// A non-stationary policy (forward training): at step t (0-based) act with `per_step[t]`
    /// (`None` = the expert); steps beyond the list use the expert.
    NonStationary(Vec<Option<&'a DVector<S>>>),
}

/// Why an oracle call failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OracleError {
    /// θ has the wrong length.
    #[error("θ has {got} entries, the policy needs {expected}")]
    Dimension {
        /// Entries the policy needs.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// θ is outside the policy's domain (e.g. the direct parameterisation off the open simplex).
    #[error("θ is outside the policy's domain: {0}")]
    Domain(String),
    /// A value that must be finite is not (NaN, ∞, or an unbounded interval).
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// A probability that divides (a score, an importance weight) is zero.
    #[error("zero probability in {0}")]
    ZeroProbability(&'static str),
    /// Interval arithmetic could not decide a branch.
    #[error(transparent)]
    Undecidable(#[from] Undecidable),
    /// The trajectory does not belong to this problem (wrong length, state or action out of range).
    #[error("invalid trajectory: {0}")]
    Trajectory(String),
    /// The behaviour is invalid (weights not in [0, 1] or not summing to 1, …).
    #[error("invalid behaviour: {0}")]
    Behaviour(String),
    /// The environment or the expert failed.
    #[error("environment: {0}")]
    Environment(String),
    /// A baseline that cannot be used here (see [`crate::baseline`]): an invalid configuration,
    /// or a time-indexed list shorter than a trajectory's scored decisions.
    #[error("baseline: {0}")]
    Baseline(String),
}

/// [`IlProblem::estimate_with_loss`]'s default: [`IlProblem::estimate`], then
/// [`IlProblem::trajectory_loss`] (also the route of a problem whose own pass does not cover a
/// form or a kind of baseline).
///
/// # Errors
/// As [`IlProblem::estimate`], then [`IlProblem::trajectory_loss`].
pub(crate) fn estimate_then_loss<S: Scalar, P: IlProblem<S> + ?Sized>(
    problem: &mut P,
    theta: &DVector<S>,
    trajectory: &P::Trajectory,
    form: EstimatorForm,
    cost: &mut Cost,
) -> Result<(DVector<S>, S), OracleError> {
    let g = problem.estimate(theta, trajectory, form, cost)?;
    let loss = problem.trajectory_loss(theta, trajectory)?;
    Ok((g, loss))
}

/// An imitation-learning problem: environment + expert + learner policy class + loss.
///
/// Generic over the scalar `S` of θ and of the returned gradients. Sampling uses an RNG owned by
/// the caller (the runner), so runs are reproducible.
///
/// The oracle's calls ([`IlProblem::rollout`], [`IlProblem::estimate`],
/// [`IlProblem::estimate_with_loss`], [`IlProblem::weighted_estimate`]) take `&mut self`: an
/// oracle may carry state from one call to the next, in plain fields (a baseline learned from
/// earlier trajectories, [`crate::baseline::Baselined`]), and the signature says so. Whoever
/// drives a run owns the oracle for it (the runner lends it to the algorithm), so two runs never
/// share that state by accident. The tasks and the toy MDPs keep none: a copy of one gives the
/// same estimates, which is how code that samples on several threads gives each thread its own.
pub trait IlProblem<S: Scalar> {
    /// A sampled trajectory with its expert labels.
    type Trajectory: Clone + std::fmt::Debug;
    /// A state together with its expert label (one supervised example).
    type Labelled: Clone + std::fmt::Debug;

    /// Number of policy parameters `d`.
    fn dim(&self) -> usize;

    /// Roll out `behaviour`, labelling every visited state with the expert.
    ///
    /// # Errors
    /// [`OracleError`] for a θ of the wrong length or outside the policy's domain, an invalid
    /// behaviour, or a sampling decision that interval arithmetic cannot make.
    fn rollout(
        &mut self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<Self::Trajectory, OracleError>;

    /// The estimator `g(θ, τ)` of eq. 3.15 in the given form.
    ///
    /// # Errors
    /// As [`IlProblem::rollout`], plus [`OracleError::Trajectory`] for a foreign trajectory.
    fn estimate(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError>;

    /// [`IlProblem::estimate`] and [`IlProblem::trajectory_loss`] at the same θ on the same
    /// trajectory, in that order: the oracle's gradient and its loss estimate. The default calls
    /// the two; a problem whose estimator pass computes every `l(s_t, θ)` anyway returns the loss
    /// from that pass (the same value, without a second pass).
    ///
    /// # Errors
    /// As [`IlProblem::estimate`], then [`IlProblem::trajectory_loss`].
    fn estimate_with_loss(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<(DVector<S>, S), OracleError> {
        estimate_then_loss(self, theta, trajectory, form, cost)
    }

    /// The importance-weighted old-point estimate of math.md §4: `w · g(θ_old, τ)` where τ was
    /// sampled at `theta_new` and `w` is the likelihood ratio p(τ; θ_old)/p(τ; θ_new)
    /// (whole-trajectory or per-decision). Unbiased for ∇F(θ_old) (identity I3).
    ///
    /// # Errors
    /// As [`IlProblem::estimate`], plus [`OracleError::ZeroProbability`] if π_new vanishes on τ.
    fn weighted_estimate(
        &mut self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &Self::Trajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError>;

    /// `Σ_{t=1}^{T−1} l(s_t, θ)` on a trajectory: an unbiased estimate of F(θ) when τ ∼ p(·; θ).
    ///
    /// # Errors
    /// As [`IlProblem::estimate`].
    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
    ) -> Result<S, OracleError>;

    /// The labelled states of a trajectory at which a loss is paid (t = 1..T−1), in order.
    fn labelled_states(&self, trajectory: &Self::Trajectory) -> Vec<Self::Labelled>;

    /// The supervised loss `l(s, θ)` at one labelled state, with its gradient `∇_θ l(s, θ)`
    /// written into `grad` (length [`IlProblem::dim`]; one gradient evaluation). The caller owns
    /// `grad`, so a loop over a dataset allocates nothing per example.
    ///
    /// # Errors
    /// As [`IlProblem::estimate`], and [`OracleError::Dimension`] for a `grad` of the wrong
    /// length.
    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &Self::Labelled,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError>;
}
