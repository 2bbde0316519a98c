//! The `ilopt` command line. Each subcommand lives in its own module; this module only parses and
//! dispatches. Errors go to stderr with a non-zero exit status (2 for usage errors, 1 for failures);
//! results go to stdout as JSON.

pub mod toy;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// ilopt: imitation learning as stochastic optimisation, checked.
#[derive(Debug, Parser)]
#[command(name = "ilopt", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Toy MDPs: exact objective, gradient and oracle moments.
    #[command(subcommand)]
    Toy(toy::ToyCommand),
}

/// Run the CLI on the process arguments; returns the exit code.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result = match cli.command {
        Command::Toy(cmd) => toy::run(&cmd),
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
