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
    toy_mdp_document().prop_map(|doc| ToyMdp::from_json(&doc).expect("generated MDPs are valid"))
}

/// A random toy-MDP document (see [`toy_mdp`]).
pub fn toy_mdp_document() -> impl Strategy<Value = Value> {
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
                json!({
                    "states": s, "actions": a, "horizon": h,
                    "initial": initial, "transition": transition, "expert": expert,
                    "policy": policy,
                })
            })
    })
}

/// Exact fraction strings from integer weights, with the mass of `excluded` entries moved away
/// (if nothing is left, all mass goes to the first entry not excluded).
fn weights_to_distribution(weights: &[u32], excluded: &[bool]) -> Vec<String> {
    let mut w: Vec<u32> = weights
        .iter()
        .zip(excluded)
        .map(|(&x, &e)| if e { 0 } else { x })
        .collect();
    if w.iter().all(|&x| x == 0) {
        let first = excluded.iter().position(|e| !e).expect("a state is kept");
        w[first] = 1;
    }
    let total: u32 = w.iter().sum();
    w.iter().map(|x| format!("{x}/{total}")).collect()
}

/// A random toy MDP with terminal states and either reset or absorbing semantics (math.md §8),
/// generated as JSON from [`toy_mdp_document`] and read through `ToyMdp::from_json`.
///
/// Reset: the initial law and the reset law (given, or defaulted to the initial law) put no mass on
/// terminal states, and at least one state is not terminal. Absorb: the initial law may start in a
/// terminal state; losses are small non-negative fractions, given per state or as one number.
pub fn terminating_toy_mdp() -> impl Strategy<Value = ToyMdp> {
    toy_mdp_document().prop_flat_map(|doc| {
        let s = doc["states"].as_u64().unwrap() as usize;
        (
            Just(doc),
            prop::collection::vec(any::<bool>(), s),
            0u8..4,
            prop::collection::vec(0u32..4, s),
            prop::collection::vec(0u32..4, s),
            prop::collection::vec((0i64..5, 1i64..4), s),
        )
            .prop_map(move |(mut doc, mut terminal, mode, w_init, w_law, losses)| {
                let reset = mode < 2;
                if terminal.iter().all(|&t| !t) {
                    terminal[s - 1] = true;
                }
                if reset {
                    if terminal.iter().all(|&t| t) {
                        terminal[0] = false;
                    }
                    doc["initial"] = json!(weights_to_distribution(&w_init, &terminal));
                    doc["on_terminal"] = if mode == 0 {
                        json!({"kind": "reset", "law": weights_to_distribution(&w_law, &terminal)})
                    } else {
                        json!({"kind": "reset"})
                    };
                } else if mode == 2 {
                    let per_state: Vec<Value> = terminal
                        .iter()
                        .zip(&losses)
                        .map(|(&t, (n, d))| if t { json!(format!("{n}/{d}")) } else { Value::Null })
                        .collect();
                    doc["on_terminal"] = json!({"kind": "absorb", "loss": per_state});
                } else {
                    let (n, d) = losses[0];
                    doc["on_terminal"] = json!({"kind": "absorb", "loss": format!("{n}/{d}")});
                }
                doc["terminal"] = json!(terminal);
                ToyMdp::from_json(&doc).expect("generated terminating MDPs are valid")
            })
    })
}

/// A terminating MDP (see [`terminating_toy_mdp`]) with two parameter points.
pub fn terminating_mdp_and_two_thetas()
-> impl Strategy<Value = (ToyMdp, Vec<BigRational>, Vec<BigRational>)> {
    terminating_toy_mdp().prop_flat_map(|m| {
        let (a, b) = (theta_for(&m), theta_for(&m));
        (Just(m), a, b)
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

/// The obstacle task with the basic features' linear-Gaussian learner.
pub type ObstacleProblem = ilopt::task::TaskProblem<
    ilopt::task::obstacle::ObstacleTask<Vec<f64>>,
    ilopt::policy::LinearGaussian<f64>,
>;

/// The obstacle task under the thesis's fixed horizon (T = 200, absorbing ends) with the basic
/// features' linear-Gaussian learner (σ = 0.3), and a θ that heads right and up at unit gain.
pub fn absorbing_obstacle_problem() -> (ObstacleProblem, nalgebra::DVector<f64>) {
    use ilopt::task::obstacle::{self, ObstacleTask};
    let problem = ilopt::task::TaskProblem::fixed(
        ObstacleTask::thesis().unwrap(),
        ilopt::policy::LinearGaussian::new(2, obstacle::FEATURES, 0.3).unwrap(),
        200,
        ilopt::task::AfterEnd::Absorb,
    )
    .unwrap();
    let mut w = vec![0.0; 2 * obstacle::FEATURES];
    w[0] = 1.0;
    w[obstacle::FEATURES + 1] = 1.0;
    (problem, nalgebra::DVector::from_vec(w))
}
