//! Running a config's seeds on a pool of scoped threads. Each seed's run depends on its seed
//! alone and writes its own files, and the results are gathered in the config's seed order, so
//! the output is the same whatever the thread count and the order in which seeds finish. A
//! progress bar over the total budget is drawn on stderr when it is a terminal.

use super::config::LoadedConfig;
use super::driver::run_seed;
use super::error::RunError;
use super::output::OutputDir;
use super::records::{SeedRun, SeedTiming};
use super::runnable::RunTask;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

/// One seed's result.
pub type SeedResult = (SeedRun, SeedTiming);

/// Run every seed of `config` on up to `threads` threads, writing each seed's files to `out` as
/// it finishes; the results in the config's seed order.
///
/// # Errors
/// The first seed's error (in seed order); the seeds not yet started are then skipped.
pub fn run_seeds<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
    out: &OutputDir,
    threads: usize,
) -> Result<Vec<SeedResult>, RunError> {
    let seeds = &config.file.run.seeds;
    let budget = config.file.run.budget_calls;
    let bar = progress_bar(budget.saturating_mul(seeds.len() as u64));
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
            let r = run_seed(task, config, seed, &report).and_then(|(run, timing)| {
                out.write_seed(&run, name, policy)?;
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
    std::thread::scope(|s| {
        for _ in 0..threads.min(task.max_threads()).clamp(1, seeds.len()) {
            s.spawn(worker);
        }
    });
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

/// A bar over `total` gradient calls on stderr, hidden unless stderr is a terminal.
fn progress_bar(total: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise} [{wide_bar}] {human_pos}/{human_len} gradient calls, eta {eta}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
