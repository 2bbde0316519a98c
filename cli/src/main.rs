//! The `ilopt` binary: parses the command line and dispatches to the subcommands of `ilopt_cli`.
//! Errors go to stderr with a non-zero exit status (2 for usage errors, 1 for failures); results
//! go to stdout as JSON. See `ilopt --help` and the README.

use clap::{Parser, Subcommand};
use ilopt_cli::{estimate, eval, expert, plot, replay, run, toy};
use std::process::ExitCode;

/// ilopt: imitation learning as stochastic optimisation, checked.
#[derive(Debug, Parser)]
// The about line is the core library's description (the root Cargo.toml's), not this package's.
#[command(
    name = "ilopt",
    version,
    about = "Imitation learning as stochastic optimisation: algorithms and checks of the thesis, generic over the scalar type",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Toy MDPs: exact objective, gradient and oracle moments.
    #[command(subcommand)]
    Toy(toy::ToyCommand),
    /// Experts: solve the velocity-obstacle problem of eq. 4.1 for a file of cases.
    #[command(subcommand)]
    Expert(ExpertCommand),
    /// Replay an environment from a given state and action sequence.
    #[command(subcommand)]
    Replay(ReplayCommand),
    /// Train a learner as a TOML config says, one run per seed; CSV and JSON per checkpoint.
    Run(run::RunArgs),
    /// Evaluate a saved policy parameter (`theta-seed-<n>.json`) on a config's task.
    Eval(eval::EvalArgs),
    /// Draw `ilopt run` output directories: mean and 95% band over seeds, to SVG or PNG.
    Plot(plot::PlotArgs),
    /// One draw of the oracle's gradient estimate (eq. 3.15) at θ on a config's task.
    Estimate(estimate::EstimateArgs),
}

#[derive(Debug, Subcommand)]
enum ExpertCommand {
    /// The velocity-obstacle expert (eq. 4.1, global optimum): JSON lines in, JSON lines out.
    Vo(expert::ExpertVoArgs),
}

#[derive(Debug, Subcommand)]
enum ReplayCommand {
    /// CartPole-v1, step for step as Gymnasium: prints the float64 state after each step.
    Cartpole(replay::ReplayCartpoleArgs),
}

/// Runs the CLI on the process arguments; returns the exit code.
fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result: Result<serde_json::Value, String> = match cli.command {
        Command::Toy(cmd) => toy::run(&cmd).map_err(|e| e.to_string()),
        Command::Expert(ExpertCommand::Vo(args)) => {
            // Streams its JSON lines itself; only errors come back.
            let stdout = std::io::stdout();
            return match expert::run(&args, &mut stdout.lock()) {
                Ok(s) if s.failed == 0 => ExitCode::SUCCESS,
                Ok(s) => {
                    eprintln!(
                        "error: {} of {} cases failed (their output lines say why)",
                        s.failed,
                        s.failed + s.solved
                    );
                    ExitCode::FAILURE
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Command::Replay(ReplayCommand::Cartpole(args)) => {
            replay::run(&args).map_err(|e| e.to_string())
        }
        Command::Run(args) => run::run(&args).map_err(|e| e.to_string()),
        Command::Eval(args) => eval::run(&args).map_err(|e| e.to_string()),
        Command::Plot(args) => plot::run(&args).map_err(|e| e.to_string()),
        Command::Estimate(args) => estimate::run(&args).map_err(|e| e.to_string()),
    };
    match result {
        Ok(out) => {
            use std::io::Write;
            let mut stdout = std::io::stdout().lock();
            match writeln!(stdout, "{out}").and_then(|()| stdout.flush()) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: cannot write the result: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
