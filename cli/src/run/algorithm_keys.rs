//! The keys of the `[algorithm]` table: [`ilopt::algo::AlgorithmConfig`]'s structs accept and
//! drop keys they do not know, so an unknown key is found by writing the parsed config out again;
//! and the resolved config keeps the numbers as the user wrote them.

use super::error::{RunError, invalid};
use ilopt::algo::AlgorithmConfig;
use std::path::Path;

/// Replace the values of `written` by those of `raw` at the same keys (tables recursively).
pub(super) fn overlay(written: &mut toml::Value, raw: &toml::Value) {
    match (written, raw) {
        (toml::Value::Table(w), toml::Value::Table(r)) => {
            for (k, rv) in r {
                match w.get_mut(k) {
                    Some(wv) => overlay(wv, rv),
                    None => {
                        w.insert(k.clone(), rv.clone());
                    }
                }
            }
        }
        (w, r) => *w = r.clone(),
    }
}

/// [`AlgorithmConfig`]'s structs accept and drop keys they do not know; this finds them: every
/// key of the `[algorithm]` table must come back when the parsed config is written out again.
pub(super) fn check_known_keys(
    raw: &toml::Value,
    parsed: &AlgorithmConfig,
    path: &Path,
) -> Result<(), RunError> {
    let written = serde_json::to_value(parsed).map_err(|e| invalid(path, "algorithm", e))?;
    let raw = serde_json::to_value(raw).map_err(|e| invalid(path, "algorithm", e))?;
    match unknown_key(&raw, &written, "algorithm") {
        Some(key) => Err(invalid(
            path,
            &key,
            "unknown key (docs/run.md lists each algorithm's keys)",
        )),
        None => Ok(()),
    }
}

/// The first key of `raw` (a table, recursively) that `written` lacks, as a dotted path.
fn unknown_key(raw: &serde_json::Value, written: &serde_json::Value, at: &str) -> Option<String> {
    let (serde_json::Value::Object(r), serde_json::Value::Object(w)) = (raw, written) else {
        return None;
    };
    for (k, v) in r {
        let key = format!("{at}.{k}");
        match w.get(k) {
            None => return Some(key),
            Some(wv) => {
                if let Some(found) = unknown_key(v, wv, &key) {
                    return Some(found);
                }
            }
        }
    }
    None
}
