//! The profile's task with its learner: the kit's [`TaskLearner`] built from a task section
//! ([`task_learner`]), evaluated on the episodes of an evaluation key ([`evaluate_learner`]),
//! the measurements only the appendix makes at a checkpoint (Fig. 4.9's resets to a full
//! episode, the obstacle task's gradient rows), and the reference policies evaluated beside the
//! learners ([`ReferencePolicy`]).

use super::{TaskKind, cartpole_max_steps};
use crate::config::TaskExperiment;
use crate::error::Error;
use crate::stats::derive_seed;
use ilopt::evaluate::Evaluation;
pub use ilopt::evaluate::builtin::TaskLearner;
use ilopt::evaluate::builtin::{CartPoleLearner, CartPolePolicy};
use ilopt::policy::Greedy;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::task::{Horizon, Task};
use nalgebra::DVector;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

/// A reference policy evaluated on the same episodes as the learners, without training: the
/// appendix's baseline rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferencePolicy {
    /// The task's expert (the velocity-obstacle expert; CartPole's PPO or LQR expert).
    Expert,
    /// Obstacle task: full speed straight at the goal, ignoring the obstacle,
    /// `v = v_max·(g − p)/‖g − p‖`.
    StraightToGoal,
}

impl ReferencePolicy {
    /// Its label in tables and figures, for the task `kind` as `task` sets it up (CartPole's
    /// expert choice).
    pub fn label(self, kind: TaskKind, task: &TaskExperiment) -> String {
        match (self, kind) {
            (ReferencePolicy::Expert, TaskKind::Obstacle) => "Expert (VO)".into(),
            (ReferencePolicy::Expert, TaskKind::Cartpole) => {
                format!("Expert ({})", task.expert.unwrap_or_default().name())
            }
            (ReferencePolicy::StraightToGoal, _) => "Straight to goal".into(),
        }
    }

    /// The baselines of a task, in table order.
    pub fn of(kind: TaskKind) -> &'static [ReferencePolicy] {
        match kind {
            TaskKind::Obstacle => &[ReferencePolicy::Expert, ReferencePolicy::StraightToGoal],
            TaskKind::Cartpole => &[ReferencePolicy::Expert],
        }
    }
}

/// The task `kind` with its learner and expert as `task` sets them up, on the objective
/// `horizon`: the obstacle task's linear-Gaussian learner (σ = `task.sigma`, default 0.02, over
/// `task.features`), CartPole's softmax learner labelled by `task.expert`.
///
/// # Errors
/// [`Error::Experiment`] if the environment, expert or policy cannot be built.
pub fn task_learner(
    kind: TaskKind,
    task: &TaskExperiment,
    horizon: Horizon,
) -> Result<TaskLearner, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment(kind.name(), x);
    match kind {
        TaskKind::Obstacle => TaskLearner::obstacle(
            task.sigma.unwrap_or(0.02),
            task.features.unwrap_or_default(),
            horizon,
        )
        .map_err(|x| e(&x)),
        TaskKind::Cartpole => {
            let expert = task
                .expert
                .unwrap_or_default()
                .expert()
                .map_err(|x| e(&x))?;
            TaskLearner::cartpole(expert, CartPolePolicy::Softmax, horizon).map_err(|x| e(&x))
        }
    }
}

/// The learner's deterministic evaluation at θ ([`TaskLearner::evaluate`]) on `episodes`
/// episodes, episode j seeded by `derive_seed(key, j)`.
///
/// # Errors
/// [`Error::Experiment`] if an episode, the expert or the policy fails.
pub(super) fn evaluate_learner(
    bench: &TaskLearner,
    theta: &[f64],
    episodes: u32,
    key: &str,
) -> Result<Evaluation, Error> {
    bench
        .evaluate(theta, episodes, &|j| derive_seed(key, j))
        .map_err(|x| Error::experiment(format!("evaluation ({key})"), x))
}

/// A reference policy's evaluation on the learners' episodes of `key` (the expert's own loss
/// is 0).
///
/// # Errors
/// [`Error::Experiment`] if an episode fails, or the task has no such reference policy.
pub(super) fn evaluate_reference(
    bench: &TaskLearner,
    b: ReferencePolicy,
    episodes: u32,
    key: &str,
) -> Result<Evaluation, Error> {
    let err = |x: &dyn std::fmt::Display| x.to_string();
    let seed_of = |j| derive_seed(key, j);
    match (bench, b) {
        (TaskLearner::Obstacle(o), ReferencePolicy::Expert) => o.episodes(
            &mut |obs, _| o.expert.act(obs).map_err(|x| err(&x)),
            episodes,
            &seed_of,
        ),
        (TaskLearner::Obstacle(o), ReferencePolicy::StraightToGoal) => {
            let env = &o.env;
            o.episodes(
                &mut |obs, _| {
                    let d = [
                        env.goal[0] - obs.agent_pos[0],
                        env.goal[1] - obs.agent_pos[1],
                    ];
                    let n = d[0].hypot(d[1]);
                    Ok(if n > 0.0 {
                        let v = env.agent_max_speed / n;
                        [d[0] * v, d[1] * v]
                    } else {
                        [0.0, 0.0]
                    })
                },
                episodes,
                &seed_of,
            )
        }
        (TaskLearner::CartPoleSoftmax(c), ReferencePolicy::Expert) => {
            c.episodes(&mut |_, _, label| Ok((*label, 0.0)), episodes, &seed_of)
        }
        (TaskLearner::CartPoleLogistic(c), ReferencePolicy::Expert) => {
            c.episodes(&mut |_, _, label| Ok((*label, 0.0)), episodes, &seed_of)
        }
        (_, b) => {
            return Err(Error::experiment(
                format!("baseline ({key})"),
                format!(
                    "the {} task has no reference policy {b:?}",
                    bench.task_name()
                ),
            ));
        }
    }
    .map_err(|x| Error::experiment(format!("evaluation ({key})"), x))
}

/// Fig. 4.9 as the thesis measures it (CartPole): the deterministic policy at θ plays seeded
/// episodes, reset after every crash, until one completes the full 500 steps; the number of
/// crashes before it, at most `cap` (= `cap`: none completed within the cap). `None` for the
/// other tasks.
///
/// # Errors
/// [`Error::Experiment`] if an episode or the policy fails.
pub(super) fn resets_to_full_episode(
    bench: &TaskLearner,
    theta: &[f64],
    cap: u32,
    key: &str,
) -> Result<Option<u32>, Error> {
    match bench {
        TaskLearner::CartPoleSoftmax(c) => resets_of(c, theta, cap, key).map(Some),
        TaskLearner::CartPoleLogistic(c) => resets_of(c, theta, cap, key).map(Some),
        TaskLearner::Obstacle(_) | TaskLearner::Toy(_) => Ok(None),
    }
}

/// [`resets_to_full_episode`] of a CartPole learner.
fn resets_of<P: Greedy<f64, Action = usize>>(
    c: &CartPoleLearner<P>,
    theta: &[f64],
    cap: u32,
    key: &str,
) -> Result<u32, Error> {
    let err = |x: &dyn std::fmt::Display| Error::experiment(format!("Fig. 4.9 ({key})"), x);
    let task = &c.problem.task;
    for j in 0..cap {
        let mut rng = KitRng::seed_from_u64(derive_seed(&format!("{key}|full"), u64::from(j)));
        let mut ep = task.start(&mut rng).map_err(|x| err(&x))?;
        loop {
            let phi = task.features(&ep);
            let a = c.problem.policy.greedy(theta, &phi).map_err(|x| err(&x))?;
            if task.advance(&mut ep, &a).map_err(|x| err(&x))? {
                break;
            }
        }
        if ep.steps >= cartpole_max_steps() {
            return Ok(j);
        }
    }
    Ok(cap)
}

/// Norms of the x and y rows of the mean eq. 3.15 estimate over `n` learner roll-outs (obstacle
/// task only; `None` for the others and for `n = 0`).
///
/// # Errors
/// [`Error::Experiment`] if a roll-out or an estimate fails.
pub(super) fn gradient_xy(
    bench: &TaskLearner,
    theta: &DVector<f64>,
    n: u32,
    seed: u64,
) -> Result<Option<(f64, f64)>, Error> {
    let TaskLearner::Obstacle(o) = bench else {
        return Ok(None);
    };
    if n == 0 {
        return Ok(None);
    }
    let g = mean_estimate(&mut o.problem.clone(), theta, u64::from(n), seed)?;
    Ok(Some(row_norms(&g)))
}

fn row_norms(g: &DVector<f64>) -> (f64, f64) {
    let n = g.len() / 2;
    let x = g.rows(0, n).norm();
    let y = g.rows(n, n).norm();
    (x, y)
}

/// The mean of `n` eq. 3.15 estimates (causal form) at θ, roll-outs from one seeded RNG.
fn mean_estimate<P: IlProblem<f64>>(
    problem: &mut P,
    theta: &DVector<f64>,
    n: u64,
    seed: u64,
) -> Result<DVector<f64>, Error> {
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    let mut sum = DVector::zeros(theta.len());
    for _ in 0..n {
        let t = problem
            .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
            .map_err(|e| Error::experiment("gradient estimate", e))?;
        sum += problem
            .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
            .map_err(|e| Error::experiment("gradient estimate", e))?;
    }
    Ok(sum / n as f64)
}
