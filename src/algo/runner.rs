//! The runner (conventions.md 5–7, argmin's `Executor` without argmin): it owns the loop, the stopping
//! rule, the observers, the seeded [`KitRng`], the cumulative [`Cost`] and the termination reason.
//!
//! Per iteration it records [`IterationMetrics`]: iteration, θ, cumulative cost (trajectories,
//! environment steps, per-state gradient evaluations = the "gradient calls" of Tables 4.1/4.3,
//! expert queries), wall time, the squared norm of the step's estimate, the step's loss estimate,
//! and optionally the exact objective through a user closure. Iteration 0 is the state after
//! [`Algorithm::init`] (which may already have sampled, e.g. STORM's d₁).
//!
//! A failing step (oracle error, undecidable interval branch, **non-finite iterate**) ends the run
//! with [`Termination::Failed`]; the record keeps everything up to that point.
//!
//! Stopping: after each step, in this order — the step failed; the algorithm finished its own
//! schedule; `max_iterations` reached; `max_gradient_evaluations` reached (the step that crosses
//! the budget completes, so the final count can exceed it by one step's cost); the target loss is
//! certainly reached (exact objective if a closure is given, else the step's loss estimate); the
//! time limit passed. Runs with a time limit are not reproducible when the limit binds.

use super::config::RunConfig;
use super::{AlgoError, Algorithm, ConfigNumber, StepContext, StepReport, invalid, norm_sq};
use crate::problem::{Cost, IlProblem, KitRng};
use crate::scalar::{JsonScalar, Scalar};
use nalgebra::DVector;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::time::Instant;

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

/// Why a run ended.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Termination {
    /// `max_iterations` reached.
    MaxIterations,
    /// The gradient-evaluation budget is used up.
    GradientBudget,
    /// The target loss was reached.
    TargetLoss,
    /// The time limit passed.
    TimeOut,
    /// The algorithm completed its own schedule (O2NC, forward training).
    Finished,
    /// A step failed (including a non-finite iterate: [`AlgoError::NonFinite`]).
    Failed(AlgoError),
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Termination::MaxIterations => write!(f, "max-iterations"),
            Termination::GradientBudget => write!(f, "gradient-budget"),
            Termination::TargetLoss => write!(f, "target-loss"),
            Termination::TimeOut => write!(f, "time-out"),
            Termination::Finished => write!(f, "finished"),
            Termination::Failed(e) => write!(f, "failed: {e}"),
        }
    }
}

/// What the runner records after each iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationMetrics<S> {
    /// 0 after `init`, then 1, 2, ….
    pub iteration: u64,
    /// The iterate.
    pub theta: DVector<S>,
    /// Cumulative cost so far.
    pub cost: Cost,
    /// Seconds since the run started.
    pub wall_time: f64,
    /// The step's direction ([`StepReport::estimate`]: the oracle estimate for SGD, `d_{k+1}` for
    /// STORM, `g_n = g(w_n, τ_n)` for O2NC), if it has one; what the theory checks compare with
    /// the exact gradient.
    pub estimate: Option<DVector<S>>,
    /// `‖estimate‖²` of the step's direction, if it has one.
    pub estimate_norm_sq: Option<S>,
    /// `‖estimate‖` for reporting (`f64`).
    pub estimate_norm: Option<f64>,
    /// The step's loss estimate, if any.
    pub loss: Option<S>,
    /// The exact objective at θ, if the runner has an objective closure.
    pub objective: Option<S>,
    /// Where the step evaluated its gradient, when that is not θ (O2NC's w_n).
    pub evaluated_at: Option<DVector<S>>,
}

/// Receives every [`IterationMetrics`] (metrics sinks, progress bars).
pub trait Observer<S> {
    /// Called after `init` (iteration 0) and after every step.
    fn observe(&mut self, metrics: &IterationMetrics<S>);
}

impl<S, F: FnMut(&IterationMetrics<S>)> Observer<S> for F {
    fn observe(&mut self, metrics: &IterationMetrics<S>) {
        self(metrics)
    }
}

/// A progress observer: one line on stderr every `every` iterations.
#[derive(Debug, Clone)]
pub struct Progress {
    /// Print every this many iterations (≥ 1).
    pub every: u64,
}

impl<S: Scalar> Observer<S> for Progress {
    fn observe(&mut self, m: &IterationMetrics<S>) {
        if m.iteration.is_multiple_of(self.every.max(1)) {
            eprintln!(
                "iter {:>8}  grads {:>10}  traj {:>8}  t {:>8.3}s  |d| {:>10}  loss {:>10}",
                m.iteration,
                m.cost.gradient_evaluations,
                m.cost.trajectories,
                m.wall_time,
                m.estimate_norm.map_or("-".into(), |x| format!("{x:.4e}")),
                m.objective
                    .as_ref()
                    .or(m.loss.as_ref())
                    .map_or("-".into(), |x| format!("{:.4e}", x.to_f64())),
            );
        }
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
        problem: &P,
    ) -> Result<RunRecord<S>, AlgoError> {
        let mut algorithm = config.algorithm.build::<S, P>()?;
        let mut rec = self.run(algorithm.as_mut(), problem, config.theta0()?, config.seed)?;
        rec.config = Some(config.clone());
        Ok(rec)
    }

    /// Run an algorithm from `theta0` with a ChaCha8 RNG seeded by `seed`.
    ///
    /// # Errors
    /// A failing `init` (later failures end the run with [`Termination::Failed`]).
    pub fn run<P: IlProblem<S> + ?Sized>(
        &mut self,
        algorithm: &mut dyn Algorithm<S, P>,
        problem: &P,
        theta0: DVector<S>,
        seed: u64,
    ) -> Result<RunRecord<S>, AlgoError> {
        let start = Instant::now();
        let mut rng = KitRng::seed_from_u64(seed);
        let mut cost = Cost::default();
        algorithm.init(
            problem,
            theta0,
            &mut StepContext {
                rng: &mut rng,
                cost: &mut cost,
            },
        )?;
        let mut history = Vec::new();
        self.record(
            &mut history,
            0,
            algorithm.theta(),
            cost,
            &start,
            &StepReport::new(None, None),
        );
        let mut iterations = 0u64;
        let termination = loop {
            let step = algorithm.step(
                problem,
                &mut StepContext {
                    rng: &mut rng,
                    cost: &mut cost,
                },
            );
            let report = match step {
                Ok(r) => r,
                Err(e) => break Termination::Failed(e),
            };
            iterations += 1;
            let loss = report.loss.clone();
            let objective = self.record(
                &mut history,
                iterations,
                algorithm.theta(),
                cost,
                &start,
                &report,
            );
            if !crate::scalar::all_finite(algorithm.theta().as_slice()) {
                break Termination::Failed(AlgoError::NonFinite("θ"));
            }
            if report.finished {
                break Termination::Finished;
            }
            if self.stop.max_iterations.is_some_and(|m| iterations >= m) {
                break Termination::MaxIterations;
            }
            if self
                .stop
                .max_gradient_evaluations
                .is_some_and(|b| cost.gradient_evaluations >= b)
            {
                break Termination::GradientBudget;
            }
            if let Some(target) = &self.target {
                let value = if self.objective.is_some() {
                    objective
                } else {
                    loss
                };
                if value.is_some_and(|v| {
                    matches!(
                        v.certain_cmp(target),
                        Some(Ordering::Less | Ordering::Equal)
                    )
                }) {
                    break Termination::TargetLoss;
                }
            }
            if self
                .stop
                .time_limit_ms
                .is_some_and(|ms| start.elapsed().as_millis() >= u128::from(ms))
            {
                break Termination::TimeOut;
            }
        };
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
            wall_time: start.elapsed().as_secs_f64(),
        })
    }

    /// Build the metrics, notify observers, store them; returns the objective value.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        history: &mut Vec<IterationMetrics<S>>,
        iteration: u64,
        theta: &DVector<S>,
        cost: Cost,
        start: &Instant,
        report: &StepReport<S>,
    ) -> Option<S> {
        if !self.keep_history && self.observers.is_empty() && self.objective.is_none() {
            return None;
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
        for o in &mut self.observers {
            o.observe(&m);
        }
        let objective = m.objective.clone();
        if self.keep_history {
            history.push(m);
        }
        objective
    }
}

/// Replay a recorded run: build the algorithm from `config` in `S` and run it with the recorded
/// seed and stopping rule (same result, bit for bit, unless a time limit binds).
///
/// # Errors
/// As [`Runner::run_config`].
pub fn replay<S: Scalar, P: IlProblem<S> + ?Sized>(
    config: &RunConfig,
    problem: &P,
) -> Result<RunRecord<S>, AlgoError> {
    Runner::new(config.stop.clone())?.run_config(config, problem)
}
