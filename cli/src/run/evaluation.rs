//! Evaluating a learner at θ as the thesis's experiments do: the policy acts deterministically
//! (the softmax's most probable action, the logistic policy's action of probability > ½, the
//! linear-Gaussian mean) on seeded episodes; CartPole records the mean episode reward (steps up
//! to 500) and the episodes that complete 500 steps, the obstacle task the successes, crashes
//! and time-outs; both the mean per-decision supervised loss against the expert on the visited
//! states. A toy MDP has no episodes to play: its metric is the exact objective F(θ).
//!
//! Episode j of a seed's evaluation draws from an RNG seeded by (seed, j) only, so every
//! checkpoint of a run meets the same episodes (common random numbers).

use ilopt::env::obstacle::ObstacleConfig;
pub use ilopt::evaluate::Evaluation;
use ilopt::evaluate::episodes::{cartpole_episodes, obstacle_episodes};
use ilopt::expert::vo_policy::VoExpertPolicy;
use ilopt::policy::SpeedLimitedGaussian;
use ilopt::policy::{Greedy, PolicyExt};
use ilopt::seeding::splitmix64;
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::CartPoleTask;
use ilopt::task::obstacle::ObstacleTask;
use ilopt::toy::ToyProblem;

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
/// completes 500 steps is a success ([`cartpole_episodes`]).
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
    let policy = &problem.policy;
    let s = cartpole_episodes(
        &problem.task,
        &mut |_, phi, label| {
            let (l, _) =
                PolicyExt::<f64>::loss(policy, theta, phi, label).map_err(|e| e.to_string())?;
            Ok((policy.greedy(theta, phi).map_err(|e| e.to_string())?, l))
        },
        episodes,
        &|j| episode_seed(seed, j),
    )?;
    Ok(Evaluation::cartpole(&s))
}

/// Obstacle episodes with the executed mean velocity ([`obstacle_episodes`]).
///
/// # Errors
/// A message if an episode, the expert or the policy fails.
pub fn evaluate_obstacle(
    problem: &TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>,
    env: &ObstacleConfig,
    expert: &VoExpertPolicy,
    theta: &[f64],
    episodes: u32,
    seed: u64,
) -> Result<Evaluation, String> {
    let s = obstacle_episodes(
        env,
        &|obs| problem.task.observation_features(obs),
        expert,
        &mut |_, phi| {
            let m = problem
                .policy
                .executed_mean(theta, phi)
                .map_err(|e| e.to_string())?;
            Ok([m[0], m[1]])
        },
        episodes,
        &|j| episode_seed(seed, j),
    )?;
    Ok(Evaluation::obstacle(&s, episodes))
}
