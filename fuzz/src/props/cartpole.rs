//! CartPole's property: any state and action sequence steps to finite states or a clean error.

use ilopt::env::cartpole::CartPoleDynamics;
use ilopt::scalar::Scalar;

/// An initial state and actions (any `u8`: only 0 and 1 are valid), plus text for the CLI's
/// argument parsers.
#[derive(Debug, Clone, PartialEq)]
pub struct CartpoleInput {
    /// x, ẋ, θ, θ̇ (any bit patterns).
    pub init: [f64; 4],
    /// Actions.
    pub actions: Vec<u8>,
    /// Text given to `parse_init` and `parse_actions` of `ilopt replay cartpole`.
    pub text: String,
}

/// Target `cartpole_replay`: no panic; every step's termination flag is Gymnasium's test on the
/// returned state; a non-finite state is an error; an invalid action is an error.
pub fn check_cartpole(inp: &CartpoleInput) {
    let dynamics = CartPoleDynamics::<f64>::new();
    let x_max = 2.4f64;
    let theta_max = 12.0 * 2.0 * std::f64::consts::PI / 360.0;
    let mut state = inp.init;
    for &a in inp.actions.iter().take(600) {
        let res = dynamics.step(&state, usize::from(a));
        if !state.iter().all(|x| x.is_finite()) {
            assert!(
                res.is_err(),
                "non-finite state {state:?} stepped to {res:?}"
            );
        }
        if a > 1 {
            assert!(res.is_err(), "action {a} accepted");
        }
        match res {
            Ok((next, term)) => {
                assert!(next.iter().all(|x| x.is_finite()), "non-finite Ok {next:?}");
                let expect = next[0] < -x_max
                    || next[0] > x_max
                    || next[2] < -theta_max
                    || next[2] > theta_max;
                assert_eq!(term, expect, "termination flag of {next:?}");
                state = next;
            }
            Err(e) => {
                assert!(!e.to_string().is_empty());
                if a > 1 {
                    continue; // an invalid action leaves the state as it was
                }
                break;
            }
        }
    }
    // The parsers of `ilopt replay cartpole`'s text forms, on the same inputs.
    match ilopt::env::cartpole_replay::parse_init(&inp.text) {
        Ok(s) => assert!(s.iter().all(|x| x.is_finite())),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
    match ilopt::env::cartpole_replay::parse_actions(&inp.text) {
        Ok(a) => assert!(!a.0.is_empty() && a.0.iter().all(|&x| x <= 1)),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}
