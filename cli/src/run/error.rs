//! [`RunError`]: why `ilopt run` or `ilopt eval` failed, each naming the file and key at fault.

use std::path::{Path, PathBuf};

/// Why a run or an evaluation could not be carried out.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The config file is not valid TOML for the schema (syntax, unknown key, wrong type); the
    /// parser's message shows the line and the key.
    #[error("{path}: {message}")]
    Parse {
        /// The config file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// A key has a value out of its range, or is not allowed for the task.
    #[error("{path}: `{key}`: {message}")]
    Invalid {
        /// The config file.
        path: PathBuf,
        /// The key (`run.budget_calls`, `policy.sigma`, …).
        key: String,
        /// What is wrong.
        message: String,
    },
    /// `--out` names a directory that already holds files, and `--overwrite` was not given.
    #[error(
        "{dir}: the output directory is not empty (it holds {}); pass --overwrite to remove the files ilopt run writes (config.toml, seed-*.csv, seed-*.json, theta-seed-*.json, summary.json, summary.txt, timings.json; other files are kept), or choose another --out",
        listing(holds)
    )]
    OutputNotEmpty {
        /// The directory.
        dir: PathBuf,
        /// The names it holds, sorted.
        holds: Vec<String>,
    },
    /// The config's first step alone would spend more gradient calls than its budget.
    #[error("{path}: {message}")]
    OverBudget {
        /// The config file.
        path: PathBuf,
        /// The first step's cost, how it is made up, and the budget.
        message: String,
    },
    /// The task, expert or policy could not be built.
    #[error("building the task: {0}")]
    Task(String),
    /// A saved θ does not fit the config's policy.
    #[error("{path}: {message}")]
    Theta {
        /// The θ file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A run could not start or an evaluation failed.
    #[error("seed {seed}: {message}")]
    Run {
        /// The seed.
        seed: u64,
        /// What went wrong.
        message: String,
    },
    /// An evaluation failed.
    #[error("evaluation: {0}")]
    Evaluation(String),
}

impl RunError {
    /// An [`RunError::Io`] for `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        RunError::Io {
            path: path.into(),
            source,
        }
    }
}

/// Up to three names, then how many more.
fn listing(names: &[String]) -> String {
    let mut s = names.iter().take(3).cloned().collect::<Vec<_>>().join(", ");
    if names.len() > 3 {
        s.push_str(&format!(" and {} more", names.len() - 3));
    }
    s
}

/// [`RunError::Invalid`] for `key` of the config file at `path`.
pub(super) fn invalid(path: &Path, key: &str, message: impl std::fmt::Display) -> RunError {
    RunError::Invalid {
        path: path.to_path_buf(),
        key: key.into(),
        message: message.to_string(),
    }
}
