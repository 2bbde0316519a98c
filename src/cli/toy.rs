//! `ilopt toy eval --mdp FILE --theta LIST [--scalar exact|f64|interval]`: the exact engine at θ.
//!
//! Prints one JSON object with `objective` (F(θ), forward DP X2), `gradient` (∇F(θ), X2),
//! `expected_estimate` (E[∇f(θ, τ)] by enumeration X1, eq. 3.15) and `second_moment` (E‖∇f‖², X1).
//! `exact` prints fraction strings (`"-13/24"`), `f64` prints numbers, `interval` prints `[lo, hi]`
//! pairs that enclose the exact values.

use crate::exact::ExactError;
use crate::exact::enumerate::moments;
use crate::exact::forward::forward;
use crate::scalar::{BigRational, Interval, JsonScalar, Scalar, parse_exact_list};
use crate::toy::{ToyError, ToyMdp, ToyProblem};
use clap::{Args, Subcommand, ValueEnum};
use serde_json::{Value, json};
use std::path::PathBuf;

/// `ilopt toy …`
#[derive(Debug, Subcommand)]
pub enum ToyCommand {
    /// Evaluate F, ∇F, E[∇f] and E‖∇f‖² exactly at θ.
    Eval(EvalArgs),
}

/// The arithmetic of `toy eval`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScalarChoice {
    /// Exact rationals (fraction strings).
    Exact,
    /// IEEE double precision (numbers).
    F64,
    /// Rigorous interval enclosures (`[lo, hi]`).
    Interval,
}

/// Arguments of `ilopt toy eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Toy-MDP file (JSON, docs/formats/toy-mdp.md).
    #[arg(long, value_name = "FILE")]
    pub mdp: PathBuf,
    /// θ as comma-separated exact numbers, e.g. "1/2,-3,0.25".
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    pub theta: String,
    /// Arithmetic.
    #[arg(long, value_enum, default_value_t = ScalarChoice::Exact)]
    pub scalar: ScalarChoice,
}

/// Why `toy eval` failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ToyCliError {
    /// The MDP file.
    #[error("{path}: {source}")]
    Mdp {
        /// The file.
        path: String,
        /// What is wrong.
        source: ToyError,
    },
    /// The θ list.
    #[error("--theta entry {index} (0-based): {message}")]
    Theta {
        /// Entry index.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// The exact engine.
    #[error("at θ: {0}")]
    Engine(#[from] ExactError),
    /// A result is not a finite number in the chosen arithmetic (e.g. f64 overflow).
    #[error("`{0}` is not finite in the chosen arithmetic; use --scalar exact")]
    NonFinite(&'static str),
}

/// Run `ilopt toy …`.
///
/// # Errors
/// [`ToyCliError`] naming the input at fault.
pub fn run(cmd: &ToyCommand) -> Result<Value, ToyCliError> {
    match cmd {
        ToyCommand::Eval(args) => eval(args),
    }
}

fn eval(args: &EvalArgs) -> Result<Value, ToyCliError> {
    let mdp = ToyMdp::load(&args.mdp).map_err(|source| ToyCliError::Mdp {
        path: args.mdp.display().to_string(),
        source,
    })?;
    let theta = parse_exact_list(&args.theta).map_err(|(index, e)| ToyCliError::Theta {
        index,
        message: e.to_string(),
    })?;
    match args.scalar {
        ScalarChoice::Exact => evaluate::<BigRational>(&mdp, &theta),
        ScalarChoice::F64 => evaluate::<f64>(&mdp, &theta),
        ScalarChoice::Interval => evaluate::<Interval>(&mdp, &theta),
    }
}

/// The four quantities of `toy eval` in scalar `S`.
///
/// # Errors
/// As [`run`].
pub fn evaluate<S: JsonScalar>(mdp: &ToyMdp, theta: &[BigRational]) -> Result<Value, ToyCliError> {
    let p = ToyProblem::<S>::new(mdp);
    let th: Vec<S> = theta.iter().map(S::from_rational).collect();
    let x2 = forward(&p, &th)?;
    let x1 = moments(&p, &th)?;
    let finite = |name: &'static str, xs: &[S]| {
        if xs.iter().all(Scalar::is_finite) {
            Ok(())
        } else {
            Err(ToyCliError::NonFinite(name))
        }
    };
    finite("objective", std::slice::from_ref(&x2.objective))?;
    finite("gradient", &x2.gradient)?;
    finite("expected_estimate", &x1.expected_estimate)?;
    finite("second_moment", std::slice::from_ref(&x1.second_moment))?;
    let list = |xs: &[S]| Value::Array(xs.iter().map(JsonScalar::to_json).collect());
    Ok(json!({
        "objective": x2.objective.to_json(),
        "gradient": list(&x2.gradient),
        "expected_estimate": list(&x1.expected_estimate),
        "second_moment": x1.second_moment.to_json(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Wrapper {
        #[command(subcommand)]
        cmd: ToyCommand,
    }

    #[test]
    fn negative_theta_in_both_forms() {
        for argv in [
            ["x", "eval", "--mdp", "m.json", "--theta", "-1/2,3"],
            [
                "x",
                "eval",
                "--mdp",
                "m.json",
                "--theta=-1/2,3",
                "--scalar=exact",
            ],
        ] {
            let w = Wrapper::try_parse_from(argv.iter().filter(|a| !a.is_empty())).unwrap();
            let ToyCommand::Eval(a) = w.cmd;
            assert_eq!(a.theta, "-1/2,3");
        }
    }
}
