//! Roll-outs of a task: one episode, or a fixed-horizon stream of decisions with resets or an
//! absorbing end, acting with the learner, the expert, a mixture or a schedule of them.

use super::{AfterEnd, Horizon, Task, TaskProblem, TaskTrajectory};
use crate::oracle::{EstimatorKernel, policy_error};
use crate::problem::{KitRng, OracleError};
use crate::scalar::Scalar;

/// The learner θ's action at φ (θ checked by the caller), inlined into each roll-out loop.
#[inline(always)]
pub(super) fn sample_learner<S: Scalar, P: EstimatorKernel<S>>(
    policy: &P,
    theta: &[S],
    phi: &[S],
    rng: &mut KitRng,
) -> Result<P::Action, OracleError> {
    policy
        .sample_validated(theta, phi, rng)
        .map_err(policy_error)
}

/// The error of a task whose feature vectors changed length during an episode.
#[cold]
#[inline(never)]
fn features_changed_length(before: usize, now: usize) -> OracleError {
    OracleError::Environment(format!(
        "the task's features changed length from {before} to {now}"
    ))
}

/// The error of an absorbing roll-out on a task without an absorbing loss.
#[cold]
#[inline(never)]
fn no_absorbing_loss() -> OracleError {
    OracleError::Environment(
        "the horizon absorbs at the end of an episode, but the task defines no absorbing loss"
            .into(),
    )
}

impl<T, P> TaskProblem<T, P> {
    /// One episode of the task from a fresh start, acting with `choose(step, φ(s), a*(s), rng)` at
    /// every decision, recording features, actions and the expert's labels.
    ///
    /// The storage for the whole episode is reserved once: with the task's time limit known, the
    /// per-step loop allocates nothing (for tasks and policies whose features, labels and actions
    /// are written in place).
    pub(super) fn rollout_with<S, F>(
        &self,
        rng: &mut KitRng,
        choose: F,
    ) -> Result<TaskTrajectory<S, T::Label, T::Action>, OracleError>
    where
        S: Scalar,
        T: Task<S>,
        P: EstimatorKernel<S>,
        F: FnMut(usize, &[S], T::Action, &mut KitRng) -> Result<T::Action, OracleError>,
    {
        let steps = self.decision_capacity();
        let mut t = TaskTrajectory {
            feature_data: Vec::with_capacity(steps * self.policy.feature_dim()),
            feature_dim: 0,
            rows: 0,
            features_finite: false,
            actions: Vec::with_capacity(steps),
            labels: Vec::with_capacity(steps),
            absorbed: None,
            resets: 0,
            notes: Default::default(),
        };
        self.rollout_into(rng, &mut t, choose)?;
        Ok(t)
    }

    /// The learner θ's roll-out ([`TaskProblem::rollout_with`] sampling with
    /// [`EstimatorKernel::sample_validated`]), keeping what the policy notes per decision
    /// ([`EstimatorKernel::sample_noting`]) and θ with it, for the estimate at the same θ. θ is
    /// checked by the caller; every φ is checked by the sampler, so the features are marked finite.
    pub(super) fn learner_rollout<S>(
        &self,
        theta: &[S],
        rng: &mut KitRng,
    ) -> Result<TaskTrajectory<S, T::Label, T::Action>, OracleError>
    where
        S: Scalar,
        T: Task<S>,
        P: EstimatorKernel<S, Action = T::Action>,
    {
        let note_len = self.policy.note_len();
        let mut t = if note_len == 0 {
            self.rollout_with(rng, |_, phi, _, rng| {
                sample_learner(&self.policy, theta, phi, rng)
            })?
        } else {
            let mut notes = Vec::with_capacity(self.decision_capacity() * note_len);
            let mut t = self.rollout_with(rng, |_, phi, _, rng| {
                self.policy
                    .sample_noting(theta, phi, rng, &mut notes)
                    .map_err(policy_error)
            })?;
            t.notes.values = notes;
            t.notes.theta = theta.to_vec();
            t
        };
        t.features_finite = true;
        Ok(t)
    }

    /// Decisions a roll-out can hold: the fixed horizon, or the task's time limit (0 if none).
    fn decision_capacity<S>(&self) -> usize
    where
        S: Scalar,
        T: Task<S>,
    {
        match self.horizon {
            Horizon::Episodic => self.task.max_episode_steps().unwrap_or(0),
            Horizon::Fixed { steps, .. } => steps,
        }
    }

    /// The loop of [`TaskProblem::rollout_with`], into the empty trajectory `t`: one episode, or
    /// a stream of the fixed horizon's decisions with resets or an absorbing end. A function of
    /// its own, not inlined, writing through `&mut t` rather than into a local that is then
    /// returned (cheaper in the hot loop). Each behaviour of [`IlProblem::rollout`] gets its own copy,
    /// with its action choice compiled in.
    #[inline(never)]
    fn rollout_into<S, F>(
        &self,
        rng: &mut KitRng,
        t: &mut TaskTrajectory<S, T::Label, T::Action>,
        mut choose: F,
    ) -> Result<(), OracleError>
    where
        S: Scalar,
        T: Task<S>,
        P: EstimatorKernel<S>,
        F: FnMut(usize, &[S], T::Action, &mut KitRng) -> Result<T::Action, OracleError>,
    {
        let (limit, after_end) = match self.horizon {
            Horizon::Episodic => (usize::MAX, None),
            Horizon::Fixed { steps, after_end } => (steps, Some(after_end)),
        };
        let mut ep = self.task.start(rng)?;
        loop {
            let step = t.actions.len();
            let (rows, feature_dim) = (&mut t.rows, &mut t.feature_dim);
            // φ is stored and handed on by the task (by value where it can): its length is
            // checked, then the expert labels the state and `choose` acts on φ.
            let (label, action) =
                self.task
                    .push_features_then(&ep, &mut t.feature_data, |phi| {
                        if *rows == 0 {
                            *feature_dim = phi.len();
                        } else if phi.len() != *feature_dim {
                            return Err(features_changed_length(*feature_dim, phi.len()));
                        }
                        *rows += 1;
                        let (label, expert_action) = self.task.expert(&ep)?;
                        Ok((label, choose(step, phi, expert_action, rng)?))
                    })?;
            let done = self.task.advance(&mut ep, &action)?;
            t.actions.push(action);
            t.labels.push(label);
            let n = t.actions.len();
            if n >= limit {
                return Ok(());
            }
            if done {
                match after_end {
                    None => return Ok(()),
                    Some(AfterEnd::Reset) => {
                        t.resets += 1;
                        ep = self.task.start(rng)?;
                    }
                    Some(AfterEnd::Absorb) => {
                        let c = self
                            .task
                            .absorbing_loss(&ep)
                            .ok_or_else(no_absorbing_loss)?;
                        t.absorbed = Some(S::from_i64((limit - n) as i64) * c);
                        return Ok(());
                    }
                }
            }
        }
    }
}
