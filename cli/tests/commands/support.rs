//! What every module of the command-line tests uses: the binary run in a directory, and scratch
//! directories that remove themselves.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Run the binary in `cwd`: (exit code, stdout, stderr).
pub fn ilopt_in(cwd: &Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ilopt"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the ilopt binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Run the binary in the repository root (where the docs' relative paths start).
pub fn ilopt(args: &[&str]) -> (i32, String, String) {
    ilopt_in(Path::new(crate::ROOT), args)
}

/// A scratch directory of its own (the process id and a counter keep tests apart), removed when
/// dropped.
pub struct Scratch(PathBuf);

impl Scratch {
    /// A new, empty directory whose name ends in `name`.
    pub fn new(name: &str) -> Self {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let p = std::env::temp_dir().join(format!("ilopt-cli-{}-{n}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).expect("a scratch directory");
        Scratch(p)
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.0
    }

    /// Write `text` to `name` in the directory (its parents created); the file's path.
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).expect("the file's directory");
        }
        std::fs::write(&p, text).expect("the file is written");
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
