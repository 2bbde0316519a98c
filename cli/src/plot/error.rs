//! What can go wrong in `ilopt plot`, each error naming the directory or file and what is wrong.

use std::path::{Path, PathBuf};

/// An `ilopt plot` failure.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A run directory, or a file in it, that is missing or cannot be read as `ilopt run`
    /// writes it.
    #[error("{}: {message}", .path.display())]
    Read {
        /// The directory or file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Runs or options that cannot be drawn together (mixed tasks or x axes, a metric a run
    /// does not record, labels that do not match the directories, an unknown extension).
    #[error("{0}")]
    Input(String),
    /// Drawing or PNG rendering failed.
    #[error("drawing {}: {message}", .path.display())]
    Draw {
        /// The figure file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// The figure file cannot be written.
    #[error("{}: cannot write the figure: {source}", .path.display())]
    Write {
        /// The figure file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl PlotError {
    /// A [`PlotError::Read`] of `path`.
    pub fn read(path: &Path, message: impl std::fmt::Display) -> Self {
        PlotError::Read {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }
}
