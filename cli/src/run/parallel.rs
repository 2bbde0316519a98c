//! Running a config's seeds on a pool of scoped threads, or on the calling thread when the pool
//! would have one (`ilopt.GymTask` then steps its environment on the thread that holds Python's
//! lock). Each seed's run depends on its seed alone and writes its own files, and the results are
//! gathered in the config's seed order, so the output is the same whatever the thread count and
//! the order in which seeds finish. Each checkpoint is written as it is reached
//! ([`super::output::SeedWriter`]). On stderr, unless quiet: a progress bar over the total budget,
//! with the last checkpoint's metrics, when stderr is a terminal; otherwise (a log file, Slurm)
//! one line per checkpoint ([`checkpoint_line`]).

use super::config::LoadedConfig;
use super::driver::run_seed;
use super::error::RunError;
use super::output::OutputDir;
use super::records::{Checkpoint, SeedRun, SeedTiming};
use super::runnable::RunTask;
use super::table::metric;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

/// One seed's result.
pub type SeedResult = (SeedRun, SeedTiming);

/// Run every seed of `config` on up to `threads` threads, writing each seed's files to `out` (if
/// given) as its checkpoints are reached, and reporting on stderr unless `quiet`; the results in
/// the config's seed order.
///
/// # Errors
/// The first seed's error (in seed order); the seeds not yet started are then skipped.
pub fn run_seeds<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
    out: Option<&OutputDir>,
    threads: usize,
    quiet: bool,
) -> Result<Vec<SeedResult>, RunError> {
    let seeds = &config.file.run.seeds;
    let budget = config.file.run.budget_calls;
    let terminal = !quiet && std::io::stderr().is_terminal();
    let lines = !quiet && !terminal;
    let bar = if terminal {
        progress_bar(budget.saturating_mul(seeds.len() as u64))
    } else {
        ProgressBar::hidden()
    };
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let results: Mutex<Vec<Option<Result<SeedResult, RunError>>>> =
        Mutex::new((0..seeds.len()).map(|_| None).collect());
    let (name, policy) = (task.task_name(), task.policy_name());
    let worker = || {
        loop {
            let i = next.fetch_add(1, Ordering::SeqCst);
            if i >= seeds.len() || failed.load(Ordering::SeqCst) {
                break;
            }
            let seed = seeds[i];
            let last = AtomicU64::new(0);
            let report = |calls: u64| {
                let prev = last.swap(calls, Ordering::Relaxed);
                bar.inc(calls.saturating_sub(prev));
            };
            let writer = out.map(|o| o.seed_writer(seed)).transpose();
            let r = writer.and_then(|mut writer| {
                let (run, timing) = run_seed(task, config, seed, &report, &mut |new| {
                    if let Some(w) = writer.as_mut() {
                        w.append(new)?;
                    }
                    for c in new {
                        let line = checkpoint_line(seed, budget, c);
                        if lines {
                            eprintln!("{line}");
                        } else {
                            bar.set_message(line);
                        }
                    }
                    Ok(())
                })?;
                if let Some(w) = writer {
                    w.finish(&run, name, policy)?;
                }
                Ok((run, timing))
            });
            bar.inc(budget.saturating_sub(last.load(Ordering::Relaxed)));
            if r.is_err() {
                failed.store(true, Ordering::SeqCst);
            }
            if let Ok(mut slots) = results.lock() {
                slots[i] = Some(r);
            }
        }
    };
    let workers = threads.min(task.max_threads()).clamp(1, seeds.len());
    if workers == 1 {
        worker();
    } else {
        std::thread::scope(|s| {
            for _ in 0..workers {
                s.spawn(worker);
            }
        });
    }
    bar.finish_and_clear();
    let slots = results
        .into_inner()
        .map_err(|_| RunError::Evaluation("a worker thread panicked".into()))?;
    let mut done = Vec::with_capacity(slots.len());
    for (i, slot) in slots.into_iter().enumerate() {
        match slot {
            Some(Ok(r)) => done.push(r),
            Some(Err(e)) => return Err(e),
            None if failed.load(Ordering::SeqCst) => continue,
            None => {
                return Err(RunError::Run {
                    seed: seeds[i],
                    message: "the run did not complete".into(),
                });
            }
        }
    }
    Ok(done)
}

/// One checkpoint for a log: `seed 3: 2000/10000 calls (2045 used), iteration 21, score 0.45`,
/// then the objective and the evaluation and training losses the task records (four significant
/// digits).
pub fn checkpoint_line(seed: u64, budget: u64, c: &Checkpoint) -> String {
    let mut line = format!(
        "seed {seed}: {}/{budget} calls ({} used), iteration {}",
        c.at_calls, c.gradient_evaluations, c.iteration
    );
    for (name, value) in [
        ("score", c.score),
        ("objective", c.objective),
        ("eval loss", c.eval_loss),
        ("train loss", c.train_loss),
    ] {
        if let Some(v) = value {
            line.push_str(&format!(", {name} {}", metric(v)));
        }
    }
    line
}

/// A bar over `total` gradient calls on stderr, with the last checkpoint's line as its message.
fn progress_bar(total: u64) -> ProgressBar {
    let bar = ProgressBar::new(total);
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise} [{wide_bar}] {human_pos}/{human_len} gradient calls, eta {eta}\n{msg}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
