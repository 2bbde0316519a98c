//! The native half of the Python package `ilopt` (module `ilopt._native`): thin bindings over
//! the routes of the `ilopt` command line — [`ilopt_cli::run::execute`] (`ilopt run`),
//! [`ilopt_cli::estimate::estimate_config`] (`ilopt estimate`, eq. 3.15) and
//! [`ilopt_cli::toy::evaluate_entries`] (`ilopt toy eval`) — so that Python gets the numbers and
//! the error messages of the CLI. The Python half (`python/ilopt/__init__.py`) turns configs
//! into the text these functions read and their results into numpy arrays, dicts and
//! `fractions.Fraction`s. Rust runs with the GIL released, but for a Gymnasium task, whose
//! environment steps in Python.

#![warn(missing_docs)]
#![deny(unsafe_code)]

mod gym;

use ilopt_cli::estimate::estimate_config;
use ilopt_cli::run::records::{Checkpoint, SeedRun};
use ilopt_cli::run::{LoadedConfig, RunFile, RunOptions, execute};
use ilopt_cli::toy::{ScalarChoice, evaluate_entries, load_mdp, parse_mdp};
use numpy::IntoPyArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// mimalloc for the kit's allocations inside Python: with the system allocator, each run's worker
/// threads meet the glibc arenas that earlier runs of the same process left behind, and the
/// training of every run after the first of a process slowed down.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

pyo3::create_exception!(
    ilopt,
    IloptError,
    PyValueError,
    "A bad config, θ, MDP or argument, or a failed run: the message is the `ilopt` command line's."
);

/// How a config reaches Rust: the path of a TOML file, or a JSON text of the schema's tables
/// (a Python dict).
fn load_config(kind: &str, text: &str) -> Result<LoadedConfig, String> {
    match kind {
        "path" => RunFile::load(Path::new(text)).map_err(|e| e.to_string()),
        "json" => {
            let name = Path::new("<config dict>");
            let value: toml::Value =
                serde_json::from_str(text).map_err(|e| format!("{}: {e}", name.display()))?;
            let toml = toml::to_string(&value).map_err(|e| format!("{}: {e}", name.display()))?;
            let cwd = std::env::current_dir()
                .map_err(|e| format!("the current directory (relative paths of a dict): {e}"))?;
            RunFile::from_toml_str(&toml, name, &cwd).map_err(|e| e.to_string())
        }
        other => Err(format!(
            "config kind {other:?} (expected \"path\" or \"json\")"
        )),
    }
}

/// The CSV columns (`seed-<n>.csv`) that are counts: never missing, integers.
const COUNT_COLUMNS: [&str; 6] = [
    "at_calls",
    "iteration",
    "gradient_evaluations",
    "trajectories",
    "env_steps",
    "expert_queries",
];

/// A seed's checkpoints as columns, read back from the very rows `seed-<n>.csv` holds: the
/// count columns as int64, the others as float64 with NaN for an empty cell.
fn columns<'py>(py: Python<'py>, run: &SeedRun) -> PyResult<Bound<'py, PyDict>> {
    let names: Vec<&str> = Checkpoint::CSV_HEADER.split(',').collect();
    let rows: Vec<String> = run.checkpoints.iter().map(Checkpoint::csv_row).collect();
    let cells: Vec<Vec<&str>> = rows.iter().map(|r| r.split(',').collect()).collect();
    let out = PyDict::new(py);
    for (j, name) in names.iter().enumerate() {
        fn cell<'a>(row: &[&'a str], j: usize) -> &'a str {
            row.get(j).copied().unwrap_or("")
        }
        if COUNT_COLUMNS.contains(name) {
            let v = cells
                .iter()
                .map(|row| {
                    cell(row, j).parse::<i64>().map_err(|e| {
                        IloptError::new_err(format!(
                            "seed {}: column {name}: {:?} is not a count: {e}",
                            run.seed,
                            cell(row, j)
                        ))
                    })
                })
                .collect::<PyResult<Vec<i64>>>()?;
            out.set_item(name, v.into_pyarray(py))?;
        } else {
            let v = cells
                .iter()
                .map(|row| match cell(row, j) {
                    "" => Ok(f64::NAN),
                    c => c.parse::<f64>().map_err(|e| {
                        IloptError::new_err(format!(
                            "seed {}: column {name}: {c:?} is not a number: {e}",
                            run.seed
                        ))
                    }),
                })
                .collect::<PyResult<Vec<f64>>>()?;
            out.set_item(name, v.into_pyarray(py))?;
        }
    }
    Ok(out)
}

/// Run a config as `ilopt run` does (`kind` "path" or "json", see `load_config`), writing the
/// run's files to `out` if given. Returns (the summary as JSON text, {seed: {column: array}},
/// {seed: final θ}).
#[pyfunction]
#[pyo3(signature = (kind, text, out=None, threads=None, overwrite=false, quiet=false))]
fn run<'py>(
    py: Python<'py>,
    kind: &str,
    text: &str,
    out: Option<PathBuf>,
    threads: Option<usize>,
    overwrite: bool,
    quiet: bool,
) -> PyResult<(String, Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    if threads == Some(0) {
        return Err(IloptError::new_err("threads must be at least 1"));
    }
    let outcome = py
        .allow_threads(|| {
            let config = load_config(kind, text)?;
            execute(
                &config,
                out.as_deref(),
                threads,
                RunOptions { overwrite, quiet },
            )
            .map_err(|e| e.to_string())
        })
        .map_err(IloptError::new_err)?;
    outcome_to_py(py, &outcome)
}

/// Run a config (`kind` "path" or "json") on a Gymnasium task (module [`gym`]), as [`run`] does
/// on a built-in one, but with the GIL held: the seeds run one at a time on this thread, and every
/// step of the environment is a call into Python.
#[pyfunction]
#[pyo3(signature = (kind, text, out, overwrite, quiet, env, eval_env, expert, features, feature_dim, space, size, steps, after_end, sigma, eval_steps, name))]
#[allow(clippy::too_many_arguments)]
fn run_gym<'py>(
    py: Python<'py>,
    kind: &str,
    text: &str,
    out: Option<PathBuf>,
    overwrite: bool,
    quiet: bool,
    env: Py<PyAny>,
    eval_env: Py<PyAny>,
    expert: Py<PyAny>,
    features: Option<Py<PyAny>>,
    feature_dim: usize,
    space: String,
    size: usize,
    steps: Option<usize>,
    after_end: String,
    sigma: f64,
    eval_steps: usize,
    name: String,
) -> PyResult<(String, Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let spec = gym::GymSpec {
        env,
        eval_env,
        expert,
        features,
        feature_dim,
        space,
        size,
        steps,
        after_end,
        sigma,
        eval_steps,
        name,
    };
    let config = load_config(kind, text).map_err(IloptError::new_err)?;
    let outcome = gym::run_gym(
        spec,
        &config,
        out.as_deref(),
        RunOptions { overwrite, quiet },
    )
    .map_err(IloptError::new_err)?;
    outcome_to_py(py, &outcome)
}

/// (the summary as JSON text, {seed: {column: array}}, {seed: final θ}).
fn outcome_to_py<'py>(
    py: Python<'py>,
    outcome: &ilopt_cli::run::RunOutcome,
) -> PyResult<(String, Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let summary = serde_json::to_string(&outcome.summary)
        .map_err(|e| IloptError::new_err(format!("the summary: {e}")))?;
    let checkpoints = PyDict::new(py);
    let thetas = PyDict::new(py);
    for r in &outcome.runs {
        checkpoints.set_item(r.seed, columns(py, r)?)?;
        thetas.set_item(r.seed, r.theta.clone().into_pyarray(py))?;
    }
    Ok((summary, checkpoints, thetas))
}

/// One draw of the oracle's estimate (eq. 3.15) at θ, as `ilopt estimate` computes it.
#[pyfunction]
fn oracle_estimate<'py>(
    py: Python<'py>,
    kind: &str,
    text: &str,
    theta: Vec<f64>,
    trajectories: u64,
    seed: u64,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let g = py
        .allow_threads(|| {
            let config = load_config(kind, text)?;
            estimate_config(&config, &theta, trajectories, seed).map_err(|e| e.to_string())
        })
        .map_err(IloptError::new_err)?;
    Ok(g.into_pyarray(py))
}

/// What `ilopt toy eval` prints (exact arithmetic), as JSON text: the MDP a file path
/// (`kind` "path") or JSON text ("json"), θ and the baselines as exact-number texts.
#[pyfunction]
#[pyo3(signature = (kind, mdp, theta, baseline=None, optimal_baseline=false))]
fn toy_eval(
    py: Python<'_>,
    kind: &str,
    mdp: &str,
    theta: Vec<String>,
    baseline: Option<Vec<String>>,
    optimal_baseline: bool,
) -> PyResult<String> {
    py.allow_threads(|| {
        let mdp = match kind {
            "path" => load_mdp(Path::new(mdp)),
            _ => parse_mdp(mdp, "<mdp dict>"),
        }
        .map_err(|e| e.to_string())?;
        let theta: Vec<&str> = theta.iter().map(String::as_str).collect();
        let baseline: Option<Vec<&str>> = baseline
            .as_ref()
            .map(|b| b.iter().map(String::as_str).collect());
        evaluate_entries(
            &mdp,
            &theta,
            baseline.as_deref(),
            optimal_baseline,
            ScalarChoice::Exact,
        )
        .map(|v| v.to_string())
        .map_err(|e| e.to_string())
    })
    .map_err(IloptError::new_err)
}

/// The module `ilopt._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("IloptError", m.py().get_type::<IloptError>())?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(run_gym, m)?)?;
    m.add_function(wrap_pyfunction!(oracle_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(toy_eval, m)?)?;
    Ok(())
}
