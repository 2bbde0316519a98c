//! A program's own environment through `ilopt_cli::run::run_task` ([`EnvRun`]): the files of
//! `ilopt run`, independent of the thread count, an `eval_task` of the saved θ that reproduces the
//! last checkpoint, and the refusals (a built-in name, `task.name = "custom"` given to the binary,
//! `[task]` keys a plug-in task does not take).

use crate::ROOT;
use ilopt::env::{Env, EnvError, Step};
use ilopt::policy::Logistic;
use ilopt::problem::KitRng;
use ilopt::task::{AfterEnd, EnvTask, Horizon};
use ilopt_cli::eval::eval_task;
use ilopt_cli::run::plugin::PluginError;
use ilopt_cli::run::{EnvRun, RunError, RunFile, RunOptions, run_task};
use rand::Rng;
use std::path::{Path, PathBuf};

#[derive(Clone)]
struct Corridor(f64);

impl Env<f64> for Corridor {
    type Obs = f64;
    type Action = usize;
    fn reset(&mut self, rng: &mut KitRng) -> f64 {
        self.0 = rng.random_range(-1.0..1.0);
        self.0
    }
    fn step(&mut self, action: usize) -> Result<Step<f64, f64>, EnvError> {
        self.0 += if action == 1 { 0.1 } else { -0.1 };
        Ok(Step::new(self.0, 1.0, self.0.abs() > 2.0, false))
    }
}

/// Runs of these tests print nothing on stderr.
const QUIET: RunOptions = RunOptions {
    overwrite: false,
    quiet: true,
};

type Features = fn(&f64) -> Vec<f64>;
type Expert = fn(&f64) -> Result<usize, String>;

fn corridor(
    name: &str,
    eval_steps: usize,
) -> Result<EnvRun<Corridor, Features, Expert, Logistic>, PluginError> {
    let features: Features = |x| vec![*x, 1.0];
    let expert: Expert = |x| Ok(usize::from(*x < 0.0));
    EnvRun::new(
        name,
        "logistic",
        EnvTask::new(Corridor(0.0), features, expert),
        Logistic::new(2).expect("two features"),
        Horizon::fixed(20, AfterEnd::Reset),
        eval_steps,
    )
}

const CONFIG: &str = r#"
[algorithm]
algorithm = "sgd"
form = "causal"
step = { kind = "constant", eta = 0.01 }
[run]
budget_calls = 4000
seeds = [3, 1, 2]
[evaluation]
every_calls = 1000
episodes = 4
"#;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ilopt-plugin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

#[test]
fn a_plugin_task_writes_the_files_of_ilopt_run_whatever_the_thread_count() {
    let task = corridor("corridor", 30).expect("a valid task");
    let config = RunFile::parse(CONFIG, Path::new("corridor.toml")).expect("a valid config");
    let (one, two) = (scratch("one"), scratch("two"));
    let summary = run_task(&task, &config, &one, Some(1), QUIET).expect("the run");
    run_task(&task, &config, &two, Some(2), QUIET).expect("the run");
    assert_eq!(summary["task"], "corridor");
    assert_eq!(summary["policy"], "logistic");
    assert_eq!(summary["dim"], 2);
    for file in [
        "config.toml",
        "summary.json",
        "seed-1.csv",
        "seed-2.json",
        "seed-3.csv",
        "theta-seed-3.json",
    ] {
        assert_eq!(read(&one, file), read(&two, file), "{file}");
    }
    assert!(read(&one, "config.toml").contains("name = \"custom\""));
    let csv = read(&one, "seed-1.csv");
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(
        rows.len(),
        1 + 5,
        "header and the checkpoints 0, 1000, …, 4000:\n{csv}"
    );
    for row in &rows[1..] {
        let score: f64 = row
            .split(',')
            .nth(8)
            .and_then(|s| s.parse().ok())
            .expect("a score");
        assert!(
            (0.0..=30.0).contains(&score),
            "a return of at most 30 steps: {row}"
        );
    }
    for dir in [one, two] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// A corridor whose copies share one event log, as a Python environment's copies are one
/// environment: every reset is logged with the environment's tag.
#[derive(Clone)]
struct Logged {
    corridor: Corridor,
    tag: &'static str,
    log: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
}

impl Env<f64> for Logged {
    type Obs = f64;
    type Action = usize;
    fn reset(&mut self, rng: &mut KitRng) -> f64 {
        self.log.lock().expect("log").push(self.tag.to_string());
        self.corridor.reset(rng)
    }
    fn step(&mut self, action: usize) -> Result<Step<f64, f64>, EnvError> {
        self.corridor.step(action)
    }
}

/// The seed hook runs before each seed's first reset (its checkpoint 0's evaluation), and the
/// evaluation episodes reset the evaluation environment, never the training one; the files are
/// those of the same task without either setting (the corridor keeps no state across episodes).
#[test]
fn the_seed_hook_runs_first_and_evaluation_episodes_use_their_own_environment() {
    let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let env = |tag| Logged {
        corridor: Corridor(0.0),
        tag,
        log: log.clone(),
    };
    let features: fn(&f64) -> Vec<f64> = |x| vec![*x, 1.0];
    let expert: fn(&f64) -> Result<usize, String> = |x| Ok(usize::from(*x < 0.0));
    let hook_log = log.clone();
    let task = EnvRun::new(
        "corridor",
        "logistic",
        EnvTask::new(env("train"), features, expert),
        Logistic::new(2).expect("two features"),
        Horizon::fixed(20, AfterEnd::Reset),
        30,
    )
    .expect("a valid task")
    .with_evaluation_env(env("eval"))
    .on_each_seed(move |seed| hook_log.lock().expect("log").push(format!("seed {seed}")))
    .one_seed_at_a_time();
    let config = RunFile::parse(CONFIG, Path::new("corridor.toml")).expect("a valid config");
    let (logged, plain) = (scratch("logged"), scratch("plain"));
    run_task(&task, &config, &logged, None, QUIET).expect("the run");
    let events = log.lock().expect("log").clone();
    let starts: Vec<usize> = (0..events.len())
        .filter(|&i| events[i].starts_with("seed "))
        .collect();
    assert_eq!(
        starts
            .iter()
            .map(|&i| events[i].as_str())
            .collect::<Vec<_>>(),
        ["seed 3", "seed 1", "seed 2"],
        "one hook call per seed, in the config's order"
    );
    for (k, &i) in starts.iter().enumerate() {
        let end = starts.get(k + 1).copied().unwrap_or(events.len());
        let seed = &events[i + 1..end];
        // checkpoint 0's four evaluation episodes come first; five checkpoints of four episodes
        assert_eq!(seed[..4], ["eval"; 4], "{seed:?}");
        assert_eq!(seed.iter().filter(|e| *e == "eval").count(), 5 * 4);
        // 4000 calls of 20-decision trajectories, each starting with a reset
        assert!(seed.iter().filter(|e| *e == "train").count() >= 4000 / 20);
    }
    run_task(
        &corridor("corridor", 30).expect("a valid task"),
        &config,
        &plain,
        Some(1),
        QUIET,
    )
    .expect("the run");
    for file in [
        "summary.json",
        "seed-1.csv",
        "seed-3.csv",
        "theta-seed-2.json",
    ] {
        assert_eq!(read(&logged, file), read(&plain, file), "{file}");
    }
    for dir in [logged, plain] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// `eval_task` at the run's final θ with the run's seed and episodes meets the episodes of the
/// last checkpoint, so its evaluation equals that checkpoint's.
#[test]
fn eval_task_of_the_saved_theta_reproduces_the_last_checkpoint() {
    let task = corridor("corridor", 30).expect("a valid task");
    let config = RunFile::parse(CONFIG, Path::new("corridor.toml")).expect("a valid config");
    let dir = scratch("eval");
    run_task(&task, &config, &dir, Some(1), QUIET).expect("the run");
    let seed_json: serde_json::Value =
        serde_json::from_str(&read(&dir, "seed-2.json")).expect("JSON");
    let saved: serde_json::Value =
        serde_json::from_str(&read(&dir, "theta-seed-2.json")).expect("JSON");
    let theta: Vec<f64> = serde_json::from_value(saved["theta"].clone()).expect("θ");
    let out = eval_task(&task, &theta, 4, 2).expect("the evaluation");
    let last = seed_json["checkpoints"]
        .as_array()
        .and_then(|c| c.last())
        .expect("checkpoints")
        .clone();
    assert_eq!(out["evaluation"]["score"], last["score"]);
    assert_eq!(out["evaluation"]["loss"], last["eval_loss"]);
    assert_eq!(out["task"], "corridor");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_plugin_tasks_and_configs_are_refused_by_name() {
    for (name, steps, needle) in [
        ("cartpole", 10, "built-in task"),
        ("", 10, "task name"),
        ("My Task", 10, "task name"),
        ("corridor", 0, "eval_steps"),
    ] {
        let e = corridor(name, steps).expect_err("refused");
        assert!(e.to_string().contains(needle), "{name:?}: {e}");
    }
    let task = corridor("corridor", 10).expect("a valid task");
    for (extra, key) in [
        ("[task]\nname = \"custom\"\nsteps = 10\n", "task.steps"),
        (
            "[task]\nname = \"custom\"\nexpert = \"lqr\"\n",
            "task.expert",
        ),
        ("[policy]\nsigma = 0.5\n", "policy.sigma"),
    ] {
        let e =
            RunFile::parse(&format!("{extra}{CONFIG}"), Path::new("c.toml")).expect_err("refused");
        assert!(
            matches!(&e, RunError::Invalid { key: k, .. } if k == key)
                && e.to_string().contains("plug-in task"),
            "{key}: {e}"
        );
    }
    let builtin =
        format!("[task]\nname = \"toy\"\nmdp = \"{ROOT}/examples/toy/three-state.json\"\n{CONFIG}");
    let config = RunFile::parse(&builtin, Path::new("c.toml")).expect("parses");
    let e =
        run_task(&task, &config, &scratch("never"), Some(1), QUIET).expect_err("a built-in [task]");
    assert!(
        matches!(&e, RunError::Invalid { key, .. } if key == "task.name")
            && e.to_string().contains("leaves out [task]"),
        "{e}"
    );
    let bad_theta = CONFIG.replace("[run]\n", "[run]\ntheta0 = [1.0, 2.0, 3.0]\n");
    let config = RunFile::parse(&bad_theta, Path::new("c.toml")).expect("parses");
    let e =
        run_task(&task, &config, &scratch("never"), Some(1), QUIET).expect_err("θ₀ of length 3");
    assert!(e.to_string().contains("run.theta0"), "{e}");
    assert!(
        !scratch("never").exists(),
        "nothing written before the checks"
    );
}

#[test]
fn the_binary_refuses_a_config_without_a_builtin_task() {
    let dir = scratch("binary");
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let config = dir.join("c.toml");
    std::fs::write(&config, CONFIG).expect("written");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ilopt"))
        .args(["run", "--config"])
        .arg(&config)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("task.name") && stderr.contains("plug-in task"),
        "{stderr}"
    );
    assert!(!dir.join("out").exists());
    let _ = std::fs::remove_dir_all(dir);
}
