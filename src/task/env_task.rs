//! Your own environment as an imitation-learning task: an [`Env`] (Gymnasium's reset/step), a
//! feature map φ(o) and an expert become a [`Task`]; with a policy and a [`Horizon`] they are a
//! [`TaskProblem`](super::TaskProblem), on which every algorithm of the kit runs.
//!
//! The episode is a copy of the template environment, reset with the run's seeded RNG, and its
//! last observation: the features, the expert's label and the learner's action are functions of
//! the observation, and [`Task::advance`] is one [`Env::step`] (the episode is over when the step
//! is `terminated` or `truncated`). `cli/examples/custom_env.rs` runs STORM and DAgger on a
//! ten-line environment.

use super::Task;
use crate::env::Env;
use crate::problem::{KitRng, OracleError};
use crate::scalar::Scalar;
use std::fmt::Debug;
use std::sync::Arc;

/// The loss per remaining step after an episode ends in an observation, for
/// [`AfterEnd::Absorb`](super::AfterEnd::Absorb) streams.
type AbsorbingLoss<O, S> = Arc<dyn Fn(&O) -> S + Send + Sync>;

/// An [`Env`] with features `F: Fn(&Obs) -> Vec<S>` and an expert `X: Fn(&Obs) -> Result<Action,
/// String>` (the expert's action, which is also the label the learner's loss compares with), as a
/// [`Task`] (module docs).
#[derive(Clone)]
pub struct EnvTask<E: Env<S>, F, X, S: Scalar> {
    env: E,
    features: F,
    expert: X,
    max_steps: Option<usize>,
    absorbing: Option<AbsorbingLoss<E::Obs, S>>,
}

impl<E: Env<S>, F, X, S: Scalar> Debug for EnvTask<E, F, X, S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvTask")
            .field("max_steps", &self.max_steps)
            .field("absorbing", &self.absorbing.is_some())
            .finish_non_exhaustive()
    }
}

/// One episode of an [`EnvTask`]: the environment, its last observation, and what the episode
/// has earned so far (an evaluation reads the return and how the episode ended).
#[derive(Debug, Clone)]
pub struct EnvEpisode<E, O, S> {
    env: E,
    observation: O,
    total_reward: S,
    steps: usize,
    terminated: bool,
}

impl<E, O, S> EnvEpisode<E, O, S> {
    /// The last observation.
    pub fn observation(&self) -> &O {
        &self.observation
    }

    /// The sum of the rewards of the steps taken (the episode's return so far).
    pub fn total_reward(&self) -> &S {
        &self.total_reward
    }

    /// The steps taken.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Whether the last step was `terminated` (a terminal state, not a time limit).
    pub fn terminated(&self) -> bool {
        self.terminated
    }
}

impl<E: Env<S>, F, X, S: Scalar> EnvTask<E, F, X, S> {
    /// The task of `env` (copied and reset for every episode) with `features` and `expert`.
    pub fn new(env: E, features: F, expert: X) -> Self {
        Self {
            env,
            features,
            expert,
            max_steps: None,
            absorbing: None,
        }
    }

    /// The same task over `env` (its features, expert, time limit and absorbing loss kept): a
    /// second instance of an environment, e.g. for evaluation episodes that must not move the
    /// training's random generator.
    #[must_use]
    pub fn with_env(mut self, env: E) -> Self {
        self.env = env;
        self
    }

    /// Declare the environment's time limit (its episodes end, truncated, after at most `steps`
    /// decisions), so that roll-outs reserve their storage once.
    #[must_use]
    pub fn with_max_steps(mut self, steps: usize) -> Self {
        self.max_steps = Some(steps);
        self
    }

    /// The loss per remaining step when an [`AfterEnd::Absorb`](super::AfterEnd::Absorb) stream
    /// ends in an observation (0 for a success, the per-step loss's supremum for a failure).
    #[must_use]
    pub fn with_absorbing_loss(
        mut self,
        loss: impl Fn(&E::Obs) -> S + Send + Sync + 'static,
    ) -> Self {
        self.absorbing = Some(Arc::new(loss));
        self
    }
}

fn env_error(e: impl std::fmt::Display) -> OracleError {
    OracleError::Environment(e.to_string())
}

impl<S, E, F, X, A> Task<S> for EnvTask<E, F, X, S>
where
    S: Scalar,
    E: Env<S, Action = A> + Clone,
    E::Obs: Clone,
    F: Fn(&E::Obs) -> Vec<S>,
    X: Fn(&E::Obs) -> Result<A, String>,
    A: Clone + Debug,
{
    type Episode = EnvEpisode<E, E::Obs, S>;
    type Label = A;
    type Action = A;

    fn start(&self, rng: &mut KitRng) -> Result<Self::Episode, OracleError> {
        let mut env = self.env.clone();
        let observation = env.reset(rng);
        Ok(EnvEpisode {
            env,
            observation,
            total_reward: S::zero(),
            steps: 0,
            terminated: false,
        })
    }

    fn features(&self, episode: &Self::Episode) -> Vec<S> {
        (self.features)(&episode.observation)
    }

    fn max_episode_steps(&self) -> Option<usize> {
        self.max_steps
    }

    fn expert(&self, episode: &Self::Episode) -> Result<(A, A), OracleError> {
        let a = (self.expert)(&episode.observation).map_err(env_error)?;
        Ok((a.clone(), a))
    }

    fn absorbing_loss(&self, episode: &Self::Episode) -> Option<S> {
        self.absorbing.as_ref().map(|f| f(&episode.observation))
    }

    fn advance(&self, episode: &mut Self::Episode, action: &A) -> Result<bool, OracleError> {
        let step = episode.env.step(action.clone()).map_err(env_error)?;
        let done = step.done();
        episode.total_reward += step.reward;
        episode.steps += 1;
        episode.terminated = step.terminated;
        episode.observation = step.observation;
        Ok(done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::cartpole::CartPole;
    use crate::problem::{Behaviour, Cost, IlProblem};
    use crate::task::cartpole::CartPoleTask;
    use crate::task::{Horizon, TaskProblem};
    use nalgebra::DVector;
    use rand::SeedableRng;

    /// CartPole through the adapter, with the LQR expert as a closure, gives the same roll-outs
    /// as the kit's own CartPole task (same reset law, same dynamics, same seeds).
    #[test]
    fn cartpole_through_the_adapter_equals_the_kits_task() {
        let native = CartPoleTask::<f64>::with_lqr().expect("task");
        let lqr = crate::expert::lqr::LqrExpert::cartpole().expect("expert");
        let adapted = EnvTask::new(
            CartPole::<f64>::new(),
            |o: &[f64; 4]| vec![o[0], o[1], o[2], o[3], 1.0],
            move |o: &[f64; 4]| lqr.action(o).map_err(|e| e.to_string()),
        )
        .with_max_steps(500);
        let policy = || crate::policy::Logistic::new(5).expect("policy");
        let mut a = TaskProblem {
            task: native,
            policy: policy(),
            horizon: Horizon::Episodic,
        };
        let mut b = TaskProblem {
            task: adapted,
            policy: policy(),
            horizon: Horizon::Episodic,
        };
        let theta = DVector::from_vec(vec![0.1, 0.5, 3.0, 0.8, 0.0]);
        for seed in 0..5 {
            let (mut ra, mut rb) = (KitRng::seed_from_u64(seed), KitRng::seed_from_u64(seed));
            let (mut ca, mut cb) = (Cost::default(), Cost::default());
            let ta = a
                .rollout(&Behaviour::Learner(&theta), &mut ra, &mut ca)
                .unwrap();
            let tb = b
                .rollout(&Behaviour::Learner(&theta), &mut rb, &mut cb)
                .unwrap();
            assert_eq!(ta.len(), tb.len(), "seed {seed}");
            let ga = a
                .estimate(&theta, &ta, crate::problem::EstimatorForm::Causal, &mut ca)
                .unwrap();
            let gb = b
                .estimate(&theta, &tb, crate::problem::EstimatorForm::Causal, &mut cb)
                .unwrap();
            assert_eq!(ga, gb, "seed {seed}");
        }
    }
}
