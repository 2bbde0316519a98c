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
//! **Score and convergence** (one definition for every algorithm): the score of a checkpoint is
//! the obstacle task's success rate, or CartPole's mean episode reward divided by 500. A run
//! *converges* at the first checkpoint whose score is ≥ the task's `converge_score`; its "gradient
//! calls to converge" are the cumulative per-state gradient evaluations ([`Cost`]) at that
//! checkpoint, its runtime the training wall time up to it (evaluation excluded).

use crate::config::{AlgorithmEntry, CartPoleExpertChoice, TaskSection};
use crate::error::Error;
use crate::stats::derive_seed;
use ilopt::algo::{Num, RunConfig, Runner, StoppingRule};
use ilopt::env::obstacle::{
    ObstacleConfig, ObstacleEnv, ObstacleObs, Outcome, VoExpertParams, VoExpertPolicy,
};
use ilopt::policy::{LinearGaussian, Policy, Softmax, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::task::cartpole::{self, CartPoleEpisode, CartPoleTask};
use ilopt::task::obstacle::{ObstacleFeatures, ObstacleTask};
use ilopt::task::{Task, TaskProblem};
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

/// The evaluation of one checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Iteration of the run (0 = θ₀).
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
    /// Index of the first checkpoint that met the convergence criterion.
    pub converged: Option<usize>,
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
pub enum Baseline {
    /// The task's expert (the velocity-obstacle expert; CartPole's PPO or LQR expert).
    Expert,
    /// Obstacle task: full speed straight at the goal, ignoring the obstacle,
    /// `v = v_max·(g − p)/‖g − p‖`.
    StraightToGoal,
}

impl Baseline {
    /// Its label in tables and figures.
    pub fn label(self, bench: &Bench) -> String {
        match (self, bench) {
            (Baseline::Expert, Bench::Obstacle { .. }) => "Expert (VO)".into(),
            (Baseline::Expert, Bench::Cartpole { expert, .. }) => {
                format!("Expert ({})", expert.name())
            }
            (Baseline::StraightToGoal, _) => "Straight to goal".into(),
        }
    }

    /// The baselines of a task, in table order.
    pub fn of(kind: TaskKind) -> &'static [Baseline] {
        match kind {
            TaskKind::Obstacle => &[Baseline::Expert, Baseline::StraightToGoal],
            TaskKind::Cartpole => &[Baseline::Expert],
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
    pub fn new(kind: TaskKind, task: &TaskSection) -> Result<Self, Error> {
        let e = |x: &dyn std::fmt::Display| Error::experiment(kind.name(), x);
        Ok(match kind {
            TaskKind::Obstacle => Self::obstacle(
                task.sigma.unwrap_or(0.02),
                task.features.unwrap_or_default(),
            )?,
            TaskKind::Cartpole => {
                let choice = task.expert.unwrap_or_default();
                let t = match choice {
                    CartPoleExpertChoice::Lqr => CartPoleTask::with_lqr(),
                    CartPoleExpertChoice::Ppo => {
                        CartPoleTask::with_ppo(&CartPoleExpertChoice::ppo_file())
                    }
                }
                .map_err(|x| e(&x))?;
                Bench::Cartpole {
                    problem: TaskProblem {
                        task: t,
                        policy: Softmax::new(2, cartpole::FEATURES).map_err(|x| e(&x))?,
                        horizon: ilopt::task::Horizon::Episodic,
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
    fn evaluate_baseline(&self, b: Baseline, episodes: u32, key: &str) -> Result<Eval, Error> {
        let err = |x: &dyn std::fmt::Display| Error::experiment(format!("baseline ({key})"), x);
        match (self, b) {
            (Bench::Obstacle { expert, .. }, Baseline::Expert) => self.evaluate_obstacle(
                &mut |obs, _| expert.act(obs).map_err(|x| err(&x)),
                episodes,
                key,
            ),
            (Bench::Obstacle { env, .. }, Baseline::StraightToGoal) => self.evaluate_obstacle(
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
            (Bench::Cartpole { .. }, Baseline::Expert) => {
                self.evaluate_cartpole(&mut |_, _, label| Ok((label, 0.0)), episodes, key)
            }
            (Bench::Cartpole { .. }, Baseline::StraightToGoal) => Err(err(&"CartPole has no goal")),
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

/// The identity of an algorithm's runs: task, label and the algorithm's config (JSON). The run's
/// RNG seed is derived from it and the seed index only.
pub fn run_key(kind: TaskKind, entry: &AlgorithmEntry) -> String {
    let json = serde_json::to_string(&entry.config).unwrap_or_default();
    format!("{}|{}|{}", kind.name(), entry.label, json)
}

/// Run one seed of one algorithm and evaluate its checkpoints.
///
/// # Errors
/// [`Error::Experiment`] if the run cannot start or an evaluation fails. A run that fails
/// mid-way (e.g. a non-finite iterate) is *not* an error: its termination says so and it keeps
/// the checkpoints reached.
pub fn run_seed(
    bench: &Bench,
    kind: TaskKind,
    task: &TaskSection,
    entry: &AlgorithmEntry,
    seed_index: u32,
) -> Result<(SeedRun, SeedTiming), Error> {
    let key = run_key(kind, entry);
    let seed = derive_seed(&key, u64::from(seed_index));
    let iterations = entry.iterations(task);
    let every = entry.eval_every(task);
    let rc = RunConfig {
        algorithm: entry.config.clone(),
        theta0: vec![Num::Float(0.0); bench.dim()],
        seed,
        stop: StoppingRule::iterations(iterations),
    };
    let what = format!("{} / {} / seed {seed_index}", kind.name(), entry.label);
    let rec = match bench {
        Bench::Obstacle { problem, .. } => Runner::new(rc.stop.clone())
            .and_then(|mut r| r.run_config(&rc, problem))
            .map_err(|e| Error::experiment(&what, e))?,
        Bench::Cartpole { problem, .. } => Runner::new(rc.stop.clone())
            .and_then(|mut r| r.run_config(&rc, problem))
            .map_err(|e| Error::experiment(&what, e))?,
    };
    let eval_key = eval_key(kind, seed_index);
    let last = rec.history.last().map_or(0, |m| m.iteration);
    let mut checkpoints = Vec::new();
    let mut seconds = Vec::new();
    for m in &rec.history {
        if !(m.iteration.is_multiple_of(every) || m.iteration == last) {
            continue;
        }
        if !m.theta.iter().all(|x| x.is_finite()) {
            break;
        }
        let ev = bench.evaluate(m.theta.as_slice(), task.eval_episodes, &eval_key)?;
        let grad = bench.gradient_xy(
            &m.theta,
            task.grad_trajectories,
            derive_seed(
                &format!("{key}|grad"),
                m.iteration * 1000 + u64::from(seed_index),
            ),
        )?;
        checkpoints.push(Checkpoint::from_eval(
            &ev,
            kind,
            task.eval_episodes,
            m.iteration,
            &m.cost,
            grad,
        ));
        seconds.push(m.wall_time);
    }
    let converged = checkpoints
        .iter()
        .position(|c| c.score >= task.converge_score);
    Ok((
        SeedRun {
            seed_index,
            seed,
            termination: rec.termination.to_string(),
            theta: rec.theta.iter().copied().collect(),
            checkpoints,
            converged,
        },
        SeedTiming {
            seed_index,
            train_seconds: rec.wall_time,
            converge_seconds: converged.map(|i| seconds[i]),
            checkpoint_seconds: seconds,
        },
    ))
}

/// The key of a seed's evaluation episodes: the same episodes for every algorithm, checkpoint
/// and baseline of that seed (common random numbers).
fn eval_key(kind: TaskKind, seed_index: u32) -> String {
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
    baseline: Baseline,
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
