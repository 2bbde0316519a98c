//! A task with a learner policy as an [`IlProblem`]: roll-outs with seeded RNGs, expert labels at
//! every visited state, and the estimator passes of [`crate::oracle`] on the recorded trajectory.

use super::rollout::sample_learner;
use super::{AfterEnd, Horizon, Task, TaskExample, TaskTrajectory};
use crate::baseline::PerDecisionTerms;
use crate::oracle::{
    DecisionTerms, EstimatorKernel, RecordedPass, ScoreProducts, causal_pass, features_valid,
    full_pass, policy_error, record_pass, sum_recorded, terms_pass,
};
use crate::policy::LikelihoodRatio;
use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use crate::scalar::{Real, Scalar};
use nalgebra::DVector;
use rand::Rng;
use smallvec::SmallVec;
use std::borrow::Borrow;

/// A task with a learner policy: an [`IlProblem`].
///
/// Adam on CartPole under the thesis's fixed-horizon objective (500 decisions, the environment
/// reset after every crash), four trajectories per gradient, each estimate with the leave-one-out
/// baseline of the other three ([`crate::baseline`]):
///
/// ```
/// use ilopt::algo::{Runner, config::RunConfig};
/// use ilopt::baseline::{Baseline, Baselined};
/// use ilopt::policy::Logistic;
/// use ilopt::task::cartpole::{self, CartPoleTask};
/// use ilopt::task::{AfterEnd, TaskProblem};
///
/// let task = CartPoleTask::with_lqr()?; // the LQR expert labels every visited state
/// let policy = Logistic::new(cartpole::FEATURES)?;
/// let problem = TaskProblem::fixed(task, policy, 500, AfterEnd::Reset)?;
/// let mut oracle = Baselined::<_, f64>::new(problem, 4, &Baseline::LeaveOneOut)?;
/// let config: RunConfig = serde_json::from_str(
///     r#"{"theta0": [0, 0, 0, 0, 0], "seed": 1, "stop": {"max_iterations": 10},
///         "algorithm": {"algorithm": "adam", "form": "causal", "alpha": 0.005,
///                       "beta1": 0.9, "beta2": 0.999, "epsilon": 1e-8}}"#,
/// )?;
/// let run = Runner::new(config.stop.clone())?.run_config(&config, &mut oracle)?;
/// // Every iteration estimated the gradient on 4 trajectories of exactly 500 decisions.
/// assert_eq!(run.cost.gradient_evaluations, 10 * 4 * 500);
/// assert!(run.theta.iter().all(|x| x.is_finite()));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct TaskProblem<T, P> {
    /// The environment with its expert.
    pub task: T,
    /// The learner's policy class.
    pub policy: P,
    /// What one trajectory is (the objective).
    pub horizon: Horizon,
}

impl<T, P> TaskProblem<T, P> {
    /// The task and policy with one episode per trajectory ([`Horizon::Episodic`]).
    pub fn episodic(task: T, policy: P) -> Self {
        Self {
            task,
            policy,
            horizon: Horizon::Episodic,
        }
    }

    /// The task and policy under the thesis's fixed-horizon objective.
    ///
    /// # Errors
    /// [`OracleError::Environment`] if `steps` is 0.
    pub fn fixed(
        task: T,
        policy: P,
        steps: usize,
        after_end: AfterEnd,
    ) -> Result<Self, OracleError> {
        if steps == 0 {
            return Err(OracleError::Environment(
                "a fixed horizon needs at least 1 decision, got 0".into(),
            ));
        }
        Ok(Self {
            task,
            policy,
            horizon: Horizon::fixed(steps, after_end),
        })
    }
}

fn check_theta<S: Scalar>(theta: &DVector<S>, dim: usize) -> Result<(), OracleError> {
    if theta.len() != dim {
        return Err(OracleError::Dimension {
            expected: dim,
            got: theta.len(),
        });
    }
    if !crate::scalar::all_finite(theta.as_slice()) {
        return Err(OracleError::NonFinite("θ"));
    }
    Ok(())
}

fn check_trajectory<S, L, A>(t: &TaskTrajectory<S, L, A>) -> Result<(), OracleError> {
    if t.rows != t.len() || t.labels.len() != t.len() || t.is_empty() {
        return Err(OracleError::Trajectory(format!(
            "{} features, {} actions, {} labels",
            t.rows,
            t.len(),
            t.labels.len()
        )));
    }
    Ok(())
}

impl<T, P> TaskProblem<T, P> {
    /// [`IlProblem::estimate`] of `form`; with `loss` (causal form only), each `l_t` of the
    /// causal pass is added to it as [`IlProblem::trajectory_loss`] sums them.
    fn estimate_summing<S>(
        &self,
        theta: &DVector<S>,
        trajectory: &TaskTrajectory<S, T::Label, T::Action>,
        form: EstimatorForm,
        loss: Option<&mut S>,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError>
    where
        S: Real,
        T: Task<S>,
        P: LikelihoodRatio<S, Action = T::Action> + EstimatorKernel<S>,
        T::Label: Borrow<P::Label>,
    {
        check_theta(theta, self.policy.param_dim())?;
        check_trajectory(trajectory)?;
        let th = theta.as_slice();
        let t = trajectory.decisions();
        let g = match form {
            EstimatorForm::Causal => causal_pass(&self.policy, th, None, false, &t, loss)?.0,
            EstimatorForm::Full => full_pass(&self.policy, th, &t)?,
        };
        cost.gradient_evaluations += trajectory.len() as u64;
        if !g.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("the gradient estimate"));
        }
        Ok(DVector::from_vec(g))
    }
}

impl<S, T, P> IlProblem<S> for TaskProblem<T, P>
where
    S: Real,
    T: Task<S>,
    P: LikelihoodRatio<S, Action = T::Action> + EstimatorKernel<S>,
    T::Label: Borrow<P::Label>,
{
    type Trajectory = TaskTrajectory<S, T::Label, T::Action>;
    type Labelled = TaskExample<S, T::Label>;

    fn dim(&self) -> usize {
        self.policy.param_dim()
    }

    fn rollout(
        &mut self,
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
        // One loop per kind of behaviour, each with its action choice compiled in: the learner's
        // roll-out (the oracle's hot loop) carries no mixture or schedule code. Every learner θ
        // of `behaviour` was checked above.
        let act = |learner: Option<&DVector<S>>, phi: &[S], expert, rng: &mut KitRng| match learner
        {
            Some(th) => sample_learner(&self.policy, th.as_slice(), phi, rng),
            None => Ok(expert),
        };
        let t = match behaviour {
            // θ's slice taken once: the loop then holds its address and length in registers.
            Behaviour::Learner(th) => self.learner_rollout(th.as_slice(), rng)?,
            Behaviour::Expert => self.rollout_with(rng, |_, _, expert, _| Ok(expert))?,
            Behaviour::Mixture {
                expert_weight,
                learners,
            } => self.rollout_with(rng, |_, phi, expert, rng| {
                let x: f64 = rng.random();
                let learner = if x < *expert_weight {
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
                };
                act(learner, phi, expert, rng)
            })?,
            Behaviour::NonStationary(steps) => self
                .rollout_with(rng, |step, phi, expert, rng| {
                    act(steps.get(step).copied().flatten(), phi, expert, rng)
                })?,
        };
        cost.trajectories += 1;
        cost.env_steps += t.len() as u64;
        cost.expert_queries += t.len() as u64;
        Ok(t)
    }

    fn estimate(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        self.estimate_summing(theta, trajectory, form, None, cost)
    }

    /// The causal form: the trajectory loss summed in the estimate's own pass (the same per-step
    /// losses, added in [`IlProblem::trajectory_loss`]'s order, so the same value).
    fn estimate_with_loss(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<(DVector<S>, S), OracleError> {
        if form != EstimatorForm::Causal {
            return crate::problem::estimate_then_loss(self, theta, trajectory, form, cost);
        }
        let mut loss = trajectory.absorbed.clone().unwrap_or_else(S::zero);
        let g = self.estimate_summing(theta, trajectory, form, Some(&mut loss), cost)?;
        Ok((g, loss))
    }

    fn weighted_estimate(
        &mut self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &Self::Trajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        check_theta(theta_old, self.dim())?;
        check_theta(theta_new, self.dim())?;
        check_trajectory(trajectory)?;
        // Term t carries w_{1:t−1} = Π_{i<t} π_old(a_i|s_i)/π_new(a_i|s_i); the last decision
        // never weighs a loss.
        let (old, new) = (theta_old.as_slice(), theta_new.as_slice());
        let g = match weighting {
            Weighting::PerDecision => {
                causal_pass(
                    &self.policy,
                    old,
                    Some(new),
                    true,
                    &trajectory.decisions(),
                    None,
                )?
                .0
            }
            Weighting::Trajectory => {
                let (g, log_w) = causal_pass(
                    &self.policy,
                    old,
                    Some(new),
                    false,
                    &trajectory.decisions(),
                    None,
                )?;
                let w = log_w.exp();
                g.into_iter().map(|x| x * &w).collect()
            }
        };
        cost.gradient_evaluations += trajectory.len() as u64;
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
        let mut total = trajectory.absorbed.clone().unwrap_or_else(S::zero);
        let mut grad = vec![S::zero(); self.dim()];
        // θ is checked above; with every φ checked once, the loss alone is computed per decision
        // (the same values as `loss_into`'s, without its gradient).
        let validated = features_valid(&self.policy, &trajectory.decisions());
        for (phi, y) in trajectory.feature_rows().zip(&trajectory.labels) {
            let th = theta.as_slice();
            total += if validated {
                self.policy.loss_validated(th, phi, y.borrow(), &mut grad)
            } else {
                self.policy.loss_into(th, phi, y.borrow(), &mut grad)
            }
            .map_err(policy_error)?;
        }
        Ok(total)
    }

    fn labelled_states(&self, trajectory: &Self::Trajectory) -> Vec<Self::Labelled> {
        trajectory
            .feature_rows()
            .zip(&trajectory.labels)
            .map(|(f, l)| TaskExample {
                features: SmallVec::from(f),
                label: l.clone(),
            })
            .collect()
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &Self::Labelled,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError> {
        check_theta(theta, self.dim())?;
        let l = self
            .policy
            .loss_into(
                theta.as_slice(),
                &example.features,
                example.label.borrow(),
                grad,
            )
            .map_err(policy_error)?;
        cost.gradient_evaluations += 1;
        Ok(l)
    }
}

impl<S, T, P> PerDecisionTerms<S> for TaskProblem<T, P>
where
    S: Real,
    T: Task<S>,
    P: LikelihoodRatio<S, Action = T::Action> + EstimatorKernel<S>,
    T::Label: Borrow<P::Label>,
{
    fn decision_terms(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        weights: Option<(&DVector<S>, Weighting)>,
        out: &mut DecisionTerms<S>,
        cost: &mut Cost,
    ) -> Result<(), OracleError> {
        check_theta(theta, self.dim())?;
        if let Some((theta_new, _)) = weights {
            check_theta(theta_new, self.dim())?;
        }
        check_trajectory(trajectory)?;
        let ratio = weights.map(|(new, w)| (new.as_slice(), w));
        terms_pass(
            &self.policy,
            theta.as_slice(),
            ratio,
            &trajectory.decisions(),
            out,
        )?;
        cost.gradient_evaluations += trajectory.len() as u64;
        Ok(())
    }

    /// On validated features, the policy's own records
    /// ([`EstimatorKernel::record_validated`]); otherwise the checked route of
    /// [`PerDecisionTerms::decision_terms`], which reports the first invalid input.
    fn record_decisions(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        out: &mut RecordedPass<S>,
        cost: &mut Cost,
    ) -> Result<(), OracleError> {
        check_theta(theta, self.dim())?;
        check_trajectory(trajectory)?;
        let t = trajectory.decisions();
        if !features_valid(&self.policy, &t) {
            return crate::baseline::record_by_terms(self, theta, trajectory, out, cost);
        }
        record_pass(&self.policy, theta.as_slice(), &t, out)?;
        cost.gradient_evaluations += trajectory.len() as u64;
        Ok(())
    }

    /// Through [`EstimatorKernel::accumulate_recorded`] when the policy recorded the decisions,
    /// else from rows.
    fn estimate_recorded(
        &self,
        trajectory: &Self::Trajectory,
        recorded: &mut RecordedPass<S>,
        losses: Option<&[S]>,
        g: &mut [S],
    ) {
        if recorded.score_rows {
            recorded.sum_rows(losses, g);
        } else {
            sum_recorded(&self.policy, &trajectory.decisions(), recorded, losses, g);
        }
    }

    /// Through [`EstimatorKernel::score_products`] when the policy recorded the decisions, else
    /// from rows.
    fn recorded_score_products(
        &self,
        trajectory: &Self::Trajectory,
        recorded: &RecordedPass<S>,
        out: ScoreProducts<'_, S>,
    ) {
        if recorded.score_rows {
            recorded.score_row_products(out);
        } else {
            let features = &trajectory.feature_data;
            (self.policy).score_products(features, &recorded.scores, out);
        }
    }

    /// The learner's features φ(s_i) of each scored decision, as the roll-out stored them.
    fn state_features<'a>(
        &self,
        trajectory: &'a Self::Trajectory,
        decisions: usize,
        _scratch: &'a mut Vec<S>,
    ) -> Result<(&'a [S], usize), OracleError> {
        if trajectory.rows < decisions {
            return Err(OracleError::Trajectory(format!(
                "{decisions} scored decisions but {} feature rows",
                trajectory.rows
            )));
        }
        let stride = trajectory.feature_dim();
        Ok((&trajectory.feature_data()[..decisions * stride], stride))
    }
}
