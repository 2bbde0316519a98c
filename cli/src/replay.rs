//! `ilopt replay cartpole`: replay an action sequence through CartPole-v1's float64 dynamics.
//!
//! ```text
//! ilopt replay cartpole --init X,XDOT,THETA,THETADOT --actions 0,1,1,…
//! ```
//!
//! prints one JSON object `{"states": [[x, x_dot, theta, theta_dot], …], "terminated": [bool, …]}`:
//! the float64 state after each step ([`cartpole_step`], bit-for-bit Gymnasium's) and whether it is
//! terminal. Numbers are printed in the shortest form that reads back to the same float64. Stepping
//! goes on after a terminal state, as `env.unwrapped.step` does in Gymnasium, and there is no time
//! limit; like Gymnasium, the command then warns (on stderr: the step that terminated and how many
//! steps followed it, whose states are outside the environment's defined behaviour) and the output
//! says so in two more fields: `"first_terminal_step"` (1-based, or `null`) and
//! `"steps_after_termination"`. The initial state is read as Python's `float()` reads it
//! (correctly rounded).
//!
//! The parsing of the text forms and the replay are the library's ([`ilopt::env::cartpole_replay`]);
//! this module reads the arguments, warns and prints.

#[cfg(doc)]
use ilopt::env::cartpole::cartpole_step;
use ilopt::env::cartpole_replay::{Actions, ReplayError, parse_actions, parse_init, replay};
use serde_json::{Value, json};

/// Arguments of `ilopt replay cartpole`.
#[derive(Debug, Clone, PartialEq, clap::Parser)]
#[command(
    name = "cartpole",
    about = "Replay actions through CartPole-v1 (Gymnasium's float64 dynamics); print the states as JSON"
)]
pub struct ReplayCartpoleArgs {
    /// The initial state, four comma-separated finite numbers (negative values are fine:
    /// `--init -0.01,0,0,0` or `--init=-0.01,0,0,0`).
    #[arg(
        long,
        value_name = "X,XDOT,THETA,THETADOT",
        allow_hyphen_values = true,
        value_parser = parse_init_arg
    )]
    pub init: [f64; 4],
    /// The actions, comma-separated, each 0 (push left) or 1 (push right); at least one.
    #[arg(long, value_name = "A,A,…", allow_hyphen_values = true, value_parser = parse_actions_arg)]
    pub actions: Actions,
}

fn parse_init_arg(text: &str) -> Result<[f64; 4], String> {
    parse_init(text).map_err(|e| e.to_string())
}

fn parse_actions_arg(text: &str) -> Result<Actions, String> {
    parse_actions(text).map_err(|e| e.to_string())
}

/// Replays the actions from the initial state and returns the JSON report (module docs).
///
/// # Errors
/// As [`replay`]: [`ReplayError::NoActions`] for an empty action list (possible only when the
/// struct is built by hand), [`ReplayError::InitNotFinite`] for a non-finite initial state, and
/// [`ReplayError::Step`] if a state becomes non-finite or an action is invalid.
pub fn run(args: &ReplayCartpoleArgs) -> Result<Value, ReplayError> {
    let r = replay(args.init, &args.actions)?;
    let first = r.first_terminal_step();
    let after = r.steps_after_termination();
    if let Some(step) = first
        && after > 0
    {
        eprintln!(
            "warning: the episode terminated at step {step} and {after} more steps were taken; \
             Gymnasium warns likewise: the states after a termination are outside the \
             environment's defined behaviour"
        );
    }
    // Every state is finite (checked by the step), so serde_json writes plain numbers.
    Ok(json!({
        "states": r.states,
        "terminated": r.terminated,
        "first_terminal_step": first,
        "steps_after_termination": after,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    fn parse(args: &[&str]) -> Result<ReplayCartpoleArgs, clap::Error> {
        ReplayCartpoleArgs::try_parse_from(std::iter::once("cartpole").chain(args.iter().copied()))
    }

    #[test]
    fn negative_values_parse_in_both_forms() {
        let a = parse(&["--init", "-0.01,0.02,-0.03,0.04", "--actions", "0,1,1"]).unwrap();
        let b = parse(&["--init=-0.01,0.02,-0.03,0.04", "--actions=0,1,1"]).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.init, [-0.01, 0.02, -0.03, 0.04]);
        assert_eq!(a.actions, Actions(vec![0, 1, 1]));
        let c = parse(&["--actions", "1", "--init", "-1e-3, -2,-3.5 ,-0"]).unwrap();
        assert_eq!(c.init, [-1e-3, -2.0, -3.5, -0.0]);
        assert!(c.init[3].is_sign_negative());
    }

    #[test]
    fn bad_input_is_named() {
        let cases: &[(&[&str], &str)] = &[
            (&["--init", "0,0,0", "--actions", "0"], "expected 4"),
            (&["--init", "0,0,0,0,0", "--actions", "0"], "got 5"),
            (
                &["--init", "0,x,0,0", "--actions", "0"],
                "component 2 (x_dot)",
            ),
            (
                &["--init", "0,0,NaN,0", "--actions", "0"],
                "component 3 (theta)",
            ),
            (&["--init", "0,0,0,inf", "--actions", "0"], "not finite"),
            (
                &["--init", "0,0,0,-inf", "--actions", "0"],
                "component 4 (theta_dot)",
            ),
            (&["--init", "0,0,0,", "--actions", "0"], "component 4"),
            (
                &["--init", "0,0,0,0", "--actions", "0,2"],
                "action 2 is \"2\"",
            ),
            (&["--init", "0,0,0,0", "--actions", "0,,1"], "action 2"),
            (
                &["--init", "0,0,0,0", "--actions", "-1"],
                "action 1 is \"-1\"",
            ),
            (&["--init", "0,0,0,0", "--actions", ""], "at least one"),
            (&["--init", "0,0,0,0"], "--actions"),
        ];
        for (args, needle) in cases {
            let err = parse(args).unwrap_err().to_string();
            assert!(err.contains(needle), "{args:?}: {err}");
        }
    }

    #[test]
    fn replay_reports_every_step() {
        let args = parse(&["--init=0,0,0.2,1", "--actions", "1,1,0"]).unwrap();
        let v = run(&args).unwrap();
        let states = v["states"].as_array().unwrap();
        let terminated = v["terminated"].as_array().unwrap();
        assert_eq!(states.len(), 3);
        assert_eq!(terminated.len(), 3);
        // θ' = θ + τ θ̇ = 0.2 + 0.02 > θ_max ≈ 0.2094 after the first step.
        assert_eq!(terminated[0], Value::Bool(true));
        assert_eq!(states[0][2].as_f64().unwrap(), 0.2 + 0.02 * 1.0);
        // Termination at step 1, two steps past it.
        assert_eq!(v["first_terminal_step"], 1);
        assert_eq!(v["steps_after_termination"], 2);
        let calm = run(&parse(&["--init=0,0,0,0", "--actions", "1,0"]).unwrap()).unwrap();
        assert_eq!(calm["first_terminal_step"], Value::Null);
        assert_eq!(calm["steps_after_termination"], 0);
    }

    #[test]
    fn overflow_is_an_error_not_a_nan() {
        let args = parse(&["--init=0,0,0,1e200", "--actions", "1,1"]).unwrap();
        let err = run(&args).unwrap_err();
        assert!(matches!(err, ReplayError::Step { step: 1, .. }), "{err}");
        let mut bad = parse(&["--init=0,0,0,0", "--actions", "1"]).unwrap();
        bad.actions = Actions(vec![]);
        assert_eq!(run(&bad), Err(ReplayError::NoActions));
        bad.actions = Actions(vec![3]);
        assert!(matches!(run(&bad), Err(ReplayError::Step { step: 1, .. })));
    }
}
