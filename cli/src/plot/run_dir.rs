//! One `ilopt run` output directory as `ilopt plot` reads it: the task and learner from its
//! `config.toml`, and per seed that config lists the checkpoints of `seed-<n>.csv` (columns found
//! by their header names) and the termination recorded in `seed-<n>.json`. Only the seeds the
//! config lists are read, so stale seed files of an earlier run in the same directory are not
//! mixed in.

use super::error::PlotError;
use super::metric::Metric;
use crate::run::RunFile;
use crate::run::config::TaskName;
use std::path::{Path, PathBuf};

/// One checkpoint row.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The nominal call count the checkpoint belongs to (`at_calls`).
    pub at_calls: u64,
    /// Cumulative gradient calls (`gradient_evaluations`).
    pub calls: f64,
    /// The iteration.
    pub iteration: f64,
    /// The metrics' cells, in the order of [`Metric::ALL`] (`None`: an empty cell).
    pub values: [Option<f64>; 6],
}

impl Row {
    /// The cell of `metric`.
    pub fn value(&self, metric: Metric) -> Option<f64> {
        let k = Metric::ALL.iter().position(|m| *m == metric)?;
        self.values[k]
    }
}

/// One seed's run.
#[derive(Debug, Clone, PartialEq)]
pub struct SeedRecord {
    /// The seed.
    pub seed: u64,
    /// Its checkpoints, in file order.
    pub rows: Vec<Row>,
    /// Whether it ended as diverged (its termination starts with `diverged`).
    pub diverged: bool,
}

/// A run directory.
#[derive(Debug, Clone, PartialEq)]
pub struct RunDir {
    /// The directory.
    pub path: PathBuf,
    /// Its task.
    pub task: TaskName,
    /// Whether its learner is a dataset learner (BC, DAgger, …), whose iterations are rounds of
    /// roll-outs and retraining rather than gradient steps.
    pub dataset_learner: bool,
    /// The seeds, in the config's order.
    pub seeds: Vec<SeedRecord>,
}

impl RunDir {
    /// Read the run in `dir`.
    ///
    /// # Errors
    /// [`PlotError::Read`] naming the directory or file: no directory, no `config.toml` or one
    /// `ilopt run` would refuse, no seed file at all, a seed file missing, a CSV without the
    /// expected columns or with a cell that is not a number, a seed JSON that is not JSON.
    pub fn read(dir: &Path) -> Result<Self, PlotError> {
        if !dir.is_dir() {
            return Err(PlotError::read(
                dir,
                "no such directory (expected the --out directory of an `ilopt run`)",
            ));
        }
        let config_path = dir.join("config.toml");
        if !config_path.is_file() {
            return Err(PlotError::read(
                dir,
                "no config.toml: not an `ilopt run` output directory",
            ));
        }
        let config = RunFile::load(&config_path).map_err(|e| PlotError::read(dir, e))?;
        let listed = &config.file.run.seeds;
        let present: Vec<u64> = listed
            .iter()
            .copied()
            .filter(|s| dir.join(format!("seed-{s}.csv")).is_file())
            .collect();
        if present.is_empty() {
            return Err(PlotError::read(
                dir,
                format!(
                    "no seed files: config.toml lists seeds {listed:?} but none of their seed-<n>.csv exists"
                ),
            ));
        }
        if let Some(s) = listed.iter().find(|s| !present.contains(s)) {
            return Err(PlotError::read(
                &dir.join(format!("seed-{s}.csv")),
                format!("missing (config.toml lists seeds {listed:?})"),
            ));
        }
        let seeds = listed
            .iter()
            .map(|&seed| {
                Ok(SeedRecord {
                    seed,
                    rows: read_csv(&dir.join(format!("seed-{seed}.csv")))?,
                    diverged: read_diverged(&dir.join(format!("seed-{seed}.json")))?,
                })
            })
            .collect::<Result<_, PlotError>>()?;
        Ok(RunDir {
            path: dir.to_path_buf(),
            task: config.file.task.name,
            dataset_learner: config.file.is_dataset_learner(),
            seeds,
        })
    }

    /// The metrics with at least one value in some seed's file.
    pub fn recorded(&self) -> Vec<Metric> {
        Metric::ALL
            .into_iter()
            .filter(|m| {
                self.seeds
                    .iter()
                    .flat_map(|s| &s.rows)
                    .any(|r| r.value(*m).is_some())
            })
            .collect()
    }
}

/// The checkpoints of a `seed-<n>.csv`.
fn read_csv(path: &Path) -> Result<Vec<Row>, PlotError> {
    let text = std::fs::read_to_string(path).map_err(|e| PlotError::read(path, e))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| PlotError::read(path, format!("no `{name}` column in the header line")))
    };
    let (at, calls, iteration) = (
        column("at_calls")?,
        column("gradient_evaluations")?,
        column("iteration")?,
    );
    let metrics: Vec<usize> = Metric::ALL
        .iter()
        .map(|m| column(m.column()))
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate().filter(|(_, l)| !l.is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let line_no = k + 2;
        let cell = |i: usize, name: &str| -> Result<Option<f64>, PlotError> {
            match cells.get(i) {
                None => Err(PlotError::read(
                    path,
                    format!(
                        "line {line_no}: {} cells, the header has {}",
                        cells.len(),
                        header.len()
                    ),
                )),
                Some(&"") => Ok(None),
                Some(c) => c.parse::<f64>().map(Some).map_err(|_| {
                    PlotError::read(
                        path,
                        format!("line {line_no}: `{name}` = {c:?} is not a number"),
                    )
                }),
            }
        };
        let required = |i: usize, name: &str| {
            cell(i, name)?
                .ok_or_else(|| PlotError::read(path, format!("line {line_no}: `{name}` is empty")))
        };
        let at_calls = cells.get(at).copied().unwrap_or_default();
        let at_calls = at_calls.parse::<u64>().map_err(|_| {
            PlotError::read(
                path,
                format!("line {line_no}: `at_calls` = {at_calls:?} is not a whole number"),
            )
        })?;
        let mut values = [None; 6];
        for (v, (m, &i)) in values.iter_mut().zip(Metric::ALL.iter().zip(&metrics)) {
            *v = cell(i, m.column())?;
        }
        rows.push(Row {
            at_calls,
            calls: required(calls, "gradient_evaluations")?,
            iteration: required(iteration, "iteration")?,
            values,
        });
    }
    Ok(rows)
}

/// Whether the run of `seed-<n>.json` diverged: its `termination` starts with `diverged` (a
/// file without a termination, of a run still going, has not).
fn read_diverged(path: &Path) -> Result<bool, PlotError> {
    let text = std::fs::read_to_string(path).map_err(|e| PlotError::read(path, e))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| PlotError::read(path, e))?;
    Ok(json
        .get("termination")
        .and_then(serde_json::Value::as_str)
        .is_some_and(|t| t.starts_with("diverged")))
}
