//! `ilopt run` and `ilopt eval`: every task with every algorithm family on a short budget,
//! byte-identical reruns across thread counts, one named error per bad config (never a panic),
//! evaluation of a saved θ, and paths relative to the config file's directory.

use crate::ROOT;
use crate::support::{Scratch, ilopt_in};
use ilopt_cli::run::RunFile;
use serde_json::Value;
use std::path::Path;

fn run(config: &Path, out: &Path, threads: Option<&str>) -> Value {
    let (c, o) = (config.to_str().unwrap(), out.to_str().unwrap());
    let mut args = vec!["run", "--config", c, "--out", o];
    if let Some(t) = threads {
        args.extend(["--threads", t]);
    }
    let (code, stdout, stderr) = ilopt_in(Path::new(ROOT), &args);
    assert_eq!(code, 0, "{config:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    serde_json::from_str(&stdout).unwrap()
}

const TOY: &str = r#"
[task]
name = "toy"
mdp = "TOY_FILE"
"#;

const CARTPOLE: &str = r#"
[task]
name = "cartpole"
expert = "lqr"
steps = 40
"#;

const OBSTACLE: &str = r#"
[task]
name = "obstacle"
steps = 40
[policy]
sigma = 0.1
"#;

/// One algorithm of each family, small enough for a debug build.
const ALGORITHMS: &[(&str, &str)] = &[
    (
        "sgd",
        r#"algorithm = "sgd"
form = "causal"
step = { kind = "constant", eta = 1e-3 }"#,
    ),
    (
        "is-storm",
        r#"algorithm = "storm"
form = "causal"
correction = "per-decision"
schedule = { kind = "constant", eta = 1e-3, a = 0.5 }"#,
    ),
    (
        "adam",
        r#"algorithm = "adam"
form = "causal"
alpha = 0.005
beta1 = 0.9
beta2 = 0.999
epsilon = 1e-8"#,
    ),
    (
        "rms-prop",
        r#"algorithm = "rms-prop"
form = "causal"
eta = 0.005
beta = 0.9
epsilon = 1e-8"#,
    ),
    (
        "o2nc",
        r#"algorithm = "o2nc"
budget = 1000
delta = 0.1
g = 4
delta0 = 2
form = "causal""#,
    ),
    (
        "bc",
        r#"algorithm = "bc"
trajectories_per_iteration = 1
retrain = "warm-start"
inner = { iterations = 5, batch_size = 16, rule = { rule = "adam", alpha = 0.01, beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8 } }"#,
    ),
    (
        "dagger",
        r#"algorithm = "dagger"
trajectories_per_iteration = 1
aggregate = true
retrain = "warm-start"
beta = { kind = "exponential", p = 0.5 }
inner = { iterations = 5, batch_size = 16, rule = { rule = "adam", alpha = 0.01, beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8 } }"#,
    ),
];

fn config(task: &str, algorithm: &str, budget: u64, every: u64, seeds: &str) -> String {
    let theta0 = if task.contains("\"toy\"") {
        "theta0 = [1, 1, 1, 1, 1, 1]"
    } else {
        ""
    };
    let task = task.replace(
        "TOY_FILE",
        &format!("{ROOT}/examples/toy/three-state.json").replace('\\', "/"),
    );
    format!(
        "{task}\n[algorithm]\n{algorithm}\n\n[run]\nbudget_calls = {budget}\nseeds = {seeds}\n{theta0}\n\n[evaluation]\nevery_calls = {every}\nepisodes = 2\n"
    )
}

/// Every task with one algorithm of each family: the run completes, its files are there, the
/// checkpoints sit at 0, every, …, budget, and the resolved config reloads to itself.
#[test]
fn every_task_runs_with_every_algorithm_family() {
    let s = Scratch::new("families");
    for (tname, task) in [("toy", TOY), ("cartpole", CARTPOLE), ("obstacle", OBSTACLE)] {
        for (aname, alg) in ALGORITHMS {
            let budget = 400;
            let every = 100;
            let cfg = s.write(
                &format!("{tname}-{aname}.toml"),
                &config(task, alg, budget, every, "[7]"),
            );
            let out = s.path().join(format!("out-{tname}-{aname}"));
            let summary = run(&cfg, &out, None);
            let r = &summary["runs"][0];
            let term = r["termination"].as_str().unwrap();
            assert!(
                term == "gradient-budget" || term == "finished",
                "{tname}/{aname}: {term}"
            );
            for f in [
                "config.toml",
                "seed-7.csv",
                "seed-7.json",
                "theta-seed-7.json",
                "summary.json",
                "timings.json",
            ] {
                assert!(out.join(f).is_file(), "{tname}/{aname}: no {f}");
            }
            let seed: Value =
                serde_json::from_str(&std::fs::read_to_string(out.join("seed-7.json")).unwrap())
                    .unwrap();
            let at: Vec<u64> = seed["checkpoints"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c["at_calls"].as_u64().unwrap())
                .collect();
            if term == "gradient-budget" {
                assert_eq!(at, vec![0, 100, 200, 300, 400], "{tname}/{aname}");
            }
            let csv = std::fs::read_to_string(out.join("seed-7.csv")).unwrap();
            assert_eq!(csv.lines().count(), at.len() + 1, "{tname}/{aname}");
            let metric = if tname == "toy" { "objective" } else { "score" };
            let last = seed["checkpoints"].as_array().unwrap().last().unwrap();
            assert!(
                last[metric].as_f64().unwrap().is_finite(),
                "{tname}/{aname}"
            );
            let written = RunFile::load(&out.join("config.toml")).unwrap();
            let original = RunFile::load(&cfg).unwrap();
            assert_eq!(written.file, original.file, "{tname}/{aname}");
        }
    }
}

/// `run.baseline`: every kind of baseline runs with SGD and IS-STORM on every task, the resolved
/// config (with its baseline) reloads to itself, and on the toy MDP the baseline changes the run
/// (the same seed without it ends elsewhere).
#[test]
fn every_baseline_kind_runs_on_every_task() {
    let s = Scratch::new("baselines");
    let kinds = [
        (1, r#"{ kind = "constant", value = "1/2" }"#),
        (
            1,
            r#"{ kind = "estimated", time_indexed = true, decay = 0.99 }"#,
        ),
        (2, r#"{ kind = "leave-one-out" }"#),
        (1, r#"{ kind = "state-dependent", time = true }"#),
    ];
    for (tname, task) in [("toy", TOY), ("cartpole", CARTPOLE), ("obstacle", OBSTACLE)] {
        for (aname, alg) in &ALGORITHMS[..2] {
            let plain = config(task, alg, 400, 200, "[3]");
            let out = s.path().join(format!("out-{tname}-{aname}"));
            let without = run(
                &s.write(&format!("{tname}-{aname}.toml"), &plain),
                &out,
                None,
            );
            for (k, (m, kind)) in kinds.iter().enumerate() {
                let text = plain.replace(
                    "[run]",
                    &format!("[run]\ntrajectories_per_gradient = {m}\nbaseline = {kind}"),
                );
                let cfg = s.write(&format!("{tname}-{aname}-{k}.toml"), &text);
                let out = s.path().join(format!("out-{tname}-{aname}-{k}"));
                let summary = run(&cfg, &out, None);
                let term = summary["runs"][0]["termination"].as_str().unwrap();
                assert_eq!(term, "gradient-budget", "{tname}/{aname}/{kind}");
                let written = RunFile::load(&out.join("config.toml")).unwrap();
                let original = RunFile::load(&cfg).unwrap();
                assert_eq!(written.file, original.file, "{tname}/{aname}/{kind}");
                assert!(original.file.run.baseline.is_some());
                if tname == "toy" && *m == 1 {
                    assert_ne!(
                        summary["final_mean"]["objective"], without["final_mean"]["objective"],
                        "{aname}/{kind}: the baseline changes the run"
                    );
                }
            }
        }
    }
}

/// The summary and `seed-7.json` of a one-seed run of `text`.
fn run_one(s: &Scratch, name: &str, text: &str) -> (Value, Value) {
    let cfg = s.write(&format!("{name}.toml"), text);
    let out = s.path().join(format!("out-{name}"));
    let summary = run(&cfg, &out, None);
    let seed = std::fs::read_to_string(out.join("seed-7.json")).unwrap();
    (summary, serde_json::from_str(&seed).unwrap())
}

/// `run.norm_bound`: SGD with a huge constant step on the toy MDP takes ‖θ‖₂ from √6 to about
/// 1.4·10⁴ in one step and to about 2.4·10⁴ in two, then little further. Under the default bound
/// (1e4) the run is diverged after its first step, its termination stating the final θ's norm and
/// the bound as paper-checks does, its θ₀ checkpoint kept; under a bound above every iterate's
/// norm the same run uses its budget; a bound crossed mid-run keeps the checkpoints before it and
/// evaluates no iterate beyond it; a θ₀ beyond the bound ends the run before any checkpoint.
#[test]
fn a_run_beyond_the_norm_bound_ends_as_diverged() {
    let s = Scratch::new("norm-bound");
    let huge = ALGORITHMS[0].1.replace("eta = 1e-3", "eta = 1e4");
    let text = config(TOY, &huge, 400, 100, "[7]");
    let with_bound = |b: &str| text.replace("[run]", &format!("[run]\nnorm_bound = {b}"));
    let norm = |seed: &Value| {
        let theta = seed["theta"].as_array().unwrap();
        theta
            .iter()
            .map(|x| x.as_f64().unwrap().powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let at_calls = |seed: &Value| -> Vec<u64> {
        seed["checkpoints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["at_calls"].as_u64().unwrap())
            .collect()
    };

    let (summary, seed) = run_one(&s, "default", &text);
    let term = seed["termination"].as_str().unwrap();
    let n = norm(&seed);
    assert!(n > 1e4, "{n}");
    assert_eq!(term, format!("diverged: ‖θ‖ = {n:.3e} > 1e4"));
    assert!(term.ends_with("e4 > 1e4"), "{term}");
    assert_eq!(summary["runs"][0]["termination"], seed["termination"]);
    assert_eq!(summary["norm_bound"].as_f64(), Some(1e4));
    assert_eq!(seed["iterations"].as_u64(), Some(1));
    assert_eq!(at_calls(&seed), vec![0]);

    let (summary, seed) = run_one(&s, "large", &with_bound("1e7"));
    assert_eq!(seed["termination"], "gradient-budget");
    assert_eq!(summary["runs"][0]["termination"], "gradient-budget");
    assert_eq!(summary["norm_bound"].as_f64(), Some(1e7));
    assert_eq!(at_calls(&seed), vec![0, 100, 200, 300, 400]);
    let budget_norm = norm(&seed);
    assert!(budget_norm > 2e4 && budget_norm <= 1e7, "{budget_norm}");

    // Each step costs 3 calls: checkpoints at 0 and 3 are reached; the iterate after the second
    // step (6 calls) is beyond 2e4 and is not evaluated.
    let text3 = with_bound("2e4").replace("every_calls = 100", "every_calls = 3");
    let (_, seed) = run_one(&s, "mid", &text3);
    let n = norm(&seed);
    assert!(n > 2e4, "{n}");
    assert_eq!(
        seed["termination"].as_str().unwrap(),
        format!("diverged: ‖θ‖ = {n:.3e} > 2e4")
    );
    assert_eq!(seed["iterations"].as_u64(), Some(2));
    assert_eq!(at_calls(&seed), vec![0, 3]);
    let csv = std::fs::read_to_string(s.path().join("out-mid/seed-7.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");

    // ‖θ₀‖ = √6 ≈ 2.449: within a bound of 2.5 (the run starts and leaves it at its first
    // step), beyond a bound of 2 (the run ends at θ₀).
    let (_, seed) = run_one(&s, "start-within", &with_bound("2.5"));
    assert_eq!(seed["iterations"].as_u64(), Some(1));
    assert_eq!(at_calls(&seed), vec![0]);
    let (summary, seed) = run_one(&s, "start", &with_bound("2"));
    assert_eq!(seed["termination"], "diverged: ‖θ‖ = 2.449e0 > 2e0");
    assert_eq!(seed["iterations"].as_u64(), Some(0));
    assert!(at_calls(&seed).is_empty());
    assert!(summary["runs"][0]["final"].is_null());
    // Finite entries whose sum of squares overflows: the stated norm is still the true one,
    // √6·10²⁰⁰.
    let (_, seed) = run_one(
        &s,
        "huge",
        &text.replace(
            "theta0 = [1, 1, 1, 1, 1, 1]",
            "theta0 = [1e200, 1e200, 1e200, 1e200, 1e200, 1e200]",
        ),
    );
    assert_eq!(seed["termination"], "diverged: ‖θ‖ = 2.449e200 > 1e4");
}

/// All files but `timings.json` of one directory.
fn data_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap() != "timings.json")
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// A rerun, one thread and two threads give the same bytes in every data file.
#[test]
fn reruns_are_byte_identical_whatever_the_thread_count() {
    let s = Scratch::new("identical");
    for (name, task, alg) in [
        ("toy", TOY, ALGORITHMS[1].1),
        ("cartpole", CARTPOLE, ALGORITHMS[2].1),
        ("obstacle", OBSTACLE, ALGORITHMS[6].1),
    ] {
        let cfg = s.write(
            &format!("{name}.toml"),
            &config(task, alg, 300, 100, "[3, 1, 2]"),
        );
        let a = s.path().join(format!("{name}-a"));
        let b = s.path().join(format!("{name}-b"));
        let c = s.path().join(format!("{name}-c"));
        run(&cfg, &a, Some("1"));
        run(&cfg, &b, Some("2"));
        run(&cfg, &c, Some("2"));
        let (fa, fb, fc) = (data_files(&a), data_files(&b), data_files(&c));
        assert_eq!(
            fa.len(),
            3 * 3 + 3,
            "{name}: {:?}",
            fa.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        assert!(fa == fb, "{name}: --threads 1 and 2 differ");
        assert!(fb == fc, "{name}: a rerun differs");
        assert!(c.join("timings.json").is_file());
    }
}

/// Each bad config fails with exit code 1 and one message naming the key; never a panic, and
/// nothing is written.
#[test]
fn bad_configs_get_one_named_error_each() {
    let s = Scratch::new("bad");
    let good = config(TOY, ALGORITHMS[0].1, 300, 100, "[1]");
    let cases: Vec<(String, &str)> = vec![
        (good.replace("[run]", "[run]\nbogus = 1"), "bogus"),
        (good.replace("[task]", "[tsak]\n[task]"), "tsak"),
        (
            good.replace("form = \"causal\"", "form = \"causal\"\netaa = 1"),
            "algorithm.etaa",
        ),
        (
            good.replace("eta = 1e-3 }", "eta = 1e-3, bogus = 2 }"),
            "algorithm.step.bogus",
        ),
        (
            good.replace("budget_calls = 300", "budget_calls = \"300\""),
            "budget_calls",
        ),
        (
            good.replace("budget_calls = 300", "budget_calls = 0"),
            "run.budget_calls",
        ),
        (
            good.replace("budget_calls = 300", "budget_calls = -5"),
            "budget_calls",
        ),
        (good.replace("seeds = [1]", "seeds = []"), "run.seeds"),
        (good.replace("seeds = [1]", "seeds = [1, 1]"), "run.seeds"),
        (good.replace("seeds = [1]", "seeds = \"1\""), "seeds"),
        (
            good.replace("every_calls = 100", "every_calls = 0"),
            "evaluation.every_calls",
        ),
        (
            good.replace("every_calls = 100", "every_calls = 301"),
            "evaluation.every_calls",
        ),
        (
            good.replace("episodes = 2", "episodes = 0"),
            "evaluation.episodes",
        ),
        (good.replace("eta = 1e-3", "eta = -1e-3"), "eta"),
        (good.replace("eta = 1e-3", "eta = nan"), "eta"),
        (
            good.replace("theta0 = [1, 1, 1, 1, 1, 1]", "theta0 = [1, 1]"),
            "run.theta0",
        ),
        (
            good.replace(
                "theta0 = [1, 1, 1, 1, 1, 1]",
                "theta0 = [1, 1, 1, 1, 1, inf]",
            ),
            "run.theta0",
        ),
        (
            good.replace("theta0 = [1, 1, 1, 1, 1, 1]", "theta0 = \"ones\""),
            "theta0",
        ),
        (
            good.replace("three-state.json", "no-such-file.json"),
            "task.mdp",
        ),
        (
            good.replace("name = \"toy\"", "name = \"toy\"\nsteps = 5"),
            "task.steps",
        ),
        (good.replace("name = \"toy\"", "name = \"maze\""), "maze"),
        (
            good.replace("algorithm = \"sgd\"", "algorithm = \"sgdd\""),
            "sgdd",
        ),
        (
            good.replace("trajectories_per_gradient", "x")
                .replace("[run]", "[run]\ntrajectories_per_gradient = 0"),
            "run.trajectories_per_gradient",
        ),
        (
            config(OBSTACLE, ALGORITHMS[0].1, 300, 100, "[1]")
                .replace("sigma = 0.1", "sigma = -0.1"),
            "policy.sigma",
        ),
        (
            config(OBSTACLE, ALGORITHMS[0].1, 300, 100, "[1]").replace("steps = 40", "steps = 0"),
            "task.steps",
        ),
        (
            config(OBSTACLE, ALGORITHMS[0].1, 300, 100, "[1]")
                .replace("[policy]", "[policy]\nkind = \"softmax\""),
            "policy.kind",
        ),
        (
            config(CARTPOLE, ALGORITHMS[0].1, 300, 100, "[1]").replace(
                "expert = \"lqr\"",
                "expert = \"ppo\"\nexpert_file = \"missing.json\"",
            ),
            "task.expert_file",
        ),
        (
            config(CARTPOLE, ALGORITHMS[0].1, 300, 100, "[1]")
                .replace("steps = 40", "horizon = \"episodic\"\nsteps = 40"),
            "task.steps",
        ),
        (
            config(CARTPOLE, ALGORITHMS[5].1, 300, 100, "[1]")
                .replace("[run]", "[run]\ntrajectories_per_gradient = 4"),
            "run.trajectories_per_gradient",
        ),
        (
            config(CARTPOLE, ALGORITHMS[6].1, 300, 100, "[1]")
                .replace("[run]", "[run]\nbaseline = { kind = \"leave-one-out\" }"),
            "run.baseline",
        ),
        (
            config(CARTPOLE, ALGORITHMS[0].1, 300, 100, "[1]")
                .replace("[run]", "[run]\nbaseline = { kind = \"leave-one-out\" }"),
            "run.baseline",
        ),
        (
            config(CARTPOLE, ALGORITHMS[0].1, 300, 100, "[1]").replace(
                "[run]",
                "[run]\nbaseline = { kind = \"state-dependent\", features = 9 }",
            ),
            "run.baseline",
        ),
        (
            good.replace("[run]", "[run]\nnorm_bound = 0"),
            "run.norm_bound",
        ),
        (
            good.replace("[run]", "[run]\nnorm_bound = -1e4"),
            "run.norm_bound",
        ),
        (
            good.replace("[run]", "[run]\nnorm_bound = nan"),
            "run.norm_bound",
        ),
        (
            good.replace("[run]", "[run]\nnorm_bound = inf"),
            "run.norm_bound",
        ),
        (
            good.replace("[run]", "[run]\nnorm_bound = \"1e4\""),
            "norm_bound",
        ),
        ("not toml [".into(), "TOML parse error"),
        (String::new(), "missing field"),
    ];
    for (i, (text, key)) in cases.iter().enumerate() {
        let cfg = s.write(&format!("bad-{i}.toml"), text);
        let out = s.path().join(format!("out-{i}"));
        let (code, stdout, stderr) = ilopt_in(
            Path::new(ROOT),
            &[
                "run",
                "--config",
                cfg.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        );
        assert_eq!(code, 1, "case {i} ({key}): {stderr}");
        assert!(stdout.is_empty(), "case {i}: {stdout}");
        assert!(!stderr.contains("panicked"), "case {i}: {stderr}");
        assert!(stderr.contains(key), "case {i}: {key} not in {stderr}");
        assert!(
            stderr.contains(&format!("bad-{i}.toml")),
            "case {i}: {stderr}"
        );
        assert!(
            !stderr.contains("NaN") || key == &"eta",
            "case {i}: {stderr}"
        );
        assert!(!out.exists(), "case {i}: wrote {out:?}");
    }
    let (code, _, stderr) = ilopt_in(
        Path::new(ROOT),
        &["run", "--config", "nowhere.toml", "--out", "x"],
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("nowhere.toml"), "{stderr}");
    let (code, _, _) = ilopt_in(Path::new(ROOT), &["run", "--out", "x"]);
    assert_eq!(code, 2);
    let (code, _, _) = ilopt_in(
        Path::new(ROOT),
        &["run", "--config", "a", "--out", "x", "--threads", "0"],
    );
    assert_eq!(code, 2);
}

/// `ilopt eval` on a saved θ: the objective with its standard error and the task's metric; a θ
/// of another task, or of the wrong length, is a clear error.
#[test]
fn eval_evaluates_a_saved_theta() {
    let s = Scratch::new("eval");
    let cfg = s.write(
        "c.toml",
        &config(CARTPOLE, ALGORITHMS[5].1, 300, 300, "[5]"),
    );
    let out = s.path().join("out");
    run(&cfg, &out, None);
    let theta = out.join("theta-seed-5.json");
    let written = out.join("config.toml");
    let args = |c: &Path| {
        vec![
            "eval".to_string(),
            "--config".into(),
            c.to_str().unwrap().into(),
            "--theta".into(),
            theta.to_str().unwrap().into(),
            "--episodes".into(),
            "3".into(),
        ]
    };
    let a: Vec<String> = args(&written);
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let (code, stdout, stderr) = ilopt_in(Path::new(ROOT), &a);
    assert_eq!(code, 0, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["task"], "cartpole");
    assert_eq!(v["dim"], 10);
    assert_eq!(v["objective"]["rollouts"], 3);
    assert!(v["objective"]["mean"].as_f64().unwrap().is_finite());
    assert!(v["objective"]["standard_error"].as_f64().unwrap() >= 0.0);
    assert!(v["evaluation"]["reward"].as_f64().unwrap() >= 1.0);
    // The same θ on the obstacle task: named mismatch.
    let other = s.write(
        "o.toml",
        &config(OBSTACLE, ALGORITHMS[0].1, 300, 100, "[1]"),
    );
    let a: Vec<String> = args(&other);
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let (code, _, stderr) = ilopt_in(Path::new(ROOT), &a);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("theta-seed-5.json") && stderr.contains("obstacle"),
        "{stderr}"
    );
    // A θ of the wrong length.
    let mut t: Value = serde_json::from_str(&std::fs::read_to_string(&theta).unwrap()).unwrap();
    t["theta"].as_array_mut().unwrap().pop();
    std::fs::write(&theta, t.to_string()).unwrap();
    let a: Vec<String> = args(&written);
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let (code, _, stderr) = ilopt_in(Path::new(ROOT), &a);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("9 entries") && stderr.contains("10 parameters"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
}

/// A toy MDP file and a PPO expert file given by relative paths are found next to the config,
/// whatever the working directory; the built-in PPO expert needs no file at all.
#[test]
fn relative_paths_resolve_against_the_config_directory() {
    let s = Scratch::new("relative");
    std::fs::create_dir_all(s.path().join("sub/mdps")).unwrap();
    std::fs::copy(
        Path::new(ROOT).join("examples/toy/three-state.json"),
        s.path().join("sub/mdps/three.json"),
    )
    .unwrap();
    std::fs::copy(
        Path::new(ROOT).join("experts/cartpole-ppo.json"),
        s.path().join("sub/ppo.json"),
    )
    .unwrap();
    let toy = config(TOY, ALGORITHMS[0].1, 200, 100, "[1]").replace(
        &format!("{ROOT}/examples/toy/three-state.json").replace('\\', "/"),
        "mdps/three.json",
    );
    s.write("sub/toy.toml", &toy);
    let ppo = config(CARTPOLE, ALGORITHMS[5].1, 200, 100, "[1]").replace(
        "expert = \"lqr\"",
        "expert = \"ppo\"\nexpert_file = \"ppo.json\"",
    );
    s.write("sub/ppo.toml", &ppo);
    let builtin = config(CARTPOLE, ALGORITHMS[5].1, 200, 100, "[1]").replace("\"lqr\"", "\"ppo\"");
    s.write("sub/builtin.toml", &builtin);
    let elsewhere = s.path().join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    for name in ["toy", "ppo", "builtin"] {
        let (code, _, stderr) = ilopt_in(
            &elsewhere,
            &[
                "run",
                "--config",
                &format!("../sub/{name}.toml"),
                "--out",
                &format!("out-{name}"),
            ],
        );
        assert_eq!(code, 0, "{name}: {stderr}");
        assert!(elsewhere.join(format!("out-{name}/seed-1.csv")).is_file());
    }
    // The file expert and the built-in one are the same expert: the same run.
    let a = std::fs::read(elsewhere.join("out-ppo/seed-1.json")).unwrap();
    let b = std::fs::read(elsewhere.join("out-builtin/seed-1.json")).unwrap();
    assert_eq!(a, b);
    // The resolved config names the MDP by an absolute path, so it works from anywhere too.
    let written = std::fs::read_to_string(elsewhere.join("out-toy/config.toml")).unwrap();
    let resolved = RunFile::load(&elsewhere.join("out-toy/config.toml")).unwrap();
    assert!(resolved.file.task.mdp.unwrap().is_absolute(), "{written}");
}

/// `ilopt run --help` names every key of the config file.
#[test]
fn help_lists_every_key() {
    let (code, stdout, _) = ilopt_in(Path::new(ROOT), &["run", "--help"]);
    assert_eq!(code, 0);
    for key in [
        "[task]",
        "name",
        "expert",
        "expert_file",
        "mdp",
        "horizon",
        "steps",
        "after_end",
        "[policy]",
        "kind",
        "sigma",
        "features",
        "[algorithm]",
        "[run]",
        "budget_calls",
        "seeds",
        "trajectories_per_gradient",
        "baseline",
        "theta0",
        "norm_bound",
        "[evaluation]",
        "every_calls",
        "episodes",
        "docs/run.md",
    ] {
        assert!(stdout.contains(key), "--help lacks {key}");
    }
}

/// The example configs of `examples/run/` load and build (their runs are in docs/run.md and .ci/run).
#[test]
fn the_example_configs_are_valid() {
    let dir = Path::new(ROOT).join("examples/run");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let c = RunFile::load(&p).unwrap_or_else(|e| panic!("{p:?}: {e}"));
            let bench = ilopt_cli::run::task::task_learner(&c).unwrap();
            ilopt_cli::run::driver::check_builtin(&bench, &c)
                .unwrap_or_else(|e| panic!("{p:?}: {e}"));
            n += 1;
        }
    }
    assert!(n >= 4, "{n} example configs");
}
