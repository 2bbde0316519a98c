//! Progress of a regeneration: a bar over the seed runs on a terminal, with the stages still
//! running (theorem table, Fig. 4.2 study, figures, documents) named beside it; one plain line per
//! finished stage, with its wall time, when standard error is not a terminal.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Progress output; silent when disabled.
pub struct Progress {
    bar: Option<ProgressBar>,
    plain: bool,
    done: AtomicUsize,
    total: usize,
    running: Mutex<Vec<String>>,
}

impl Progress {
    /// Progress over `total` seed runs (0: stages only); `enabled = false` prints nothing.
    pub fn new(total: usize, enabled: bool) -> Self {
        let tty = std::io::stderr().is_terminal();
        let bar = (enabled && tty).then(|| {
            let b = ProgressBar::new(total as u64);
            let template = if total > 0 {
                "{elapsed_precise} [{bar:40}] {pos}/{len} seed runs  {msg}"
            } else {
                "{elapsed_precise} {spinner} {msg}"
            };
            if let Ok(style) = ProgressStyle::with_template(template) {
                b.set_style(style.progress_chars("=> "));
            }
            // The elapsed time keeps moving while a long stage runs after the last seed.
            b.enable_steady_tick(Duration::from_millis(250));
            b
        });
        Progress {
            bar,
            plain: enabled && !tty,
            done: AtomicUsize::new(0),
            total,
            running: Mutex::new(Vec::new()),
        }
    }

    fn show_running(&self, last: Option<&str>) {
        if let Some(b) = &self.bar {
            let running = self
                .running
                .lock()
                .map(|r| r.join(", "))
                .unwrap_or_default();
            let msg = match (last, running.is_empty()) {
                (Some(l), true) => l.to_string(),
                (Some(l), false) => format!("{l}  | running: {running}"),
                (None, false) => format!("running: {running}"),
                (None, true) => String::new(),
            };
            b.set_message(msg);
        }
    }

    /// One seed run finished (`what`: its task and row).
    pub fn seed_done(&self, what: &str) {
        let k = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(b) = &self.bar {
            b.inc(1);
            self.show_running(Some(what));
        } else if self.plain && (k == self.total || k.is_multiple_of(10)) {
            eprintln!("[{k}/{}] seed runs done (last: {what})", self.total);
        }
    }

    /// Print a line above the bar (or plainly).
    pub fn line(&self, msg: &str) {
        if let Some(b) = &self.bar {
            b.println(msg);
        } else if self.plain {
            eprintln!("{msg}");
        }
    }

    /// Run `f` as the stage `name`: named beside the bar while it runs, and one line with its
    /// wall time when it ends (either way).
    pub fn stage<T>(&self, name: &str, f: impl FnOnce() -> T) -> T {
        if let Ok(mut r) = self.running.lock() {
            r.push(name.to_string());
        }
        self.show_running(None);
        if self.plain {
            eprintln!("{name}: started");
        }
        let start = Instant::now();
        let out = f();
        if let Ok(mut r) = self.running.lock() {
            r.retain(|s| s != name);
        }
        self.show_running(None);
        self.line(&format!(
            "{name}: finished in {:.1} s",
            start.elapsed().as_secs_f64()
        ));
        out
    }

    /// Remove the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
