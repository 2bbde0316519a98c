//! Environments as imitation-learning problems: the eq. 3.15 oracle on the real tasks.
//!
//! A [`Task`] is an episodic simulator with an expert (CartPole with the LQR expert, the obstacle
//! task with the velocity-obstacle expert); a [`crate::policy::Policy`] is the learner over the
//! task's features. [`TaskProblem`] joins them into an [`IlProblem`]: roll-outs with seeded RNGs,
//! expert labels at every visited state, and on a trajectory with decisions t = 1..n
//!
//! * the causal estimator of eq. 3.15, `g = Σ_t ∇l_t + Σ_{i<n} ψ_i Σ_{t>i} l_t`;
//! * the full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i`;
//! * the importance-weighted old-point estimates of math.md §4, with per-decision ratios
//!   `π_old(a_i|s_i)/π_new(a_i|s_i) = exp(log π_old − log π_new)` ([`LikelihoodRatio`]).
//!
//! Episodes end when the task says so (termination or truncation); the objective is
//! F(θ) = E Σ_{t=1}^{n} l(s_t, θ) with the random episode length n (a stopping time of the state
//! process), for which eq. 3.15 is still unbiased (states after the end carry no loss).

pub mod cartpole;
pub mod obstacle;

use crate::policy::{LikelihoodRatio, Policy, PolicyError};
use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use crate::scalar::{Real, Scalar};
use nalgebra::DVector;
use rand::Rng;
use std::borrow::Borrow;

/// An episodic environment with an expert, over the scalar `S`.
pub trait Task<S: Scalar> {
    /// The per-episode simulator state.
    type Episode: Clone;
    /// The expert's label at a state (what the loss compares the policy's output with).
    type Label: Clone + std::fmt::Debug;
    /// An action in the environment.
    type Action: Clone + std::fmt::Debug;

    /// Start an episode (seeded reset).
    ///
    /// # Errors
    /// [`OracleError::Environment`] if the environment cannot start.
    fn start(&self, rng: &mut KitRng) -> Result<Self::Episode, OracleError>;
    /// The learner's features φ(s) of the current state.
    fn features(&self, episode: &Self::Episode) -> Vec<S>;
    /// The expert's label and the action the expert would take at the current state.
    ///
    /// # Errors
    /// [`OracleError`] if the expert cannot decide (undecidable comparison, no solution).
    fn expert(&self, episode: &Self::Episode) -> Result<(Self::Label, Self::Action), OracleError>;
    /// Apply an action; `Ok(true)` when the episode is over (terminated or truncated).
    ///
    /// # Errors
    /// [`OracleError::Environment`] for an invalid action or a failed step.
    fn advance(
        &self,
        episode: &mut Self::Episode,
        action: &Self::Action,
    ) -> Result<bool, OracleError>;
}

/// A trajectory on a task: per decision, the features, the action taken and the expert's label.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTrajectory<S, L, A> {
    /// φ(s_t), t = 1..n.
    pub features: Vec<Vec<S>>,
    /// a_t.
    pub actions: Vec<A>,
    /// π*(s_t).
    pub labels: Vec<L>,
}

impl<S, L, A> TaskTrajectory<S, L, A> {
    /// Number of decisions n.
    pub fn len(&self) -> usize {
        self.actions.len()
    }
    /// `true` for an empty trajectory.
    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }
}

/// A labelled state: features and the expert's label.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskExample<S, L> {
    /// φ(s).
    pub features: Vec<S>,
    /// π*(s).
    pub label: L,
}

/// A task with a learner policy: an [`IlProblem`].
#[derive(Debug, Clone)]
pub struct TaskProblem<T, P> {
    /// The environment with its expert.
    pub task: T,
    /// The learner's policy class.
    pub policy: P,
}

fn policy_error(e: PolicyError) -> OracleError {
    match e {
        PolicyError::Undecidable(u) => OracleError::Undecidable(u),
        other => OracleError::Domain(other.to_string()),
    }
}

fn check_theta<S: Scalar>(theta: &DVector<S>, dim: usize) -> Result<(), OracleError> {
    if theta.len() != dim {
        return Err(OracleError::Dimension {
            expected: dim,
            got: theta.len(),
        });
    }
    if !theta.iter().all(Scalar::is_finite) {
        return Err(OracleError::NonFinite("θ"));
    }
    Ok(())
}

/// Per-decision losses, loss gradients and scores at θ on a trajectory.
#[allow(clippy::type_complexity)]
fn terms<S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &TaskTrajectory<S, L, A>,
) -> Result<(Vec<S>, Vec<Vec<S>>, Vec<Vec<S>>), OracleError>
where
    S: Scalar,
    P: Policy<S, Action = A>,
    L: Borrow<P::Label>,
{
    let mut losses = Vec::with_capacity(t.len());
    let mut grads = Vec::with_capacity(t.len());
    let mut scores = Vec::with_capacity(t.len());
    for ((phi, a), y) in t.features.iter().zip(&t.actions).zip(&t.labels) {
        let (l, g) = policy.loss(theta, phi, y.borrow()).map_err(policy_error)?;
        losses.push(l);
        grads.push(g);
        scores.push(policy.score(theta, phi, a).map_err(policy_error)?);
    }
    Ok((losses, grads, scores))
}

fn check_trajectory<S, L, A>(t: &TaskTrajectory<S, L, A>) -> Result<(), OracleError> {
    if t.features.len() != t.len() || t.labels.len() != t.len() || t.is_empty() {
        return Err(OracleError::Trajectory(format!(
            "{} features, {} actions, {} labels",
            t.features.len(),
            t.len(),
            t.labels.len()
        )));
    }
    Ok(())
}

/// `Σ_t ∇l_t + Σ_{i<n} ψ_i Σ_{t>i} l_t` (causal) with optional per-decision weights
/// (`w_{1:t−1}` on term t; math.md §4).
fn causal_weighted<S: Scalar>(
    d: usize,
    losses: &[S],
    grads: &[Vec<S>],
    scores: &[Vec<S>],
    prefix_weights: Option<&[S]>,
) -> Vec<S> {
    let mut g = vec![S::zero(); d];
    let mut score_sum = vec![S::zero(); d];
    for t in 0..losses.len() {
        let w = prefix_weights.map_or_else(S::one, |w| w[t].clone());
        let wl = w.clone() * &losses[t];
        for j in 0..d {
            g[j] += w.clone() * &grads[t][j] + wl.clone() * &score_sum[j];
        }
        for j in 0..d {
            score_sum[j] += &scores[t][j];
        }
    }
    g
}

impl<S, T, P> IlProblem<S> for TaskProblem<T, P>
where
    S: Real,
    T: Task<S>,
    P: LikelihoodRatio<S, Action = T::Action>,
    T::Label: Borrow<P::Label>,
{
    type Trajectory = TaskTrajectory<S, T::Label, T::Action>;
    type Labelled = TaskExample<S, T::Label>;

    fn dim(&self) -> usize {
        self.policy.param_dim()
    }

    fn rollout(
        &self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<Self::Trajectory, OracleError> {
        let d = self.dim();
        match behaviour {
            Behaviour::Learner(th) => check_theta(th, d)?,
            Behaviour::Mixture {
                expert_weight,
                learners,
            } => {
                let all = std::iter::once(*expert_weight).chain(learners.iter().map(|l| l.0));
                if all.clone().any(|w| !(0.0..=1.0).contains(&w))
                    || (all.sum::<f64>() - 1.0).abs() > 1e-9
                {
                    return Err(OracleError::Behaviour(
                        "mixture weights must lie in [0, 1] and sum to 1".into(),
                    ));
                }
                for (_, th) in learners {
                    check_theta(th, d)?;
                }
            }
            Behaviour::NonStationary(steps) => {
                for th in steps.iter().flatten() {
                    check_theta(th, d)?;
                }
            }
            _ => {}
        }
        let mut ep = self.task.start(rng)?;
        let mut t = TaskTrajectory {
            features: vec![],
            actions: vec![],
            labels: vec![],
        };
        loop {
            let phi = self.task.features(&ep);
            let (label, expert_action) = self.task.expert(&ep)?;
            let step = t.len();
            let learner: Option<&DVector<S>> = match behaviour {
                Behaviour::Learner(th) => Some(th),
                Behaviour::Expert => None,
                Behaviour::Mixture {
                    expert_weight,
                    learners,
                } => {
                    let x: f64 = rng.random();
                    if x < *expert_weight {
                        None
                    } else {
                        let mut acc = *expert_weight;
                        let mut pick = learners.last().map(|l| l.1);
                        for (w, th) in learners {
                            acc += w;
                            if x < acc {
                                pick = Some(*th);
                                break;
                            }
                        }
                        pick
                    }
                }
                Behaviour::NonStationary(steps) => steps.get(step).copied().flatten(),
            };
            let action = match learner {
                Some(th) => self
                    .policy
                    .sample(th.as_slice(), &phi, rng)
                    .map_err(policy_error)?,
                None => expert_action,
            };
            let done = self.task.advance(&mut ep, &action)?;
            t.features.push(phi);
            t.actions.push(action);
            t.labels.push(label);
            if done {
                break;
            }
        }
        cost.trajectories += 1;
        cost.env_steps += t.len() as u64;
        cost.expert_queries += t.len() as u64;
        Ok(t)
    }

    fn estimate(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        check_theta(theta, self.dim())?;
        check_trajectory(trajectory)?;
        let (losses, grads, scores) = terms(&self.policy, theta.as_slice(), trajectory)?;
        let d = self.dim();
        let g = match form {
            EstimatorForm::Causal => causal_weighted(d, &losses, &grads, &scores, None),
            EstimatorForm::Full => {
                let total = losses.iter().fold(S::zero(), |a, l| a + l);
                let n = losses.len();
                let mut g = vec![S::zero(); d];
                for t in 0..n {
                    for j in 0..d {
                        g[j] += &grads[t][j];
                        if t + 1 < n {
                            g[j] += total.clone() * &scores[t][j];
                        }
                    }
                }
                g
            }
        };
        cost.gradient_evaluations += trajectory.len() as u64;
        if !g.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("the gradient estimate"));
        }
        Ok(DVector::from_vec(g))
    }

    fn weighted_estimate(
        &self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &Self::Trajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        check_theta(theta_old, self.dim())?;
        check_theta(theta_new, self.dim())?;
        check_trajectory(trajectory)?;
        let (losses, grads, scores) = terms(&self.policy, theta_old.as_slice(), trajectory)?;
        let n = trajectory.len();
        // prefix[t] = Π_{i<t} π_old(a_i|s_i)/π_new(a_i|s_i); the last decision never weighs a loss.
        let mut prefix = Vec::with_capacity(n);
        let mut log_w = S::zero();
        for t in 0..n {
            prefix.push(log_w.exp());
            if t + 1 < n {
                log_w += self
                    .policy
                    .log_likelihood_ratio(
                        theta_old.as_slice(),
                        theta_new.as_slice(),
                        &trajectory.features[t],
                        &trajectory.actions[t],
                    )
                    .map_err(policy_error)?;
            }
        }
        let d = self.dim();
        let g = match weighting {
            Weighting::PerDecision => causal_weighted(d, &losses, &grads, &scores, Some(&prefix)),
            Weighting::Trajectory => {
                let w = log_w.exp();
                causal_weighted(d, &losses, &grads, &scores, None)
                    .into_iter()
                    .map(|x| x * &w)
                    .collect()
            }
        };
        cost.gradient_evaluations += n as u64;
        if !g.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("the weighted gradient estimate"));
        }
        Ok(DVector::from_vec(g))
    }

    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
    ) -> Result<S, OracleError> {
        check_theta(theta, self.dim())?;
        check_trajectory(trajectory)?;
        let mut total = S::zero();
        for (phi, y) in trajectory.features.iter().zip(&trajectory.labels) {
            total += self
                .policy
                .loss(theta.as_slice(), phi, y.borrow())
                .map_err(policy_error)?
                .0;
        }
        Ok(total)
    }

    fn labelled_states(&self, trajectory: &Self::Trajectory) -> Vec<Self::Labelled> {
        trajectory
            .features
            .iter()
            .zip(&trajectory.labels)
            .map(|(f, l)| TaskExample {
                features: f.clone(),
                label: l.clone(),
            })
            .collect()
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &Self::Labelled,
        cost: &mut Cost,
    ) -> Result<(S, DVector<S>), OracleError> {
        check_theta(theta, self.dim())?;
        let (l, g) = self
            .policy
            .loss(theta.as_slice(), &example.features, example.label.borrow())
            .map_err(policy_error)?;
        cost.gradient_evaluations += 1;
        Ok((l, DVector::from_vec(g)))
    }
}
