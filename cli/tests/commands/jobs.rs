//! `ilopt run` for long jobs: a non-empty `--out` refused unless `--overwrite` (which removes only
//! the kit's files), every output naming the build, the closing table, and integer keys out of
//! range named in the user's words.

use crate::ROOT;
use crate::support::{Scratch, ilopt};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// SGD on the three-state toy MDP (3 gradient calls a step), with `seeds`.
fn toy(seeds: &str) -> String {
    let mdp = format!("{ROOT}/examples/toy/three-state.json").replace('\\', "/");
    format!(
        "[task]\nname = \"toy\"\nmdp = \"{mdp}\"\n\n[algorithm]\nalgorithm = \"sgd\"\nform = \"causal\"\nstep = {{ kind = \"constant\", eta = 0.2 }}\n\n[run]\nbudget_calls = 300\nseeds = {seeds}\ntheta0 = [1, 1, 1, 1, 1, 1]\n\n[evaluation]\nevery_calls = 100\n"
    )
}

fn run_args<'a>(cfg: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    v.extend_from_slice(extra);
    v
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A second run into the same `--out` is refused with a message naming the directory and
/// `--overwrite`, and writes nothing; with `--overwrite` the first run's files go (seeds 1–4 do
/// not survive beside seed 9) and a foreign file and a subdirectory stay.
#[test]
fn a_non_empty_out_is_refused_unless_overwrite() {
    let s = Scratch::new("overwrite");
    let four = s.write("four.toml", &toy("[1, 2, 3, 4]"));
    let nine = s.write("nine.toml", &toy("[9]"));
    let out = s.path().join("out");
    let (code, _, stderr) = ilopt(&run_args(&four, &out, &[]));
    assert_eq!(code, 0, "{stderr}");
    let first = names(&out);
    assert!(first.contains(&"seed-4.csv".to_string()), "{first:?}");

    let (code, stdout, stderr) = ilopt(&run_args(&nine, &out, &[]));
    assert_eq!(code, 1, "{stderr}");
    assert!(stdout.is_empty());
    assert!(stderr.contains(out.to_str().unwrap()), "{stderr}");
    assert!(
        stderr.contains("--overwrite") && stderr.contains("not empty"),
        "{stderr}"
    );
    assert_eq!(names(&out), first, "a refused run wrote something");

    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("seed-x.csv"), "mine too").unwrap();
    std::fs::create_dir(out.join("plots")).unwrap();
    let (code, _, stderr) = ilopt(&run_args(&nine, &out, &["--overwrite"]));
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(
        names(&out),
        [
            "config.toml",
            "notes.txt",
            "plots",
            "seed-9.csv",
            "seed-9.json",
            "seed-x.csv",
            "summary.json",
            "summary.txt",
            "theta-seed-9.json",
            "timings.json"
        ]
    );
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );

    // Only foreign files: still not empty, still refused.
    let other = s.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("README"), "x").unwrap();
    let (code, _, stderr) = ilopt(&run_args(&nine, &other, &[]));
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("README"), "{stderr}");
    // An empty directory is fine.
    let empty = s.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let (code, _, stderr) = ilopt(&run_args(&nine, &empty, &[]));
    assert_eq!(code, 0, "{stderr}");
}

/// The kit's file names, and nothing that merely resembles them.
#[test]
fn overwrite_recognises_only_the_kits_files() {
    use ilopt_cli::run::output::is_kit_file;
    for ours in [
        "config.toml",
        "summary.json",
        "summary.txt",
        "timings.json",
        "seed-0.csv",
        "seed-18446744073709551615.json",
        "theta-seed-12.json",
        ".seed-3.csv.tmp-4242",
        ".summary.json.tmp-1",
    ] {
        assert!(is_kit_file(ours), "{ours}");
    }
    for theirs in [
        "config.toml.bak",
        "seed-.csv",
        "seed-1a.csv",
        "seed--1.csv",
        "seed-18446744073709551616.csv",
        "seed-1.txt",
        "theta-seed-1.csv",
        "notes.txt",
        ".seed-3.csv.tmp-",
        ".notes.tmp-1",
        "Summary.json",
    ] {
        assert!(!is_kit_file(theirs), "{theirs}");
    }
}

/// `summary.json`, each `seed-<n>.json` and `config.toml` name the kit's version and commit, and
/// whether the build had uncommitted changes (a boolean, or null when unknown, as the comment
/// line says).
#[test]
fn every_output_names_the_build() {
    let s = Scratch::new("provenance");
    let cfg = s.write("c.toml", &toy("[5]"));
    let out = s.path().join("out");
    let (code, stdout, stderr) = ilopt(&run_args(&cfg, &out, &[]));
    assert_eq!(code, 0, "{stderr}");
    let version = env!("CARGO_PKG_VERSION");
    let check = |v: &Value, what: &str| {
        assert_eq!(v["ilopt"]["version"], version, "{what}");
        let commit = v["ilopt"]["commit"].as_str().unwrap();
        assert!(
            commit == "unknown"
                || (commit.len() == 40 && commit.bytes().all(|b| b.is_ascii_hexdigit())),
            "{what}: {commit}"
        );
        let changes = &v["ilopt"]["uncommitted_changes"];
        assert!(
            changes.is_boolean() || changes.is_null(),
            "{what}: {changes}"
        );
        let marked = if changes == &Value::Bool(true) {
            ", with uncommitted changes"
        } else {
            ""
        };
        format!("{commit}{marked}")
    };
    let printed: Value = serde_json::from_str(&stdout).unwrap();
    let commit = check(&printed, "stdout");
    let read = |f: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(f)).unwrap()).unwrap()
    };
    check(&read("summary.json"), "summary.json");
    check(&read("seed-5.json"), "seed-5.json");
    let config = std::fs::read_to_string(out.join("config.toml")).unwrap();
    assert_eq!(
        config.lines().next().unwrap(),
        format!("# written by ilopt {version}, commit {commit}")
    );
}

/// A table cell is `value` to four significant digits.
fn close(cell: &str, value: f64) {
    let shown: f64 = cell.parse().unwrap();
    assert!(
        (shown - value).abs() <= 5e-4 * value.abs(),
        "{cell} vs {value}"
    );
    let digits = cell.trim_start_matches(['-', '0', '.']).replace('.', "");
    assert_eq!(digits.len(), 4, "{cell}");
}

/// The run ends with a table on stderr, also written to `summary.txt`, while stdout stays one
/// JSON line; `--quiet` leaves stderr empty.
#[test]
fn the_run_ends_with_a_table() {
    let s = Scratch::new("table");
    let cfg = s.write("c.toml", &toy("[2, 1]"));
    let out = s.path().join("out");
    let (code, stdout, stderr) = ilopt(&run_args(&cfg, &out, &[]));
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(stdout.lines().count(), 1);
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    let table = std::fs::read_to_string(out.join("summary.txt")).unwrap();
    assert!(stderr.ends_with(&table), "{stderr}");
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 5, "{table}");
    assert!(
        lines[0].starts_with("toy task, toy policy, sgd, budget 300 gradient calls, 2 seed(s)")
    );
    assert!(
        lines[1].contains("seed")
            && lines[1].contains("termination")
            && lines[1].contains("objective")
    );
    assert!(
        !lines[1].contains("score"),
        "the toy MDP has no score: {table}"
    );
    for (line, run) in lines[2..4].iter().zip(summary["runs"].as_array().unwrap()) {
        let cells: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(cells[0], run["seed"].to_string());
        assert_eq!(cells[1], run["termination"].as_str().unwrap());
        assert_eq!(cells[2], run["iterations"].to_string());
        assert_eq!(cells[3], run["cost"]["gradient_evaluations"].to_string());
        let objective = run["final"]["objective"].as_f64().unwrap();
        close(cells[4], objective);
    }
    let mean: Vec<&str> = lines[4].split_whitespace().collect();
    assert_eq!(mean.len(), 3, "{table}");
    assert_eq!(mean[0], "mean");
    close(
        mean[1],
        summary["final_mean"]["objective"].as_f64().unwrap(),
    );
    close(
        mean[2],
        summary["final_mean"]["train_loss"].as_f64().unwrap(),
    );

    let quiet = s.path().join("quiet");
    let (code, stdout2, stderr) = ilopt(&run_args(&cfg, &quiet, &["--quiet"]));
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    assert_eq!(stdout2, stdout);
    assert_eq!(
        std::fs::read_to_string(quiet.join("summary.txt")).unwrap(),
        table
    );
}

/// Every integer key of the schema, given a value out of its range, is refused with the key and
/// the range in words ("must be an integer ≥ 1, got -5"), never the deserialiser's "u64".
#[test]
fn integer_keys_out_of_range_are_named_in_the_users_words() {
    let s = Scratch::new("integers");
    let toy = toy("[1]");
    let obstacle = "[task]\nname = \"obstacle\"\nsteps = 20\n[policy]\nfeatures = { kind = \"rbf\", per_axis = 3, width = 1.0, x_range = [-5, 5], y_range = [-5, 5] }\n\n[algorithm]\nalgorithm = \"sgd\"\nform = \"causal\"\nstep = { kind = \"constant\", eta = 0.2 }\n\n[run]\nbudget_calls = 300\nseeds = [1]\n";
    let dataset = |alg: &str| {
        format!(
            "[task]\nname = \"cartpole\"\nexpert = \"lqr\"\nsteps = 20\n\n[algorithm]\nalgorithm = \"{alg}\"\ntrajectories_per_iteration = 1\nretrain = \"warm-start\"\nbeta = {{ kind = \"linear\", iterations = 3 }}\ninner = {{ iterations = 5, batch_size = 16, rule = {{ rule = \"adam\", alpha = 0.01, beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8 }} }}\n\n[run]\nbudget_calls = 300\nseeds = [1]\n"
        )
    };
    let dagger = dataset("dagger");
    let o2nc = toy.replace(
        "algorithm = \"sgd\"\nform = \"causal\"\nstep = { kind = \"constant\", eta = 0.2 }",
        "algorithm = \"o2nc\"\nbudget = 100\ndelta = 0.1\ng = 4\ndelta0 = 2\nform = \"causal\"",
    );
    let baseline = |b: &str| toy.replace("[run]", &format!("[run]\nbaseline = {b}"));
    // (config, what it replaces, with what, key, range words, value as printed)
    let cases: Vec<(String, &str, &str, &str, &str, &str)> = vec![
        (
            obstacle.into(),
            "steps = 20",
            "steps = 0",
            "task.steps",
            "an integer in 1..=100000",
            "0",
        ),
        (
            obstacle.into(),
            "steps = 20",
            "steps = -3",
            "task.steps",
            "an integer in 1..=100000",
            "-3",
        ),
        (
            toy.clone(),
            "budget_calls = 300",
            "budget_calls = -5",
            "run.budget_calls",
            "an integer ≥ 1",
            "-5",
        ),
        (
            toy.clone(),
            "budget_calls = 300",
            "budget_calls = 0",
            "run.budget_calls",
            "an integer ≥ 1",
            "0",
        ),
        (
            toy.clone(),
            "budget_calls = 300",
            "budget_calls = 2.5",
            "run.budget_calls",
            "an integer ≥ 1",
            "2.5",
        ),
        (
            toy.clone(),
            "seeds = [1]",
            "seeds = [-1]",
            "run.seeds",
            "entry 0 (0-based) must be an integer ≥ 0",
            "-1",
        ),
        (
            toy.clone(),
            "seeds = [1]",
            "seeds = [4, -1]",
            "run.seeds",
            "entry 1 (0-based) must be an integer ≥ 0",
            "-1",
        ),
        (
            toy.clone(),
            "[run]",
            "[run]\ntrajectories_per_gradient = 0",
            "run.trajectories_per_gradient",
            "an integer in 1..=100000",
            "0",
        ),
        (
            toy.clone(),
            "[run]",
            "[run]\ntrajectories_per_gradient = -2",
            "run.trajectories_per_gradient",
            "an integer in 1..=100000",
            "-2",
        ),
        (
            toy.clone(),
            "every_calls = 100",
            "every_calls = -5",
            "evaluation.every_calls",
            "an integer ≥ 1",
            "-5",
        ),
        (
            toy.clone(),
            "every_calls = 100",
            "every_calls = 0",
            "evaluation.every_calls",
            "an integer ≥ 1",
            "0",
        ),
        (
            toy.clone(),
            "every_calls = 100",
            "every_calls = 100\nepisodes = 0",
            "evaluation.episodes",
            "an integer in 1..=1000000",
            "0",
        ),
        (
            toy.clone(),
            "every_calls = 100",
            "every_calls = 100\nepisodes = 5000000000",
            "evaluation.episodes",
            "an integer in 1..=1000000",
            "5000000000",
        ),
        (
            obstacle.into(),
            "per_axis = 3",
            "per_axis = -4",
            "policy.features.per_axis",
            "an integer ≥ 0",
            "-4",
        ),
        (
            baseline("{ kind = \"state-dependent\", features = 2 }"),
            "features = 2",
            "features = -1",
            "run.baseline.features",
            "an integer ≥ 0",
            "-1",
        ),
        (
            baseline("{ kind = \"state-dependent\", fit_every = 2 }"),
            "fit_every = 2",
            "fit_every = -1",
            "run.baseline.fit_every",
            "an integer ≥ 0",
            "-1",
        ),
        (
            dagger.clone(),
            "trajectories_per_iteration = 1",
            "trajectories_per_iteration = -1",
            "algorithm.trajectories_per_iteration",
            "an integer ≥ 0",
            "-1",
        ),
        (
            dagger.clone(),
            "iterations = 5",
            "iterations = -5",
            "algorithm.inner.iterations",
            "an integer ≥ 0",
            "-5",
        ),
        (
            dagger.clone(),
            "batch_size = 16",
            "batch_size = -16",
            "algorithm.inner.batch_size",
            "an integer ≥ 0",
            "-16",
        ),
        (
            dagger.clone(),
            "iterations = 3",
            "iterations = -3",
            "algorithm.beta.iterations",
            "an integer ≥ 0",
            "-3",
        ),
        (
            o2nc,
            "budget = 100",
            "budget = -100",
            "algorithm.budget",
            "an integer ≥ 0",
            "-100",
        ),
    ];
    for (i, (text, from, to, key, words, got)) in cases.iter().enumerate() {
        assert!(text.contains(from), "case {i}: {from}");
        let cfg = s.write(&format!("bad-{i}.toml"), &text.replacen(from, to, 1));
        let out = s.path().join(format!("out-{i}"));
        let (code, stdout, stderr) = ilopt(&run_args(&cfg, &out, &[]));
        assert_eq!(code, 1, "case {i} ({key}): {stderr}");
        assert!(stdout.is_empty());
        let line = stderr.trim_end();
        assert!(
            line.starts_with(&format!("error: {}: `{key}`: ", cfg.display())),
            "case {i}: {line}"
        );
        assert!(
            line.ends_with(&format!("{words}, got {got}")),
            "case {i}: {line}"
        );
        assert!(!line.contains("u64") && !line.contains("u32") && !line.contains("usize"));
        assert!(!out.exists(), "case {i}");
    }
}

/// A config whose first step alone costs more gradient calls than the budget is refused before
/// anything is written, with the numbers; the bound counts only what is certain (an absorbing end
/// or an episode may stop after one decision), and a first step of exactly the budget runs.
#[test]
fn a_first_step_beyond_the_budget_is_refused_with_the_numbers() {
    use ilopt_cli::run::first_step::{FirstStep, first_step};
    use ilopt_cli::run::task::TaskLearner;
    use ilopt_cli::run::{LoadedConfig, RunFile};
    fn least_of(t: &TaskLearner, c: &LoadedConfig) -> Option<FirstStep> {
        match t {
            TaskLearner::CartPoleSoftmax(t) => first_step(t, c),
            TaskLearner::CartPoleLogistic(t) => first_step(t, c),
            TaskLearner::Obstacle(t) => first_step(t, c),
            TaskLearner::Toy(t) => first_step(t, c),
        }
    }
    let s = Scratch::new("first-step");
    let sgd = "algorithm = \"sgd\"\nform = \"causal\"\nstep = { kind = \"constant\", eta = 1e-3 }";
    let inner = |batch: &str| {
        format!(
            "trajectories_per_iteration = 2\nretrain = \"warm-start\"\ninner = {{ iterations = 5, {batch}rule = {{ rule = \"sgd\", step = {{ kind = \"constant\", eta = 0.1 }} }} }}"
        )
    };
    let cartpole = |task: &str, alg: &str, run: &str| {
        format!(
            "[task]\nname = \"cartpole\"\nexpert = \"lqr\"\n{task}\n[algorithm]\n{alg}\n[run]\nbudget_calls = 1000\nseeds = [1]\n{run}\n"
        )
    };
    // (config, the least first step, or none)
    let cases: Vec<(String, Option<u128>)> = vec![
        (
            cartpole("", sgd, "trajectories_per_gradient = 100000"),
            Some(50_000_000),
        ),
        (
            cartpole("steps = 40", sgd, "trajectories_per_gradient = 3"),
            Some(120),
        ),
        (
            cartpole(
                "steps = 40\nafter_end = \"absorb\"",
                sgd,
                "trajectories_per_gradient = 3",
            ),
            Some(3),
        ),
        (
            cartpole(
                "horizon = \"episodic\"",
                sgd,
                "trajectories_per_gradient = 3000",
            ),
            Some(3000),
        ),
        (
            toy("[1]").replace("[run]", "[run]\ntrajectories_per_gradient = 400"),
            Some(1200),
        ),
        (
            cartpole(
                "steps = 40",
                &format!("algorithm = \"bc\"\n{}", inner("batch_size = 300, ")),
                "",
            ),
            Some(1500),
        ),
        (
            cartpole(
                "steps = 40",
                &format!(
                    "algorithm = \"dagger\"\naggregate = true\nbeta = {{ kind = \"constant\", beta = 0.5 }}\n{}",
                    inner("")
                ),
                "",
            ),
            Some(400),
        ),
        (
            cartpole(
                "steps = 40",
                &format!("algorithm = \"forward-training\"\n{}", inner(""))
                    .replace("retrain = \"warm-start\"\n", ""),
                "",
            ),
            Some(10),
        ),
        (
            cartpole(
                "horizon = \"episodic\"",
                &format!("algorithm = \"rrm\"\n{}", inner("")),
                "",
            ),
            Some(10),
        ),
    ];
    for (i, (text, least)) in cases.iter().enumerate() {
        let cfg = s.write(&format!("c-{i}.toml"), text);
        let c = RunFile::load(&cfg).unwrap_or_else(|e| panic!("case {i}: {e}"));
        let bench = ilopt_cli::run::task::task_learner(&c).unwrap();
        let got = least_of(&bench, &c).map(|f| f.calls);
        assert_eq!(got, *least, "case {i}");
        let over = least.is_some_and(|n| n > u128::from(c.file.run.budget_calls));
        if over {
            let out = s.path().join(format!("out-{i}"));
            let (code, stdout, stderr) = ilopt(&run_args(&cfg, &out, &[]));
            assert_eq!(code, 1, "case {i}: {stderr}");
            assert!(stdout.is_empty());
            assert!(
                stderr.contains("above run.budget_calls = "),
                "case {i}: {stderr}"
            );
            assert!(!out.exists(), "case {i}");
        }
    }
    let (_, stderr) = {
        let cfg = s.write("big.toml", &cases[0].0);
        let (code, _, stderr) = ilopt(&run_args(&cfg, &s.path().join("big"), &[]));
        (code, stderr)
    };
    assert!(
        stderr.contains("the first step alone costs at least run.trajectories_per_gradient × task.steps = 100000 × 500 = 5·10⁷ gradient calls, above run.budget_calls = 1000"),
        "{stderr}"
    );
    // A toy MDP with absorbing states: nothing certain, nothing refused.
    let absorbing = toy("[1]")
        .replace("three-state.json", "terminal-absorb.json")
        .replace("theta0 = [1, 1, 1, 1, 1, 1]\n", "")
        .replace("[run]", "[run]\ntrajectories_per_gradient = 100000");
    let cfg = s.write("absorbing.toml", &absorbing);
    let c = RunFile::load(&cfg).unwrap();
    assert_eq!(
        least_of(&ilopt_cli::run::task::task_learner(&c).unwrap(), &c),
        None
    );
    // Exactly the budget: 100 trajectories × 3 decisions = 300 calls, one step, and it runs.
    let cfg = s.write(
        "exact.toml",
        &toy("[1]").replace("[run]", "[run]\ntrajectories_per_gradient = 100"),
    );
    let (code, stdout, stderr) = ilopt(&run_args(&cfg, &s.path().join("exact"), &["--quiet"]));
    assert_eq!(code, 0, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["runs"][0]["iterations"], 1);
    assert_eq!(v["runs"][0]["cost"]["gradient_evaluations"], 300);
}

/// Kills the child process when dropped, so that a failing test leaves no run behind.
struct Child(std::process::Child);

impl Drop for Child {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A run killed (SIGKILL) after its first checkpoints keeps them: `seed-1.csv` holds the header
/// and one complete row per checkpoint reached, the same ones the per-checkpoint lines on a
/// non-terminal stderr announced, and `seed-1.json` the checkpoints written so far under
/// `"termination": "running"`.
#[test]
fn a_killed_run_keeps_its_checkpoints_and_logged_them() {
    use std::io::{BufRead, BufReader};
    let s = Scratch::new("killed");
    let cfg = s.write(
        "long.toml",
        "[task]\nname = \"cartpole\"\nexpert = \"lqr\"\nsteps = 100\n\n[algorithm]\nalgorithm = \"sgd\"\nform = \"causal\"\nstep = { kind = \"constant\", eta = 1e-3 }\n\n[run]\nbudget_calls = 100_000_000\nseeds = [1]\n\n[evaluation]\nevery_calls = 100\nepisodes = 1\n",
    );
    let out = s.path().join("out");
    let mut child = Child(
        Command::new(env!("CARGO_BIN_EXE_ilopt"))
            .args(run_args(&cfg, &out, &[]))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let stderr = child.0.stderr.take().unwrap();
    let mut lines = Vec::new();
    for line in BufReader::new(stderr).lines() {
        let line = line.unwrap();
        assert!(line.starts_with("seed 1: "), "{line}");
        lines.push(line);
        if lines.len() == 3 {
            break;
        }
    }
    child.0.kill().unwrap();
    child.0.wait().unwrap();
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert!(
        lines[0].starts_with("seed 1: 0/100000000 calls (0 used), iteration 0, score "),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].starts_with("seed 1: 100/100000000 calls (100 used), iteration 1, score "),
        "{}",
        lines[1]
    );
    assert!(lines[1].contains(", eval loss ") && lines[1].contains(", train loss "));
    assert!(!out.join("summary.json").exists());

    let csv = std::fs::read_to_string(out.join("seed-1.csv")).unwrap();
    assert!(csv.ends_with('\n'), "a partial row: {csv}");
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("at_calls,iteration,"));
    assert!(rows.len() > 3, "{csv}");
    let fields = rows[0].split(',').count();
    for (k, row) in rows[1..].iter().enumerate() {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells.len(), fields, "{row}");
        assert_eq!(cells[0], (100 * k).to_string(), "{row}");
        assert_eq!(cells[1], k.to_string(), "{row}");
    }
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("seed-1.json")).unwrap()).unwrap();
    assert_eq!(json["termination"], "running");
    assert_eq!(json["seed"], 1);
    let kept = json["checkpoints"].as_array().unwrap();
    assert!(
        !kept.is_empty() && kept.len() < rows.len(),
        "{}",
        kept.len()
    );
    assert_eq!(kept[0]["at_calls"], 0);
}

/// A completed run's CSV, written a row at a time, is its checkpoints as `seed-<n>.json` records
/// them, and its `seed-<n>.json` is the full record.
#[test]
fn the_appended_csv_is_the_completed_runs_checkpoints() {
    let s = Scratch::new("appended");
    let cfg = s.write("c.toml", &toy("[3, 8]"));
    let out = s.path().join("out");
    let (code, _, stderr) = ilopt(&run_args(&cfg, &out, &[]));
    assert_eq!(code, 0, "{stderr}");
    for seed in [3, 8] {
        let json: Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("seed-{seed}.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(json["termination"], "gradient-budget");
        let checkpoints: Vec<ilopt_cli::run::records::Checkpoint> =
            serde_json::from_value(json["checkpoints"].clone()).unwrap();
        assert_eq!(checkpoints.len(), 4);
        let mut expected = format!("{}\n", ilopt_cli::run::records::Checkpoint::CSV_HEADER);
        for c in &checkpoints {
            expected.push_str(&c.csv_row());
            expected.push('\n');
        }
        let csv = std::fs::read_to_string(out.join(format!("seed-{seed}.csv"))).unwrap();
        assert_eq!(csv, expected);
        // The log lines of this non-terminal stderr: one per checkpoint and seed.
        assert_eq!(
            stderr
                .lines()
                .filter(|l| l.starts_with(&format!("seed {seed}: ")))
                .count(),
            4,
            "{stderr}"
        );
    }
}
