//! Each kind of invalid toy-MDP file gives its own clear error naming the field and the index.

use ilopt::toy::{ToyError, ToyMdp};
use serde_json::{Value, json};

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
