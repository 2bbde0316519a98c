//! One seed's run: the algorithm steps until the budget in gradient calls is used up, and the
//! iterate is evaluated at the checkpoints 0, `every_calls`, …, the budget (each at the first
//! iterate whose cumulative calls reach it; a step that crosses several serves each). The run's
//! RNG is seeded by the seed alone, so a run does not depend on which thread carries it out.
//! A failing step, a non-finite θ or ‖θ‖₂ beyond `run.norm_bound` (checked at θ₀ and after every
//! step, before that iterate is evaluated, as the appendix's runs are judged) ends the run as
//! *diverged*; that is data, not an error.

use super::config::{LoadedConfig, TaskName};
use super::error::RunError;
use super::first_step::check_first_step;
use super::oracle::{OnOracle, baseline_message, with_oracle};
use super::records::{Checkpoint, SeedRun, SeedTiming};
use super::runnable::{RunTask, theta0};
use super::task::TaskLearner;
use ilopt::algo::{
    CheckpointObserver, IterationMetrics, NormBound, RunFailure, Runner, Schedule, StoppingRule,
    Termination,
};
use ilopt::baseline::Baselined;
use ilopt::problem::{Cost, IlProblem, KitRng};
use rand::SeedableRng;
use std::time::Instant;

/// Run one seed of a config on its task; `progress` receives the calls used so far (capped at
/// the budget) after every step, and `reached` each checkpoint as soon as it is evaluated (a step
/// that crosses several checkpoint call counts gives one per count), in order; an error of
/// `reached` (e.g. the CSV cannot be written) ends the run with it.
///
/// # Errors
/// [`RunError::Invalid`] for an algorithm or θ₀ the problem rejects; [`RunError::Run`] if an
/// evaluation fails.
pub fn run_seed<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
    reached: &mut dyn FnMut(&[Checkpoint]) -> Result<(), RunError>,
) -> Result<(SeedRun, SeedTiming), RunError> {
    /// [`drive`] on whichever oracle the config asks for.
    struct Drive<'a, 'r, T: ?Sized> {
        task: &'a T,
        config: &'a LoadedConfig,
        seed: u64,
        progress: &'a (dyn Fn(u64) + Sync),
        reached: &'a mut (dyn FnMut(&[Checkpoint]) -> Result<(), RunError> + 'r),
    }
    impl<T: RunTask + ?Sized> OnOracle for Drive<'_, '_, T> {
        type Output = (SeedRun, SeedTiming);
        fn on<P: IlProblem<f64>>(self, oracle: &mut P) -> Result<Self::Output, RunError> {
            drive(
                self.task,
                oracle,
                self.config,
                self.seed,
                self.progress,
                self.reached,
            )
        }
    }
    let m = config.file.run.trajectories_per_gradient;
    task.seed_started(seed);
    let drive = Drive {
        task,
        config,
        seed,
        progress,
        reached,
    };
    with_oracle(task, config, m, drive)
}

/// The runner ([`Runner`]) with a gradient budget, [`NormBound`], the progress callback and the
/// checkpoint evaluations ([`Evaluations`]).
fn drive<T: RunTask + ?Sized, P: IlProblem<f64>>(
    task: &T,
    problem: &mut P,
    config: &LoadedConfig,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
    reached: &mut dyn FnMut(&[Checkpoint]) -> Result<(), RunError>,
) -> Result<(SeedRun, SeedTiming), RunError> {
    let f = &config.file;
    let budget = f.run.budget_calls;
    let mut algorithm = f
        .algorithm
        .build::<f64, P>()
        .map_err(|e| config.invalid("algorithm", e))?;
    let stop = StoppingRule {
        max_gradient_evaluations: Some(budget),
        max_free_steps: Some(ilopt::algo::MAX_FREE_STEPS),
        ..StoppingRule::default()
    };
    let mut evaluations = Evaluations {
        task,
        episodes: f.evaluation.episodes.unwrap_or(1),
        seed,
        checkpoints: Vec::new(),
        evaluation_seconds: 0.0,
        reached,
    };
    let rec = Runner::new(stop)
        .map_err(|e| config.invalid("run.budget_calls", e))?
        .keep_history(false)
        .with_observer(NormBound {
            bound: f.run.norm_bound,
        })
        .with_observer(|m: &IterationMetrics<f64>| {
            if m.iteration > 0 {
                progress(m.cost.gradient_evaluations.min(budget));
            }
        })
        .run_with_checkpoints(
            algorithm.as_mut(),
            problem,
            theta0(task, config)?,
            seed,
            Some(Schedule::every(
                f.evaluation.every_calls.unwrap_or(budget),
                budget,
            )),
            &mut evaluations,
        )
        .map_err(|e| match e {
            RunFailure::Start(e) => config.invalid("algorithm", e),
            RunFailure::Checkpoint(e) => e,
        })?;
    Ok((
        SeedRun {
            seed,
            seed_index: None,
            algorithm: rec.algorithm.to_string(),
            termination: (&rec.termination).into(),
            iterations: rec.iterations,
            cost: rec.cost,
            theta: rec.theta.iter().copied().collect(),
            checkpoints: evaluations.checkpoints,
            status: None,
            hyper_parameters: None,
        },
        SeedTiming {
            seed,
            seed_index: None,
            train_seconds: rec.train_seconds,
            evaluation_seconds: evaluations.evaluation_seconds,
            checkpoint_seconds: rec.seconds_at_checkpoints,
            converge_seconds: None,
        },
    ))
}

/// The checkpoint observer of `ilopt run`: [`RunTask::evaluate`] at the iterate, one [`Checkpoint`] per
/// call count it serves, each passed on to `reached` at once.
struct Evaluations<'b, T: ?Sized> {
    task: &'b T,
    episodes: u32,
    seed: u64,
    checkpoints: Vec<Checkpoint>,
    evaluation_seconds: f64,
    reached: &'b mut dyn FnMut(&[Checkpoint]) -> Result<(), RunError>,
}

impl<T: RunTask + ?Sized> CheckpointObserver<f64> for Evaluations<'_, T> {
    type Error = RunError;
    fn checkpoint(
        &mut self,
        m: &IterationMetrics<f64>,
        at_calls: &[u64],
    ) -> Result<Option<Termination>, RunError> {
        let started = Instant::now();
        let seed = self.seed;
        let ev = self
            .task
            .evaluate(m.theta.as_slice(), self.episodes, seed)
            .map_err(|message| RunError::Run { seed, message })?;
        self.evaluation_seconds += started.elapsed().as_secs_f64();
        let c = Checkpoint::of_iterate(m, &ev);
        let before = self.checkpoints.len();
        self.checkpoints
            .extend(at_calls.iter().map(|&at_calls| Checkpoint {
                at_calls,
                ..c.clone()
            }));
        (self.reached)(&self.checkpoints[before..])?;
        Ok(None)
    }
}

/// Every check of a config against its task before anything is written: θ₀'s length
/// ([`theta0`]), the algorithm ([`check_algorithm`]), the baseline ([`check_baseline`]) and the
/// first step's least cost against the budget ([`check_first_step`]).
///
/// # Errors
/// [`RunError::Invalid`] naming the key at fault; [`RunError::OverBudget`].
pub fn check_config<T: RunTask + ?Sized>(task: &T, config: &LoadedConfig) -> Result<(), RunError> {
    let named = config.file.task.name;
    if named != TaskName::Custom && named.name() != task.task_name() {
        return Err(config.invalid(
            "task.name",
            format!(
                "the config names the built-in task \"{}\", but the task passed with it is \
                 \"{}\": a plug-in task's config leaves out [task] and [policy], which the task \
                 brings",
                named.name(),
                task.task_name()
            ),
        ));
    }
    theta0(task, config)?;
    check_algorithm(task, config)?;
    check_baseline(task, config)?;
    check_first_step(task, config)
}

/// [`check_config`] on a config's built-in task.
///
/// # Errors
/// As [`check_config`].
pub fn check_builtin(learner: &TaskLearner, config: &LoadedConfig) -> Result<(), RunError> {
    ilopt::with_task_learner!(learner, t => check_config(t, config))
}

/// Build the config's algorithm for the task's problem once, so that invalid hyper-parameters
/// are reported before anything is written.
///
/// # Errors
/// [`RunError::Invalid`] naming `algorithm` with the algorithm's own message.
pub fn check_algorithm<T: RunTask + ?Sized>(
    _task: &T,
    config: &LoadedConfig,
) -> Result<(), RunError> {
    config
        .file
        .algorithm
        .build::<f64, T::Problem>()
        .map(drop)
        .map_err(|e| config.invalid("algorithm", e))
}

/// Check the config's baseline against the problem before anything is written: its parameters
/// ([`Baselined::new`]) and, on one throwaway roll-out at θ₀, what only the problem can tell
/// (e.g. more state features asked for than it has). Other failures of that roll-out are left to
/// the runs, where they are data.
///
/// # Errors
/// [`RunError::Invalid`] naming `run.baseline`.
pub fn check_baseline<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
) -> Result<(), RunError> {
    use ilopt::problem::{Behaviour, EstimatorForm, OracleError};
    let Some(b) = config
        .file
        .run
        .baseline
        .as_ref()
        .filter(|b| **b != ilopt::baseline::Baseline::None)
    else {
        return Ok(());
    };
    let m = config.file.run.trajectories_per_gradient;
    let theta = theta0(task, config)?;
    let bad = |e: OracleError| config.invalid("run.baseline", baseline_message(e));
    let mut o = Baselined::<_, f64>::new(task.problem().clone(), m, b).map_err(bad)?;
    let mut rng = KitRng::seed_from_u64(0);
    let mut cost = Cost::default();
    let tried = o
        .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
        .and_then(|t| o.estimate(&theta, &t, EstimatorForm::Causal, &mut cost));
    match tried {
        Err(e @ OracleError::Baseline(_)) => Err(bad(e)),
        _ => Ok(()),
    }
}
