//! The experiments: one seeded run of one algorithm on one task, evaluated at checkpoints (the
//! gradient-error study of Fig. 4.2 is in [`crate::gradient_error`]).
//!
//! **Evaluation.** At every checkpoint the learned policy acts *deterministically* (the
//! linear-Gaussian mean `Wφ(s)`; the softmax's most probable action) on `eval_episodes` seeded
//! episodes. The episodes depend only on (task, seed index, episode index), so every algorithm and
//! every checkpoint of one seed meets the same episodes (common random numbers). Recorded: the
//! outcomes (obstacle: success / crash / time-out; CartPole: completed 500 steps / crash = the
//! episode terminated earlier), the mean episode reward, and the mean per-decision supervised loss
//! `l(s, θ)` on the states the deterministic policy visits (obstacle: split into the x and y
//! coordinates of the velocity).
//!
//! **Budget and checkpoints**: every run of a task gets the same budget of
//! gradient calls (per-state gradient evaluations, [`Cost`]; DAgger's full-batch retraining
//! counts epochs × |D|), and is evaluated at the fixed call counts 0, `checkpoint_every`, …,
//! `budget` (at the first iterate whose cumulative calls reach each). θ₁ is the task's
//! [`Theta1`] (zero unless a profile says otherwise).
//!
//! **Score and sustained convergence** (one definition for every algorithm): the score of a
//! checkpoint is the obstacle task's success rate, or CartPole's mean episode reward divided by
//! 500. A run *converges* at checkpoint i when the score is ≥ `converge_score` at checkpoints
//! i, i+1, …, i+`sustain`−1 (3 by default; [`sustained`]); its "gradient calls to converge" are the
//! calls at checkpoint i, its time the training wall time up to it (evaluation excluded).
//!
//! **Failure is data** ([`RunStatus`]): a run whose ‖θ‖₂ exceeds the task's `norm_bound`, whose θ
//! is not finite, or whose step fails is *diverged* — it stops there, is never converged (even if
//! it had met the criterion before), and is counted among the failed runs.

use crate::config::{AlgorithmEntry, CartPoleExpertChoice, TaskSection, Theta1};
use crate::error::Error;
use crate::stats::derive_seed;
use ilopt::algo::{AlgorithmConfig, StepContext};
use ilopt::baseline::{Baseline as OracleBaseline, Baselined};
use ilopt::batched::Batched;
use ilopt::env::cartpole::MAX_EPISODE_STEPS;
use ilopt::env::obstacle::{ObstacleConfig, ObstacleEnv, ObstacleObs, Outcome};
use ilopt::expert::vo_policy::{VoExpertParams, VoExpertPolicy};
use ilopt::policy::{LinearGaussian, Policy, Softmax, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError};
use ilopt::task::cartpole::{self, CartPoleEpisode, CartPoleExpert, CartPoleTask};
use ilopt::task::obstacle::{ObstacleFeatures, ObstacleTask};
use ilopt::task::{Horizon, Task, TaskProblem};
use nalgebra::DVector;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

/// The two tasks of chapter 4.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskKind {
    /// §4.1, linear-Gaussian learner, velocity-obstacle expert.
    Obstacle,
    /// §4.2, softmax learner, PPO or LQR expert.
    Cartpole,
}

impl TaskKind {
    /// `"obstacle"` / `"cartpole"`.
    pub fn name(self) -> &'static str {
        match self {
            TaskKind::Obstacle => "obstacle",
            TaskKind::Cartpole => "cartpole",
        }
    }
}

/// How a run ended (serialised with a `status` tag: `converged`, `not-converged`, `diverged`).
///
/// Wall times are kept out of it (they live in [`SeedTiming`], so that the results files are
/// byte-identical across reruns): the time to convergence is [`SeedTiming::converge_seconds`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "kebab-case")]
pub enum RunStatus {
    /// Sustained convergence: the score held the threshold at `sustain` consecutive checkpoints
    /// from `checkpoint` on, and the run never diverged.
    Converged {
        /// Index of the first checkpoint of the window.
        checkpoint: usize,
        /// Gradient calls at that checkpoint.
        gradient_evaluations: u64,
    },
    /// Ran to its budget (or, when tuning, ended) without sustained convergence.
    NotConverged,
    /// ‖θ‖ left the norm bound, θ became non-finite, or a step failed: never converged.
    Diverged {
        /// What happened (e.g. `‖θ‖ = 3.2e5 > 1e4`, `non-finite θ`, the step's error).
        reason: String,
        /// Gradient calls when it happened.
        gradient_evaluations: u64,
    },
}

impl RunStatus {
    /// Whether the run converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, RunStatus::Converged { .. })
    }
    /// Whether the run diverged.
    pub fn is_diverged(&self) -> bool {
        matches!(self, RunStatus::Diverged { .. })
    }
    /// The convergence checkpoint, if converged.
    pub fn checkpoint(&self) -> Option<usize> {
        match self {
            RunStatus::Converged { checkpoint, .. } => Some(*checkpoint),
            _ => None,
        }
    }
}

/// The first index i with `scores[i..i + sustain]` all ≥ `threshold` (the window must be complete).
pub fn sustained(scores: &[f64], threshold: f64, sustain: usize) -> Option<usize> {
    let k = sustain.max(1);
    if scores.len() < k {
        return None;
    }
    (0..=scores.len() - k).find(|&i| scores[i..i + k].iter().all(|&s| s >= threshold))
}

/// The status of a run from its checkpoints and its divergence, if any: a diverged run is never
/// converged.
pub fn status_of(
    checkpoints: &[Checkpoint],
    threshold: f64,
    sustain: usize,
    diverged: Option<(String, u64)>,
) -> RunStatus {
    if let Some((reason, gradient_evaluations)) = diverged {
        return RunStatus::Diverged {
            reason,
            gradient_evaluations,
        };
    }
    let scores: Vec<f64> = checkpoints.iter().map(|c| c.score).collect();
    match sustained(&scores, threshold, sustain) {
        Some(i) => RunStatus::Converged {
            checkpoint: i,
            gradient_evaluations: checkpoints[i].gradient_evaluations,
        },
        None => RunStatus::NotConverged,
    }
}

/// The evaluation of one checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The checkpoint's nominal call count (0, `checkpoint_every`, …, budget): checkpoints of
    /// different runs are aligned by it.
    pub at_calls: u64,
    /// Iteration of the run (0 = θ₁).
    pub iteration: u64,
    /// Cumulative trajectories rolled out by the algorithm.
    pub trajectories: u64,
    /// Cumulative per-state gradient evaluations ("gradient calls").
    pub gradient_evaluations: u64,
    /// Cumulative expert queries.
    pub expert_queries: u64,
    /// Success rate (obstacle) or mean reward / 500 (CartPole).
    pub score: f64,
    /// Successful episodes (obstacle) or episodes that completed 500 steps (CartPole).
    pub successes: u32,
    /// Crashed episodes.
    pub crashes: u32,
    /// Timed-out episodes (obstacle only).
    pub timeouts: u32,
    /// Mean episode reward.
    pub reward: f64,
    /// Mean per-decision loss on the evaluation states.
    pub loss: f64,
    /// Its x part (obstacle).
    pub loss_x: Option<f64>,
    /// Its y part (obstacle).
    pub loss_y: Option<f64>,
    /// ‖x-row of the mean eq. 3.15 estimate‖ at θ (obstacle, `grad_trajectories` roll-outs).
    pub grad_x: Option<f64>,
    /// ‖y-row of it‖.
    pub grad_y: Option<f64>,
    /// Fig. 4.9 (CartPole): crashes (resets) before the deterministic policy completes one full
    /// 500-step episode, counting at most the task's `full_episode_cap` (= the cap: not completed).
    #[serde(default)]
    pub resets_to_full_episode: Option<u32>,
}

impl Checkpoint {
    /// A checkpoint from an evaluation and the run's cost so far.
    fn from_eval(
        ev: &Eval,
        kind: TaskKind,
        episodes: u32,
        iteration: u64,
        cost: &Cost,
        grad: Option<(f64, f64)>,
    ) -> Self {
        let score = match kind {
            TaskKind::Obstacle => f64::from(ev.successes) / f64::from(episodes),
            TaskKind::Cartpole => ev.reward / cartpole_max_steps() as f64,
        };
        Checkpoint {
            at_calls: 0,
            resets_to_full_episode: None,
            iteration,
            trajectories: cost.trajectories,
            gradient_evaluations: cost.gradient_evaluations,
            expert_queries: cost.expert_queries,
            score,
            successes: ev.successes,
            crashes: ev.crashes,
            timeouts: ev.timeouts,
            reward: ev.reward,
            loss: ev.loss,
            loss_x: ev.loss_xy.map(|l| l.0),
            loss_y: ev.loss_xy.map(|l| l.1),
            grad_x: grad.map(|g| g.0),
            grad_y: grad.map(|g| g.1),
        }
    }
}

/// One seeded run (deterministic part).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedRun {
    /// The seed's index 0..seeds.
    pub seed_index: u32,
    /// The run's RNG seed, derived from (task, label, algorithm config, seed index).
    pub seed: u64,
    /// Why the run ended (ilopt's termination).
    pub termination: String,
    /// Final θ.
    pub theta: Vec<f64>,
    /// The checkpoints.
    pub checkpoints: Vec<Checkpoint>,
    /// Index of the sustained-convergence checkpoint (= `status`'s, for the tables).
    pub converged: Option<usize>,
    /// How the run ended ([`RunStatus`]); the verdicts read it.
    pub status: RunStatus,
    /// The hyper-parameters the run used (the selected grid point), e.g. `alpha=0.005, m=16`.
    pub hyper_parameters: String,
}

/// One seeded run's wall times (kept out of the deterministic results).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedTiming {
    /// The seed's index.
    pub seed_index: u32,
    /// Training wall time of the run in seconds.
    pub train_seconds: f64,
    /// Training wall time at each checkpoint.
    pub checkpoint_seconds: Vec<f64>,
    /// Training wall time to convergence, if converged.
    pub converge_seconds: Option<f64>,
}

/// A task with its learner, expert and evaluation settings.
// Two instances exist per run, so the size difference between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum Bench {
    /// The obstacle task.
    Obstacle {
        /// The IL problem (velocities stored inline: no allocation per step).
        problem: ObstacleProblem,
        /// The environment configuration.
        env: ObstacleConfig,
        /// The expert (for the evaluation loss).
        expert: VoExpertPolicy,
    },
    /// CartPole.
    Cartpole {
        /// The IL problem.
        problem: TaskProblem<CartPoleTask<f64>, Softmax>,
        /// Which expert labels the states.
        expert: CartPoleExpertChoice,
    },
}

/// The obstacle task's IL problem: linear-Gaussian learner (P3) over the profile's features, with
/// the loss of the executed (speed-clipped) velocity ([`SpeedLimitedGaussian`]); velocities
/// stored inline as `[f64; 2]`.
pub type ObstacleProblem = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

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
    /// Its label in tables and figures.
    pub fn label(self, bench: &Bench) -> String {
        match (self, bench) {
            (ReferencePolicy::Expert, Bench::Obstacle { .. }) => "Expert (VO)".into(),
            (ReferencePolicy::Expert, Bench::Cartpole { expert, .. }) => {
                format!("Expert ({})", expert.name())
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

/// An obstacle-task policy for evaluation: (observation, φ(s)) ↦ velocity.
type ObstacleAct<'a> = dyn FnMut(&ObstacleObs, &[f64]) -> Result<[f64; 2], Error> + 'a;

/// A CartPole policy for evaluation: (episode, φ(s), expert's action) ↦ (action, its loss).
type CartPoleAct<'a> =
    dyn FnMut(&CartPoleEpisode<f64>, &[f64], usize) -> Result<(usize, f64), Error> + 'a;

/// What one evaluation gives.
#[derive(Default)]
struct Eval {
    successes: u32,
    crashes: u32,
    timeouts: u32,
    reward: f64,
    loss: f64,
    loss_xy: Option<(f64, f64)>,
}

impl Bench {
    /// Build the task's bench.
    ///
    /// # Errors
    /// [`Error::Experiment`] if the environment, expert or policy cannot be built.
    pub fn new(kind: TaskKind, task: &TaskSection, horizon: Horizon) -> Result<Self, Error> {
        let e = |x: &dyn std::fmt::Display| Error::experiment(kind.name(), x);
        Ok(match kind {
            TaskKind::Obstacle => {
                let mut b = Self::obstacle(
                    task.sigma.unwrap_or(0.02),
                    task.features.unwrap_or_default(),
                )?;
                if let Bench::Obstacle { problem, .. } = &mut b {
                    problem.horizon = horizon;
                }
                b
            }
            TaskKind::Cartpole => {
                let choice = task.expert.unwrap_or_default();
                let t = match choice {
                    CartPoleExpertChoice::Lqr => CartPoleTask::with_lqr(),
                    CartPoleExpertChoice::Ppo => CartPoleExpertChoice::ppo_expert()
                        .map_err(OracleError::Environment)
                        .and_then(|x| CartPoleTask::new(CartPoleExpert::Ppo(x), MAX_EPISODE_STEPS)),
                }
                .map_err(|x| e(&x))?;
                Bench::Cartpole {
                    problem: TaskProblem {
                        task: t,
                        policy: Softmax::new(2, cartpole::FEATURES).map_err(|x| e(&x))?,
                        horizon,
                    },
                    expert: choice,
                }
            }
        })
    }

    /// The obstacle task's bench: the linear-Gaussian learner of standard deviation `sigma` over
    /// `features`, trained on the loss of the executed velocity.
    ///
    /// # Errors
    /// [`Error::Experiment`] if the environment, expert or policy cannot be built.
    pub fn obstacle(sigma: f64, features: ObstacleFeatures) -> Result<Self, Error> {
        let e = |x: &dyn std::fmt::Display| Error::experiment("obstacle", x);
        let env = ObstacleConfig::default();
        let params = VoExpertParams::default();
        let task = ObstacleTask::new(env.clone(), params)
            .and_then(|t| t.with_features(features))
            .map_err(|x| e(&x))?
            .with_actions::<[f64; 2]>();
        let inner = LinearGaussian::new(2, task.feature_dim(), sigma)
            .and_then(LinearGaussian::with_actions::<[f64; 2]>)
            .map_err(|x| e(&x))?;
        Ok(Bench::Obstacle {
            problem: TaskProblem {
                policy: SpeedLimitedGaussian::new(inner, env.agent_max_speed).map_err(|x| e(&x))?,
                task,
                horizon: ilopt::task::Horizon::Episodic,
            },
            expert: VoExpertPolicy::new(&env, params).map_err(|x| e(&x))?,
            env,
        })
    }

    /// The objective of the bench's problem.
    pub fn horizon(&self) -> Horizon {
        match self {
            Bench::Obstacle { problem, .. } => problem.horizon,
            Bench::Cartpole { problem, .. } => problem.horizon,
        }
    }

    /// Fig. 4.9 as the thesis measures it (CartPole): the deterministic policy at θ plays
    /// seeded episodes, reset after every crash, until one completes the full 500 steps; the
    /// number of crashes before it, at most `cap` (= `cap`: none completed within the cap).
    fn resets_to_full_episode(
        &self,
        theta: &[f64],
        cap: u32,
        key: &str,
    ) -> Result<Option<u32>, Error> {
        let Bench::Cartpole { problem, .. } = self else {
            return Ok(None);
        };
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("Fig. 4.9 ({key})"), x);
        let task = &problem.task;
        for j in 0..cap {
            let mut rng = KitRng::seed_from_u64(derive_seed(&format!("{key}|full"), u64::from(j)));
            let mut ep = task.start(&mut rng).map_err(|x| err(&x))?;
            loop {
                let phi = task.features(&ep);
                let z = problem.policy.logits(theta, &phi).map_err(|x| err(&x))?;
                let a = usize::from(z[1] > z[0]);
                if task.advance(&mut ep, &a).map_err(|x| err(&x))? {
                    break;
                }
            }
            if ep.steps >= cartpole_max_steps() {
                return Ok(Some(j));
            }
        }
        Ok(Some(cap))
    }

    /// Number of policy parameters.
    pub fn dim(&self) -> usize {
        match self {
            Bench::Obstacle { problem, .. } => IlProblem::<f64>::dim(problem),
            Bench::Cartpole { problem, .. } => IlProblem::<f64>::dim(problem),
        }
    }

    /// Evaluate the learner at θ (deterministic: the Gaussian mean, the most probable action).
    fn evaluate(&self, theta: &[f64], episodes: u32, key: &str) -> Result<Eval, Error> {
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("evaluation ({key})"), x);
        match self {
            Bench::Obstacle { problem, .. } => self.evaluate_obstacle(
                &mut |_, phi| {
                    let m = problem
                        .policy
                        .executed_mean(theta, phi)
                        .map_err(|x| err(&x))?;
                    Ok([m[0], m[1]])
                },
                episodes,
                key,
            ),
            Bench::Cartpole { problem, .. } => self.evaluate_cartpole(
                &mut |_, phi, label| {
                    let (l, _) = Policy::<f64>::loss(&problem.policy, theta, phi, &label)
                        .map_err(|x| err(&x))?;
                    let z = problem.policy.logits(theta, phi).map_err(|x| err(&x))?;
                    Ok((usize::from(z[1] > z[0]), l))
                },
                episodes,
                key,
            ),
        }
    }

    /// Evaluate a baseline policy on the same episodes as the learners.
    fn evaluate_baseline(
        &self,
        b: ReferencePolicy,
        episodes: u32,
        key: &str,
    ) -> Result<Eval, Error> {
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("baseline ({key})"), x);
        match (self, b) {
            (Bench::Obstacle { expert, .. }, ReferencePolicy::Expert) => self.evaluate_obstacle(
                &mut |obs, _| expert.act(obs).map_err(|x| err(&x)),
                episodes,
                key,
            ),
            (Bench::Obstacle { env, .. }, ReferencePolicy::StraightToGoal) => self
                .evaluate_obstacle(
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
                    key,
                ),
            (Bench::Cartpole { .. }, ReferencePolicy::Expert) => {
                self.evaluate_cartpole(&mut |_, _, label| Ok((label, 0.0)), episodes, key)
            }
            (Bench::Cartpole { .. }, ReferencePolicy::StraightToGoal) => {
                Err(err(&"CartPole has no goal"))
            }
        }
    }

    /// Obstacle episodes driven by `act(observation, φ(s))`; non-finite velocities are replaced
    /// by zero (the episode then times out) and counted in the loss as they are.
    fn evaluate_obstacle(
        &self,
        act: &mut ObstacleAct<'_>,
        episodes: u32,
        key: &str,
    ) -> Result<Eval, Error> {
        let Bench::Obstacle {
            env,
            expert,
            problem,
        } = self
        else {
            return Err(Error::experiment(key, "not the obstacle task"));
        };
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("evaluation ({key})"), x);
        let mut ev = Eval::default();
        let mut decisions = 0u64;
        let (mut lx, mut ly) = (0.0, 0.0);
        for j in 0..episodes {
            let mut rng = KitRng::seed_from_u64(derive_seed(key, u64::from(j)));
            let mut e = ObstacleEnv::new(env.clone()).map_err(|x| err(&x))?;
            let mut obs = e.reset(&mut rng);
            loop {
                let phi = problem.task.observation_features(&obs);
                let m = act(&obs, &phi)?;
                let star = expert.act(&obs).map_err(|x| err(&x))?;
                lx += (m[0] - star[0]).powi(2);
                ly += (m[1] - star[1]).powi(2);
                decisions += 1;
                let a = if m.iter().all(|v| v.is_finite()) {
                    m
                } else {
                    [0.0, 0.0]
                };
                let s = e.step(a).map_err(|x| err(&x))?;
                ev.reward += s.reward;
                obs = s.obs;
                match s.outcome {
                    Outcome::Running => {}
                    Outcome::Success => {
                        ev.successes += 1;
                        break;
                    }
                    Outcome::Crash => {
                        ev.crashes += 1;
                        break;
                    }
                    _ => {
                        ev.timeouts += 1;
                        break;
                    }
                }
            }
        }
        let n = decisions.max(1) as f64;
        ev.loss_xy = Some((lx / n, ly / n));
        ev.loss = (lx + ly) / n;
        ev.reward /= f64::from(episodes);
        Ok(ev)
    }

    /// CartPole episodes driven by `act(episode, φ(s), expert's action) = (action, loss)`; the
    /// loss is the learner's per-decision supervised loss (the expert's own is 0).
    fn evaluate_cartpole(
        &self,
        act: &mut CartPoleAct<'_>,
        episodes: u32,
        key: &str,
    ) -> Result<Eval, Error> {
        let Bench::Cartpole { problem, .. } = self else {
            return Err(Error::experiment(key, "not CartPole"));
        };
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("evaluation ({key})"), x);
        let task = &problem.task;
        let mut ev = Eval::default();
        let mut decisions = 0u64;
        for j in 0..episodes {
            let mut rng = KitRng::seed_from_u64(derive_seed(key, u64::from(j)));
            let mut ep = task.start(&mut rng).map_err(|x| err(&x))?;
            loop {
                let phi = task.features(&ep);
                let (label, _) = task.expert(&ep).map_err(|x| err(&x))?;
                let (a, l) = act(&ep, &phi, label)?;
                ev.loss += l;
                decisions += 1;
                if task.advance(&mut ep, &a).map_err(|x| err(&x))? {
                    break;
                }
            }
            ev.reward += ep.steps as f64;
            if ep.steps >= cartpole_max_steps() {
                ev.successes += 1;
            } else {
                ev.crashes += 1;
            }
        }
        ev.loss /= decisions.max(1) as f64;
        ev.reward /= f64::from(episodes);
        Ok(ev)
    }

    /// Norms of the x and y rows of the mean eq. 3.15 estimate over `n` learner roll-outs
    /// (obstacle task only).
    fn gradient_xy(
        &self,
        theta: &DVector<f64>,
        n: u32,
        seed: u64,
    ) -> Result<Option<(f64, f64)>, Error> {
        let Bench::Obstacle { problem, .. } = self else {
            return Ok(None);
        };
        if n == 0 {
            return Ok(None);
        }
        let g = mean_estimate(problem, theta, u64::from(n), seed)?;
        Ok(Some(row_norms(&g)))
    }
}

/// CartPole-v1's episode length.
pub fn cartpole_max_steps() -> usize {
    ilopt::env::cartpole::MAX_EPISODE_STEPS
}

fn row_norms(g: &DVector<f64>) -> (f64, f64) {
    let n = g.len() / 2;
    let x = g.rows(0, n).norm();
    let y = g.rows(n, n).norm();
    (x, y)
}

/// The mean of `n` eq. 3.15 estimates (causal form) at θ, roll-outs from one seeded RNG.
fn mean_estimate<P: IlProblem<f64>>(
    problem: &P,
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

/// The identity of a row's runs at given hyper-parameters: task, label, the algorithm's config
/// (JSON), m, the objective and the baseline (named only when there is one, so that the keys
/// of rows without one do not depend on the option). Run seeds are derived from it and the
/// seed index only.
pub fn run_key_of(
    kind: TaskKind,
    label: &str,
    config: &AlgorithmConfig,
    m: usize,
    horizon: Horizon,
    baseline: &OracleBaseline,
) -> String {
    let json = serde_json::to_string(config).unwrap_or_default();
    let key = format!("{}|{label}|{json}|m={m}|{}", kind.name(), horizon.label());
    match baseline {
        OracleBaseline::None => key,
        b => format!(
            "{key}|baseline={}",
            serde_json::to_string(b).unwrap_or_default()
        ),
    }
}

/// [`run_key_of`] for a row at its configured hyper-parameters.
pub fn run_key(kind: TaskKind, task: &TaskSection, entry: &AlgorithmEntry) -> String {
    run_key_of(
        kind,
        &entry.label,
        &entry.config,
        entry.m.unwrap_or(1),
        entry.horizon(task, kind.name()),
        &entry.baseline.clone().unwrap_or_default(),
    )
}

/// One run to carry out.
#[derive(Debug, Clone)]
pub struct RunSpec<'a> {
    /// The task.
    pub kind: TaskKind,
    /// Its section (budget, checkpoints, bound, θ₁, evaluation).
    pub task: &'a TaskSection,
    /// The algorithm.
    pub config: &'a AlgorithmConfig,
    /// Trajectories per gradient (oracle methods; 1 = the plain problem).
    pub m: usize,
    /// The oracle's baseline ([`OracleBaseline::None`]: eq. 3.15 as it is).
    pub baseline: OracleBaseline,
    /// The run key (seed derivation of θ₁ and of Fig. 4.5's estimates).
    pub key: String,
    /// The run's RNG seed.
    pub seed: u64,
    /// The seed's index.
    pub seed_index: u32,
    /// The evaluation episodes' key.
    pub eval_key: String,
    /// Stop at sustained convergence (tuning runs; report runs use the whole budget).
    pub stop_at_convergence: bool,
    /// Hyper-parameters, for the record.
    pub hyper_parameters: String,
}

/// θ₁ of a run.
fn theta1(law: Theta1, dim: usize, key: &str) -> DVector<f64> {
    match law {
        Theta1::Zero => DVector::zeros(dim),
        Theta1::Normal { std } => {
            use rand::Rng;
            let mut rng = KitRng::seed_from_u64(derive_seed(&format!("{key}|theta1"), 0));
            DVector::from_fn(dim, |_, _| {
                // Box–Muller.
                let u: f64 = 1.0 - rng.random::<f64>();
                let v: f64 = rng.random::<f64>();
                std * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
            })
        }
    }
}

/// Run one seed of one row (the report's runs: the row's configured hyper-parameters, the report
/// seed and evaluation episodes).
///
/// # Errors
/// As [`run_spec`].
pub fn run_seed(
    bench: &Bench,
    kind: TaskKind,
    task: &TaskSection,
    entry: &AlgorithmEntry,
    seed_index: u32,
) -> Result<(SeedRun, SeedTiming), Error> {
    let key = run_key(kind, task, entry);
    let m = entry.m.unwrap_or(1);
    run_spec(
        bench,
        &RunSpec {
            kind,
            task,
            config: &entry.config,
            m,
            baseline: entry.baseline.clone().unwrap_or_default(),
            seed: derive_seed(&key, u64::from(seed_index)),
            key,
            seed_index,
            eval_key: eval_key(kind, seed_index),
            stop_at_convergence: false,
            hyper_parameters: entry
                .grid_points()
                .ok()
                .and_then(|p| p.into_iter().next())
                .map_or_else(String::new, |p| p.describe()),
        },
    )
}

/// Carry out one run and evaluate its checkpoints.
///
/// # Errors
/// [`Error::Experiment`] if the run cannot start or an evaluation fails. A run that fails
/// mid-way (a non-finite iterate, a failing step, ‖θ‖ beyond the bound) is *not* an error: its
/// status is [`RunStatus::Diverged`] and it keeps the checkpoints reached.
pub fn run_spec(bench: &Bench, spec: &RunSpec<'_>) -> Result<(SeedRun, SeedTiming), Error> {
    match bench {
        Bench::Obstacle { problem, .. } => drive_with(bench, problem, spec),
        Bench::Cartpole { problem, .. } => drive_with(bench, problem, spec),
    }
}

/// [`drive`] on `problem` as the spec wants it: with its baseline ([`Baselined`], m
/// trajectories per gradient), m trajectories per gradient ([`Batched`]), or as it is.
fn drive_with<P: IlProblem<f64> + Clone>(
    bench: &Bench,
    problem: &P,
    spec: &RunSpec<'_>,
) -> Result<(SeedRun, SeedTiming), Error> {
    if spec.baseline != OracleBaseline::None {
        let b = Baselined::<P, f64>::new(problem.clone(), spec.m, &spec.baseline)
            .map_err(|e| Error::experiment("baseline", e))?;
        drive(bench, &b, spec)
    } else if spec.m > 1 {
        let b =
            Batched::new(problem.clone(), spec.m).map_err(|e| Error::experiment("minibatch", e))?;
        drive(bench, &b, spec)
    } else {
        drive(bench, problem, spec)
    }
}

/// The run loop: steps until the budget, divergence or (tuning) sustained convergence; the
/// checkpoints at the fixed call counts; training time without the evaluations.
fn drive<P: IlProblem<f64>>(
    bench: &Bench,
    problem: &P,
    spec: &RunSpec<'_>,
) -> Result<(SeedRun, SeedTiming), Error> {
    let task = spec.task;
    let what = format!(
        "{} / {} / seed {}",
        spec.kind.name(),
        spec.key,
        spec.seed_index
    );
    let mut algorithm = spec
        .config
        .build::<f64, P>()
        .map_err(|e| Error::experiment(&what, e))?;
    let mut rng = KitRng::seed_from_u64(spec.seed);
    let mut cost = Cost::default();
    let mut train = std::time::Duration::ZERO;
    let mut clock = std::time::Instant::now();
    algorithm
        .init(
            problem,
            theta1(task.theta1, bench.dim(), &spec.key),
            &mut StepContext {
                rng: &mut rng,
                cost: &mut cost,
            },
        )
        .map_err(|e| Error::experiment(&what, e))?;
    let mut checkpoints: Vec<Checkpoint> = Vec::new();
    let mut seconds = Vec::new();
    let mut next = 0u64;
    let mut iteration = 0u64;
    let mut diverged: Option<(String, u64)> = None;
    loop {
        let theta = algorithm.theta();
        let norm = theta.norm();
        if !norm.is_finite() {
            diverged = Some(("non-finite θ".into(), cost.gradient_evaluations));
        } else if norm > task.norm_bound {
            diverged = Some((
                format!("‖θ‖ = {norm:.3e} > {:e}", task.norm_bound),
                cost.gradient_evaluations,
            ));
        }
        if diverged.is_some() {
            break;
        }
        // Checkpoints due (a step that crosses several call counts serves each).
        if next <= task.budget && cost.gradient_evaluations >= next {
            train += clock.elapsed();
            let ev = bench.evaluate(theta.as_slice(), task.eval_episodes, &spec.eval_key)?;
            let grad = bench.gradient_xy(
                theta,
                task.grad_trajectories,
                derive_seed(
                    &format!("{}|grad", spec.key),
                    iteration * 1000 + u64::from(spec.seed_index),
                ),
            )?;
            let full = bench.resets_to_full_episode(
                theta.as_slice(),
                task.full_episode_cap,
                &spec.eval_key,
            )?;
            let mut c =
                Checkpoint::from_eval(&ev, spec.kind, task.eval_episodes, iteration, &cost, grad);
            c.resets_to_full_episode = full;
            while next <= task.budget && cost.gradient_evaluations >= next {
                let mut c = c.clone();
                c.at_calls = next;
                checkpoints.push(c);
                seconds.push(train.as_secs_f64());
                next = if next == task.budget {
                    u64::MAX
                } else {
                    (next + task.checkpoint_every).min(task.budget)
                };
            }
            clock = std::time::Instant::now();
            if spec.stop_at_convergence {
                let scores: Vec<f64> = checkpoints.iter().map(|c| c.score).collect();
                if sustained(&scores, task.converge_score, task.sustain).is_some() {
                    break;
                }
            }
        }
        if cost.gradient_evaluations >= task.budget {
            break;
        }
        match algorithm.step(
            problem,
            &mut StepContext {
                rng: &mut rng,
                cost: &mut cost,
            },
        ) {
            Ok(_) => iteration += 1,
            Err(e) => {
                diverged = Some((format!("step failed: {e}"), cost.gradient_evaluations));
                break;
            }
        }
    }
    train += clock.elapsed();
    let status = status_of(
        &checkpoints,
        task.converge_score,
        task.sustain,
        diverged.clone(),
    );
    let converged = status.checkpoint();
    let termination = match &diverged {
        Some((reason, _)) => format!("diverged: {reason}"),
        None if cost.gradient_evaluations >= task.budget => "gradient-budget".into(),
        None => "sustained-convergence".into(),
    };
    Ok((
        SeedRun {
            seed_index: spec.seed_index,
            seed: spec.seed,
            termination,
            theta: algorithm.theta().iter().copied().collect(),
            checkpoints,
            converged,
            status,
            hyper_parameters: spec.hyper_parameters.clone(),
        },
        SeedTiming {
            seed_index: spec.seed_index,
            train_seconds: train.as_secs_f64(),
            converge_seconds: converged.map(|i| seconds[i]),
            checkpoint_seconds: seconds,
        },
    ))
}

/// The key of a seed's evaluation episodes: the same episodes for every algorithm, checkpoint
/// and baseline of that seed (common random numbers).
pub fn eval_key(kind: TaskKind, seed_index: u32) -> String {
    format!("{}-eval|{seed_index}", kind.name())
}

/// A baseline evaluated on seed `seed_index`'s evaluation episodes (no training, zero cost).
///
/// # Errors
/// [`Error::Experiment`] if an episode fails.
pub fn baseline_seed(
    bench: &Bench,
    kind: TaskKind,
    task: &TaskSection,
    baseline: ReferencePolicy,
    seed_index: u32,
) -> Result<Checkpoint, Error> {
    let ev = bench.evaluate_baseline(baseline, task.eval_episodes, &eval_key(kind, seed_index))?;
    Ok(Checkpoint::from_eval(
        &ev,
        kind,
        task.eval_episodes,
        0,
        &Cost::default(),
        None,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp(score: f64, calls: u64) -> Checkpoint {
        Checkpoint {
            at_calls: calls,
            iteration: 0,
            trajectories: 0,
            gradient_evaluations: calls,
            expert_queries: 0,
            score,
            successes: 0,
            crashes: 0,
            timeouts: 0,
            reward: 0.0,
            loss: 0.0,
            loss_x: None,
            loss_y: None,
            grad_x: None,
            grad_y: None,
            resets_to_full_episode: None,
        }
    }

    #[test]
    fn sustained_convergence_needs_three_consecutive_checkpoints() {
        let t = 0.8;
        // Two above, a dip, then three above: converged at index 3, not 0.
        let s = [0.9, 0.9, 0.5, 0.85, 0.8, 1.0];
        assert_eq!(sustained(&s, t, 3), Some(3));
        // Above at the last two checkpoints only: an incomplete window is not convergence.
        assert_eq!(sustained(&[0.1, 0.9, 0.9], t, 3), None);
        assert_eq!(sustained(&[0.9, 0.9], t, 3), None);
        // Alternating never holds.
        assert_eq!(sustained(&[0.9, 0.1, 0.9, 0.1, 0.9], t, 3), None);
        let cps: Vec<Checkpoint> = s
            .iter()
            .enumerate()
            .map(|(i, &x)| cp(x, 100 * i as u64))
            .collect();
        assert_eq!(
            status_of(&cps, t, 3, None),
            RunStatus::Converged {
                checkpoint: 3,
                gradient_evaluations: 300
            }
        );
        assert_eq!(status_of(&cps[..3], t, 3, None), RunStatus::NotConverged);
    }

    #[test]
    fn diverged_runs_are_never_counted_converged() {
        // Converged by its scores, then ‖θ‖ left the bound: diverged, not converged.
        let cps: Vec<Checkpoint> = (0..5).map(|i| cp(1.0, 100 * i)).collect();
        let s = status_of(&cps, 0.8, 3, Some(("‖θ‖ = 2e34 > 1e4".into(), 450)));
        assert!(s.is_diverged());
        assert!(!s.is_converged());
        assert_eq!(s.checkpoint(), None);
        assert_eq!(
            crate::tuning::selection_score(std::slice::from_ref(&s), 1000),
            2000.0
        );
        // The serialised status names itself (the verdict code reads it).
        let json = serde_json::to_string(&s).unwrap();
        assert!(json.contains(r#""status":"diverged""#), "{json}");
    }
}
