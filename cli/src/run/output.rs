//! The output directory: every file written atomically (a temporary file in the same directory,
//! then a rename), so an interrupted run never leaves a half-written file.

use super::error::RunError;
use super::records::{Checkpoint, SavedTheta, SeedRun};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where a run writes.
#[derive(Debug, Clone)]
pub struct OutputDir {
    dir: PathBuf,
}

impl OutputDir {
    /// Create the directory (and its parents) if needed.
    ///
    /// # Errors
    /// [`RunError::Io`] if it cannot be created.
    pub fn create(dir: &Path) -> Result<Self, RunError> {
        std::fs::create_dir_all(dir).map_err(|e| RunError::io(dir, e))?;
        Ok(OutputDir {
            dir: dir.to_path_buf(),
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Write `text` to `name` atomically.
    ///
    /// # Errors
    /// [`RunError::Io`] if the file cannot be written or renamed.
    pub fn write(&self, name: &str, text: &str) -> Result<(), RunError> {
        let target = self.dir.join(name);
        let tmp = self.dir.join(format!(".{name}.tmp-{}", std::process::id()));
        let result = (|| {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(text.as_bytes())?;
            f.sync_all()?;
            std::fs::rename(&tmp, &target)
        })();
        result.map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            RunError::io(&target, e)
        })
    }

    /// Write a value as pretty JSON (with a final newline) atomically.
    ///
    /// # Errors
    /// As [`OutputDir::write`].
    pub fn write_json(&self, name: &str, value: &impl Serialize) -> Result<(), RunError> {
        let mut text = serde_json::to_string_pretty(value)
            .map_err(|e| RunError::io(self.dir.join(name), std::io::Error::other(e)))?;
        text.push('\n');
        self.write(name, &text)
    }

    /// A seed's files: `seed-<n>.csv`, `seed-<n>.json` and `theta-seed-<n>.json`.
    ///
    /// # Errors
    /// As [`OutputDir::write`].
    pub fn write_seed(&self, run: &SeedRun, task: &str, policy: &str) -> Result<(), RunError> {
        let n = run.seed;
        let mut csv = String::from(Checkpoint::CSV_HEADER);
        csv.push('\n');
        for c in &run.checkpoints {
            csv.push_str(&c.csv_row());
            csv.push('\n');
        }
        self.write(&format!("seed-{n}.csv"), &csv)?;
        self.write_json(&format!("seed-{n}.json"), run)?;
        self.write_json(
            &format!("theta-seed-{n}.json"),
            &SavedTheta {
                task: task.into(),
                policy: policy.into(),
                seed: n,
                theta: run.theta.clone(),
            },
        )
    }
}
