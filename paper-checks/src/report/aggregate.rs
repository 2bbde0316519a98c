//! Per-configuration aggregates over seeds (Student-t 95% intervals, [`Summary`]) and their
//! printed form.

use crate::experiment::{Checkpoint, SeedRun};
use crate::results::{ConfigResult, ConfigTiming};
use crate::stats::Summary;
use serde::Serialize;

/// Gradient calls (or runtime) to converge of one configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConvergenceRow {
    /// Algorithm.
    pub label: String,
    /// Seeds that converged.
    pub converged: usize,
    /// Seeds.
    pub seeds: usize,
    /// Over the converged seeds.
    pub gradient_calls: Summary,
    /// Gradient calls of the whole run (all seeds).
    pub total_gradient_calls: Summary,
    /// Final score (all seeds).
    pub final_score: Summary,
    /// Final crashes (all seeds).
    pub final_crashes: Summary,
    /// Final mean reward (all seeds).
    pub final_reward: Summary,
    /// Final evaluation loss (all seeds).
    pub final_loss: Summary,
    /// Diverged runs ([`crate::experiment::RunStatus::Diverged`]: ‖θ‖ beyond the bound, a
    /// non-finite iterate, a failed step).
    pub failed_runs: usize,
}

/// A run's last checkpoint.
pub(crate) fn last(r: &SeedRun) -> Option<&Checkpoint> {
    r.checkpoints.last()
}

/// A summary over seeds of `f` at each run's last checkpoint.
pub(crate) fn summarise(c: &ConfigResult, f: impl Fn(&Checkpoint) -> f64) -> Summary {
    let xs: Vec<f64> = c.runs.iter().filter_map(last).map(f).collect();
    Summary::of(&xs)
}

/// The convergence row of one configuration.
pub fn convergence_row(c: &ConfigResult) -> ConvergenceRow {
    let calls: Vec<f64> = c
        .runs
        .iter()
        .filter_map(|r| {
            r.converged
                .map(|i| r.checkpoints[i].gradient_evaluations as f64)
        })
        .collect();
    ConvergenceRow {
        label: c.label.clone(),
        converged: calls.len(),
        seeds: c.runs.len(),
        gradient_calls: Summary::of(&calls),
        total_gradient_calls: summarise(c, |k| k.gradient_evaluations as f64),
        final_score: summarise(c, |k| k.score),
        final_crashes: summarise(c, |k| f64::from(k.crashes)),
        final_reward: summarise(c, |k| k.reward),
        final_loss: summarise(c, |k| k.loss),
        failed_runs: c.runs.iter().filter(|r| r.status.is_diverged()).count(),
    }
}

/// Wall seconds to converge (converged seeds) and to train (all seeds) of one configuration;
/// empty without timings.
pub(crate) fn runtime(t: Option<&ConfigTiming>) -> (Summary, Summary) {
    let Some(t) = t else {
        return (Summary::of(&[]), Summary::of(&[]));
    };
    let conv: Vec<f64> = t.runs.iter().filter_map(|r| r.converge_seconds).collect();
    let total: Vec<f64> = t.runs.iter().map(|r| r.train_seconds).collect();
    (Summary::of(&conv), Summary::of(&total))
}

/// Four significant digits.
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return "—".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.3e}")
    }
}

/// `mean ± half-width` of a summary (`—` without seeds).
pub fn ci(s: &Summary) -> String {
    if s.n == 0 {
        "—".into()
    } else if s.half_width.is_finite() {
        format!("{} ± {}", num(s.mean), num(s.half_width))
    } else {
        num(s.mean)
    }
}

/// A success-rate summary in percent.
pub(crate) fn percent(s: &Summary) -> Summary {
    Summary {
        mean: 100.0 * s.mean,
        half_width: 100.0 * s.half_width,
        n: s.n,
    }
}
