//! CartPole-v1 against Gymnasium itself, and the environment's contract.
//!
//! The reference data `tests/data/cartpole_reference.json` is written by
//! `scripts/cartpole_reference.py` with Gymnasium's own `CartPoleEnv`; every float is stored as the
//! string of its Python `repr` and parsed here with Rust's correctly rounded parser, so the
//! comparison is bit-for-bit.

use ilopt::env::cartpole::{
    CartPole, CartPoleDynamics, MAX_EPISODE_STEPS, cartpole_step, gymnasium_observation,
    sample_reset_state, theta_threshold_rational, x_threshold_rational,
};
use ilopt::env::{Env, EnvError};
use ilopt::expert::lqr::LqrExpert;
use ilopt::problem::KitRng;
use ilopt::scalar::BigRational;
use rand::SeedableRng;
use serde_json::Value;

fn reference() -> Value {
    let text = include_str!("../data/cartpole_reference.json");
    serde_json::from_str(text).expect("reference JSON")
}

fn float(v: &Value) -> f64 {
    v.as_str()
        .expect("floats are stored as repr strings")
        .parse()
        .expect("a float repr")
}

fn state(v: &Value) -> [f64; 4] {
    let a = v.as_array().expect("a state");
    assert_eq!(a.len(), 4);
    std::array::from_fn(|i| float(&a[i]))
}

#[test]
fn thresholds_are_gymnasiums_float64_values() {
    let r = reference();
    let x = float(&r["x_threshold"]);
    let theta = float(&r["theta_threshold_radians"]);
    assert_eq!(BigRational::from_float(x).unwrap(), x_threshold_rational());
    assert_eq!(
        BigRational::from_float(theta).unwrap(),
        theta_threshold_rational()
    );
}

#[test]
fn matches_gymnasium_bit_for_bit() {
    let r = reference();
    let cases = r["cases"].as_array().unwrap();
    assert!(cases.len() >= 20);
    let dynamics = CartPoleDynamics::<f64>::new();
    let (mut steps, mut terminating_cases) = (0, 0);
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let mut s = state(&case["init"]);
        let actions = case["actions"].as_array().unwrap();
        let states = case["states"].as_array().unwrap();
        let terminated = case["terminated"].as_array().unwrap();
        assert_eq!(actions.len(), states.len());
        assert_eq!(actions.len(), terminated.len());
        for (t, a) in actions.iter().enumerate() {
            let a = a.as_u64().unwrap() as usize;
            let (next, term) = dynamics.step(&s, a).unwrap();
            let want = state(&states[t]);
            for i in 0..4 {
                assert_eq!(
                    next[i].to_bits(),
                    want[i].to_bits(),
                    "{name}, step {}, component {i}: {:?} vs Gymnasium {:?}",
                    t + 1,
                    next[i],
                    want[i]
                );
            }
            assert_eq!(
                term,
                terminated[t].as_bool().unwrap(),
                "{name}, step {}",
                t + 1
            );
            s = next;
            steps += 1;
        }
        if terminated.iter().any(|b| b.as_bool() == Some(true)) {
            terminating_cases += 1;
        }
    }
    assert!(steps >= 4000, "{steps} steps");
    assert!(terminating_cases >= 10 && terminating_cases < cases.len());
}

/// The replay behind `ilopt replay cartpole`, from the text forms of every reference case: same
/// states bit for bit, same flags, and the states printed as JSON numbers read back to the same
/// float64.
#[test]
fn replay_matches_gymnasium() {
    use ilopt::env::cartpole_replay::{parse_actions, parse_init, replay};
    let r = reference();
    for case in r["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let init = case["init"].as_array().unwrap();
        let init: Vec<&str> = init.iter().map(|v| v.as_str().unwrap()).collect();
        let actions: Vec<String> = case["actions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.to_string())
            .collect();
        let init = parse_init(&init.join(",")).unwrap();
        let actions = parse_actions(&actions.join(",")).unwrap();
        let out = replay(init, &actions).unwrap();
        assert_eq!(
            serde_json::to_value(&out.terminated).unwrap(),
            case["terminated"],
            "{name}"
        );
        let want = case["states"].as_array().unwrap();
        assert_eq!(out.states.len(), want.len());
        for (t, (g, w)) in out.states.iter().zip(want).enumerate() {
            let w = state(w);
            for i in 0..4 {
                assert_eq!(g[i].to_bits(), w[i].to_bits(), "{name}, step {}", t + 1);
                // What the command prints, read back with a correctly rounded parser.
                let text = serde_json::to_string(&g[i]).unwrap();
                assert_eq!(
                    text.parse::<f64>().unwrap().to_bits(),
                    g[i].to_bits(),
                    "{text}"
                );
            }
        }
    }
}

/// Gymnasium's float32 observation is the float64 state cast to float32.
#[test]
fn observation_cast_matches_gymnasium() {
    let r = reference();
    let mut compared = 0;
    for case in r["cases"].as_array().unwrap() {
        let states = case["states"].as_array().unwrap();
        for (t, obs) in case["observations_float32"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            let want = state(obs);
            let got = gymnasium_observation(&state(&states[t]));
            for i in 0..4 {
                assert_eq!(f64::from(got[i]).to_bits(), want[i].to_bits());
            }
            compared += 1;
        }
    }
    assert!(compared >= 200);
}

/// The generic code instantiated with dual numbers computes the same values, bit for bit (the value
/// part of each dual operation is the float operation), with derivatives alongside.
#[test]
fn dual_run_has_gymnasiums_values() {
    use ilopt::scalar::Dual;
    let r = reference();
    let dynamics = CartPoleDynamics::<Dual<f64>>::new();
    for case in r["cases"].as_array().unwrap().iter().take(6) {
        let init = state(&case["init"]);
        let mut s: [Dual<f64>; 4] = std::array::from_fn(|i| Dual::variable(init[i], i, 4));
        let states = case["states"].as_array().unwrap();
        for (t, a) in case["actions"].as_array().unwrap().iter().enumerate() {
            let (next, _) = dynamics.step(&s, a.as_u64().unwrap() as usize).unwrap();
            let want = state(&states[t]);
            for i in 0..4 {
                assert_eq!(
                    next[i].value().to_bits(),
                    want[i].to_bits(),
                    "step {}",
                    t + 1
                );
            }
            s = next;
        }
    }
}

#[test]
fn the_free_function_is_the_dynamics() {
    let s = [0.01, -0.02, 0.03, -0.04];
    for a in 0..2 {
        assert_eq!(
            cartpole_step(&s, a).unwrap(),
            CartPoleDynamics::new().step(&s, a).unwrap()
        );
    }
    assert!(matches!(
        cartpole_step(&s, 2),
        Err(EnvError::InvalidAction { .. })
    ));
}

/// A full-length episode needs a controller: the LQR expert keeps the pole up for 500 steps.
#[test]
fn truncation_at_500_steps_and_reward_one_per_step() {
    let expert = LqrExpert::cartpole().unwrap();
    let mut env = CartPole::<f64>::new();
    let mut rng = KitRng::seed_from_u64(7);
    let mut obs = env.reset(&mut rng);
    let mut total = 0.0;
    for t in 1..=MAX_EPISODE_STEPS {
        let step = env.step(expert.action(&obs).unwrap()).unwrap();
        total += step.reward;
        assert_eq!(step.reward, 1.0);
        assert!(!step.terminated, "the expert dropped the pole at step {t}");
        assert_eq!(step.truncated, t == MAX_EPISODE_STEPS, "step {t}");
        assert_eq!(env.elapsed_steps(), t);
        obs = step.observation;
    }
    assert_eq!(total, 500.0);
    assert_eq!(env.step(0), Err(EnvError::EpisodeOver));
    // A reset starts a new episode.
    env.reset(&mut rng);
    assert!(env.step(1).is_ok());
    let mut short = CartPole::<f64>::with_max_episode_steps(3);
    short.reset(&mut rng);
    let flags: Vec<bool> = (0..3).map(|_| short.step(0).unwrap().truncated).collect();
    assert_eq!(flags, [false, false, true]);
}

#[test]
fn reward_one_on_the_terminating_step_then_episode_over() {
    let mut env = CartPole::<f64>::new();
    // θ = 0.2 and θ̇ = 1: θ' = 0.22 > 12° on the first step.
    env.reset_to([0.0, 0.0, 0.2, 1.0]);
    let step = env.step(1).unwrap();
    assert!(step.terminated && !step.truncated);
    assert_eq!(step.reward, 1.0);
    assert_eq!(env.step(1), Err(EnvError::EpisodeOver));
}

#[test]
fn contract_errors() {
    let mut env = CartPole::<f64>::new();
    assert_eq!(env.step(0), Err(EnvError::NotReset));
    env.reset(&mut KitRng::seed_from_u64(1));
    assert!(matches!(env.step(2), Err(EnvError::InvalidAction { .. })));
    // An invalid action does not end the episode.
    assert!(env.step(1).is_ok());
    // A state that overflows is an error, not a NaN, and ends the episode.
    env.reset_to([0.0, 0.0, 0.0, 1e200]);
    assert!(matches!(env.step(1), Err(EnvError::NonFinite { .. })));
    assert_eq!(env.step(1), Err(EnvError::EpisodeOver));
}

/// The non-finite error names the first non-finite component of the next state — found here by
/// evaluating Gymnasium's update in plain `f64` arithmetic, independently of the kit's step — and
/// leaves the state unchanged.
#[test]
fn non_finite_error_names_the_first_non_finite_component() {
    let names = ["x", "x_dot", "theta", "theta_dot"];
    let reference_next = |s: [f64; 4], force: f64| {
        let [x, x_dot, th, th_dot] = s;
        let (total_mass, pml) = (1.1, 0.05);
        let temp = (force + pml * (th_dot * th_dot) * th.sin()) / total_mass;
        let ta = (9.8 * th.sin() - th.cos() * temp)
            / (0.5 * (4.0 / 3.0 - 0.1 * (th.cos() * th.cos()) / total_mass));
        let xa = temp - pml * ta * th.cos() / total_mass;
        [
            x + 0.02 * x_dot,
            x_dot + 0.02 * xa,
            th + 0.02 * th_dot,
            th_dot + 0.02 * ta,
        ]
    };
    let dynamics = CartPoleDynamics::<f64>::new();
    let big = f64::MAX;
    let mut seen = std::collections::BTreeSet::new();
    for state in [
        [big, big, 0.0, 0.0],
        [0.0, 0.0, 0.0, 1e200],
        [0.0, 0.0, big, big],
        [0.0, 0.0, 0.0, big],
        [f64::NAN, 0.0, 0.0, 0.0],
        [0.0, 0.0, f64::INFINITY, 0.0],
    ] {
        for action in [0, 1] {
            let next = reference_next(state, if action == 1 { 10.0 } else { -10.0 });
            let expected = names
                .iter()
                .zip(next)
                .find(|(_, v)| !v.is_finite())
                .map(|(name, _)| *name)
                .expect("the reference step overflows too");
            let mut s = state;
            assert_eq!(
                dynamics.step_in_place(&mut s, action),
                Err(EnvError::NonFinite { what: expected }),
                "{state:?}, action {action}"
            );
            assert_eq!(s.map(f64::to_bits), state.map(f64::to_bits));
            seen.insert(expected);
        }
    }
    // Both components that can fail first (x alone; every other overflow runs through ẍ into ẋ).
    assert!(seen.contains("x") && seen.contains("x_dot"), "{seen:?}");
}

#[test]
fn reset_is_in_range_and_seeded() {
    let mut rng = KitRng::seed_from_u64(2025);
    let mut lo = [f64::INFINITY; 4];
    let mut hi = [f64::NEG_INFINITY; 4];
    for _ in 0..2000 {
        let s = sample_reset_state(&mut rng);
        for i in 0..4 {
            assert!((-0.05..=0.05).contains(&s[i]), "{s:?}");
            lo[i] = lo[i].min(s[i]);
            hi[i] = hi[i].max(s[i]);
        }
    }
    // Uniform on the whole box: 2000 draws come within 0.001 of both ends (failure chance ~1e-17).
    for i in 0..4 {
        assert!(lo[i] < -0.049 && hi[i] > 0.049, "{lo:?} {hi:?}");
    }
    let run = |seed| {
        let mut env = CartPole::<f64>::new();
        let mut rng = KitRng::seed_from_u64(seed);
        (env.reset(&mut rng), env.reset(&mut rng))
    };
    assert_eq!(run(3), run(3));
    assert_ne!(run(3), run(4));
    let (first, second) = run(3);
    assert_ne!(first, second);
}

#[test]
fn lqr_expert_mean_return_over_100_episodes() {
    let expert = LqrExpert::cartpole().unwrap();
    let mut returns = Vec::new();
    for seed in 0..100 {
        let mut env = CartPole::<f64>::new();
        let mut rng = KitRng::seed_from_u64(seed);
        let mut obs = env.reset(&mut rng);
        let mut ret = 0.0;
        loop {
            let step = env.step(expert.action(&obs).unwrap()).unwrap();
            ret += step.reward;
            if step.done() {
                break;
            }
            obs = step.observation;
        }
        returns.push(ret);
    }
    let mean = returns.iter().sum::<f64>() / returns.len() as f64;
    let min = returns.iter().copied().fold(f64::INFINITY, f64::min);
    eprintln!("LQR expert: mean return {mean} over 100 episodes, min {min}");
    assert!(mean >= 495.0, "mean return {mean}");
}

#[cfg(feature = "mpfr")]
mod intervals {
    use super::*;
    use ilopt::scalar::{Interval, Scalar};

    fn point(v: f64) -> Interval {
        Interval::try_from((v, v)).unwrap()
    }

    fn contains(x: Interval, v: f64) -> bool {
        x.inf() <= v && v <= x.sup()
    }

    /// From a point initial state, the interval run encloses the f64 run (and the exact-real one;
    /// see the module docs of `ilopt::env::cartpole`) for as long as termination stays decidable.
    #[test]
    fn interval_run_encloses_the_f64_run() {
        let r = reference();
        let f = CartPoleDynamics::<f64>::new();
        let iv = CartPoleDynamics::<Interval>::new();
        let mut checked = 0;
        for case in r["cases"].as_array().unwrap() {
            let name = case["name"].as_str().unwrap();
            let mut s = state(&case["init"]);
            let mut x: [Interval; 4] = std::array::from_fn(|i| point(s[i]));
            let actions = case["actions"].as_array().unwrap();
            for (t, a) in actions.iter().take(100).enumerate() {
                let a = a.as_u64().unwrap() as usize;
                let (sn, term) = f.step(&s, a).unwrap();
                let (xn, iterm) = match iv.step(&x, a) {
                    Ok(v) => v,
                    Err(EnvError::Undecidable(_)) => break,
                    Err(e) => panic!("{name}, step {}: {e}", t + 1),
                };
                for i in 0..4 {
                    assert!(
                        contains(xn[i], sn[i]),
                        "{name}, step {}, component {i}: {:?} not in {:?}",
                        t + 1,
                        sn[i],
                        xn[i]
                    );
                }
                assert_eq!(term, iterm, "{name}, step {}", t + 1);
                s = sn;
                x = xn;
                checked += 1;
            }
            let width = x.iter().map(|v| v.wid()).fold(0.0, f64::max);
            eprintln!("{name}: enclosure checked, final max width {width:e}");
        }
        assert!(checked >= 1000, "{checked} steps checked");
    }

    #[test]
    fn interval_widths_stay_small_on_a_balanced_run() {
        // The LQR expert keeps the f64 run up; the enclosure of the same actions stays tight.
        let expert = LqrExpert::cartpole().unwrap();
        let f = CartPoleDynamics::<f64>::new();
        let iv = CartPoleDynamics::<Interval>::new();
        let mut s = [0.01, -0.02, 0.03, 0.04];
        let mut x: [Interval; 4] = std::array::from_fn(|i| point(s[i]));
        for t in 1..=200 {
            let a = expert.action(&s).unwrap();
            let (sn, _) = f.step(&s, a).unwrap();
            let (xn, term) = iv.step(&x, a).unwrap();
            assert!(!term);
            assert!((0..4).all(|i| contains(xn[i], sn[i])), "step {t}");
            s = sn;
            x = xn;
        }
        let width = x.iter().map(|v| v.wid()).fold(0.0, f64::max);
        eprintln!("LQR run: max width after 200 steps {width:e}");
        // A loose regression guard: the enclosure must stay useful (far below the state's scale).
        assert!(width < 1e-6, "width {width:e}");
    }

    #[test]
    fn straddling_the_threshold_is_undecidable() {
        let iv = CartPoleDynamics::<Interval>::new();
        let x_max = Interval::from_rational(&x_threshold_rational());
        let around = Interval::try_from((x_max.inf() - 1e-6, x_max.sup() + 1e-6)).unwrap();
        let s = [around, Interval::zero(), Interval::zero(), Interval::zero()];
        assert!(matches!(iv.step(&s, 1), Err(EnvError::Undecidable(_))));
        // Certainly beyond on one side is decided even when the other test is not.
        let theta_out = point(0.3);
        let s = [around, Interval::zero(), theta_out, Interval::zero()];
        assert!(iv.step(&s, 1).unwrap().1);
        // And the environment ends the episode on the error.
        let mut env = CartPole::<Interval>::new();
        env.reset_to([around, Interval::zero(), Interval::zero(), Interval::zero()]);
        assert!(matches!(env.step(0), Err(EnvError::Undecidable(_))));
        assert_eq!(env.step(0), Err(EnvError::EpisodeOver));
    }
}
