//! Records the git commit the binary is built from (`ILOPT_GIT_COMMIT`, read by
//! `ilopt_cli::provenance`): `git rev-parse HEAD` when the sources are a git checkout and git is
//! installed, else `unknown` (a tarball, a vendored copy), so that a build never fails for it; and
//! whether tracked files differed from that commit (`ILOPT_GIT_DIRTY`: `true`, `false`, or
//! `unknown` with the commit).

use std::path::PathBuf;
use std::process::Command;

/// git's trimmed output (possibly empty), or `None` when git cannot run or fails.
fn git_output(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    Some(String::from_utf8(out.stdout).ok()?.trim().to_string())
}

/// git's trimmed output when it is not empty.
fn git(args: &[&str]) -> Option<String> {
    git_output(args).filter(|text| !text.is_empty())
}

fn main() {
    let commit = git(&["rev-parse", "HEAD"])
        .filter(|c| c.len() == 40 && c.bytes().all(|b| b.is_ascii_hexdigit()))
        .unwrap_or_else(|| "unknown".into());
    let dirty = if commit == "unknown" {
        "unknown".to_string()
    } else {
        match git_output(&["status", "--porcelain", "--untracked-files=no"]) {
            Some(changes) => (!changes.is_empty()).to_string(),
            None => "unknown".to_string(),
        }
    };
    println!("cargo:rustc-env=ILOPT_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=ILOPT_GIT_DIRTY={dirty}");
    // Rebuild when a source the binary is built from changes, so that the flag follows edits.
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default());
    if let Some(root) = manifest.parent() {
        for rel in [
            "Cargo.toml",
            "Cargo.lock",
            "src",
            "plot/src",
            "cli/src",
            "experts",
        ] {
            let path = root.join(rel);
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    // Rebuild when HEAD moves: HEAD itself (a checkout), the branch it names (a commit) and the
    // packed refs. Paths from `git rev-parse --git-path` are right in worktrees too.
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
        watched.push(branch);
    }
    for name in watched {
        if let Some(path) = git(&["rev-parse", "--git-path", &name]) {
            let path = PathBuf::from(path);
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    println!("cargo:rerun-if-changed=build.rs");
}
