//! The runner (conventions.md 5–7, argmin's `Executor` without argmin): the one loop that steps
//! an [`Algorithm`]. It owns the seeded [`KitRng`], the cumulative [`Cost`], the stopping rule,
//! the observers and the termination reason; `ilopt run`, paper-checks and the examples all run
//! through it.
//!
//! Iteration 0 is the state after [`Algorithm::init`] (which may already have sampled, e.g.
//! STORM's d₁). At every iterate k = 0, 1, …, in this order:
//! 1. the [`Observer`]s see its [`IterationMetrics`] (θ, cumulative cost — trajectories,
//!    environment steps, per-state gradient evaluations = the "gradient calls" of Tables 4.1/4.3,
//!    expert queries —, wall time, the step's estimate and loss, optionally the exact objective
//!    through a user closure); one may end the run (e.g. [`NormBound`](super::NormBound));
//! 2. a non-finite θ ends the run ([`Divergence::NonFiniteTheta`]);
//! 3. (k ≥ 1) the algorithm finished its own schedule ([`Termination::Finished`]);
//! 4. `max_free_steps` steps in a row without a gradient call ([`Divergence::NoGradientCall`]);
//! 5. the [`CheckpointObserver`] evaluates the iterate at every scheduled call count it reaches
//!    ([`Schedule`]) and may end the run ([`Termination::Stopped`]);
//! 6. the stopping rule: `max_iterations` reached; `max_gradient_evaluations` reached (the step
//!    that crosses the budget completes, so the final count can exceed it by one step's cost);
//!    the target loss is certainly reached (exact objective if a closure is given, else the
//!    step's loss estimate); the time limit passed;
//! 7. the next step; a failing step ends the run ([`Divergence::StepFailed`]).
//!
//! A run that diverges is data: the record keeps everything up to that point. Runs with a time
//! limit are not reproducible when the limit binds. Time spent in the checkpoint observer is
//! measured apart, so that training time excludes evaluation time.

use super::config::RunConfig;
use super::observer::{CheckpointObserver, IterationMetrics, Observer, Schedule};
use super::termination::{Divergence, Termination};
use super::{AlgoError, Algorithm, ConfigNumber, StepContext, StepReport, invalid, norm_sq};
use crate::problem::{Cost, IlProblem, KitRng};
use crate::scalar::{JsonScalar, Scalar};
use nalgebra::DVector;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::time::{Duration, Instant};

/// The `max_free_steps` that `ilopt run` and the appendix's runs set: steps in a row without a
/// gradient call after which a run ends as diverged (an algorithm whose steps cost nothing would
/// never use up a gradient budget).
pub const MAX_FREE_STEPS: u64 = 10_000;

/// When a run stops (at least one of the bounds must be set).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StoppingRule {
    /// Maximum number of steps (≥ 1).
    pub max_iterations: Option<u64>,
    /// Budget of per-state gradient evaluations ([`Cost::gradient_evaluations`], ≥ 1).
    pub max_gradient_evaluations: Option<u64>,
    /// Stop once the loss is certainly ≤ this value.
    pub target_loss: Option<ConfigNumber>,
    /// Wall-clock limit in milliseconds (≥ 1).
    pub time_limit_ms: Option<u64>,
    /// End the run as diverged after this many steps in a row without a gradient call (≥ 1): an
    /// algorithm whose steps cost nothing would never use up a gradient budget.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_free_steps: Option<u64>,
}

impl StoppingRule {
    /// Stop after `n` iterations.
    pub fn iterations(n: u64) -> Self {
        StoppingRule {
            max_iterations: Some(n),
            ..Default::default()
        }
    }

    /// Stop after a budget of `n` gradient evaluations.
    pub fn gradient_budget(n: u64) -> Self {
        StoppingRule {
            max_gradient_evaluations: Some(n),
            ..Default::default()
        }
    }

    /// Check the rule.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] for a zero bound, a non-finite target, or no bound at all.
    pub fn validate(&self) -> Result<(), AlgoError> {
        for (name, v) in [
            ("stop.max_iterations", self.max_iterations),
            (
                "stop.max_gradient_evaluations",
                self.max_gradient_evaluations,
            ),
            ("stop.time_limit_ms", self.time_limit_ms),
            ("stop.max_free_steps", self.max_free_steps),
        ] {
            if v == Some(0) {
                return Err(invalid(name, "must be at least 1 (a zero budget)"));
            }
        }
        if let Some(t) = &self.target_loss {
            t.exact("stop.target_loss")?;
        }
        if self.max_iterations.is_none()
            && self.max_gradient_evaluations.is_none()
            && self.time_limit_ms.is_none()
        {
            return Err(invalid(
                "stop",
                "set at least one of max_iterations, max_gradient_evaluations, time_limit_ms",
            ));
        }
        Ok(())
    }
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct RunRecord<S> {
    /// The config, when the run was started from one (always for [`replay`]).
    pub config: Option<RunConfig>,
    /// The algorithm's name.
    pub algorithm: &'static str,
    /// The RNG seed.
    pub seed: u64,
    /// The final iterate.
    pub theta: DVector<S>,
    /// The algorithm's further outputs ([`Algorithm::outputs`]).
    pub outputs: Vec<DVector<S>>,
    /// Steps taken.
    pub iterations: u64,
    /// Total cost.
    pub cost: Cost,
    /// Why the run ended.
    pub termination: Termination,
    /// Per-iteration metrics (empty if history was switched off).
    pub history: Vec<IterationMetrics<S>>,
    /// Total wall time in seconds.
    pub wall_time: f64,
    /// Wall time in seconds without the time spent in the checkpoint observer.
    pub train_seconds: f64,
    /// Time spent in the checkpoint observer (the evaluations), in seconds.
    pub checkpoint_seconds: f64,
    /// Training time ([`RunRecord::train_seconds`] so far) at each scheduled call count served.
    pub seconds_at_checkpoints: Vec<f64>,
}

impl<S: Scalar> RunRecord<S> {
    /// Same run up to wall-clock times: config, seed, iterates, outputs, costs, termination,
    /// and every recorded metric except `wall_time`. (For floats, `==` is used, which is
    /// bit-equality for the finite values a run can hold, up to the sign of zero.)
    pub fn same_run(&self, other: &RunRecord<S>) -> bool {
        self.config == other.config
            && self.algorithm == other.algorithm
            && self.seed == other.seed
            && self.theta == other.theta
            && self.outputs == other.outputs
            && self.iterations == other.iterations
            && self.cost == other.cost
            && self.termination == other.termination
            && self.history.len() == other.history.len()
            && self.history.iter().zip(&other.history).all(|(a, b)| {
                a.iteration == b.iteration
                    && a.theta == b.theta
                    && a.cost == b.cost
                    && a.estimate == b.estimate
                    && a.estimate_norm_sq == b.estimate_norm_sq
                    && a.loss == b.loss
                    && a.objective == b.objective
                    && a.evaluated_at == b.evaluated_at
            })
    }

    /// A JSON summary: config, algorithm, seed, termination, iterations, cost, final θ, outputs.
    pub fn summary_json(&self) -> serde_json::Value
    where
        S: JsonScalar,
    {
        serde_json::json!({
            "config": self.config,
            "algorithm": self.algorithm,
            "seed": self.seed,
            "termination": self.termination.to_string(),
            "iterations": self.iterations,
            "cost": self.cost,
            "theta": self.theta.iter().map(JsonScalar::to_json).collect::<Vec<_>>(),
            "outputs": self.outputs.iter()
                .map(|o| o.iter().map(JsonScalar::to_json).collect::<Vec<_>>())
                .collect::<Vec<_>>(),
            "wall_time": self.wall_time,
        })
    }

    /// Every recorded [`IterationMetrics`] as a JSON array.
    pub fn history_json(&self) -> serde_json::Value
    where
        S: JsonScalar,
    {
        serde_json::Value::Array(self.history.iter().map(IterationMetrics::to_json).collect())
    }
}

impl<S: JsonScalar> IterationMetrics<S> {
    /// The metrics as JSON (scalars as [`JsonScalar`] writes them: exact fractions for
    /// rationals, `[lo, hi]` for intervals).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "iteration": self.iteration,
            "theta": self.theta.iter().map(JsonScalar::to_json).collect::<Vec<_>>(),
            "cost": self.cost,
            "wall_time": self.wall_time,
            "estimate_norm_sq": self.estimate_norm_sq.as_ref().map(JsonScalar::to_json),
            "loss": self.loss.as_ref().map(JsonScalar::to_json),
            "objective": self.objective.as_ref().map(JsonScalar::to_json),
            "evaluated_at": self.evaluated_at.as_ref()
                .map(|w| w.iter().map(JsonScalar::to_json).collect::<Vec<_>>()),
        })
    }
}

/// A boxed objective closure.
type Objective<'a, S> = Box<dyn Fn(&DVector<S>) -> Option<S> + 'a>;

/// The runner: stopping rule, observers, optional exact objective.
pub struct Runner<'a, S> {
    stop: StoppingRule,
    target: Option<S>,
    objective: Option<Objective<'a, S>>,
    observers: Vec<Box<dyn Observer<S> + 'a>>,
    keep_history: bool,
}

impl<S> std::fmt::Debug for Runner<'_, S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Runner")
            .field("stop", &self.stop)
            .field("observers", &self.observers.len())
            .field("objective", &self.objective.is_some())
            .field("keep_history", &self.keep_history)
            .finish()
    }
}

impl<'a, S: Scalar> Runner<'a, S> {
    /// A runner with the given stopping rule; history is kept.
    ///
    /// # Errors
    /// As [`StoppingRule::validate`].
    pub fn new(stop: StoppingRule) -> Result<Self, AlgoError> {
        stop.validate()?;
        let target = match &stop.target_loss {
            Some(t) => Some(t.to::<S>("stop.target_loss")?),
            None => None,
        };
        Ok(Runner {
            stop,
            target,
            objective: None,
            observers: Vec::new(),
            keep_history: true,
        })
    }

    /// Evaluate the exact objective at every iterate (e.g. the toy engine's F); `None` from the
    /// closure leaves the metric empty.
    pub fn with_objective(mut self, f: impl Fn(&DVector<S>) -> Option<S> + 'a) -> Self {
        self.objective = Some(Box::new(f));
        self
    }

    /// Add an observer.
    pub fn with_observer(mut self, o: impl Observer<S> + 'a) -> Self {
        self.observers.push(Box::new(o));
        self
    }

    /// Keep (default) or drop the per-iteration history in the record.
    pub fn keep_history(mut self, keep: bool) -> Self {
        self.keep_history = keep;
        self
    }

    /// Run a config: build its algorithm in `S` ([`crate::algo::AlgorithmConfig::build`]), seed
    /// the RNG, run.
    ///
    /// # Errors
    /// Invalid configuration (including [`AlgoError::NeedsRoots`]) or a failing `init`.
    pub fn run_config<P: IlProblem<S> + ?Sized>(
        &mut self,
        config: &RunConfig,
        problem: &mut P,
    ) -> Result<RunRecord<S>, AlgoError> {
        let mut algorithm = config.algorithm.build::<S, P>()?;
        let mut rec = self.run(algorithm.as_mut(), problem, config.theta0()?, config.seed)?;
        rec.config = Some(config.clone());
        Ok(rec)
    }

    /// Run an algorithm from `theta0` with a ChaCha8 RNG seeded by `seed`.
    ///
    /// # Errors
    /// A failing `init` (later failures end the run with [`Termination::Diverged`]).
    pub fn run<P: IlProblem<S> + ?Sized>(
        &mut self,
        algorithm: &mut dyn Algorithm<S, P>,
        problem: &mut P,
        theta0: DVector<S>,
        seed: u64,
    ) -> Result<RunRecord<S>, AlgoError> {
        self.run_with_checkpoints(algorithm, problem, theta0, seed, None, &mut NoCheckpoints)
            .map_err(|e| match e {
                RunFailure::Start(e) => e,
                RunFailure::Checkpoint(never) => match never {},
            })
    }

    /// [`Runner::run`] with a checkpoint observer told at the call counts of `schedule` (none
    /// without a schedule).
    ///
    /// # Errors
    /// [`RunFailure::Start`] for a failing `init`, [`RunFailure::Checkpoint`] for a failing
    /// evaluation (later step failures end the run with [`Termination::Diverged`]).
    pub fn run_with_checkpoints<P, C>(
        &mut self,
        algorithm: &mut dyn Algorithm<S, P>,
        problem: &mut P,
        theta0: DVector<S>,
        seed: u64,
        mut schedule: Option<Schedule>,
        checkpoints: &mut C,
    ) -> Result<RunRecord<S>, RunFailure<C::Error>>
    where
        P: IlProblem<S> + ?Sized,
        C: CheckpointObserver<S> + ?Sized,
    {
        let start = Instant::now();
        let mut in_checkpoints = Duration::ZERO;
        let mut seconds_at_checkpoints = Vec::new();
        let mut rng = KitRng::seed_from_u64(seed);
        let mut cost = Cost::default();
        algorithm
            .init(
                problem,
                theta0,
                &mut StepContext {
                    rng: &mut rng,
                    cost: &mut cost,
                },
            )
            .map_err(RunFailure::Start)?;
        let mut history = Vec::new();
        let mut iterations = 0u64;
        let mut report = StepReport::new(None, None);
        let mut free_steps = 0u64;
        let termination = loop {
            let scheduled = schedule.is_some();
            let (unkept, stop) = self.record(
                &mut history,
                iterations,
                algorithm.theta(),
                cost,
                &start,
                &report,
                scheduled,
            );
            let m = unkept.as_ref().or(history.last());
            if let Some(t) = stop {
                break t;
            }
            if !crate::scalar::all_finite(algorithm.theta().as_slice()) {
                break Termination::Diverged(Divergence::NonFiniteTheta);
            }
            if report.finished {
                break Termination::Finished;
            }
            if self.stop.max_free_steps.is_some_and(|k| free_steps >= k) {
                break Termination::Diverged(Divergence::NoGradientCall { steps: free_steps });
            }
            let due = schedule
                .as_mut()
                .map_or_else(Vec::new, |s| s.due(cost.gradient_evaluations));
            if let (false, Some(m)) = (due.is_empty(), m) {
                let train = start.elapsed().saturating_sub(in_checkpoints).as_secs_f64();
                seconds_at_checkpoints.extend(due.iter().map(|_| train));
                let began = Instant::now();
                let verdict = checkpoints.checkpoint(m, &due);
                in_checkpoints += began.elapsed();
                if let Some(t) = verdict.map_err(RunFailure::Checkpoint)? {
                    break t;
                }
            }
            if let Some(t) = self.stopping_rule(iterations, &cost, m, &report, &start) {
                break t;
            }
            let before = cost.gradient_evaluations;
            report = match algorithm.step(
                problem,
                &mut StepContext {
                    rng: &mut rng,
                    cost: &mut cost,
                },
            ) {
                Ok(r) => r,
                Err(e) => break Termination::Diverged(Divergence::StepFailed(e)),
            };
            iterations += 1;
            free_steps = if cost.gradient_evaluations == before {
                free_steps + 1
            } else {
                0
            };
        };
        let wall = start.elapsed();
        Ok(RunRecord {
            config: None,
            algorithm: algorithm.name(),
            seed,
            theta: algorithm.theta().clone(),
            outputs: algorithm.outputs(),
            iterations,
            cost,
            termination,
            history,
            wall_time: wall.as_secs_f64(),
            train_seconds: wall.saturating_sub(in_checkpoints).as_secs_f64(),
            checkpoint_seconds: in_checkpoints.as_secs_f64(),
            seconds_at_checkpoints,
        })
    }

    /// The stopping rule at iterate `iterations` (step 6 of the module's order).
    fn stopping_rule(
        &self,
        iterations: u64,
        cost: &Cost,
        metrics: Option<&IterationMetrics<S>>,
        report: &StepReport<S>,
        start: &Instant,
    ) -> Option<Termination> {
        if self.stop.max_iterations.is_some_and(|m| iterations >= m) {
            return Some(Termination::MaxIterations);
        }
        if self
            .stop
            .max_gradient_evaluations
            .is_some_and(|b| cost.gradient_evaluations >= b)
        {
            return Some(Termination::GradientBudget);
        }
        if let Some(target) = &self.target {
            let value = if self.objective.is_some() {
                metrics.and_then(|m| m.objective.as_ref())
            } else {
                report.loss.as_ref()
            };
            if value.is_some_and(|v| {
                matches!(
                    v.certain_cmp(target),
                    Some(Ordering::Less | Ordering::Equal)
                )
            }) {
                return Some(Termination::TargetLoss);
            }
        }
        if self
            .stop
            .time_limit_ms
            .is_some_and(|ms| start.elapsed().as_millis() >= u128::from(ms))
        {
            return Some(Termination::TimeOut);
        }
        None
    }

    /// Build the metrics (when anything needs them), tell every observer, store them in the
    /// history if it is kept; returns them when they are not stored, and the first observer's
    /// stop.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        history: &mut Vec<IterationMetrics<S>>,
        iteration: u64,
        theta: &DVector<S>,
        cost: Cost,
        start: &Instant,
        report: &StepReport<S>,
        scheduled: bool,
    ) -> (Option<IterationMetrics<S>>, Option<Termination>) {
        if !self.keep_history && self.observers.is_empty() && self.objective.is_none() && !scheduled
        {
            return (None, None);
        }
        let estimate_norm_sq = report.estimate.as_ref().map(norm_sq);
        let m = IterationMetrics {
            iteration,
            theta: theta.clone(),
            cost,
            wall_time: start.elapsed().as_secs_f64(),
            estimate_norm: estimate_norm_sq.as_ref().map(|x| x.to_f64().sqrt()),
            estimate_norm_sq,
            estimate: report.estimate.clone(),
            loss: report.loss.clone(),
            evaluated_at: report.evaluated_at.clone(),
            objective: self.objective.as_ref().and_then(|f| {
                if theta.iter().all(Scalar::is_finite) {
                    f(theta)
                } else {
                    None
                }
            }),
        };
        let mut stop = None;
        for o in &mut self.observers {
            let t = o.observe(&m);
            stop = stop.or(t);
        }
        if self.keep_history {
            history.push(m);
            return (None, stop);
        }
        (Some(m), stop)
    }
}

/// Why [`Runner::run_with_checkpoints`] returned no record.
#[derive(Debug, Clone, PartialEq)]
pub enum RunFailure<E> {
    /// [`Algorithm::init`] failed.
    Start(AlgoError),
    /// The checkpoint observer failed.
    Checkpoint(E),
}

/// The checkpoint observer of a run without checkpoints.
struct NoCheckpoints;

impl<S> CheckpointObserver<S> for NoCheckpoints {
    type Error = std::convert::Infallible;
    fn checkpoint(
        &mut self,
        _: &IterationMetrics<S>,
        _: &[u64],
    ) -> Result<Option<Termination>, Self::Error> {
        Ok(None)
    }
}

/// Replay a recorded run: build the algorithm from `config` in `S` and run it with the recorded
/// seed and stopping rule (same result, bit for bit, unless a time limit binds).
///
/// # Errors
/// As [`Runner::run_config`].
pub fn replay<S: Scalar, P: IlProblem<S> + ?Sized>(
    config: &RunConfig,
    problem: &mut P,
) -> Result<RunRecord<S>, AlgoError> {
    Runner::new(config.stop.clone())?.run_config(config, problem)
}

#[cfg(test)]
mod tests;
