//! Each kind of invalid toy-MDP file gives its own clear error naming the field and the index.

use ilopt::scalar::{BigRational, parse_exact};
use ilopt::toy::{Termination, ToyError, ToyMdp};
use serde_json::{Value, json};

fn q(s: &str) -> BigRational {
    parse_exact(s).unwrap()
}

fn valid() -> Value {
    json!({
        "states": 3, "actions": 2, "horizon": 4,
        "initial": ["1/2", "1/2", "0"],
        "transition": [
            [["1/2", "1/2", "0"], ["0", "1/3", "2/3"]],
            [["1", "0", "0"], ["0", "0", "1"]],
            [["0", "1/2", "1/2"], ["1/4", "1/4", "1/2"]]
        ],
        "expert": [0, 1, 1],
        "policy": { "kind": "rational-softmax", "c": "1/10" }
    })
}

fn err(edit: impl FnOnce(&mut Value)) -> (ToyError, String) {
    let mut v = valid();
    edit(&mut v);
    let e = ToyMdp::from_json_str(&v.to_string()).unwrap_err();
    let msg = e.to_string();
    (e, msg)
}

#[test]
fn the_format_example_is_valid() {
    let m = ToyMdp::from_json(&valid()).unwrap();
    assert_eq!(
        (m.states, m.actions, m.horizon, m.policy.dim()),
        (3, 2, 4, 6)
    );
}

#[test]
fn not_json() {
    let e = ToyMdp::from_json_str("{\"states\": 3,\n oops}").unwrap_err();
    assert!(matches!(e, ToyError::Json { line: 2, .. }), "{e}");
}

#[test]
fn row_not_summing_to_one() {
    let (e, m) = err(|v| v["transition"][1][0] = json!(["1/2", "1/3", "0"]));
    assert!(matches!(e, ToyError::RowSum { .. }), "{m}");
    assert!(m.contains("transition[1][0]") && m.contains("5/6"), "{m}");
    let (e, m) = err(|v| v["initial"] = json!(["1/2", "1/4", "0"]));
    assert!(
        matches!(e, ToyError::RowSum { .. }) && m.contains("initial"),
        "{m}"
    );
}

#[test]
fn negative_probability() {
    let (e, m) = err(|v| v["transition"][2][1] = json!(["-1/4", "3/4", "1/2"]));
    assert!(matches!(e, ToyError::NegativeProbability { .. }), "{m}");
    assert!(m.contains("transition[2][1][0]"), "{m}");
}

#[test]
fn wrong_shape() {
    let (e, m) = err(|v| v["transition"][0] = json!([["1", "0", "0"]]));
    assert!(
        matches!(
            e,
            ToyError::Length {
                expected: 2,
                got: 1,
                ..
            }
        ),
        "{m}"
    );
    assert!(m.contains("transition[0]"), "{m}");
    let (e, m) = err(|v| v["transition"][2][0] = json!(["1/2", "1/2"]));
    assert!(
        m.contains("transition[2][0]") && matches!(e, ToyError::Length { .. }),
        "{m}"
    );
    let (e, m) = err(|v| v["initial"] = json!(["1"]));
    assert!(
        m.contains("initial") && matches!(e, ToyError::Length { .. }),
        "{m}"
    );
    let (e, m) = err(|v| v["expert"] = json!([0, 1]));
    assert!(
        m.contains("expert") && matches!(e, ToyError::Length { .. }),
        "{m}"
    );
    let (e, m) = err(|v| v["transition"] = json!("none"));
    assert!(
        m.contains("transition") && matches!(e, ToyError::Type { .. }),
        "{m}"
    );
}

#[test]
fn expert_action_out_of_range() {
    let (e, m) = err(|v| v["expert"][2] = json!(2));
    assert!(matches!(e, ToyError::ExpertAction { index: 2, .. }), "{m}");
    let (e, _) = err(|v| v["expert"][0] = json!(-1));
    assert!(matches!(e, ToyError::ExpertAction { index: 0, .. }));
}

#[test]
fn non_positive_c() {
    for c in ["0", "-1/2"] {
        let (e, m) = err(|v| v["policy"]["c"] = json!(c));
        assert!(matches!(e, ToyError::NonPositiveC(_)), "{m}");
    }
}

#[test]
fn horizon_below_two_and_other_ranges() {
    let (e, m) = err(|v| v["horizon"] = json!(1));
    assert!(
        matches!(
            e,
            ToyError::Range {
                field: "horizon",
                ..
            }
        ),
        "{m}"
    );
    let (e, _) = err(|v| v["actions"] = json!(1));
    assert!(matches!(
        e,
        ToyError::Range {
            field: "actions",
            ..
        }
    ));
    let (e, _) = err(|v| v["states"] = json!(0));
    assert!(matches!(
        e,
        ToyError::Range {
            field: "states",
            ..
        }
    ));
    let (e, _) = err(|v| v["horizon"] = json!(1u64 << 40));
    assert!(matches!(
        e,
        ToyError::Range {
            field: "horizon",
            ..
        }
    ));
    let (e, _) = err(|v| v["states"] = json!("2.5"));
    assert!(matches!(e, ToyError::Type { .. }));
}

#[test]
fn inexact_numbers() {
    let (e, m) = err(|v| v["initial"][0] = json!(0.5));
    assert!(matches!(e, ToyError::NonIntegerNumber { .. }), "{m}");
    assert!(m.contains("initial[0]"), "{m}");
    let (e, m) = err(|v| v["initial"][1] = json!("half"));
    assert!(
        matches!(e, ToyError::Number { .. }) && m.contains("initial[1]"),
        "{m}"
    );
    let (e, m) = err(|v| v["transition"][0][0][0] = json!("1/0"));
    assert!(
        matches!(e, ToyError::Number { .. }) && m.contains("zero denominator"),
        "{m}"
    );
    // Exact decimals are fine.
    let mut v = valid();
    v["initial"] = json!(["0.5", "0.50", "0"]);
    assert!(ToyMdp::from_json(&v).is_ok());
}

#[test]
fn missing_and_unknown_fields() {
    let (e, _) = err(|v| {
        v.as_object_mut().unwrap().remove("expert");
    });
    assert_eq!(e, ToyError::Missing("expert".into()));
    let (e, _) = err(|v| v["horizn"] = json!(4));
    assert_eq!(e, ToyError::Unknown("horizn".into()));
    let (e, _) = err(|v| v["policy"]["temperature"] = json!(1));
    assert_eq!(e, ToyError::Unknown("policy.temperature".into()));
}

#[test]
fn bad_policies() {
    let (e, _) = err(|v| v["policy"]["kind"] = json!("softmax"));
    assert!(matches!(e, ToyError::PolicyKind(_)));
    let (e, _) = err(|v| {
        v["policy"].as_object_mut().unwrap().remove("c");
    });
    assert_eq!(e, ToyError::Missing("policy.c".into()));
    let (e, m) = err(|v| v["policy"] = json!({"kind": "direct", "c": "1"}));
    assert!(matches!(e, ToyError::Policy { .. }), "{m}");
    let (e, m) = err(|v| {
        v["actions"] = json!(3);
        v["transition"] = json!([
            [["1", "0", "0"], ["1", "0", "0"], ["1", "0", "0"]],
            [["1", "0", "0"], ["1", "0", "0"], ["1", "0", "0"]],
            [["1", "0", "0"], ["1", "0", "0"], ["1", "0", "0"]]
        ]);
        v["policy"] = json!({"kind": "tied-softmax", "c": "1/2"});
    });
    assert!(
        matches!(e, ToyError::Policy { .. }) && m.contains("2 actions"),
        "{m}"
    );
    let (e, m) = err(|v| v["policy"]["groups"] = json!([0, 2, 2]));
    assert!(
        matches!(e, ToyError::Policy { .. }) && m.contains("unused"),
        "{m}"
    );
    let (e, m) = err(|v| v["policy"]["groups"] = json!([0, 5, 1]));
    assert!(
        m.contains("policy.groups[1]") && matches!(e, ToyError::Policy { .. }),
        "{m}"
    );
}

#[test]
fn unreadable_file() {
    let e = ToyMdp::load(std::path::Path::new("/nonexistent/mdp.json")).unwrap_err();
    assert!(matches!(e, ToyError::Io { .. }) && e.to_string().contains("/nonexistent/mdp.json"));
}

/// The format's example with state 2 terminal (it has no initial mass) and the given rule.
fn terminating(rule: Value) -> Value {
    let mut v = valid();
    v["terminal"] = json!([false, false, true]);
    v["on_terminal"] = rule;
    v
}

fn termination_err(rule: Value, edit: impl FnOnce(&mut Value)) -> (ToyError, String) {
    let mut v = terminating(rule);
    edit(&mut v);
    let e = ToyMdp::from_json_str(&v.to_string()).unwrap_err();
    let msg = e.to_string();
    (e, msg)
}

#[test]
fn termination_is_read() {
    let m = ToyMdp::from_json(&terminating(
        json!({"kind": "reset", "law": ["0", "1", "0"]}),
    ))
    .unwrap();
    assert_eq!(
        m.termination,
        Termination::Reset {
            terminal: vec![false, false, true],
            law: vec![q("0"), q("1"), q("0")],
        }
    );
    // Without a law the reset law is the initial law.
    let m = ToyMdp::from_json(&terminating(json!({"kind": "reset"}))).unwrap();
    assert!(matches!(&m.termination, Termination::Reset { law, .. } if *law == m.initial));
    let m = ToyMdp::from_json(&terminating(json!({"kind": "absorb", "loss": "3/2"}))).unwrap();
    assert_eq!(
        m.termination,
        Termination::Absorb {
            loss: vec![None, None, Some(q("3/2"))]
        }
    );
    let mut v = terminating(json!({"kind": "absorb", "loss": [null, "0", 4]}));
    v["terminal"] = json!([false, true, true]);
    let m = ToyMdp::from_json(&v).unwrap();
    assert_eq!(
        m.termination,
        Termination::Absorb {
            loss: vec![None, Some(q("0")), Some(q("4"))]
        }
    );
    assert!(m.termination.is_terminal(1) && !m.termination.is_terminal(0));
    assert_eq!(
        ToyMdp::from_json(&valid()).unwrap().termination,
        Termination::None
    );
}

#[test]
fn terminal_flags_and_on_terminal_need_each_other() {
    let mut v = valid();
    v["terminal"] = json!([false, false, true]);
    let m = ToyMdp::from_json(&v).unwrap_err().to_string();
    assert!(
        m.starts_with("`terminal`: ") && m.contains("need `on_terminal`"),
        "{m}"
    );
    let mut v = valid();
    v["on_terminal"] = json!({"kind": "absorb", "loss": "1"});
    let e = ToyMdp::from_json(&v).unwrap_err();
    let m = e.to_string();
    assert!(matches!(e, ToyError::Termination { .. }), "{m}");
    assert!(
        m.starts_with("`on_terminal`: ") && m.contains("no `terminal` array"),
        "{m}"
    );
}

#[test]
fn bad_terminal_flags() {
    let rule = json!({"kind": "absorb", "loss": "1"});
    let (e, m) = termination_err(rule.clone(), |v| v["terminal"] = json!([false, true]));
    assert!(
        matches!(
            e,
            ToyError::Length {
                expected: 3,
                got: 2,
                ..
            }
        ),
        "{m}"
    );
    assert!(m.contains("`terminal`"), "{m}");
    let (e, m) = termination_err(rule.clone(), |v| v["terminal"][1] = json!(1));
    assert_eq!(
        e,
        ToyError::Type {
            field: "terminal[1]".into(),
            expected: "a boolean"
        },
        "{m}"
    );
    let (e, _) = termination_err(rule, |v| v["terminal"] = json!("all"));
    assert!(matches!(e, ToyError::Type { .. }));
}

#[test]
fn bad_on_terminal() {
    let (e, m) = termination_err(json!({"kind": "restart"}), |_| {});
    assert!(matches!(e, ToyError::Termination { .. }), "{m}");
    assert!(
        m.contains("`on_terminal.kind`") && m.contains("not one of reset, absorb"),
        "{m}"
    );
    let (e, _) = termination_err(json!({"law": ["0", "1", "0"]}), |_| {});
    assert_eq!(e, ToyError::Missing("on_terminal.kind".into()));
    let (e, _) = termination_err(json!({"kind": "reset", "lawn": []}), |_| {});
    assert_eq!(e, ToyError::Unknown("on_terminal.lawn".into()));
    let (e, _) = termination_err(json!("reset"), |_| {});
    assert!(matches!(e, ToyError::Type { .. }));
    let (_, m) = termination_err(json!({"kind": "reset", "loss": "1"}), |_| {});
    assert!(
        m.contains("`on_terminal.loss`") && m.contains("no absorbing loss"),
        "{m}"
    );
    let (_, m) = termination_err(
        json!({"kind": "absorb", "loss": "1", "law": ["1", "0", "0"]}),
        |_| {},
    );
    assert!(
        m.contains("`on_terminal.law`") && m.contains("no reset law"),
        "{m}"
    );
}

#[test]
fn bad_reset_laws() {
    let (e, m) = termination_err(json!({"kind": "reset", "law": ["1/2", "1/4", "0"]}), |_| {});
    assert!(matches!(e, ToyError::RowSum { .. }), "{m}");
    assert!(m.contains("`on_terminal.law` sums to 3/4"), "{m}");
    let (e, m) = termination_err(
        json!({"kind": "reset", "law": ["1", "1/2", "-1/2"]}),
        |_| {},
    );
    assert!(matches!(e, ToyError::NegativeProbability { .. }), "{m}");
    assert!(m.contains("on_terminal.law[2]"), "{m}");
    let (e, m) = termination_err(json!({"kind": "reset", "law": ["1", "0"]}), |_| {});
    assert!(
        matches!(e, ToyError::Length { .. }) && m.contains("on_terminal.law"),
        "{m}"
    );
    let (e, m) = termination_err(json!({"kind": "reset", "law": ["0", "1/2", "1/2"]}), |_| {});
    assert!(matches!(e, ToyError::Termination { .. }), "{m}");
    assert!(
        m.contains("`on_terminal.law[2]`") && m.contains("terminal state 2"),
        "{m}"
    );
    // The chain never starts in a terminal state either.
    let (_, m) = termination_err(json!({"kind": "reset", "law": ["1", "0", "0"]}), |v| {
        v["initial"] = json!(["1/2", "0", "1/2"]);
    });
    assert!(
        m.contains("`initial[2]`") && m.contains("terminal state 2"),
        "{m}"
    );
}

#[test]
fn bad_absorbing_losses() {
    let (e, _) = termination_err(json!({"kind": "absorb"}), |_| {});
    assert_eq!(e, ToyError::Missing("on_terminal.loss".into()));
    let (e, m) = termination_err(json!({"kind": "absorb", "loss": "-1"}), |_| {});
    assert!(matches!(e, ToyError::Termination { .. }), "{m}");
    assert!(
        m.contains("`on_terminal.loss`") && m.contains("negative"),
        "{m}"
    );
    let (e, m) = termination_err(json!({"kind": "absorb", "loss": 0.5}), |_| {});
    assert!(matches!(e, ToyError::NonIntegerNumber { .. }), "{m}");
    let (_, m) = termination_err(
        json!({"kind": "absorb", "loss": [null, null, "-2"]}),
        |_| {},
    );
    assert!(
        m.contains("`on_terminal.loss[2]`") && m.contains("negative"),
        "{m}"
    );
    let (_, m) = termination_err(
        json!({"kind": "absorb", "loss": [null, null, null]}),
        |_| {},
    );
    assert!(
        m.contains("`on_terminal.loss[2]`") && m.contains("terminal state 2 needs"),
        "{m}"
    );
    let (_, m) = termination_err(json!({"kind": "absorb", "loss": ["1", null, "1"]}), |_| {});
    assert!(
        m.contains("`on_terminal.loss[0]`") && m.contains("state 0 is not terminal"),
        "{m}"
    );
    let (e, _) = termination_err(json!({"kind": "absorb", "loss": [null, "1"]}), |_| {});
    assert!(matches!(e, ToyError::Length { .. }));
    let (e, m) = termination_err(json!({"kind": "absorb", "loss": [null, null, "x"]}), |_| {});
    assert!(
        matches!(e, ToyError::Number { .. }) && m.contains("on_terminal.loss[2]"),
        "{m}"
    );
}
