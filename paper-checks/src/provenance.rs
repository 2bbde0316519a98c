//! The provenance record (`provenance.json`: configuration, seeds, commit, toolchain, CPU) and the
//! run's timings (`timings.json`: threads, wall times), kept apart so that `provenance.json` is
//! identical across reruns on one machine and commit.

use crate::config::Profile;
use crate::error::Error;
use crate::pipeline::{Results, to_json, write_atomic};
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

/// Write `provenance.json` and `timings.json`.
///
/// # Errors
/// I/O or serialisation failures.
pub fn write(
    profile: &Profile,
    profile_file: &Path,
    profile_text: &str,
    r: &Results,
    out: &Path,
    wall_seconds: f64,
) -> Result<(), Error> {
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
    let prov = serde_json::json!({
        "command": if profile.name == "full" {
            "cargo run --release -p paper-checks -- --full"
        } else {
            "cargo run --release -p paper-checks"
        },
        "profile": profile.name,
        "profile_file": profile_file.file_name().map(|f| f.to_string_lossy().to_string()),
        "profile_toml": profile_text,
        "profile_parsed": profile,
        "seed_derivation": "seed = SplitMix64(FNV-1a(\"task|label|algorithm-config-json\") XOR SplitMix64(seed index)); evaluation episodes and Fig. 4.2 streams likewise from their own keys",
        "run_seeds": seeds,
        "git_commit": command_output("git", &["rev-parse", "HEAD"]),
        "git_dirty": command_output("git", &["status", "--porcelain"]).map(|s| !s.is_empty()),
        "rustc": command_output("rustc", &["--version"]),
        "cpu": cpu_model(),
        "logical_cpus": std::thread::available_parallelism().map(|n| n.get()).ok(),
        "package_version": env!("CARGO_PKG_VERSION"),
    });
    write_atomic(&out.join("provenance.json"), &to_json("provenance", &prov)?)?;
    let timings = serde_json::json!({
        "threads": rayon::current_num_threads(),
        "wall_seconds": wall_seconds,
        "computed_this_run": r.computed,
        "configurations": r.obstacle.iter().chain(&r.cartpole).map(|(c, t)| serde_json::json!({
            "task": c.task.name(), "algorithm": c.label,
            "wall_seconds": t.as_ref().map(|t| t.wall_seconds),
        })).collect::<Vec<_>>(),
    });
    write_atomic(&out.join("timings.json"), &to_json("timings", &timings)?)
}
