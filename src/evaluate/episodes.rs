//! Deterministic evaluation episodes, as the thesis's chapter 4 scores a learned policy: the
//! policy acts on its output (no sampling) from seeded starts, and each episode's reward, outcome
//! and per-decision supervised loss against the expert are tallied. One loop for every task: a
//! [`Task`] (a program's own environment) through [`task_episodes`], CartPole through
//! [`cartpole_episodes`], the obstacle environment, whose outcome is one of four, through
//! [`obstacle_episodes`]. The caller chooses
//! the action (a learner's deterministic action or a reference policy's) and the seed of episode j
//! (`seed_of(j)`), so that every checkpoint of a run can meet the same episodes.

use crate::env::cartpole::MAX_EPISODE_STEPS;
use crate::env::obstacle::{ObstacleConfig, ObstacleEnv, ObstacleObs, Outcome};
use crate::expert::vo_policy::VoExpertPolicy;
use crate::problem::KitRng;
use crate::task::Task;
use crate::task::cartpole::CartPoleTask;
use rand::SeedableRng;

/// A policy acting in a [`Task`]'s evaluation: (episode, φ(s), the expert's label) ↦ (action, its
/// per-decision loss).
pub type TaskAct<'a, T> = dyn FnMut(
        &<T as Task<f64>>::Episode,
        &[f64],
        &<T as Task<f64>>::Label,
    ) -> Result<(<T as Task<f64>>::Action, f64), String>
    + 'a;

/// A policy acting in the obstacle environment: (observation, φ(observation)) ↦ velocity.
pub type ObstacleAct<'a> = dyn FnMut(&ObstacleObs, &[f64]) -> Result<[f64; 2], String> + 'a;

/// What a set of evaluation episodes gives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EpisodeStats {
    /// Episodes that succeeded (the task's criterion: the obstacle task's goal, CartPole's 500
    /// steps).
    pub successes: u32,
    /// Episodes that crashed.
    pub crashes: u32,
    /// Episodes that timed out (the obstacle task).
    pub timeouts: u32,
    /// The mean episode reward.
    pub reward: f64,
    /// The mean per-decision supervised loss against the expert over every decision of every
    /// episode.
    pub loss: f64,
    /// The obstacle task: the loss's x and y parts (their sum is `loss`).
    pub loss_xy: Option<(f64, f64)>,
}

/// `episodes` episodes of `task`, episode j started from an RNG seeded by `seed_of(j)`, each
/// decision `act(episode, φ(s), the expert's label) = (action, its loss)`, until the task ends
/// the episode or `max_decisions` decisions are made. `finish(episode, decisions, stats)` then
/// adds the episode's reward and outcome to `stats`; `reward` is divided by `episodes` at the end
/// and `loss` by the decisions made.
///
/// # Errors
/// The first error of `act`, or of the task's start, expert or step, as a message.
pub fn task_episodes<T: Task<f64>>(
    task: &T,
    act: &mut TaskAct<'_, T>,
    episodes: u32,
    seed_of: &dyn Fn(u64) -> u64,
    max_decisions: Option<usize>,
    finish: &mut dyn FnMut(&T::Episode, usize, &mut EpisodeStats),
) -> Result<EpisodeStats, String> {
    let mut stats = EpisodeStats::default();
    let mut decisions = 0u64;
    for j in 0..episodes {
        let mut rng = KitRng::seed_from_u64(seed_of(u64::from(j)));
        let mut ep = task.start(&mut rng).map_err(|e| e.to_string())?;
        let mut steps = 0usize;
        while max_decisions.is_none_or(|m| steps < m) {
            let phi = task.features(&ep);
            let (label, _) = task.expert(&ep).map_err(|e| e.to_string())?;
            let (a, l) = act(&ep, &phi, &label)?;
            stats.loss += l;
            decisions += 1;
            steps += 1;
            if task.advance(&mut ep, &a).map_err(|e| e.to_string())? {
                break;
            }
        }
        finish(&ep, steps, &mut stats);
    }
    stats.loss /= decisions.max(1) as f64;
    stats.reward /= f64::from(episodes.max(1));
    Ok(stats)
}

/// CartPole's evaluation episodes: [`task_episodes`] on the CartPole task, each episode's reward
/// its steps, an episode that completes [`MAX_EPISODE_STEPS`] a success and any shorter one a
/// crash.
///
/// # Errors
/// As [`task_episodes`].
pub fn cartpole_episodes(
    task: &CartPoleTask<f64>,
    act: &mut TaskAct<'_, CartPoleTask<f64>>,
    episodes: u32,
    seed_of: &dyn Fn(u64) -> u64,
) -> Result<EpisodeStats, String> {
    task_episodes(task, act, episodes, seed_of, None, &mut |_, steps, s| {
        s.reward += steps as f64;
        if steps >= MAX_EPISODE_STEPS {
            s.successes += 1;
        } else {
            s.crashes += 1;
        }
    })
}

/// `episodes` episodes of the obstacle environment `env`, episode j started from an RNG seeded
/// by `seed_of(j)`, each step the velocity `act(observation, φ(observation))` with `features`
/// the learner's φ; a non-finite velocity is replaced by zero (the episode then times out) and
/// counted in the loss as it is. The loss is ‖v − v*‖² against `expert`'s velocity v*, its x and
/// y parts summed apart.
///
/// # Errors
/// The first error of `act`, the environment or the expert, as a message.
pub fn obstacle_episodes(
    env: &ObstacleConfig,
    features: &dyn Fn(&ObstacleObs) -> Vec<f64>,
    expert: &VoExpertPolicy,
    act: &mut ObstacleAct<'_>,
    episodes: u32,
    seed_of: &dyn Fn(u64) -> u64,
) -> Result<EpisodeStats, String> {
    let mut stats = EpisodeStats::default();
    let mut decisions = 0u64;
    let (mut lx, mut ly) = (0.0, 0.0);
    for j in 0..episodes {
        let mut rng = KitRng::seed_from_u64(seed_of(u64::from(j)));
        let mut e = ObstacleEnv::new(env.clone()).map_err(|e| e.to_string())?;
        let mut obs = e.reset(&mut rng);
        loop {
            let phi = features(&obs);
            let m = act(&obs, &phi)?;
            let star = expert.act(&obs).map_err(|e| e.to_string())?;
            lx += (m[0] - star[0]).powi(2);
            ly += (m[1] - star[1]).powi(2);
            decisions += 1;
            let a = if m.iter().all(|v| v.is_finite()) {
                m
            } else {
                [0.0, 0.0]
            };
            let s = e.step(a).map_err(|e| e.to_string())?;
            stats.reward += s.reward;
            obs = s.observation;
            match s.outcome {
                Outcome::Running => {}
                Outcome::Success => {
                    stats.successes += 1;
                    break;
                }
                Outcome::Crash => {
                    stats.crashes += 1;
                    break;
                }
                Outcome::TimeOut => {
                    stats.timeouts += 1;
                    break;
                }
            }
        }
    }
    let n = decisions.max(1) as f64;
    stats.loss_xy = Some((lx / n, ly / n));
    stats.loss = (lx + ly) / n;
    stats.reward /= f64::from(episodes.max(1));
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::cartpole::MAX_EPISODE_STEPS;
    use crate::expert::vo_policy::VoExpertParams;
    use crate::task::cartpole::CartPoleTask;

    /// The LQR expert acting on its own labels balances every episode to the time limit with a
    /// zero loss; `finish` sees each episode's decisions.
    #[test]
    fn the_cartpole_expert_balances_with_zero_loss() {
        let task = CartPoleTask::with_lqr().unwrap();
        let mut seen = Vec::new();
        let s = task_episodes(
            &task,
            &mut |_, _, label| Ok((*label, 0.0)),
            3,
            &|j| 100 + j,
            None,
            &mut |_, steps, s| {
                seen.push(steps);
                s.reward += steps as f64;
            },
        )
        .unwrap();
        assert_eq!(seen, vec![MAX_EPISODE_STEPS; 3]);
        assert_eq!(s.reward, MAX_EPISODE_STEPS as f64);
        assert_eq!(s.loss, 0.0);
    }

    /// `max_decisions` ends an episode early; the loss is the mean over every decision made.
    #[test]
    fn episodes_end_at_max_decisions_and_the_loss_is_per_decision() {
        let task = CartPoleTask::with_lqr().unwrap();
        let mut seen = Vec::new();
        let s = task_episodes(
            &task,
            &mut |_, _, label| Ok((*label, 2.0)),
            2,
            &|j| j,
            Some(7),
            &mut |_, steps, _| seen.push(steps),
        )
        .unwrap();
        assert_eq!(seen, vec![7, 7]);
        assert_eq!(s.loss, 2.0);
        let e = task_episodes(
            &task,
            &mut |_, _, _| Err("no action".into()),
            1,
            &|j| j,
            None,
            &mut |_, _, _| {},
        )
        .unwrap_err();
        assert_eq!(e, "no action");
    }

    /// The velocity-obstacle expert acting on the obstacle task reaches the goal with a zero loss
    /// in both coordinates; a policy that stands still times out.
    #[test]
    fn the_obstacle_expert_succeeds_and_standing_still_times_out() {
        let env = ObstacleConfig::default();
        let expert = VoExpertPolicy::new(&env, VoExpertParams::default()).unwrap();
        let s = obstacle_episodes(
            &env,
            &|_| vec![1.0],
            &expert,
            &mut |obs, _| expert.act(obs).map_err(|e| e.to_string()),
            3,
            &|j| 7 + j,
        )
        .unwrap();
        assert_eq!((s.successes, s.crashes, s.timeouts), (3, 0, 0));
        assert_eq!(s.loss_xy, Some((0.0, 0.0)));
        let still = obstacle_episodes(
            &env,
            &|_| vec![1.0],
            &expert,
            &mut |_, _| Ok([0.0, 0.0]),
            2,
            &|j| 7 + j,
        )
        .unwrap();
        assert_eq!(still.timeouts, 2);
        assert!(still.loss > 0.0);
        let (x, y) = still.loss_xy.unwrap();
        assert!((x + y - still.loss).abs() <= 1e-12 * still.loss);
    }
}
