//! Wall time per part of the suite, printed to stderr when the environment variable
//! `ILOPT_THEORY_TIMINGS` is set (to any value): a diagnostic for finding where a profile's time
//! goes. It never changes a row.

use std::time::Instant;

/// The environment variable that turns the stage timings on.
pub const TIMINGS_VAR: &str = "ILOPT_THEORY_TIMINGS";

/// Run `f`; if [`TIMINGS_VAR`] is set, print `theory stage <what>: <seconds> s` to stderr.
pub fn timed<T>(what: &str, f: impl FnOnce() -> T) -> T {
    if std::env::var_os(TIMINGS_VAR).is_none() {
        return f();
    }
    let start = Instant::now();
    let out = f();
    eprintln!(
        "theory stage {what}: {:.1} s",
        start.elapsed().as_secs_f64()
    );
    out
}
