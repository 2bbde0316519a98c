//! The library's errors.

/// Why the appendix could not be produced.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A configuration file is malformed or invalid (the message names the field).
    #[error("config {file}: {message}")]
    Config {
        /// The file.
        file: String,
        /// What is wrong, naming the field.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// An experiment failed (environment, expert, policy or algorithm error).
    #[error("{what}: {message}")]
    Experiment {
        /// The experiment.
        what: String,
        /// The error.
        message: String,
    },
    /// The theorem-check suite failed.
    #[error("theorem checks: {0}")]
    Theory(String),
    /// `paper-checks merge` found work no shard has done.
    #[error(
        "merge: {missing} of the profile's units are not in {store} ({what}); run the jobs that have not finished (each shard in passes until it says its report runs are stored; `paper-checks theory` for the theorem table) and merge again"
    )]
    Incomplete {
        /// How many units are missing.
        missing: usize,
        /// Which parts are missing.
        what: String,
        /// The unit store.
        store: String,
    },
    /// Serialising a result failed.
    #[error("serialising {what}: {message}")]
    Serialise {
        /// What was serialised.
        what: String,
        /// The error.
        message: String,
    },
}

impl Error {
    /// An [`Error::Io`] for `path`.
    pub fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.display().to_string(),
            source,
        }
    }
    /// An [`Error::Experiment`].
    pub fn experiment(what: impl Into<String>, e: impl std::fmt::Display) -> Self {
        Error::Experiment {
            what: what.into(),
            message: e.to_string(),
        }
    }
}
