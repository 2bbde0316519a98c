//! Shared helpers for the integration tests: random toy MDPs (as JSON, so the reader is exercised
//! too) and random parameters, as proptest strategies.
#![allow(dead_code)]

use ilopt::scalar::{BigRational, parse_exact};
use ilopt::toy::{PolicyKind, ToyMdp};
use proptest::prelude::*;
use serde_json::{Value, json};

pub fn q(s: &str) -> BigRational {
    parse_exact(s).unwrap()
}

pub fn qs(s: &[&str]) -> Vec<BigRational> {
    s.iter().map(|x| q(x)).collect()
}

pub fn example(name: &str) -> ToyMdp {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/toy")
        .join(name);
    ToyMdp::load(&path).unwrap()
}

/// A probability vector of length n with small denominators (zeros allowed, at least one > 0).
fn distribution(n: usize) -> impl Strategy<Value = Vec<String>> {
    prop::collection::vec(0u32..4, n).prop_map(|mut w| {
        if w.iter().all(|&x| x == 0) {
            w[0] = 1;
        }
        let total: u32 = w.iter().sum();
        w.iter().map(|x| format!("{x}/{total}")).collect()
    })
}

/// A random toy MDP, generated as a JSON document and read through `ToyMdp::from_json`.
pub fn toy_mdp() -> impl Strategy<Value = ToyMdp> {
    (1usize..=3, 2usize..=3, 2usize..=4, 0u8..3).prop_flat_map(|(s, a, h, kind)| {
        let kind = match (kind, a) {
            (0, _) => "rational-softmax",
            (1, _) => "direct",
            (_, 2) => "tied-softmax",
            _ => "rational-softmax",
        };
        (
            distribution(s),
            prop::collection::vec(prop::collection::vec(distribution(s), a), s),
            prop::collection::vec(0..a, s),
            prop::collection::vec(0..s, s),
            (1u32..8, 1u32..8),
        )
            .prop_map(move |(initial, transition, expert, raw_groups, (cn, cd))| {
                // Relabel groups compactly (first appearance order), as the format requires.
                let mut seen = Vec::new();
                let groups: Vec<usize> = raw_groups
                    .iter()
                    .map(|g| match seen.iter().position(|x| x == g) {
                        Some(i) => i,
                        None => {
                            seen.push(*g);
                            seen.len() - 1
                        }
                    })
                    .collect();
                let mut policy = json!({ "kind": kind, "groups": groups });
                if kind != "direct" {
                    policy["c"] = Value::String(format!("{cn}/{cd}"));
                }
                let doc = json!({
                    "states": s, "actions": a, "horizon": h,
                    "initial": initial, "transition": transition, "expert": expert,
                    "policy": policy,
                });
                ToyMdp::from_json(&doc).expect("generated MDPs are valid")
            })
    })
}

/// A random θ in the policy's domain (the open simplex for `direct`).
pub fn theta_for(mdp: &ToyMdp) -> BoxedStrategy<Vec<BigRational>> {
    let spec = &mdp.policy;
    let (groups, block, actions) = (spec.group_count(), spec.block(), spec.actions());
    match spec.kind {
        PolicyKind::Direct => {
            prop::collection::vec(prop::collection::vec(1i64..6, actions), groups)
                .prop_map(move |ws| {
                    ws.iter()
                        .flat_map(|w| {
                            let total: i64 = w.iter().sum();
                            w[..actions - 1]
                                .iter()
                                .map(move |x| BigRational::new((*x).into(), total.into()))
                                .collect::<Vec<_>>()
                        })
                        .collect()
                })
                .boxed()
        }
        _ => prop::collection::vec((-8i64..=8, 1i64..=4), groups * block)
            .prop_map(|v| {
                v.into_iter()
                    .map(|(n, d)| BigRational::new(n.into(), d.into()))
                    .collect()
            })
            .boxed(),
    }
}

/// An MDP with two parameter points.
pub fn mdp_and_two_thetas() -> impl Strategy<Value = (ToyMdp, Vec<BigRational>, Vec<BigRational>)> {
    toy_mdp().prop_flat_map(|m| {
        let (a, b) = (theta_for(&m), theta_for(&m));
        (Just(m), a, b)
    })
}
