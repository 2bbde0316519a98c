//! The output directory: refused when it holds files unless `--overwrite` (which removes only the
//! kit's own files, [`is_kit_file`]), and every file written atomically (a temporary file in the
//! same directory, then a rename), so an interrupted run never leaves a half-written file.

use super::error::RunError;
use super::records::{Checkpoint, SavedTheta, SeedRun};
use crate::provenance::{self, Provenance};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files `ilopt run` writes besides the per-seed ones.
pub const KIT_FILES: [&str; 4] = ["config.toml", "summary.json", "summary.txt", "timings.json"];

/// Whether `name` is a file `ilopt run` writes: one of [`KIT_FILES`], `seed-<n>.csv`,
/// `seed-<n>.json`, `theta-seed-<n>.json` (n a seed), or the temporary file of one of them
/// (`.<name>.tmp-<pid>`, left by a killed run). `--overwrite` removes these and nothing else.
pub fn is_kit_file(name: &str) -> bool {
    let name = match name
        .strip_prefix('.')
        .and_then(|rest| rest.rsplit_once(".tmp-"))
    {
        Some((inner, pid)) if !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()) => inner,
        _ => name,
    };
    let seed = |s: &str| {
        !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) && s.parse::<u64>().is_ok()
    };
    KIT_FILES.contains(&name)
        || [
            ("seed-", ".csv"),
            ("seed-", ".json"),
            ("theta-seed-", ".json"),
        ]
        .iter()
        .any(|(pre, ext)| {
            name.strip_prefix(pre)
                .and_then(|s| s.strip_suffix(ext))
                .is_some_and(seed)
        })
}

/// A seed's `seed-<n>.json`: the build that wrote it, then the run.
#[derive(Serialize)]
struct SeedFile<'a> {
    ilopt: Provenance,
    #[serde(flatten)]
    run: &'a SeedRun,
}

/// Where a run writes.
#[derive(Debug, Clone)]
pub struct OutputDir {
    dir: PathBuf,
}

impl OutputDir {
    /// Make `dir` ready for a run: created (with its parents) if needed; if it holds anything,
    /// refused unless `overwrite`, which removes the kit's own files ([`is_kit_file`]) and keeps
    /// every other file and every subdirectory.
    ///
    /// # Errors
    /// [`RunError::OutputNotEmpty`] for a non-empty directory without `overwrite`;
    /// [`RunError::Io`] if it cannot be created, listed or cleared.
    pub fn prepare(dir: &Path, overwrite: bool) -> Result<Self, RunError> {
        std::fs::create_dir_all(dir).map_err(|e| RunError::io(dir, e))?;
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .map_err(|e| RunError::io(dir, e))?
            .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect::<Result<_, _>>()
            .map_err(|e| RunError::io(dir, e))?;
        names.sort();
        if !names.is_empty() && !overwrite {
            return Err(RunError::OutputNotEmpty {
                dir: dir.to_path_buf(),
                holds: names,
            });
        }
        for name in names.iter().filter(|n| is_kit_file(n)) {
            let path = dir.join(name);
            if path.is_file() {
                std::fs::remove_file(&path).map_err(|e| RunError::io(&path, e))?;
            }
        }
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

    /// `config.toml`: a comment naming the build ([`provenance::BUILD`]), then the resolved
    /// config.
    ///
    /// # Errors
    /// As [`OutputDir::write`].
    pub fn write_config(&self, toml: &str) -> Result<(), RunError> {
        self.write(
            "config.toml",
            &format!("# written by {}\n{toml}", provenance::BUILD.line()),
        )
    }

    /// Start a seed's files: `seed-<n>.csv` with its header, to which [`SeedWriter::append`]
    /// adds each checkpoint as it is reached.
    ///
    /// # Errors
    /// [`RunError::Io`] if the file cannot be created.
    pub fn seed_writer(&self, seed: u64) -> Result<SeedWriter, RunError> {
        let path = self.dir.join(format!("seed-{seed}.csv"));
        let mut csv = std::fs::File::create(&path).map_err(|e| RunError::io(&path, e))?;
        writeln!(csv, "{}", Checkpoint::CSV_HEADER).map_err(|e| RunError::io(&path, e))?;
        Ok(SeedWriter {
            out: self.clone(),
            seed,
            csv,
            csv_path: path,
            checkpoints: Vec::new(),
            json_written: None,
        })
    }
}

/// How often, at most, `seed-<n>.json` is rewritten while a run goes on (the CSV gets every
/// checkpoint at once); a run with many checkpoints a second then costs no more than one
/// rewrite a second.
pub const PARTIAL_JSON_EVERY: std::time::Duration = std::time::Duration::from_secs(1);

/// A seed's `seed-<n>.json` while its run goes on: the build, the seed, `"termination":
/// "running"` and the checkpoints so far.
#[derive(Serialize)]
struct PartialSeedFile<'a> {
    ilopt: Provenance,
    seed: u64,
    termination: &'static str,
    checkpoints: &'a [Checkpoint],
}

/// One seed's files as its run goes on: each checkpoint appended to `seed-<n>.csv` and flushed
/// when it is reached, `seed-<n>.json` rewritten (atomically, at most every
/// [`PARTIAL_JSON_EVERY`]) with the checkpoints so far, and at the end ([`SeedWriter::finish`])
/// the full `seed-<n>.json` and `theta-seed-<n>.json`. A killed run keeps every checkpoint it
/// reached in the CSV, as complete rows.
#[derive(Debug)]
pub struct SeedWriter {
    out: OutputDir,
    seed: u64,
    csv: std::fs::File,
    csv_path: PathBuf,
    checkpoints: Vec<Checkpoint>,
    json_written: Option<std::time::Instant>,
}

impl SeedWriter {
    /// Append checkpoints: one CSV row each, written and flushed together; then the partial
    /// `seed-<n>.json` if it was last written [`PARTIAL_JSON_EVERY`] ago or never.
    ///
    /// # Errors
    /// [`RunError::Io`] if a file cannot be written.
    pub fn append(&mut self, new: &[Checkpoint]) -> Result<(), RunError> {
        let rows: String = new.iter().map(|c| c.csv_row() + "\n").collect();
        self.csv
            .write_all(rows.as_bytes())
            .and_then(|()| self.csv.flush())
            .map_err(|e| RunError::io(&self.csv_path, e))?;
        self.checkpoints.extend_from_slice(new);
        if self
            .json_written
            .is_none_or(|t| t.elapsed() >= PARTIAL_JSON_EVERY)
        {
            self.out.write_json(
                &format!("seed-{}.json", self.seed),
                &PartialSeedFile {
                    ilopt: provenance::BUILD,
                    seed: self.seed,
                    termination: "running",
                    checkpoints: &self.checkpoints,
                },
            )?;
            self.json_written = Some(std::time::Instant::now());
        }
        Ok(())
    }

    /// The run has ended: the CSV synced to disk, `seed-<n>.json` (the build, then the run) and
    /// `theta-seed-<n>.json` written. The run's checkpoints are those appended.
    ///
    /// # Errors
    /// [`RunError::Io`] if a file cannot be written.
    pub fn finish(self, run: &SeedRun, task: &str, policy: &str) -> Result<(), RunError> {
        self.csv
            .sync_all()
            .map_err(|e| RunError::io(&self.csv_path, e))?;
        let n = run.seed;
        self.out.write_json(
            &format!("seed-{n}.json"),
            &SeedFile {
                ilopt: provenance::BUILD,
                run,
            },
        )?;
        self.out.write_json(
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
