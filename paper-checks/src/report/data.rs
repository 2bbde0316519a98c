//! The appendix's data files: every checkpoint of every seed (`checkpoints.csv`), the Fig. 4.2
//! study (`gradient_error.csv`), the wall times (`timings.csv`) and the aggregated tables
//! (`tables.json`).

use super::aggregate::ConvergenceRow;
use super::claims::Claim;
use crate::error::Error;
use crate::experiment::{AppendixRun, Evaluated};
use crate::results::Results;
use crate::storage::{to_json, write_atomic};
use std::fmt::Write as _;
use std::path::Path;

/// Write `checkpoints.csv` (one line per checkpoint of every seed run), `gradient_error.csv`
/// and `timings.csv` (one line per seed run with timings) into `out`.
///
/// # Errors
/// [`Error::Io`].
pub fn write_per_seed(r: &Results, out: &Path) -> Result<(), Error> {
    let mut csv = String::from(
        "task,algorithm,seed_index,seed,iteration,trajectories,gradient_evaluations,expert_queries,score,successes,crashes,timeouts,reward,loss,loss_x,loss_y,grad_x,grad_y,converged_here,at_calls,resets_to_full_episode,run_status\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
    for (c, _) in r.obstacle.iter().chain(&r.cartpole) {
        for run in &c.runs {
            for (i, k) in run.checkpoints.iter().enumerate() {
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    c.task.name(),
                    c.label,
                    run.seed_index(),
                    run.seed,
                    k.iteration,
                    k.trajectories,
                    k.gradient_evaluations,
                    k.expert_queries,
                    k.score(),
                    k.successes(),
                    k.crashes(),
                    k.timeouts(),
                    k.reward(),
                    k.loss(),
                    opt(k.loss_x),
                    opt(k.loss_y),
                    opt(k.grad_x),
                    opt(k.grad_y),
                    run.converged() == Some(i),
                    k.at_calls,
                    k.resets_to_full_episode
                        .map_or(String::new(), |x| x.to_string()),
                    match run.status() {
                        crate::experiment::RunStatus::Converged { .. } => "converged",
                        crate::experiment::RunStatus::NotConverged => "not-converged",
                        crate::experiment::RunStatus::Diverged { .. } => "diverged",
                    }
                );
            }
        }
    }
    write_atomic(&out.join("checkpoints.csv"), csv.as_bytes())?;
    let g = crate::gradient_error::csv(&r.gradient_error);
    write_atomic(&out.join("gradient_error.csv"), g.as_bytes())?;
    let mut t = String::from("task,algorithm,seed_index,train_seconds,converge_seconds\n");
    for (c, tm) in r.obstacle.iter().chain(&r.cartpole) {
        if let Some(tm) = tm {
            for s in &tm.runs {
                let _ = writeln!(
                    t,
                    "{},{},{},{},{}",
                    c.task.name(),
                    c.label,
                    s.seed_index.unwrap_or(0),
                    s.train_seconds,
                    opt(s.converge_seconds)
                );
            }
        }
    }
    write_atomic(&out.join("timings.csv"), t.as_bytes())?;
    Ok(())
}

/// Write `tables.json`: both tasks' convergence rows and the claims with their verdicts.
///
/// # Errors
/// [`Error::Io`], [`Error::Serialise`].
pub fn write_tables(
    out: &Path,
    obstacle: &[ConvergenceRow],
    cartpole: &[ConvergenceRow],
    claims: &[Claim],
) -> Result<(), Error> {
    write_atomic(
        &out.join("tables.json"),
        &to_json(
            "tables",
            &serde_json::json!({
                "confidence_interval": "95% over seeds, per quantity (each interval's `method`): \
                    bounded quantities (success rate, crashes, CartPole reward) a seeded percentile \
                    bootstrap of the mean; non-negative ones (gradient calls, loss) Student-t \
                    mean ± t(0.975, n−1)·s/√n with the lower end clamped to 0 (`clamped_lo`)",
                "obstacle": obstacle, "cartpole": cartpole, "claims": claims,
            }),
        )?,
    )
}
