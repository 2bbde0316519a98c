//! The provenance record (`provenance.json`: configuration, seeds, the command line, the commit
//! and source hash the binary was built from, toolchain, machine) and
//! the run's timings (`timings.json`: date, threads, wall times), kept apart so that
//! `provenance.json` is identical across reruns on one machine and commit.
//!
//! [`Machine`] gathers the machine description once; the appendix prints it above its runtime
//! table and the two JSON files record it.

use crate::config::Profile;
use crate::error::Error;
use crate::pipeline::Options;
use crate::results::Results;
use crate::storage::{to_json, write_atomic};
use std::path::Path;
use std::process::Command;

fn command_output(cmd: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(cmd).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The CPU model name from `/proc/cpuinfo`, if readable.
pub fn cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    text.lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map(|s| s.trim().to_string())
}

/// Logical processors listed in `/proc/cpuinfo` (every hardware thread of the machine), if
/// readable.
pub fn cpuinfo_processors() -> Option<usize> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let n = text.lines().filter(|l| l.starts_with("processor")).count();
    (n > 0).then_some(n)
}

/// The civil date `(year, month, day)` of a day count since 1970-01-01 (proleptic Gregorian;
/// H. Hinnant's `civil_from_days`).
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// `YYYY-MM-DD HH:MM UTC` of a time given in seconds since the Unix epoch.
pub fn utc_timestamp(unix_seconds: u64) -> String {
    let secs = unix_seconds as i64;
    let (y, m, d) = civil_from_days(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        s / 3600,
        (s % 3600) / 60
    )
}

/// The machine and toolchain a run used: what a reader needs to weigh its wall times.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Machine {
    /// CPU model (`/proc/cpuinfo`'s `model name`).
    pub cpu: Option<String>,
    /// Logical processors of the machine (`/proc/cpuinfo`).
    pub logical_cpus: Option<usize>,
    /// Logical processors this process may use (`std::thread::available_parallelism`: affinity
    /// and cgroup limits applied).
    pub available_cpus: Option<usize>,
    /// Threads of rayon's global pool (the seeds' parallelism).
    pub rayon_threads: usize,
    /// Operating system, architecture and (Linux) kernel release.
    pub os: String,
    /// `rustc --version` of the toolchain on the `PATH` when the run started.
    pub rustc: Option<String>,
    /// Cargo build profile of this binary (`release` or `debug`, from `debug_assertions`).
    pub build_profile: String,
    /// When the run's report was written (`YYYY-MM-DD HH:MM UTC`).
    pub date_utc: String,
}

impl Machine {
    /// Describe the current machine, toolchain and time.
    pub fn current() -> Self {
        let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease")
            .ok()
            .map(|s| s.trim().to_string());
        let os = match kernel {
            Some(k) => format!(
                "{} {} (kernel {k})",
                std::env::consts::OS,
                std::env::consts::ARCH
            ),
            None => format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
        };
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        Machine {
            cpu: cpu_model(),
            logical_cpus: cpuinfo_processors(),
            available_cpus: std::thread::available_parallelism().map(|n| n.get()).ok(),
            rayon_threads: rayon::current_num_threads(),
            os,
            rustc: command_output("rustc", &["--version"]),
            build_profile: if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            }
            .into(),
            date_utc: utc_timestamp(now),
        }
    }
}

/// Write `provenance.json` and `timings.json`.
///
/// # Errors
/// I/O or serialisation failures.
pub fn write(
    profile: &Profile,
    profile_file: &Path,
    profile_text: &str,
    r: &Results,
    opts: &Options,
    wall_seconds: f64,
) -> Result<(), Error> {
    let out = opts.out.as_path();
    let machine = Machine::current();
    let seeds: Vec<serde_json::Value> = r
        .obstacle
        .iter()
        .chain(&r.cartpole)
        .map(|(c, _)| {
            serde_json::json!({
                "task": c.task.name(),
                "algorithm": c.label,
                "seeds": c.runs.iter().map(|s| s.seed).collect::<Vec<_>>(),
            })
        })
        .collect();
    let selected: Vec<serde_json::Value> = r
        .tuning
        .iter()
        .map(|t| {
            let p = t.chosen();
            serde_json::json!({
                "task": t.task.name(),
                "algorithm": t.label,
                "selected": p.describe(),
                "config": p.config,
                "m": p.m,
                "baseline": p.baseline,
                "grid_points": t.points.len(),
                "selection_score": if t.dims.is_empty() { None } else { t.points[t.selected].score.clone() },
                "tuning_seeds": t.points.iter().flat_map(|q| q.runs.iter().map(|x| x.seed)).collect::<Vec<_>>(),
            })
        })
        .collect();
    // Every tuned row's rounds of selection, extensions and where its pick lies.
    let t_rounds: Vec<serde_json::Value> = r
        .tuning
        .iter()
        .filter(|t| t.is_tuned())
        .map(|t| {
            serde_json::json!({
                "task": t.task.name(),
                "algorithm": t.label,
                "rounds": t.rounds,
                "on_edge": t.on_edge,
                "tied_with": t.tied_with,
                "weakness": t.weakness(),
            })
        })
        .collect();
    let prov = serde_json::json!({
        "selected_hyper_parameters": selected,
        "selection_rule": "lexicographic: the median over tuning seeds of the gradient calls to sustained convergence (not converged or diverged = +inf), then the larger mean area under the learning curve (a diverged run scores 0 from its divergence), then the smaller step, then the smaller m; successive halving over the profile's rungs on grids of at least `exhaustive_below` points; a pick on an end of a log range extends it, up to `extensions` times (the profile's [tuning])",
        "tuning": t_rounds,
        "command": opts.command,
        "profile": profile.name,
        "profile_file": profile_file.file_name().map(|f| f.to_string_lossy().to_string()),
        "profile_toml": profile_text,
        "profile_parsed": profile,
        // The size the theorem table ran at: `profile_toml`'s `theory_profile`, or `--theory`.
        "theory_table": profile.theory_profile,
        "seed_derivation": "report seed = SplitMix64(FNV-1a(\"task|label|algorithm-config-json|m=…|objective[|baseline=baseline-json]\") XOR SplitMix64(seed index)); tuning seed likewise from \"tuning|\" + that key; evaluation episodes (\"<task>-eval\" / \"<task>-tuning-eval\") and Fig. 4.2 streams likewise from their own keys",
        "run_seeds": seeds,
        "git_commit": crate::build_info::GIT_COMMIT,
        "git_dirty_at_build": crate::build_info::GIT_DIRTY,
        "source_hash": crate::build_info::SOURCE_HASH,
        "cache_code_version": opts.source_version,
        "rustc": machine.rustc,
        "cpu": machine.cpu,
        "logical_cpus": machine.logical_cpus,
        "available_cpus": machine.available_cpus,
        "os": machine.os,
        "build_profile": machine.build_profile,
        "package_version": env!("CARGO_PKG_VERSION"),
    });
    write_atomic(&out.join("provenance.json"), &to_json("provenance", &prov)?)?;
    let timings = serde_json::json!({
        "date_utc": machine.date_utc,
        "threads": machine.rayon_threads,
        "wall_seconds": wall_seconds,
        "computed_this_run": r.computed,
        "configurations": r.obstacle.iter().chain(&r.cartpole).map(|(c, t)| serde_json::json!({
            "task": c.task.name(), "algorithm": c.label,
            "wall_seconds": t.as_ref().map(|t| t.wall_seconds),
        })).collect::<Vec<_>>(),
    });
    write_atomic(&out.join("timings.json"), &to_json("timings", &timings)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(utc_timestamp(1_700_000_000), "2023-11-14 22:13 UTC");
    }
}
