//! Removing what this profile does not produce from the output directory.

use crate::config::{Profile, TheorySize};
use crate::error::Error;
use crate::experiment::TaskKind;
use crate::naming::slug;
use std::path::Path;

/// Remove from `runs/` and `timings/` every file this profile does not produce (results of
/// rows an earlier profile had, left-over temporaries), so that the directory holds exactly the
/// data the appendix was built from. Returns the removed files (relative to the output
/// directory), sorted.
///
/// # Errors
/// [`Error::Io`] if a directory cannot be read or a file cannot be removed.
pub fn remove_stale(
    profile: &Profile,
    runs_dir: &Path,
    timings_dir: &Path,
) -> Result<Vec<String>, Error> {
    let mut keep_runs = vec!["gradient-error.json".to_string()];
    if profile.theory_profile != TheorySize::None {
        keep_runs.push("theory.json".into());
    }
    let mut keep_timings = vec!["gradient-error.json".to_string()];
    for (kind, t) in [
        (TaskKind::Obstacle, &profile.obstacle),
        (TaskKind::Cartpole, &profile.cartpole),
    ] {
        for e in &t.algorithms {
            let stem = format!("{}-{}.json", kind.name(), slug(&e.label));
            if e.has_grid() && e.hyper_parameters_of.is_none() {
                keep_runs.push(format!("tuning-{stem}"));
            }
            keep_runs.push(stem.clone());
            keep_timings.push(stem);
        }
    }
    let mut removed = Vec::new();
    for (dir, keep) in [(runs_dir, &keep_runs), (timings_dir, &keep_timings)] {
        let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(dir, e))?;
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_file() && !keep.contains(&name) {
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
                let sub = dir.file_name().map(|d| d.to_string_lossy().into_owned());
                removed.push(format!("{}/{name}", sub.unwrap_or_default()));
            }
        }
    }
    // Every configuration is assembled by now and its units removed: what is left in the unit
    // store belongs to other code versions or profiles.
    let units_dir = runs_dir.join("units");
    if units_dir.is_dir() {
        let entries = std::fs::read_dir(&units_dir).map_err(|e| Error::io(&units_dir, e))?;
        for entry in entries {
            let path = entry.map_err(|e| Error::io(&units_dir, e))?.path();
            if path.is_file() {
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
                let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
                removed.push(format!("runs/units/{}", name.unwrap_or_default()));
            }
        }
        // Empty now: a single run's directory has none.
        let _ = std::fs::remove_dir(&units_dir);
    }
    removed.sort();
    Ok(removed)
}
