//! Records which sources this binary was built from, so that the appendix's cache can key every
//! result by the code that computed it and its provenance can name the commit without asking the
//! directory it happens to run in.
//!
//! * `PAPER_CHECKS_SOURCE_HASH`: FNV-1a (64 bit) over the relative path and bytes of every file
//!   that can change a number in the appendix: the workspace manifests and lock file, the sources
//!   of the kit, of `theory/` and of this package, its profiles, and the committed experts.
//! * `PAPER_CHECKS_GIT_COMMIT`, `PAPER_CHECKS_GIT_DIRTY`: `git rev-parse HEAD` and whether
//!   `git status --porcelain` was non-empty at build time (`unknown` outside a git checkout).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The inputs hashed, relative to the workspace root (this package's parent directory).
const INPUTS: &[&str] = &[
    "Cargo.toml",
    "Cargo.lock",
    "src",
    "experts",
    "examples/toy",
    "theory/Cargo.toml",
    "theory/src",
    "paper-checks/Cargo.toml",
    "paper-checks/build.rs",
    "paper-checks/src",
    "paper-checks/configs",
];

fn fnv1a(h: &mut u64, bytes: &[u8]) {
    for b in bytes {
        *h ^= u64::from(*b);
        *h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

fn files_under(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        if let Ok(rd) = std::fs::read_dir(p) {
            for e in rd.flatten() {
                files_under(&e.path(), out);
            }
        }
    } else if p.is_file() {
        out.push(p.to_path_buf());
    }
}

fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(root)
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let root = manifest.parent().unwrap_or(&manifest).to_path_buf();
    let mut files = Vec::new();
    for rel in INPUTS {
        let p = root.join(rel);
        // A path that does not exist would make cargo rerun this script on every build.
        if p.exists() {
            println!("cargo:rerun-if-changed={}", p.display());
        }
        files_under(&p, &mut files);
    }
    files.sort();
    let mut h = 0xcbf2_9ce4_8422_2325_u64;
    for f in &files {
        let rel = f.strip_prefix(&root).unwrap_or(f);
        fnv1a(&mut h, rel.to_string_lossy().as_bytes());
        fnv1a(&mut h, &[0]);
        if let Ok(bytes) = std::fs::read(f) {
            fnv1a(&mut h, &bytes);
        }
        fnv1a(&mut h, &[0]);
    }
    println!("cargo:rustc-env=PAPER_CHECKS_SOURCE_HASH={h:016x}");

    let commit = git(&root, &["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    let dirty = match git(&root, &["status", "--porcelain", "--untracked-files=no"]) {
        Some(s) => (!s.is_empty()).to_string(),
        None => "unknown".into(),
    };
    println!("cargo:rustc-env=PAPER_CHECKS_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=PAPER_CHECKS_GIT_DIRTY={dirty}");
    // A new commit with unchanged sources must still update the recorded commit.
    for p in ["HEAD", "refs/heads", "packed-refs"] {
        if let Some(path) = git(&root, &["rev-parse", "--git-path", p]) {
            let path = if Path::new(&path).is_absolute() {
                PathBuf::from(path)
            } else {
                root.join(path)
            };
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
}
