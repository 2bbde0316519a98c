//! One seed's run: the algorithm steps until the budget in gradient calls is used up, and the
//! iterate is evaluated at the checkpoints 0, `every_calls`, …, the budget (each at the first
//! iterate whose cumulative calls reach it; a step that crosses several serves each). The run's
//! RNG is seeded by the seed alone, so a run does not depend on which thread carries it out.
//! A failing step, a non-finite θ or ‖θ‖₂ beyond `run.norm_bound` (checked at θ₀ and after every
//! step, before that iterate is evaluated, as the appendix's runs are judged) ends the run as
//! *diverged*; that is data, not an error.

use super::config::LoadedConfig;
use super::error::RunError;
use super::evaluation::evaluate;
use super::records::{Checkpoint, SeedRun, SeedTiming};
use super::task::Bench;
use ilopt::algo::StepContext;
use ilopt::baseline::Baselined;
use ilopt::batched::Batched;
use ilopt::problem::{Cost, IlProblem, KitRng};
use nalgebra::DVector;
use rand::SeedableRng;
use std::time::{Duration, Instant};

/// Steps in a row without a gradient call after which a run is stopped (an algorithm whose
/// steps cost nothing would never use up the budget).
const MAX_FREE_STEPS: u64 = 10_000;

/// Run one seed of a config on its bench; `progress` receives the calls used so far (capped at
/// the budget) after every step.
///
/// # Errors
/// [`RunError::Invalid`] for an algorithm or θ₀ the problem rejects; [`RunError::Run`] if an
/// evaluation fails.
pub fn run_seed(
    bench: &Bench,
    config: &LoadedConfig,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(SeedRun, SeedTiming), RunError> {
    let m = config.file.run.trajectories_per_gradient;
    let baseline = config
        .file
        .run
        .baseline
        .as_ref()
        .filter(|b| **b != ilopt::baseline::Baseline::None);
    macro_rules! on {
        ($p:expr) => {
            if let Some(b) = baseline {
                let b = Baselined::<_, f64>::new($p.clone(), m, b)
                    .map_err(|e| config.invalid("run.baseline", baseline_message(e)))?;
                drive(bench, &b, config, seed, progress)
            } else if m > 1 {
                let b = Batched::new($p.clone(), m)
                    .map_err(|e| config.invalid("run.trajectories_per_gradient", e))?;
                drive(bench, &b, config, seed, progress)
            } else {
                drive(bench, $p, config, seed, progress)
            }
        };
    }
    match bench {
        Bench::CartPoleSoftmax(p) => on!(p),
        Bench::CartPoleLogistic(p) => on!(p),
        Bench::Obstacle { problem, .. } => on!(problem),
        Bench::Toy(p) => on!(p),
    }
}

fn drive<P: IlProblem<f64>>(
    bench: &Bench,
    problem: &P,
    config: &LoadedConfig,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(SeedRun, SeedTiming), RunError> {
    let f = &config.file;
    let budget = f.run.budget_calls;
    let every = f.evaluation.every_calls.unwrap_or(budget).max(1);
    let episodes = f.evaluation.episodes.unwrap_or(1);
    let bound = f.run.norm_bound;
    let mut algorithm = f
        .algorithm
        .build::<f64, P>()
        .map_err(|e| config.invalid("algorithm", e))?;
    let name = algorithm.name().to_string();
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    let (mut train, mut eval_time) = (Duration::ZERO, Duration::ZERO);
    let mut clock = Instant::now();
    algorithm
        .init(
            problem,
            bench.theta0(config)?,
            &mut StepContext {
                rng: &mut rng,
                cost: &mut cost,
            },
        )
        .map_err(|e| config.invalid("algorithm", e))?;
    let mut checkpoints = Vec::new();
    let mut seconds = Vec::new();
    let mut next = 0u64;
    let mut iteration = 0u64;
    let (mut train_loss, mut gradient_norm) = (None, None);
    let mut free_steps = 0u64;
    let termination = loop {
        let theta = algorithm.theta();
        if !theta.iter().all(|x| x.is_finite()) {
            break "diverged: non-finite θ".to_string();
        }
        let norm = norm_of(theta);
        if norm > bound {
            break format!("diverged: ‖θ‖ = {norm:.3e} > {bound:e}");
        }
        if next <= budget && cost.gradient_evaluations >= next {
            train += clock.elapsed();
            let started = Instant::now();
            let ev = evaluate(bench, theta.as_slice(), episodes, seed)
                .map_err(|message| RunError::Run { seed, message })?;
            eval_time += started.elapsed();
            let c = Checkpoint::new(0, iteration, &cost, train_loss, gradient_norm, &ev);
            while next <= budget && cost.gradient_evaluations >= next {
                checkpoints.push(Checkpoint {
                    at_calls: next,
                    ..c.clone()
                });
                seconds.push(train.as_secs_f64());
                next = if next == budget {
                    u64::MAX
                } else {
                    (next + every).min(budget)
                };
            }
            clock = Instant::now();
        }
        if cost.gradient_evaluations >= budget {
            break "gradient-budget".to_string();
        }
        let before = cost.gradient_evaluations;
        let step = algorithm.step(
            problem,
            &mut StepContext {
                rng: &mut rng,
                cost: &mut cost,
            },
        );
        match step {
            Ok(report) => {
                iteration += 1;
                train_loss = report.loss.filter(|l: &f64| l.is_finite());
                gradient_norm = report
                    .estimate
                    .as_ref()
                    .map(|d: &DVector<f64>| d.norm())
                    .filter(|n| n.is_finite());
                progress(cost.gradient_evaluations.min(budget));
                if report.finished {
                    break "finished".to_string();
                }
            }
            Err(e) => break format!("diverged: step failed: {e}"),
        }
        free_steps = if cost.gradient_evaluations == before {
            free_steps + 1
        } else {
            0
        };
        if free_steps >= MAX_FREE_STEPS {
            break format!("diverged: {MAX_FREE_STEPS} steps in a row without a gradient call");
        }
    };
    train += clock.elapsed();
    Ok((
        SeedRun {
            seed,
            algorithm: name,
            termination,
            iterations: iteration,
            cost,
            theta: algorithm.theta().iter().copied().collect(),
            checkpoints,
        },
        SeedTiming {
            seed,
            train_seconds: train.as_secs_f64(),
            evaluation_seconds: eval_time.as_secs_f64(),
            checkpoint_seconds: seconds,
        },
    ))
}

/// ‖θ‖₂ of a finite θ. When the sum of squares overflows, the largest |θᵢ| is factored out so
/// that the reported norm is the true one (finite whenever it is representable).
fn norm_of(theta: &DVector<f64>) -> f64 {
    let norm = theta.norm();
    if norm.is_finite() {
        return norm;
    }
    let largest = theta.amax();
    largest * (theta / largest).norm()
}

/// Build the config's algorithm for the bench's problem once, so that invalid hyper-parameters
/// are reported before anything is written.
///
/// # Errors
/// [`RunError::Invalid`] naming `algorithm` with the algorithm's own message.
pub fn check_algorithm(bench: &Bench, config: &LoadedConfig) -> Result<(), RunError> {
    let alg = &config.file.algorithm;
    let r = match bench {
        Bench::CartPoleSoftmax(_) => alg.build::<f64, super::task::CartPoleSoftmax>().map(drop),
        Bench::CartPoleLogistic(_) => alg.build::<f64, super::task::CartPoleLogistic>().map(drop),
        Bench::Obstacle { .. } => alg.build::<f64, super::task::ObstacleProblem>().map(drop),
        Bench::Toy(_) => alg.build::<f64, ilopt::toy::ToyProblem<f64>>().map(drop),
    };
    r.map_err(|e| config.invalid("algorithm", e))
}

/// Check the config's baseline against the problem before anything is written: its parameters
/// ([`Baselined::new`]) and, on one throwaway roll-out at θ₀, what only the problem can tell
/// (e.g. more state features asked for than it has). Other failures of that roll-out are left to
/// the runs, where they are data.
///
/// # Errors
/// [`RunError::Invalid`] naming `run.baseline`.
pub fn check_baseline(bench: &Bench, config: &LoadedConfig) -> Result<(), RunError> {
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
    let theta = bench.theta0(config)?;
    let bad = |e: OracleError| config.invalid("run.baseline", baseline_message(e));
    macro_rules! on {
        ($p:expr) => {{
            let o = Baselined::<_, f64>::new($p.clone(), m, b).map_err(bad)?;
            let mut rng = KitRng::seed_from_u64(0);
            let mut cost = Cost::default();
            let tried = o
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
                .and_then(|t| o.estimate(&theta, &t, EstimatorForm::Causal, &mut cost));
            match tried {
                Err(e @ OracleError::Baseline(_)) => Err(bad(e)),
                _ => Ok(()),
            }
        }};
    }
    match bench {
        Bench::CartPoleSoftmax(p) => on!(p),
        Bench::CartPoleLogistic(p) => on!(p),
        Bench::Obstacle { problem, .. } => on!(problem),
        Bench::Toy(p) => on!(p),
    }
}

/// An oracle's error about its baseline without the "baseline: " its message starts with (the
/// key `run.baseline` already says it); any other error as it is.
fn baseline_message(e: ilopt::problem::OracleError) -> String {
    match e {
        ilopt::problem::OracleError::Baseline(m) => m,
        e => e.to_string(),
    }
}
