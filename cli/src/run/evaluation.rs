//! Evaluating a learner at θ as the thesis's experiments do: the policy acts deterministically
//! (the softmax's most probable action, the logistic policy's action of probability > ½, the
//! linear-Gaussian mean) on seeded episodes; CartPole records the mean episode reward (steps up
//! to 500) and the episodes that complete 500 steps, the obstacle task the successes, crashes
//! and time-outs; both the mean per-decision supervised loss against the expert on the visited
//! states. A toy MDP has no episodes to play: its metric is the exact objective F(θ).
//!
//! Episode j of a seed's evaluation draws from an RNG seeded by (seed, j) only, so every
//! checkpoint of a run meets the same episodes (common random numbers).

use super::task::ObstacleLearner;
use ilopt::env::cartpole::MAX_EPISODE_STEPS;
use ilopt::env::obstacle::{ObstacleEnv, Outcome};
use ilopt::policy::{Greedy, PolicyExt};
use ilopt::problem::KitRng;
use ilopt::seeding::splitmix64;
use ilopt::task::cartpole::CartPoleTask;
use ilopt::task::{Task, TaskProblem};
use ilopt::toy::ToyProblem;
use rand::SeedableRng;
use serde::Serialize;

/// What one evaluation gives.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Evaluation {
    /// CartPole: mean reward / 500; obstacle: success rate; toy: none.
    pub score: Option<f64>,
    /// Mean episode reward (CartPole, obstacle).
    pub reward: Option<f64>,
    /// Episodes that reached the goal (obstacle) or completed 500 steps (CartPole).
    pub successes: Option<u32>,
    /// Crashed episodes (CartPole: ended before 500 steps).
    pub crashes: Option<u32>,
    /// Timed-out episodes (obstacle).
    pub timeouts: Option<u32>,
    /// Mean per-decision supervised loss against the expert on the visited states.
    pub loss: Option<f64>,
    /// Toy: the exact objective F(θ).
    pub objective: Option<f64>,
}

/// The RNG seed of evaluation episode `j` of `seed` (SplitMix64 of both, with a tag that keeps
/// it apart from the run's own seed).
pub fn episode_seed(seed: u64, j: u64) -> u64 {
    splitmix64(splitmix64(seed ^ 0x6576_616c_7561_7465) ^ j)
}

/// The toy MDP's evaluation: its exact objective F(θ) (no episodes).
///
/// # Errors
/// A message if the forward pass fails.
pub fn evaluate_toy(problem: &ToyProblem<f64>, theta: &[f64]) -> Result<Evaluation, String> {
    let f = ilopt::exact::forward::forward(problem, theta).map_err(|e| e.to_string())?;
    Ok(Evaluation {
        objective: Some(f.objective),
        ..Evaluation::default()
    })
}

/// CartPole episodes with the learner's deterministic action ([`Greedy`]); an episode that
/// completes 500 steps is a success.
///
/// # Errors
/// A message if an episode, the expert or the policy fails.
pub fn evaluate_cartpole<P>(
    problem: &TaskProblem<CartPoleTask<f64>, P>,
    theta: &[f64],
    episodes: u32,
    seed: u64,
) -> Result<Evaluation, String>
where
    P: Greedy<f64, Action = usize, Label = usize>,
{
    let (task, policy) = (&problem.task, &problem.policy);
    let (mut reward, mut loss, mut decisions, mut successes) = (0.0, 0.0, 0u64, 0u32);
    for j in 0..episodes {
        let mut rng = KitRng::seed_from_u64(episode_seed(seed, u64::from(j)));
        let mut ep = task.start(&mut rng).map_err(|e| e.to_string())?;
        loop {
            let phi = task.features(&ep);
            let (label, _) = task.expert(&ep).map_err(|e| e.to_string())?;
            let (l, _) =
                PolicyExt::<f64>::loss(policy, theta, &phi, &label).map_err(|e| e.to_string())?;
            let a = policy.greedy(theta, &phi).map_err(|e| e.to_string())?;
            loss += l;
            decisions += 1;
            if task.advance(&mut ep, &a).map_err(|e| e.to_string())? {
                break;
            }
        }
        reward += ep.steps as f64;
        if ep.steps >= MAX_EPISODE_STEPS {
            successes += 1;
        }
    }
    let reward = reward / f64::from(episodes);
    Ok(Evaluation {
        score: Some(reward / MAX_EPISODE_STEPS as f64),
        reward: Some(reward),
        successes: Some(successes),
        crashes: Some(episodes - successes),
        timeouts: None,
        loss: Some(loss / decisions.max(1) as f64),
        objective: None,
    })
}

/// Obstacle episodes with the executed mean velocity; a non-finite velocity is replaced by zero
/// (the episode then times out) and counted in the loss as it is.
///
/// # Errors
/// A message if an episode, the expert or the policy fails.
pub fn evaluate_obstacle(
    learner: &ObstacleLearner,
    theta: &[f64],
    episodes: u32,
    seed: u64,
) -> Result<Evaluation, String> {
    let ObstacleLearner {
        problem,
        env,
        expert,
    } = learner;
    let (mut successes, mut crashes, mut timeouts) = (0u32, 0u32, 0u32);
    let (mut reward, mut loss, mut decisions) = (0.0, 0.0, 0u64);
    for j in 0..episodes {
        let mut rng = KitRng::seed_from_u64(episode_seed(seed, u64::from(j)));
        let mut e = ObstacleEnv::new(env.clone()).map_err(|e| e.to_string())?;
        let mut obs = e.reset(&mut rng);
        loop {
            let phi = problem.task.observation_features(&obs);
            let m = problem
                .policy
                .executed_mean(theta, &phi)
                .map_err(|e| e.to_string())?;
            let star = expert.act(&obs).map_err(|e| e.to_string())?;
            loss += (m[0] - star[0]).powi(2) + (m[1] - star[1]).powi(2);
            decisions += 1;
            let a = if m.iter().all(|v| v.is_finite()) {
                [m[0], m[1]]
            } else {
                [0.0, 0.0]
            };
            let s = e.step(a).map_err(|e| e.to_string())?;
            reward += s.reward;
            obs = s.observation;
            match s.outcome {
                Outcome::Running => {}
                Outcome::Success => {
                    successes += 1;
                    break;
                }
                Outcome::Crash => {
                    crashes += 1;
                    break;
                }
                Outcome::TimeOut => {
                    timeouts += 1;
                    break;
                }
            }
        }
    }
    Ok(Evaluation {
        score: Some(f64::from(successes) / f64::from(episodes)),
        reward: Some(reward / f64::from(episodes)),
        successes: Some(successes),
        crashes: Some(crashes),
        timeouts: Some(timeouts),
        loss: Some(loss / decisions.max(1) as f64),
        objective: None,
    })
}
