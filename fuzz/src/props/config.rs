//! The run-config parser's property: arbitrary bytes give a config or a clean error.

use super::toy::check_mdp_invariants;
use ilopt::algo::RunConfig;
use ilopt::scalar::{BigRational, Interval};
use ilopt::toy::{ToyMdp, ToyProblem};

/// Target `config`: arbitrary bytes as a run configuration ([`RunConfig::from_json`]) and as a
/// toy-MDP file: never a panic. An accepted run configuration builds its algorithm (or returns a
/// clear error), converts θ₀, and survives a JSON round trip unchanged.
pub fn check_config(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    if let Ok(m) = ToyMdp::from_json_str(text) {
        check_mdp_invariants(&m);
    }
    let cfg = match RunConfig::from_json(text) {
        Ok(c) => c,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    let _ = cfg.theta0::<f64>();
    let _ = cfg.theta0::<BigRational>();
    let _ = cfg.theta0::<Interval>();
    if let Err(e) = cfg.algorithm.build::<f64, ToyProblem<f64>>() {
        assert!(!e.to_string().is_empty());
    }
    if let Err(e) = cfg
        .algorithm
        .build::<BigRational, ToyProblem<BigRational>>()
    {
        assert!(!e.to_string().is_empty());
    }
    let json = cfg.to_json().expect("an accepted config serialises");
    let back = RunConfig::from_json(&json)
        .unwrap_or_else(|e| panic!("the config's own JSON is rejected: {e}\n{json}"));
    assert_eq!(
        back.to_json().expect("serialises"),
        json,
        "JSON round trip changed the config"
    );
}
