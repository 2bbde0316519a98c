//! Hostile input at small scale: the fuzz targets' properties (`fuzz/src/props/`, the
//! same code) as proptest suites that run in `cargo test`. Seeded (`RngSeed::Fixed`), so every
//! run checks the same cases; failures found by the fuzzers are pinned in `tests/inputs/fuzz_regressions.rs`.

use crate::props;

use crate::props::{CartpoleInput, Frac, MdpSpec, OracleInput, TrajSpec, VoInput};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x1107_7ea7),
        failure_persistence: None,
        ..Config::default()
    }
}

fn frac() -> impl Strategy<Value = Frac> {
    prop_oneof![
        4 => (-8i16..=8, 1u8..=8).prop_map(|(num, den)| Frac { num, den }),
        1 => (any::<i16>(), any::<u8>()).prop_map(|(num, den)| Frac { num, den }),
    ]
}

fn mdp_spec() -> impl Strategy<Value = MdpSpec> {
    (
        (
            prop_oneof![9 => 1u8..=3, 1 => Just(0u8)],
            prop_oneof![9 => 2u8..=3, 1 => Just(1u8)],
            prop_oneof![9 => 2u8..=4, 1 => Just(1u8)],
        ),
        prop::collection::vec(frac(), 0..12),
        prop::bool::weighted(0.9),
        prop::collection::vec(prop_oneof![15 => 0u8..=1, 1 => 0u8..=3], 0..3),
        prop_oneof![9 => 0u8..=2, 1 => Just(3u8)],
        prop_oneof![
            7 => (1i16..=8, 1u8..=8).prop_map(|(num, den)| Frac { num, den }),
            1 => frac(),
        ],
        prop::option::weighted(0.25, prop::collection::vec(0u8..=3, 0..3)),
    )
        .prop_map(
            |((states, actions, horizon), probs, normalize, expert, kind, c, groups)| MdpSpec {
                states,
                actions,
                horizon,
                probs,
                normalize,
                expert,
                kind,
                c,
                groups,
            },
        )
}

fn traj_spec() -> impl Strategy<Value = TrajSpec> {
    let v = || prop::collection::vec(prop_oneof![8 => 0u8..=3, 1 => any::<u8>()], 0..5);
    (v(), v(), v(), prop::bool::weighted(0.9)).prop_map(|(states, actions, labels, conform)| {
        TrajSpec {
            states,
            actions,
            labels,
            conform,
        }
    })
}

fn oracle_input() -> impl Strategy<Value = OracleInput> {
    (
        mdp_spec(),
        prop::collection::vec(frac(), 0..9),
        prop::collection::vec(frac(), 0..9),
        prop::bool::weighted(0.9),
        traj_spec(),
        any::<u64>(),
        prop_oneof![3 => (0u8..=4).prop_map(|k| f64::from(k) / 4.0), 1 => any::<f64>()],
    )
        .prop_map(
            |(mdp, theta, theta_new, fit_theta, traj, seed, expert_weight)| OracleInput {
                mdp,
                theta,
                theta_new,
                fit_theta,
                traj,
                seed,
                expert_weight,
            },
        )
}

/// Floats as the fuzzers draw them: small fractions, special values, or any bit pattern.
fn hostile_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        5 => (any::<i16>(), 1u8..=16).prop_map(|(n, d)| f64::from(n) / f64::from(d)),
        1 => prop::sample::select(vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            1e150,
            1e-300,
            f64::EPSILON,
        ]),
        2 => any::<f64>(),
    ]
}

fn vo_input() -> impl Strategy<Value = VoInput> {
    prop::array::uniform12(hostile_f64()).prop_map(|v| VoInput {
        r: [v[0], v[1]],
        v_o: [v[2], v[3]],
        v_r: [v[4], v[5]],
        v_des: [v[6], v[7]],
        lam: v[8],
        big_r: v[9],
        probes: [v[10], v[11]],
    })
}

fn cartpole_input() -> impl Strategy<Value = CartpoleInput> {
    (
        prop::array::uniform4(hostile_f64()),
        prop::collection::vec(prop_oneof![30 => 0u8..=1, 1 => any::<u8>()], 0..64),
        prop_oneof!["[-0-9.,eE ]{0,24}", ".{0,24}", "(0|1)(,(0|1)){0,8}",],
    )
        .prop_map(|(init, actions, text)| CartpoleInput {
            init,
            actions,
            text,
        })
}

/// The example files with a byte range replaced: mostly still JSON, often invalid in one field.
fn mutated_example() -> impl Strategy<Value = Vec<u8>> {
    let files: Vec<Vec<u8>> = ["m1-direct", "m1-softmax", "m1-tied", "three-state"]
        .iter()
        .map(|f| {
            std::fs::read(format!(
                "{}/examples/toy/{f}.json",
                env!("CARGO_MANIFEST_DIR")
            ))
            .unwrap()
        })
        .collect();
    (
        prop::sample::select(files),
        any::<prop::sample::Index>(),
        0usize..6,
        prop_oneof![
            prop::collection::vec(any::<u8>(), 0..6),
            prop::sample::select(vec![
                b"\"-1/2\"".to_vec(),
                b"\"1/0\"".to_vec(),
                b"1e999".to_vec(),
                b"\"1e99999\"".to_vec(),
                b"0.5".to_vec(),
                b"null".to_vec(),
                b"[]".to_vec(),
                b"99999999999999999999".to_vec(),
                b"-1".to_vec(),
            ]),
        ],
    )
        .prop_map(|(mut file, at, len, with)| {
            let start = at.index(file.len());
            let end = (start + len).min(file.len());
            file.splice(start..end, with);
            file
        })
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn toy_parser_survives_mutated_examples(bytes in mutated_example()) {
        props::check_toy_parser(&bytes);
    }

    #[test]
    fn toy_parser_survives_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..64)) {
        props::check_toy_parser(&bytes);
    }

    #[test]
    fn config_survives_hostile_json(bytes in mutated_example()) {
        props::check_config(&bytes);
    }

    #[test]
    fn vo_expert_is_feasible_optimal_or_a_clear_error(input in vo_input()) {
        props::check_vo(&input);
    }

    #[test]
    fn cartpole_replay_flags_match_the_state(input in cartpole_input()) {
        props::check_cartpole(&input);
    }
}

proptest! {
    #![proptest_config(config(128))]

    #[test]
    fn oracle_never_panics_and_is_finite(input in oracle_input()) {
        props::check_oracle(&input);
    }

    #[test]
    fn oracle_f64_interval_rational_agree(input in oracle_input()) {
        props::check_differential(&input);
    }
}

/// Run configurations: every committed fuzz seed (the kit's own configs) with a byte range
/// replaced.
fn mutated_config() -> impl Strategy<Value = Vec<u8>> {
    let dir = format!("{}/fuzz/corpus/config", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<Vec<u8>> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            p.file_name()?
                .to_str()?
                .starts_with("run-")
                .then(|| std::fs::read(p).ok())?
        })
        .collect();
    files.sort();
    assert!(!files.is_empty(), "fuzz/corpus/config has no run-* seeds");
    (
        prop::sample::select(files),
        any::<prop::sample::Index>(),
        0usize..8,
        prop_oneof![
            prop::collection::vec(any::<u8>(), 0..6),
            prop::sample::select(vec![
                b"\"NaN\"".to_vec(),
                b"\"inf\"".to_vec(),
                b"\"-1\"".to_vec(),
                b"\"1/0\"".to_vec(),
                b"1e308".to_vec(),
                b"\"1e4096\"".to_vec(),
                b"0".to_vec(),
                b"null".to_vec(),
                b"18446744073709551615".to_vec(),
            ]),
        ],
    )
        .prop_map(|(mut file, at, len, with)| {
            let start = at.index(file.len());
            let end = (start + len).min(file.len());
            file.splice(start..end, with);
            file
        })
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn run_configs_survive_mutation(bytes in mutated_config()) {
        props::check_config(&bytes);
    }
}

/// The oracle suites are not vacuous: most generated inputs parse, and most of those reach the
/// oracle's arithmetic (an `Ok` estimate) rather than an early rejection.
#[test]
fn oracle_inputs_mostly_reach_the_arithmetic() {
    use proptest::strategy::ValueTree;
    let mut runner = proptest::test_runner::TestRunner::new(config(200));
    let strategy = oracle_input();
    let (mut parsed, mut ok) = (0, 0);
    for _ in 0..200 {
        let input = strategy.new_tree(&mut runner).unwrap().current();
        let Some(mdp) = input.parse() else { continue };
        parsed += 1;
        let (th, th_new) = input.thetas(&mdp);
        let traj = input.traj.build(mdp.states, mdp.actions, mdp.horizon);
        let out = props::run_oracle::<ilopt::scalar::BigRational>(
            &mdp,
            &th,
            &th_new,
            &traj,
            input.seed,
            input.expert_weight,
        );
        ok += usize::from(out.estimates[0].is_ok());
    }
    assert!(
        parsed >= 80 && ok >= 40,
        "parsed {parsed}/200, Ok estimates {ok}"
    );
}
