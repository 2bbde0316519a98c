//! Per-configuration aggregates over seeds (Student-t 95% intervals, [`Summary`]) and their
//! printed form.

use crate::experiment::{Checkpoint, RunStatus, SeedRun};
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
    /// Gradient calls of the whole run (all seeds; a diverged run's when it diverged).
    pub total_gradient_calls: Summary,
    /// Final score (the seeds that did not diverge: a diverged run has no final policy, and its
    /// last checkpoint evaluated an earlier one, θ₁ when it diverged before the first).
    pub final_score: Summary,
    /// Final crashes (the seeds that did not diverge).
    pub final_crashes: Summary,
    /// Final mean reward (the seeds that did not diverge).
    pub final_reward: Summary,
    /// Final evaluation loss (the seeds that did not diverge).
    pub final_loss: Summary,
    /// Diverged runs ([`crate::experiment::RunStatus::Diverged`]: ‖θ‖ beyond the bound, a
    /// non-finite iterate, a failed step).
    pub failed_runs: usize,
}

/// A run's last checkpoint.
pub(crate) fn last(r: &SeedRun) -> Option<&Checkpoint> {
    r.checkpoints.last()
}

/// A summary of `f` at the last checkpoint of each run that did not diverge.
pub(crate) fn summarise(c: &ConfigResult, f: impl Fn(&Checkpoint) -> f64) -> Summary {
    let xs: Vec<f64> = c
        .runs
        .iter()
        .filter(|r| !r.status.is_diverged())
        .filter_map(last)
        .map(f)
        .collect();
    Summary::of(&xs)
}

/// The gradient calls a run spent: when it diverged, or at its last checkpoint.
fn spent(r: &SeedRun) -> Option<f64> {
    match &r.status {
        RunStatus::Diverged {
            gradient_evaluations,
            ..
        } => Some(*gradient_evaluations as f64),
        _ => last(r).map(|k| k.gradient_evaluations as f64),
    }
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
        total_gradient_calls: Summary::of(&c.runs.iter().filter_map(spent).collect::<Vec<_>>()),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn checkpoint(calls: u64, score: f64) -> Checkpoint {
        serde_json::from_value(serde_json::json!({
            "at_calls": calls, "iteration": 0, "trajectories": 0,
            "gradient_evaluations": calls, "expert_queries": 0, "score": score,
            "successes": 0, "crashes": 3, "timeouts": 0, "reward": 0.0, "loss": 0.5,
            "loss_x": null, "loss_y": null, "grad_x": null, "grad_y": null
        }))
        .expect("a checkpoint")
    }

    fn run(i: u32, checkpoints: Vec<Checkpoint>, status: RunStatus) -> SeedRun {
        SeedRun {
            seed_index: i,
            seed: u64::from(i),
            termination: String::new(),
            theta: vec![],
            checkpoints,
            converged: None,
            status,
            hyper_parameters: String::new(),
        }
    }

    /// A diverged run has no final policy: its last checkpoint (here θ₁'s, before the first
    /// checkpoint after it) stays out of the final means, and its whole run ends where it
    /// diverged, not at its last checkpoint.
    #[test]
    fn diverged_runs_stay_out_of_the_final_means_and_count_their_own_calls() {
        let diverged = RunStatus::Diverged {
            reason: "‖θ‖ beyond the bound".into(),
            gradient_evaluations: 1300,
        };
        let c = crate::results::storm_config_for_tests(vec![
            run(
                0,
                vec![checkpoint(0, 0.0), checkpoint(1000, 0.5)],
                RunStatus::NotConverged,
            ),
            run(1, vec![checkpoint(0, 0.0)], diverged.clone()),
            run(
                2,
                vec![checkpoint(0, 0.0), checkpoint(1000, 0.7)],
                RunStatus::NotConverged,
            ),
        ]);
        let row = convergence_row(&c);
        assert_eq!(row.failed_runs, 1);
        assert_eq!(row.final_score.n, 2);
        assert!((row.final_score.mean - 0.6).abs() < 1e-12);
        assert_eq!(row.total_gradient_calls.n, 3);
        assert!((row.total_gradient_calls.mean - 1100.0).abs() < 1e-9);
        // Every run diverged: no final value at all, but the calls they spent.
        let all = crate::results::storm_config_for_tests(vec![run(
            0,
            vec![checkpoint(0, 0.0)],
            diverged,
        )]);
        let row = convergence_row(&all);
        assert_eq!((row.final_score.n, row.final_loss.n), (0, 0));
        assert_eq!(ci(&row.final_score), "—");
        assert!((row.total_gradient_calls.mean - 1300.0).abs() < 1e-9);
    }
}
