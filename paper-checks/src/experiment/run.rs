//! One seeded run: its key and seed, θ₁, the driver that trains and evaluates at the
//! checkpoints ([`run_spec`]), and the reference policies' seeds.

use super::task_learner::{
    evaluate_learner, evaluate_reference, gradient_xy, resets_to_full_episode,
};
use super::{
    Checkpoint, Evaluated, ReferencePolicy, SeedRun, SeedTiming, TaskKind, TaskLearner, status_of,
    sustained,
};
use crate::config::{AlgorithmEntry, TaskExperiment, Theta1};
use crate::error::Error;
use crate::stats::derive_seed;
use ilopt::algo::{
    AlgorithmConfig, CheckpointObserver, IterationMetrics, NormBound, RunFailure, Runner, Schedule,
    StoppingRule, Termination,
};
use ilopt::baseline::{Baseline as OracleBaseline, Baselined, PerDecisionTerms};
use ilopt::batched::Batched;
use ilopt::problem::{Cost, IlProblem, KitRng};
use ilopt::task::Horizon;
use nalgebra::DVector;
use rand::SeedableRng;

/// CartPole-v1's episode length.
pub fn cartpole_max_steps() -> usize {
    ilopt::env::cartpole::MAX_EPISODE_STEPS
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
pub fn run_key(kind: TaskKind, task: &TaskExperiment, entry: &AlgorithmEntry) -> String {
    run_key_of(
        kind,
        &entry.label,
        &entry.config,
        entry.m.unwrap_or(1),
        entry.horizon(task, kind),
        &entry.baseline.clone().unwrap_or_default(),
    )
}

/// One run to carry out.
#[derive(Debug, Clone)]
pub struct RunSpec<'a> {
    /// The task.
    pub kind: TaskKind,
    /// Its section (budget, checkpoints, bound, θ₁, evaluation).
    pub task: &'a TaskExperiment,
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
    bench: &TaskLearner,
    kind: TaskKind,
    task: &TaskExperiment,
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
/// status is [`RunStatus::Diverged`](super::RunStatus::Diverged) and it keeps the checkpoints reached.
pub fn run_spec(bench: &TaskLearner, spec: &RunSpec<'_>) -> Result<(SeedRun, SeedTiming), Error> {
    ilopt::with_task_learner!(bench, l => drive_with(bench, &l.problem, spec))
}

/// [`drive`] on `problem` as the spec wants it: with its baseline ([`Baselined`], m
/// trajectories per gradient), m trajectories per gradient ([`Batched`]), or as it is.
fn drive_with<P: PerDecisionTerms<f64> + Clone>(
    bench: &TaskLearner,
    problem: &P,
    spec: &RunSpec<'_>,
) -> Result<(SeedRun, SeedTiming), Error> {
    if spec.baseline != OracleBaseline::None {
        let mut b = Baselined::<P, f64>::new(problem.clone(), spec.m, &spec.baseline)
            .map_err(|e| Error::experiment("baseline", e))?;
        drive(bench, &mut b, spec)
    } else if spec.m > 1 {
        let mut b =
            Batched::new(problem.clone(), spec.m).map_err(|e| Error::experiment("minibatch", e))?;
        drive(bench, &mut b, spec)
    } else {
        drive(bench, &mut problem.clone(), spec)
    }
}

/// The run: ilopt's [`Runner`] with the task's budget, its [`NormBound`] and the checkpoint
/// evaluations ([`Evaluations`], which also stop tuning runs at sustained convergence);
/// training time without the evaluations.
fn drive<P: IlProblem<f64>>(
    bench: &TaskLearner,
    problem: &mut P,
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
    let stop = StoppingRule {
        max_gradient_evaluations: Some(task.budget),
        max_free_steps: Some(ilopt::algo::MAX_FREE_STEPS),
        ..StoppingRule::default()
    };
    let mut evaluations = Evaluations {
        bench,
        spec,
        checkpoints: Vec::new(),
        seconds: 0.0,
    };
    let rec = Runner::new(stop)
        .map_err(|e| Error::experiment(&what, e))?
        .keep_history(false)
        .with_observer(NormBound {
            bound: task.norm_bound,
        })
        .run_with_checkpoints(
            algorithm.as_mut(),
            problem,
            theta1(task.theta1, bench.dim(), &spec.key),
            spec.seed,
            Some(Schedule::every(task.checkpoint_every, task.budget)),
            &mut evaluations,
        )
        .map_err(|e| match e {
            RunFailure::Start(e) => Error::experiment(&what, e),
            RunFailure::Checkpoint(e) => e,
        })?;
    let (checkpoints, evaluation_seconds) = (evaluations.checkpoints, evaluations.seconds);
    let diverged = rec
        .termination
        .divergence()
        .map(|d| (d.to_string(), rec.cost.gradient_evaluations));
    let status = status_of(&checkpoints, task.converge_score, task.sustain, diverged);
    let converged = status.checkpoint();
    let seconds = rec.seconds_at_checkpoints;
    Ok((
        SeedRun {
            seed: spec.seed,
            seed_index: Some(spec.seed_index),
            algorithm: rec.algorithm.to_string(),
            termination: (&rec.termination).into(),
            iterations: rec.iterations,
            cost: rec.cost,
            theta: rec.theta.iter().copied().collect(),
            checkpoints,
            status: Some(status),
            hyper_parameters: Some(spec.hyper_parameters.clone()),
        },
        SeedTiming {
            seed: spec.seed,
            seed_index: Some(spec.seed_index),
            train_seconds: rec.train_seconds,
            evaluation_seconds,
            converge_seconds: converged.map(|i| seconds[i]),
            checkpoint_seconds: seconds,
        },
    ))
}

/// The checkpoint observer of the appendix's runs: the evaluation episodes, the obstacle task's
/// gradient rows and CartPole's resets to a full episode at the iterate, one [`Checkpoint`] per
/// call count it serves; tuning runs stop at sustained convergence.
struct Evaluations<'b, 's> {
    bench: &'b TaskLearner,
    spec: &'b RunSpec<'s>,
    checkpoints: Vec<Checkpoint>,
    seconds: f64,
}

impl CheckpointObserver<f64> for Evaluations<'_, '_> {
    type Error = Error;
    fn checkpoint(
        &mut self,
        m: &IterationMetrics<f64>,
        at_calls: &[u64],
    ) -> Result<Option<Termination>, Error> {
        let started = std::time::Instant::now();
        let (spec, task) = (self.spec, self.spec.task);
        let theta = &m.theta;
        let ev = evaluate_learner(
            self.bench,
            theta.as_slice(),
            task.eval_episodes,
            &spec.eval_key,
        )?;
        let grad = gradient_xy(
            self.bench,
            theta,
            task.grad_trajectories,
            derive_seed(
                &format!("{}|grad", spec.key),
                m.iteration * 1000 + u64::from(spec.seed_index),
            ),
        )?;
        let full = resets_to_full_episode(
            self.bench,
            theta.as_slice(),
            task.full_episode_cap,
            &spec.eval_key,
        )?;
        self.seconds += started.elapsed().as_secs_f64();
        let c = Checkpoint {
            loss_x: ev.loss_xy.map(|l| l.0),
            loss_y: ev.loss_xy.map(|l| l.1),
            grad_x: grad.map(|g| g.0),
            grad_y: grad.map(|g| g.1),
            resets_to_full_episode: full,
            ..Checkpoint::of_iterate(m, &ev)
        };
        self.checkpoints
            .extend(at_calls.iter().map(|&at_calls| Checkpoint {
                at_calls,
                ..c.clone()
            }));
        // At the budget the run ends anyway, as `gradient-budget`.
        if spec.stop_at_convergence && m.cost.gradient_evaluations < task.budget {
            let scores: Vec<f64> = self.checkpoints.iter().map(Evaluated::score).collect();
            if sustained(&scores, task.converge_score, task.sustain).is_some() {
                return Ok(Some(Termination::Stopped(SUSTAINED_CONVERGENCE)));
            }
        }
        Ok(None)
    }
}

/// The termination of a tuning run stopped at sustained convergence.
pub const SUSTAINED_CONVERGENCE: &str = "sustained-convergence";

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
    bench: &TaskLearner,
    kind: TaskKind,
    task: &TaskExperiment,
    baseline: ReferencePolicy,
    seed_index: u32,
) -> Result<Checkpoint, Error> {
    let ev = evaluate_reference(
        bench,
        baseline,
        task.eval_episodes,
        &eval_key(kind, seed_index),
    )?;
    Ok(Checkpoint {
        loss_x: ev.loss_xy.map(|l| l.0),
        loss_y: ev.loss_xy.map(|l| l.1),
        ..Checkpoint::new(0, 0, &Cost::default(), None, None, &ev)
    })
}
