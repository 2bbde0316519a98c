//! `ilopt toy eval`: the output contract, exact values, negative θ in both forms, and clear errors
//! (non-zero exit, a message naming the input, never a panic) for bad input.

use crate::support::ilopt;
use serde_json::{Value, json};

const M1: &str = "examples/toy/m1-tied.json";

#[test]
fn exact_output_matches_the_reference_values() {
    // math.md §1.4 at θ = 0: F = 11/8, F′ = −1/2, E g² = 185/192.
    let (code, out, err) = ilopt(&["toy", "eval", "--mdp", M1, "--theta", "0"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        v,
        json!({"objective": "11/8", "gradient": ["-1/2"], "expected_estimate": ["-1/2"],
               "second_moment": "185/192"})
    );
}

#[test]
fn negative_theta_works_in_both_forms() {
    let a = ilopt(&["toy", "eval", "--mdp", M1, "--theta", "-1/2"]);
    let b = ilopt(&["toy", "eval", "--mdp", M1, "--theta=-1/2"]);
    assert_eq!(a.0, 0, "{}", a.2);
    assert_eq!(a.1, b.1);
    let three = "examples/toy/three-state.json";
    let c = ilopt(&[
        "toy",
        "eval",
        "--mdp",
        three,
        "--theta",
        "-1/2,3,0.25,-7/2,0,1",
    ]);
    let d = ilopt(&[
        "toy",
        "eval",
        "--mdp",
        three,
        "--theta=-1/2,3,0.25,-7/2,0,1",
    ]);
    assert_eq!(c.0, 0, "{}", c.2);
    assert_eq!(c.1, d.1);
}

#[test]
fn f64_and_interval_outputs_agree_with_exact() {
    let (_, out, _) = ilopt(&[
        "toy", "eval", "--mdp", M1, "--theta", "1/3", "--scalar", "f64",
    ]);
    let f: Value = serde_json::from_str(&out).unwrap();
    let (_, out, _) = ilopt(&[
        "toy", "eval", "--mdp", M1, "--theta", "1/3", "--scalar", "interval",
    ]);
    let i: Value = serde_json::from_str(&out).unwrap();
    for key in ["objective", "second_moment"] {
        let x = f[key].as_f64().unwrap();
        let (lo, hi) = (i[key][0].as_f64().unwrap(), i[key][1].as_f64().unwrap());
        assert!(lo <= x && x <= hi, "{key}: {x} ∉ [{lo}, {hi}]");
    }
    let x = f["gradient"][0].as_f64().unwrap();
    let (lo, hi) = (
        i["gradient"][0][0].as_f64().unwrap(),
        i["gradient"][0][1].as_f64().unwrap(),
    );
    assert!(lo <= x && x <= hi);
}

#[test]
fn bad_input_is_a_clear_error() {
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
            "not an exact number",
        ),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "1/0"],
            "zero denominator",
        ),
        (&["toy", "eval", "--mdp", M1, "--theta", "1,2"], "needs 1"),
        (
            &["toy", "eval", "--mdp", M1, "--theta", "1,"],
            "--theta entry 1",
        ),
        (
            &["toy", "eval", "--mdp", "/nonexistent.json", "--theta", "0"],
            "/nonexistent.json",
        ),
        (
            &["toy", "eval", "--mdp", "Cargo.toml", "--theta", "0"],
            "not valid JSON",
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
            "invalid value",
        ),
        (&["toy", "eval", "--theta", "0"], "--mdp"),
        (&["toy", "eval", "--mdp", M1], "--theta"),
        (&["toy"], "Usage"),
        (&["frobnicate"], "unrecognized subcommand"),
    ];
    for (args, needle) in cases {
        let (code, out, err) = ilopt(args);
        assert_ne!(code, 0, "{args:?} succeeded");
        assert!(
            code == 1 || code == 2,
            "{args:?}: exit {code} (a panic exits 101)"
        );
        assert!(out.is_empty(), "{args:?} printed {out}");
        assert!(err.contains(needle), "{args:?}: {err:?} lacks {needle:?}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn overflow_in_f64_is_an_error_not_nan() {
    // θ = 1e200: θ² overflows in f64 (the exact value is fine).
    let (code, _, err) = ilopt(&[
        "toy", "eval", "--mdp", M1, "--theta", "1e200", "--scalar", "f64",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("not finite") || err.contains("non-finite"),
        "{err}"
    );
    let (code, out, _) = ilopt(&["toy", "eval", "--mdp", M1, "--theta", "1e200"]);
    assert_eq!(code, 0);
    assert!(out.contains("objective"));
}

/// The termination examples (math.md §8) at θ = 1/3, against values derived by hand from their
/// descriptions: reset F = θ + 2θ², F′ = 1 + 4θ; absorb F = −θ³/2 + 7θ²/2 + 3θ/4,
/// F′ = −3θ²/2 + 7θ + 3/4; E‖g‖² summed over the four prefixes of each file by hand.
#[test]
fn terminating_examples_evaluate_exactly() {
    for (file, want) in [
        (
            "examples/toy/terminal-reset.json",
            json!({"objective": "5/9", "gradient": ["7/3"], "expected_estimate": ["7/3"],
                   "second_moment": "52/9"}),
        ),
        (
            "examples/toy/terminal-absorb.json",
            json!({"objective": "67/108", "gradient": ["35/12"], "expected_estimate": ["35/12"],
                   "second_moment": "253/24"}),
        ),
    ] {
        let (code, out, err) = ilopt(&["toy", "eval", "--mdp", file, "--theta", "1/3"]);
        assert_eq!(code, 0, "{file}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v, want, "{file}");
        let (code, out, err) = ilopt(&[
            "toy", "eval", "--mdp", file, "--theta", "1/3", "--scalar", "interval",
        ]);
        assert_eq!(code, 0, "{file}: {err}");
        let i: Value = serde_json::from_str(&out).unwrap();
        let exact = |s: &str| {
            let (n, d) = s.split_once('/').unwrap();
            n.parse::<f64>().unwrap() / d.parse::<f64>().unwrap()
        };
        let (lo, hi) = (
            i["objective"][0].as_f64().unwrap(),
            i["objective"][1].as_f64().unwrap(),
        );
        let x = exact(want["objective"].as_str().unwrap());
        assert!(lo <= x && x <= hi, "{file}: {x} ∉ [{lo}, {hi}]");
    }
}

#[test]
fn terminal_flags_without_a_rule_are_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("ilopt-cli-toy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(
        std::path::Path::new(crate::ROOT).join("examples/toy/terminal-absorb.json"),
    )
    .unwrap();
    let mut doc: Value = serde_json::from_str(&text).unwrap();
    doc.as_object_mut().unwrap().remove("on_terminal");
    let path = dir.join("no-rule.json");
    std::fs::write(&path, doc.to_string()).unwrap();
    let (code, out, err) = ilopt(&[
        "toy",
        "eval",
        "--mdp",
        path.to_str().unwrap(),
        "--theta",
        "1/3",
    ]);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    assert!(
        err.contains("`terminal`: terminal states need `on_terminal`"),
        "{err}"
    );
}

/// An infeasible enumeration is refused naming the size and the limit (that it is refused before
/// any prefix is visited is shown in the exact engine's unit tests, not by a timing).
#[test]
fn an_infeasible_horizon_is_refused_at_once_naming_size_and_limit() {
    let text = std::fs::read_to_string(std::path::Path::new(crate::ROOT).join(M1)).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["horizon"] = json!(20);
    let path = std::env::temp_dir().join(format!("ilopt-horizon-20-{}.json", std::process::id()));
    std::fs::write(&path, v.to_string()).unwrap();
    let (code, out, err) = ilopt(&[
        "toy",
        "eval",
        "--mdp",
        path.to_str().unwrap(),
        "--theta",
        "0",
    ]);
    std::fs::remove_file(&path).ok();
    assert_eq!(code, 1, "{out}");
    // M1: two initial states, and from each state action 0 branches to 2 states and action 1 to
    // one, so T = 20 has 2 · 3¹⁸ = 774,840,978 prefixes.
    assert!(
        err.contains("7.748e8 trajectory prefixes") && err.contains("limit of 20000000"),
        "{err}"
    );
    // Exact inputs are bounded too.
    let (code, _, err) = ilopt(&["toy", "eval", "--mdp", M1, "--theta", "1e4000"]);
    assert_eq!(code, 1);
    assert!(err.contains("exponent beyond ±1000"), "{err}");
}

#[test]
fn baseline_flag_prints_the_baselined_moments() {
    // M1 at θ = 0 (math.md §1.4 prefix table): ψ(1) = 1, ψ(0) = −1/3, E[gψ] = 5/24, E ψ² = 1/3, so
    // with b = 1: E g_b² = 185/192 − 2·5/24 + 1/3 = 169/192, and E g_b = F′(0) = −1/2.
    let (code, out, err) = ilopt(&[
        "toy",
        "eval",
        "--mdp",
        M1,
        "--theta",
        "0",
        "--baseline",
        "1",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["expected_estimate"], json!(["-1/2"]));
    assert_eq!(v["gradient"], json!(["-1/2"]));
    assert_eq!(v["second_moment"], json!("169/192"));
    // b* = (5/24)/(1/3) = 5/8; E g_b*² = 185/192 − (5/24)²·3 = 5/6; reduction 185/160 = 37/32.
    let (code, out, err) = ilopt(&[
        "toy",
        "eval",
        "--mdp",
        M1,
        "--theta",
        "0",
        "--optimal-baseline",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let o = &v["optimal_baseline"];
    assert_eq!(o["constant"], json!("5/8"));
    assert_eq!(o["time_indexed"], json!(["5/8"]));
    assert_eq!(o["second_moment_constant"], json!("5/6"));
    assert_eq!(o["reduction_constant"], json!("37/32"));
    assert_eq!(
        v["second_moment"],
        json!("185/192"),
        "no --baseline: the plain moment"
    );
}

#[test]
fn bad_baselines_are_clear_errors() {
    for (list, needle) in [
        ("1,2", "--baseline has 2 numbers"),
        ("1/0", "--baseline entry 0"),
        ("x", "--baseline entry 0"),
        ("1,,2", "--baseline entry 1"),
    ] {
        let (code, out, err) = ilopt(&[
            "toy",
            "eval",
            "--mdp",
            M1,
            "--theta",
            "0",
            &format!("--baseline={list}"),
        ]);
        assert_ne!(code, 0, "{list}: {out}");
        assert!(err.contains(needle), "{list}: {err}");
        assert!(!err.contains("panicked"), "{list}: {err}");
    }
}
