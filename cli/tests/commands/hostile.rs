//! Every subcommand of the `ilopt` binary with bad arguments. Each must fail with exit
//! status 1 (a failure) or 2 (a usage error) — never 101, a panic — print a message on stderr that
//! names the bad argument, print nothing on stdout, and never print `NaN`/`inf` as a result.

use crate::support::ilopt;
use std::io::Write;

const M1: &str = "examples/toy/m1-tied.json";

/// A temporary file with `content`, removed on drop.
struct TempFile(std::path::PathBuf);

impl TempFile {
    fn new(name: &str, content: &[u8]) -> Self {
        let dir = std::env::temp_dir().join(format!("ilopt-cli-hostile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::File::create(&path)
            .unwrap()
            .write_all(content)
            .unwrap();
        TempFile(path)
    }
    fn path(&self) -> &str {
        self.0.to_str().unwrap()
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// A result printed as a number must never be NaN or infinite.
fn no_nan(text: &str, args: &[&str]) {
    for bad in ["NaN", "nan", "inf", "Infinity"] {
        // Error messages may quote the user's own text (`"nan" is not …`); results never.
        assert!(
            !text.contains(&format!(":{bad}"))
                && !text.contains(&format!("[{bad}"))
                && !text.contains(&format!(",{bad}")),
            "{args:?} printed {bad} as a result: {text}"
        );
    }
}

fn expect_failure(args: &[&str], needle: &str) {
    let (code, out, err) = ilopt(args);
    assert!(
        code == 1 || code == 2,
        "{args:?}: exit {code} (1 or 2 expected; a panic exits 101)\n{err}"
    );
    assert!(out.is_empty(), "{args:?} printed on stdout: {out}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(
        err.contains(needle),
        "{args:?}: the message does not name {needle:?}: {err}"
    );
}

#[test]
fn top_level_help_unknown_and_missing_subcommands() {
    let (code, out, _) = ilopt(&["--help"]);
    assert_eq!(code, 0);
    for sub in ["toy", "expert", "replay"] {
        assert!(out.contains(sub), "--help does not list {sub}: {out}");
    }
    for args in [
        &["toy", "--help"][..],
        &["toy", "eval", "--help"],
        &["expert", "--help"],
        &["expert", "vo", "--help"],
        &["replay", "--help"],
        &["replay", "cartpole", "--help"],
        &["--version"],
    ] {
        let (code, out, err) = ilopt(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(!out.is_empty(), "{args:?}");
    }
    expect_failure(&[], "Usage");
    expect_failure(&["frobnicate"], "frobnicate");
    expect_failure(&["toy"], "Usage");
    expect_failure(&["toy", "frobnicate"], "frobnicate");
    expect_failure(&["expert"], "Usage");
    expect_failure(&["expert", "lqr"], "lqr");
    expect_failure(&["replay"], "Usage");
    expect_failure(&["replay", "mountaincar"], "mountaincar");
    expect_failure(&["--frobnicate"], "--frobnicate");
    expect_failure(
        &["toy", "eval", "--mdp", M1, "--theta", "0", "--bogus"],
        "--bogus",
    );
}

#[test]
fn toy_eval_bad_arguments() {
    let not_json = TempFile::new("not-json.json", b"{\"states\": 2,");
    let bad_row = TempFile::new(
        "bad-row.json",
        br#"{"states":1,"actions":2,"horizon":2,"initial":["1/3"],"transition":[[["1"],["1"]]],"expert":[0],"policy":{"kind":"direct"}}"#,
    );
    let huge = TempFile::new(
        "huge.json",
        br#"{"states":99999999999999999999999,"actions":2,"horizon":2,"initial":[],"transition":[],"expert":[],"policy":{"kind":"direct"}}"#,
    );
    let binary = TempFile::new("binary.json", &[0xff, 0xfe, 0x00, 0x7b]);
    let dir = std::env::temp_dir();
    let dir = dir.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (
            &["toy", "eval", "--mdp", M1, "--theta", "x"],
            "--theta entry 0",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", ""],
            "--theta entry 0",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "nan"],
            "--theta entry 0",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "inf"],
            "--theta entry 0",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "1/0"],
            "zero denominator",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "1e99999"],
            "exponent",
        ),
        (&["toy", "eval", "--mdp", M1, "--theta", "1,2"], "θ"),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "0,"],
            "--theta entry 1",
        ),
        (
            &[
                "toy",
                "eval",
                "--mdp",
                "/nonexistent/x.json",
                "--theta",
                "0",
            ],
            "/nonexistent/x.json",
        ),
        (&["toy", "eval", "--mdp", dir, "--theta", "0"], dir),
        (
            &["toy", "eval", "--mdp", not_json.path(), "--theta", "0"],
            "not valid JSON",
        ),
        (
            &["toy", "eval", "--mdp", bad_row.path(), "--theta", "0"],
            "initial",
        ),
        (
            &["toy", "eval", "--mdp", huge.path(), "--theta", "0"],
            "states",
        ),
        (
            &["toy", "eval", "--mdp", binary.path(), "--theta", "0"],
            binary.path(),
        ),
        (
            &[
                "toy",
                "eval",
                "--mdp",
                "examples/toy/m1-direct.json",
                "--theta",
                "3/2",
            ],
            "open simplex",
        ),
        (
            &[
                "toy", "eval", "--mdp", M1, "--theta", "0", "--scalar", "f16",
            ],
            "--scalar",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "0", "--scalar"],
            "--scalar",
        ),
        (&["toy", "eval", "--theta", "0"], "--mdp"),
        (&["toy", "eval", "--mdp", M1], "--theta"),
        (&["toy", "eval", "--mdp"], "--mdp"),
        (
            &[
                "toy", "eval", "--mdp", M1, "--theta", "1e200", "--scalar", "f64",
            ],
            "non-finite",
        ),
    ];
    for (args, needle) in cases {
        expect_failure(args, needle);
    }
}

#[test]
fn toy_eval_results_are_never_nan() {
    for scalar in ["exact", "f64", "interval"] {
        for theta in ["0", "-7/2", "1e-300", "123456789", "1e150"] {
            let args = [
                "toy", "eval", "--mdp", M1, "--theta", theta, "--scalar", scalar,
            ];
            let (code, out, err) = ilopt(&args);
            assert!(code == 0 || code == 1, "{args:?}: exit {code}: {err}");
            assert!(!err.contains("panicked"), "{args:?}: {err}");
            no_nan(&out, &args);
            if code == 1 {
                assert!(
                    err.contains("not finite") || err.contains("non-finite"),
                    "{args:?}: {err}"
                );
            }
        }
    }
}

#[test]
fn replay_cartpole_bad_arguments() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["replay", "cartpole", "--init", "0,0,0", "--actions", "0"],
            "--init",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,0,0,0",
                "--actions",
                "0",
            ],
            "--init",
        ),
        (
            &["replay", "cartpole", "--init", "", "--actions", "0"],
            "--init",
        ),
        (
            &["replay", "cartpole", "--init", "0,x,0,0", "--actions", "0"],
            "x_dot",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,nan,0",
                "--actions",
                "0",
            ],
            "theta",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "inf,0,0,0",
                "--actions",
                "0",
            ],
            "x",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,0,1e999",
                "--actions",
                "0",
            ],
            "theta_dot",
        ),
        (
            &["replay", "cartpole", "--init", "0,0,0,0", "--actions", ""],
            "--actions",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,0,0",
                "--actions",
                "0,2",
            ],
            "--actions",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,0,0",
                "--actions",
                "0,,1",
            ],
            "--actions",
        ),
        (
            &["replay", "cartpole", "--init", "0,0,0,0", "--actions", "-1"],
            "--actions",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,0,1e200",
                "--actions",
                "1,1",
            ],
            "step",
        ),
        (&["replay", "cartpole", "--init", "0,0,0,0"], "--actions"),
        (&["replay", "cartpole", "--actions", "0"], "--init"),
        (&["replay", "cartpole", "--init"], "--init"),
    ];
    for (args, needle) in cases {
        expect_failure(args, needle);
    }
}

#[test]
fn replay_cartpole_extreme_but_finite_states_print_no_nan() {
    for init in [
        "1e300,1e300,1e300,0",
        "-1e-320,0,3.14159,0",
        "0,0,1e300,1e150",
        "0,0,0,1e154",
    ] {
        let args = [
            "replay",
            "cartpole",
            "--init",
            init,
            "--actions",
            "1,0,1,1,0",
        ];
        let (code, out, err) = ilopt(&args);
        assert!(code == 0 || code == 1, "{args:?}: exit {code}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        no_nan(&out, &args);
        if code == 1 {
            assert!(
                err.contains("step") && err.contains("non-finite"),
                "{args:?}: {err}"
            );
        }
    }
}

#[test]
fn expert_vo_bad_arguments_and_cases() {
    let dir = std::env::temp_dir();
    let dir = dir.to_str().unwrap();
    expect_failure(&["expert", "vo"], "--cases");
    expect_failure(&["expert", "vo", "--cases"], "--cases");
    expect_failure(&["expert", "vo", "cases.jsonl"], "cases.jsonl");
    expect_failure(
        &["expert", "vo", "--cases", "/nonexistent/c.jsonl"],
        "/nonexistent/c.jsonl",
    );
    expect_failure(&["expert", "vo", "--cases", dir], dir);
    // Bad cases do not stop the batch: each is an {"error": …} line naming the line and field.
    let cases = TempFile::new(
        "cases.jsonl",
        concat!(
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":0.5}"#,
            "\n",
            r#"{"r":[1e308,1e308],"v_o":[0,0],"v_r":[0,0],"v_des":[1e308,-1e308],"lam":1e308,"R":0.5}"#,
            "\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":-1,"R":0.5}"#,
            "\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":0}"#,
            "\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":"x"}"#,
            "\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":1e999}"#,
            "\n",
            "\u{0}\u{1}garbage\n",
        )
        .as_bytes(),
    );
    let args = ["expert", "vo", "--cases", cases.path()];
    let (code, out, err) = ilopt(&args);
    // Every line is answered; failures make the exit status 1.
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("cases failed"), "{err}");
    no_nan(&out, &args);
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 7, "{out}");
    assert!(lines[0]["J"].is_number());
    let err = |k: usize| lines[k]["error"].as_str().unwrap_or_default().to_owned();
    assert!(
        lines[1]["J"].is_number() || err(1).contains("overflow"),
        "{out}"
    );
    assert!(
        err(2).starts_with("line 3") && err(2).contains('λ'),
        "{}",
        err(2)
    );
    assert!(
        err(3).starts_with("line 4") && err(3).contains('R'),
        "{}",
        err(3)
    );
    assert!(
        err(4).starts_with("line 5") && err(4).contains("malformed"),
        "{}",
        err(4)
    );
    assert!(err(5).starts_with("line 6"), "{}", err(5));
    assert!(
        err(6).starts_with("line 7") && err(6).contains("malformed"),
        "{}",
        err(6)
    );
}
