//! Per-configuration aggregates over seeds (95% intervals that respect each quantity's range,
//! [`Interval`]) and their printed form.

use crate::experiment::{AppendixRun, Evaluated};
use crate::experiment::{Checkpoint, RunStatus, SeedRun, TaskKind};
use crate::results::{ConfigResult, ConfigTiming};
use crate::stats::{Interval, Range};
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
    pub gradient_calls: Interval,
    /// Gradient calls of the whole run (all seeds; a diverged run's when it diverged).
    pub total_gradient_calls: Interval,
    /// Final score (the seeds that did not diverge: a diverged run has no final policy, and its
    /// last checkpoint evaluated an earlier one, θ₁ when it diverged before the first).
    pub final_score: Interval,
    /// Final crashes (the seeds that did not diverge).
    pub final_crashes: Interval,
    /// Final mean reward (the seeds that did not diverge).
    pub final_reward: Interval,
    /// Final evaluation loss (the seeds that did not diverge).
    pub final_loss: Interval,
    /// Diverged runs ([`crate::experiment::RunStatus::Diverged`]: ‖θ‖ beyond the bound, a
    /// non-finite iterate, a failed step).
    pub failed_runs: usize,
}

/// A run's last checkpoint.
pub(crate) fn last(r: &SeedRun) -> Option<&Checkpoint> {
    r.checkpoints.last()
}

/// The interval of `f` (a quantity of `range`, named `what`) at the last checkpoint of each run
/// that did not diverge.
pub(crate) fn summarise(
    c: &ConfigResult,
    what: &str,
    range: Range,
    f: impl Fn(&Checkpoint) -> f64,
) -> Interval {
    let xs: Vec<f64> = c
        .runs
        .iter()
        .filter(|r| !r.status().is_diverged())
        .filter_map(last)
        .map(f)
        .collect();
    Interval::of(&xs, range, &key(c, what))
}

/// The bootstrap key of a configuration's quantity: task, algorithm and quantity.
pub(crate) fn key(c: &ConfigResult, what: &str) -> String {
    format!("{}/{}/{what}", c.task.name(), c.label)
}

/// The range of a success rate (a fraction of the evaluation episodes).
pub(crate) const FRACTION: Range = Range::Bounded { lo: 0.0, hi: 1.0 };

/// The range of a count out of `n` (crashes in n episodes, a reward of at most n steps).
pub(crate) fn out_of(n: f64) -> Range {
    Range::Bounded { lo: 0.0, hi: n }
}

/// The gradient calls a run spent: when it diverged, or at its last checkpoint.
fn spent(r: &SeedRun) -> Option<f64> {
    match r.status() {
        RunStatus::Diverged {
            gradient_evaluations,
            ..
        } => Some(*gradient_evaluations as f64),
        _ => last(r).map(|k| k.gradient_evaluations as f64),
    }
}

/// The evaluation episodes of a configuration's checkpoints (each ends in a success, a crash or
/// a time-out): the range of its crash counts.
pub(crate) fn episodes(c: &ConfigResult) -> f64 {
    c.runs
        .iter()
        .flat_map(|r| &r.checkpoints)
        .map(|k| f64::from(k.successes() + k.crashes() + k.timeouts()))
        .fold(0.0, f64::max)
}

/// The range of a task's mean episode reward: CartPole earns 1 a step for at most 500 steps
/// (its score is reward / 500); the obstacle task's reward has no stated bound.
pub(crate) fn reward_range(task: TaskKind) -> Range {
    match task {
        TaskKind::Cartpole => out_of(500.0),
        TaskKind::Obstacle => Range::Real,
    }
}

/// The convergence row of one configuration.
pub fn convergence_row(c: &ConfigResult) -> ConvergenceRow {
    let episodes = episodes(c);
    let calls: Vec<f64> = c
        .runs
        .iter()
        .filter_map(|r| {
            r.converged()
                .map(|i| r.checkpoints[i].gradient_evaluations as f64)
        })
        .collect();
    ConvergenceRow {
        label: c.label.clone(),
        converged: calls.len(),
        seeds: c.runs.len(),
        gradient_calls: Interval::of(&calls, Range::NonNegative, &key(c, "calls")),
        total_gradient_calls: Interval::of(
            &c.runs.iter().filter_map(spent).collect::<Vec<_>>(),
            Range::NonNegative,
            &key(c, "total-calls"),
        ),
        final_score: summarise(c, "score", FRACTION, |k| k.score()),
        final_crashes: summarise(c, "crashes", out_of(episodes), |k| f64::from(k.crashes())),
        final_reward: summarise(c, "reward", reward_range(c.task), |k| k.reward()),
        final_loss: summarise(c, "loss", Range::NonNegative, |k| k.loss()),
        failed_runs: c.runs.iter().filter(|r| r.status().is_diverged()).count(),
    }
}

/// Wall seconds to converge (converged seeds) and to train (all seeds) of one configuration;
/// empty without timings.
pub(crate) fn runtime(t: Option<&ConfigTiming>) -> (Interval, Interval) {
    let Some(t) = t else {
        return (seconds(&[]), seconds(&[]));
    };
    let conv: Vec<f64> = t.runs.iter().filter_map(|r| r.converge_seconds).collect();
    let total: Vec<f64> = t.runs.iter().map(|r| r.train_seconds).collect();
    (seconds(&conv), seconds(&total))
}

/// The interval of wall times (non-negative: a clamped t interval, no bootstrap key needed).
pub(crate) fn seconds(xs: &[f64]) -> Interval {
    Interval::of(xs, Range::NonNegative, "seconds")
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

/// `mean [lo, hi]` of an interval, a lower end raised to the range's bound marked `†` (`—`
/// without seeds, the mean alone for one seed).
pub fn ci(s: &Interval) -> String {
    if s.n == 0 {
        "—".into()
    } else if s.has_ends() {
        format!(
            "{} [{}{}, {}]",
            num(s.mean),
            num(s.lo),
            if s.clamped_lo { "†" } else { "" },
            num(s.hi)
        )
    } else {
        num(s.mean)
    }
}

/// A success-rate interval in percent.
pub(crate) fn percent(s: &Interval) -> Interval {
    s.scaled(100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checkpoint(calls: u64, score: f64) -> Checkpoint {
        serde_json::from_value(serde_json::json!({
            "at_calls": calls, "iteration": 0, "trajectories": 0, "env_steps": 0,
            "gradient_evaluations": calls, "expert_queries": 0, "score": score,
            "successes": 0, "crashes": 3, "timeouts": 0, "reward": 0.0, "eval_loss": 0.5,
            "loss_x": null, "loss_y": null, "grad_x": null, "grad_y": null
        }))
        .expect("a checkpoint")
    }

    fn run(i: u32, checkpoints: Vec<Checkpoint>, status: RunStatus) -> SeedRun {
        SeedRun {
            seed: u64::from(i),
            seed_index: Some(i),
            algorithm: "sgd".into(),
            termination: ilopt::algo::RecordedTermination::GradientBudget,
            iterations: 0,
            cost: ilopt::problem::Cost::default(),
            theta: vec![],
            checkpoints,
            status: Some(status),
            hyper_parameters: None,
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

    /// Bounded quantities get intervals inside their range (the t interval of the same
    /// success rates runs below 0); gradient calls a t interval clamped at 0 and marked †.
    #[test]
    fn intervals_stay_inside_the_quantitys_range() {
        let mut runs: Vec<SeedRun> = (0..8)
            .map(|i| {
                let score = if i == 0 { 1.0 } else { 0.0 };
                run(
                    i,
                    vec![checkpoint(0, 0.0), checkpoint(1000, score)],
                    RunStatus::NotConverged,
                )
            })
            .collect();
        // Converged runs with very different costs: the t interval of their calls runs below 0.
        for (r, calls) in runs.iter_mut().zip([500u64, 600, 90_000]) {
            r.checkpoints.push(checkpoint(calls, 1.0));
            r.status = Some(RunStatus::Converged {
                checkpoint: 2,
                gradient_evaluations: calls,
            });
        }
        let c = crate::results::storm_config_for_tests(runs);
        let row = convergence_row(&c);
        let s = row.final_score;
        assert_eq!(s.method, crate::stats::Method::Bootstrap);
        assert!(s.lo >= 0.0 && s.hi <= 1.0 && s.lo <= s.mean, "{s:?}");
        assert!(!ci(&percent(&s)).contains('−') && !ci(&percent(&s)).contains('-'));
        // Crashes: 3 in each of the 3 episodes the checkpoints record, so inside [0, 3].
        assert!(row.final_crashes.lo >= 0.0 && row.final_crashes.hi <= 3.0);
        let g = row.gradient_calls;
        assert_eq!(g.n, 3);
        assert!(g.clamped_lo && g.lo == 0.0, "{g:?}");
        assert!(ci(&g).contains("[0†, "), "{}", ci(&g));
    }
}
