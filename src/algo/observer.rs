//! What the [`Runner`](super::Runner) tells during a run: every iteration's
//! [`IterationMetrics`] to the [`Observer`]s ([`Progress`], [`NormBound`], metrics closures), and
//! the iterates at a [`Schedule`] of gradient-call counts to one [`CheckpointObserver`] (the
//! evaluations of `ilopt run` and paper-checks). Either may stop the run with a [`Termination`].

use super::Termination;
use super::termination::Divergence;
use crate::problem::Cost;
use crate::scalar::Scalar;
use nalgebra::DVector;

/// What the runner records after `init` (iteration 0) and after each step.
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
    /// The step's direction ([`StepReport::estimate`](super::StepReport::estimate): the oracle
    /// estimate for SGD, `d_{k+1}` for STORM, `g_n = g(w_n, τ_n)` for O2NC), if it has one; what
    /// the theory checks compare with the exact gradient.
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

/// Receives every [`IterationMetrics`] (metrics sinks, progress bars, the ‖θ‖ bound) and may end
/// the run by returning a [`Termination`].
pub trait Observer<S> {
    /// Called after `init` (iteration 0) and after every step, before the stopping rule.
    fn observe(&mut self, metrics: &IterationMetrics<S>) -> Option<Termination>;
}

/// A closure that looks at the metrics and never stops the run.
impl<S, F: FnMut(&IterationMetrics<S>)> Observer<S> for F {
    fn observe(&mut self, metrics: &IterationMetrics<S>) -> Option<Termination> {
        self(metrics);
        None
    }
}

/// A progress observer: one line on stderr every `every` iterations.
#[derive(Debug, Clone)]
pub struct Progress {
    /// Print every this many iterations (≥ 1).
    pub every: u64,
}

impl<S: Scalar> Observer<S> for Progress {
    fn observe(&mut self, m: &IterationMetrics<S>) -> Option<Termination> {
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
        None
    }
}

/// Ends the run with [`Divergence::NormBound`] when a finite θ has ‖θ‖₂ > `bound` (θ₀ included).
/// A non-finite θ is left to the runner ([`Divergence::NonFiniteTheta`]).
#[derive(Debug, Clone, Copy)]
pub struct NormBound {
    /// The bound on ‖θ‖₂.
    pub bound: f64,
}

impl Observer<f64> for NormBound {
    fn observe(&mut self, m: &IterationMetrics<f64>) -> Option<Termination> {
        if !m.theta.iter().all(|x| x.is_finite()) {
            return None;
        }
        let norm = norm_of(&m.theta);
        (norm > self.bound).then_some(Termination::Diverged(Divergence::NormBound {
            norm,
            bound: self.bound,
        }))
    }
}

/// ‖θ‖₂ of a finite θ. When the sum of squares overflows, the largest |θᵢ| is factored out so
/// that the norm is the true one (finite whenever it is representable).
pub fn norm_of(theta: &DVector<f64>) -> f64 {
    let norm = theta.norm();
    if norm.is_finite() {
        return norm;
    }
    let largest = theta.amax();
    largest * (theta / largest).norm()
}

/// The gradient-call counts 0, `every`, 2·`every`, …, `budget` (the last one `budget` itself).
/// The checkpoint of a count is the first iterate whose cumulative gradient calls reach it; a
/// step that crosses several counts serves each.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Schedule {
    every: u64,
    budget: u64,
    next: Option<u64>,
}

impl Schedule {
    /// Counts every `every` calls (0 is read as 1) up to `budget`.
    pub fn every(every: u64, budget: u64) -> Self {
        Schedule {
            every: every.max(1),
            budget,
            next: Some(0),
        }
    }

    /// The counts reached at `calls` cumulative gradient calls and not served before (in order;
    /// empty when none is due).
    pub fn due(&mut self, calls: u64) -> Vec<u64> {
        let mut due = Vec::new();
        while let Some(n) = self.next.filter(|&n| calls >= n) {
            due.push(n);
            self.next = (n < self.budget).then(|| (n + self.every).min(self.budget));
        }
        due
    }
}

/// Evaluates the iterate at the scheduled call counts (its time is kept apart from training
/// time: [`RunRecord::checkpoint_seconds`](super::RunRecord::checkpoint_seconds)).
pub trait CheckpointObserver<S> {
    /// What a failing evaluation reports (the run then ends with this error).
    type Error;

    /// Called with the iterate's metrics and the counts it serves (one or more). `Ok(Some(t))`
    /// ends the run with `t`.
    ///
    /// # Errors
    /// A failing evaluation.
    fn checkpoint(
        &mut self,
        metrics: &IterationMetrics<S>,
        at_calls: &[u64],
    ) -> Result<Option<Termination>, Self::Error>;
}
