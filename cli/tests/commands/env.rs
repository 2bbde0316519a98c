//! `ilopt replay cartpole` and `ilopt expert vo` through the binary: the output contracts, both
//! forms of negative numbers, and clear errors (exit status 1 or 2, a message, never a panic).

use crate::support::ilopt;
use approx::abs_diff_eq;
use serde_json::Value;
use std::io::Write;
use std::process::Command;

#[test]
fn replay_prints_round_trip_states_and_flags() {
    let a = ilopt(&[
        "replay",
        "cartpole",
        "--init",
        "-0.01,0.02,-0.03,0.04",
        "--actions",
        "0,1,1,0",
    ]);
    let b = ilopt(&[
        "replay",
        "cartpole",
        "--init=-0.01,0.02,-0.03,0.04",
        "--actions=0,1,1,0",
    ]);
    assert_eq!(a.0, 0, "{}", a.2);
    assert_eq!(a.1, b.1);
    let v: Value = serde_json::from_str(&a.1).unwrap();
    let states = v["states"].as_array().unwrap();
    let flags = v["terminated"].as_array().unwrap();
    assert_eq!((states.len(), flags.len()), (4, 4));
    // Independent check of the first Euler step (Gymnasium's equations, action 0 = −10 N).
    let (x, xd, th, thd) = (-0.01f64, 0.02f64, -0.03f64, 0.04f64);
    let (g, mc, mp, l, f, tau) = (9.8, 1.0, 0.1, 0.5, -10.0, 0.02);
    let (tm, pml) = (mp + mc, mp * l);
    let (c, s) = (th.cos(), th.sin());
    let temp = (f + pml * thd.powi(2) * s) / tm;
    let thacc = (g * s - c * temp) / (l * (4.0 / 3.0 - mp * c.powi(2) / tm));
    let xacc = temp - pml * thacc * c / tm;
    let want = [
        x + tau * xd,
        xd + tau * xacc,
        th + tau * thd,
        thd + tau * thacc,
    ];
    let got: Vec<f64> = states[0]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    for (g, w) in got.iter().zip(want) {
        assert!(
            abs_diff_eq!(*g, w, epsilon = 1e-15 * w.abs().max(1e-3)),
            "{got:?} vs {want:?}"
        );
    }
}

#[test]
fn replay_bad_input() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["replay", "cartpole", "--init", "0,0,0", "--actions", "0"],
            "--init",
        ),
        (
            &["replay", "cartpole", "--init", "0,0,0,x", "--actions", "0"],
            "--init",
        ),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "0,0,0,nan",
                "--actions",
                "0",
            ],
            "--init",
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
            &["replay", "cartpole", "--init", "0,0,0,0", "--actions", ""],
            "--actions",
        ),
        (&["replay", "cartpole", "--init", "0,0,0,0"], "--actions"),
        (
            &[
                "replay",
                "cartpole",
                "--init",
                "1e308,1e308,0,1e308",
                "--actions",
                "1,1,1",
            ],
            "step",
        ),
        (&["replay", "walker"], "unrecognized subcommand"),
    ];
    for (args, needle) in cases {
        let (code, out, err) = ilopt(args);
        assert!(
            code == 1 || code == 2,
            "{args:?}: exit {code}, stderr {err}"
        );
        assert!(out.is_empty(), "{args:?} printed {out}");
        assert!(err.contains(needle), "{args:?}: {err:?} lacks {needle:?}");
        assert!(
            !err.contains("panicked") && !err.to_lowercase().contains("nan,"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn expert_vo_lines_in_order_with_errors_inline() {
    let dir = std::env::temp_dir().join(format!("ilopt-vo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cases.jsonl");
    let mut f = std::fs::File::create(&path).unwrap();
    // 1: obstacle dead ahead, must deflect; 2: inside the obstacle; 3: malformed; 4: feasible as is.
    writeln!(
        f,
        r#"{{"r":[1,0],"v_o":[0,0],"v_r":[0.1,0],"v_des":[0.1,0],"lam":0.5,"R":0.45}}"#
    )
    .unwrap();
    writeln!(
        f,
        r#"{{"r":[0.1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[0.1,0],"lam":0.5,"R":0.45}}"#
    )
    .unwrap();
    writeln!(f, "not json").unwrap();
    writeln!(
        f,
        r#"{{"r":[0,1],"v_o":[0,0],"v_r":[0,0],"v_des":[0.1,0],"lam":1,"R":0.45}}"#
    )
    .unwrap();
    drop(f);
    let (code, out, err) = ilopt(&["expert", "vo", "--cases", path.to_str().unwrap()]);
    // Two of four cases fail: every line is written, and the status says so.
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("2 of 4 cases failed"), "{err}");
    let lines: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 4);
    // 1: the agent must turn: u has a non-zero y component, and J > 0.
    assert!(
        lines[0]["u"][1].as_f64().unwrap().abs() > 1e-3,
        "{}",
        lines[0]
    );
    assert!(lines[0]["J"].as_f64().unwrap() > 0.0);
    assert!(lines[1]["error"].as_str().unwrap().starts_with("line 2"));
    assert!(lines[2]["error"].as_str().unwrap().starts_with("line 3"));
    // 4: obstacle beside the path, unconstrained optimum u₀ = (v_des − v_r)/(1+λ) = (0.05, 0).
    assert_eq!(lines[3]["u"][0].as_f64().unwrap(), 0.05);
    assert_eq!(lines[3]["u"][1].as_f64().unwrap(), 0.0);
    // The same cases from standard input; a batch without failures exits 0.
    let from_stdin = |input: &str| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_ilopt"))
            .args(["expert", "vo", "--cases", "-"])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        child
            .stdin
            .take()
            .unwrap()
            .write_all(input.as_bytes())
            .unwrap();
        let o = child.wait_with_output().unwrap();
        (o.status.code(), String::from_utf8(o.stdout).unwrap())
    };
    let (code, piped) = from_stdin(&std::fs::read_to_string(&path).unwrap());
    assert_eq!((code, piped.as_str()), (Some(1), out.as_str()));
    let good = r#"{"r":[0,1],"v_o":[0,0],"v_r":[0,0],"v_des":[0.1,0],"lam":1,"R":0.45}"#;
    let (code, piped) = from_stdin(good);
    assert_eq!(code, Some(0), "{piped}");
    let (code, _, err) = ilopt(&["expert", "vo", "--cases", "/nonexistent/cases.jsonl"]);
    assert_eq!(code, 1);
    assert!(err.contains("/nonexistent/cases.jsonl"), "{err}");
    let (code, _, err) = ilopt(&["expert", "vo"]);
    assert_eq!(code, 2);
    assert!(err.contains("--cases"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
