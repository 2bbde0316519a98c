//! Files of the output directory: atomic writes, JSON in and out, directories.

use crate::error::Error;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Write `bytes` to `path` atomically (a temporary file in the same directory, then rename).
///
/// # Errors
/// [`Error::Io`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let tmp = path.with_extension(format!(
        "{}.tmp",
        path.extension().and_then(|e| e.to_str()).unwrap_or("")
    ));
    // A failed write or rename (full disk, permissions) must not leave the temporary behind.
    let cleanup = |e: std::io::Error, at: &Path| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(at, e)
    };
    std::fs::write(&tmp, bytes).map_err(|e| cleanup(e, &tmp))?;
    std::fs::rename(&tmp, path).map_err(|e| cleanup(e, path))
}

/// Serialise as pretty JSON with a trailing newline.
///
/// # Errors
/// [`Error::Serialise`].
pub fn to_json<T: Serialize>(what: &str, v: &T) -> Result<Vec<u8>, Error> {
    let mut s = serde_json::to_string_pretty(v).map_err(|e| Error::Serialise {
        what: what.into(),
        message: e.to_string(),
    })?;
    s.push('\n');
    Ok(s.into_bytes())
}

/// Read a JSON file as `T`; `None` when it is missing, unreadable or of another shape (a cache
/// miss).
pub fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Option<T> {
    let text = std::fs::read_to_string(path).ok()?;
    serde_json::from_str(&text).ok()
}

/// Create a directory and its parents.
///
/// # Errors
/// [`Error::Io`].
pub fn mkdir(p: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(p).map_err(|e| Error::io(p, e))
}
