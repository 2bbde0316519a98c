//! `ilopt toy eval --mdp FILE --theta LIST [--scalar exact|f64|interval] [--baseline LIST]
//! [--optimal-baseline]`: the exact engine at θ.
//!
//! Prints one JSON object with `objective` (F(θ), forward DP X2), `gradient` (∇F(θ), X2),
//! `expected_estimate` (E[∇f(θ, τ)] by enumeration X1, eq. 3.15) and `second_moment` (E‖∇f‖², X1).
//! With `--baseline` (one number b for every decision, or T − 2 numbers b_1..b_{T−2}) the last two
//! are those of the baselined estimator `g_b = g − Σ_i b_i ψ_i` (math.md §9; [`ilopt::baseline`]),
//! and `baseline` echoes the values. `--optimal-baseline` adds `optimal_baseline`: E[g·ψ_i],
//! E‖ψ_i‖², the variance-minimising b*_i and b*_const, the second moments they reach, and the
//! reduction factors E‖g‖²/E‖g_{b*}‖² ([`ilopt::exact::baseline`]); its `state` object gives the
//! same for the variance-minimising baseline per state, `b_i = w*_{s_i}` (`cross` c_s, `score_moment`
//! A_ss, `weights` w*_s = c_s/A_ss, `second_moment`, `reduction`).
//! `exact` prints fraction strings (`"-13/24"`), `f64` prints numbers, `interval` prints `[lo, hi]`
//! pairs that enclose the exact values.
//!
//! The quantities are the library's [`ilopt::exact::evaluation::evaluate`]; this module reads the
//! files and arguments and prints.

use clap::{Args, Subcommand, ValueEnum};
use ilopt::exact::evaluation::{EvaluationError, EvaluationOptions, evaluate};
use ilopt::scalar::{BigRational, Interval, JsonScalar, parse_exact};
use ilopt::toy::{ToyError, ToyMdp};
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
    /// Baselines of the estimator as comma-separated exact numbers: one b for every decision, or
    /// T − 2 numbers b_1..b_{T−2}; `expected_estimate` and `second_moment` are then those of
    /// g_b = g − Σ_i b_i ψ_i.
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    pub baseline: Option<String>,
    /// Also print the exact variance-minimising baselines and reduction factors.
    #[arg(long)]
    pub optimal_baseline: bool,
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
    /// A `--baseline` entry that is not an exact number.
    #[error("--baseline entry {index} (0-based): {message}")]
    Baseline {
        /// Entry index.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A `--baseline` list of the wrong length.
    #[error(
        "--baseline has {got} numbers; give one (the same b for every decision) or T − 2 = {expected}"
    )]
    BaselineLength {
        /// Numbers given.
        got: usize,
        /// T − 2.
        expected: usize,
    },
    /// The exact engine at θ, or a result that is not a finite number in the chosen arithmetic
    /// (e.g. f64 overflow).
    #[error("{0}{hint}", hint = if matches!(.0, EvaluationError::NonFinite(_)) { "; use --scalar exact" } else { "" })]
    Evaluation(#[from] EvaluationError),
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
    let mdp = load_mdp(&args.mdp)?;
    let theta: Vec<&str> = args.theta.split(',').collect();
    let baseline: Option<Vec<&str>> = args.baseline.as_ref().map(|b| b.split(',').collect());
    evaluate_entries(
        &mdp,
        &theta,
        baseline.as_deref(),
        args.optimal_baseline,
        args.scalar,
    )
}

/// Read a toy-MDP file (docs/formats/toy-mdp.md).
///
/// # Errors
/// [`ToyCliError::Mdp`] naming the file.
pub fn load_mdp(path: &std::path::Path) -> Result<ToyMdp, ToyCliError> {
    ToyMdp::load(path).map_err(|source| ToyCliError::Mdp {
        path: path.display().to_string(),
        source,
    })
}

/// Parse a toy MDP from JSON text, `name` naming it in the error.
///
/// # Errors
/// [`ToyCliError::Mdp`] naming `name`.
pub fn parse_mdp(text: &str, name: &str) -> Result<ToyMdp, ToyCliError> {
    ToyMdp::from_json_str(text).map_err(|source| ToyCliError::Mdp {
        path: name.into(),
        source,
    })
}

/// What `ilopt toy eval` prints for `mdp` at θ: θ and the baselines as exact-number texts, one
/// entry each (`"1/3"`, `"-2"`, `"0.25"`).
///
/// # Errors
/// [`ToyCliError`] naming the entry at fault, or the exact engine's error.
pub fn evaluate_entries(
    mdp: &ToyMdp,
    theta: &[&str],
    baseline: Option<&[&str]>,
    optimal_baseline: bool,
    scalar: ScalarChoice,
) -> Result<Value, ToyCliError> {
    let theta = theta
        .iter()
        .enumerate()
        .map(|(index, t)| {
            parse_exact(t).map_err(|e| ToyCliError::Theta {
                index,
                message: e.to_string(),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let baseline = match baseline {
        None => None,
        Some(entries) => {
            let b = entries
                .iter()
                .enumerate()
                .map(|(index, t)| {
                    parse_exact(t).map_err(|e| ToyCliError::Baseline {
                        index,
                        message: e.to_string(),
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            let expected = mdp.horizon - 2;
            if b.len() != 1 && b.len() != expected {
                return Err(ToyCliError::BaselineLength {
                    got: b.len(),
                    expected,
                });
            }
            Some(b)
        }
    };
    let options = EvaluationOptions {
        baseline: baseline.as_deref(),
        optimal_baseline,
    };
    match scalar {
        ScalarChoice::Exact => evaluate_with::<BigRational>(mdp, &theta, &options),
        ScalarChoice::F64 => evaluate_with::<f64>(mdp, &theta, &options),
        ScalarChoice::Interval => evaluate_with::<Interval>(mdp, &theta, &options),
    }
}

/// The quantities of `toy eval` in scalar `S`, with `options`, as the printed JSON object.
fn evaluate_with<S: JsonScalar>(
    mdp: &ToyMdp,
    theta: &[BigRational],
    options: &EvaluationOptions<'_>,
) -> Result<Value, ToyCliError> {
    let e = evaluate::<S>(mdp, theta, options)?;
    let list = |xs: &[S]| Value::Array(xs.iter().map(JsonScalar::to_json).collect());
    let mut out = json!({
        "objective": e.objective.to_json(),
        "gradient": list(&e.gradient),
        "expected_estimate": list(&e.expected_estimate),
        "second_moment": e.second_moment.to_json(),
    });
    if let Some(b) = &e.baseline {
        out["baseline"] = list(b);
    }
    // A value that is not finite in this arithmetic (a ratio whose enclosure reaches 0) prints as
    // null.
    let one = |x: Option<S>| match x {
        Some(x) if x.is_finite() => x.to_json(),
        _ => Value::Null,
    };
    if let Some(o) = &e.optimal_baseline {
        out["optimal_baseline"] = json!({
            "cross": list(&o.cross),
            "score_moment": list(&o.score_moment),
            "time_indexed": Value::Array(o.time_indexed.iter().cloned().map(Some).map(one).collect()),
            "constant": one(Some(o.constant.clone())),
            "second_moment_plain": o.second_moment.to_json(),
            "second_moment_time_indexed": one(Some(o.second_moment_time_indexed.clone())),
            "second_moment_constant": one(Some(o.second_moment_constant.clone())),
            "reduction_time_indexed": one(o.reduction_time_indexed()),
            "reduction_constant": one(o.reduction_constant()),
        });
    }
    if let Some(st) = &e.optimal_state_baseline {
        out["optimal_baseline"]["state"] = json!({
            "cross": list(&st.cross),
            "score_moment": list(&st.score_moment),
            "weights": Value::Array(st.weights.iter().cloned().map(Some).map(one).collect()),
            "second_moment": one(Some(st.second_moment_optimal.clone())),
            "reduction": one(st.reduction()),
        });
    }
    Ok(out)
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
