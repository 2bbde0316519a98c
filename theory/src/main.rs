//! `ilopt-theory`: print the theorem-check table (Markdown to stdout, JSON to a file).
use clap::Parser;
use ilopt_theory::report::{json, markdown};
use ilopt_theory::suite::{Profile, whole_table};
use std::process::ExitCode;

/// mimalloc instead of the system allocator: the interval and exact-arithmetic checks allocate
/// many short-lived buffers, and glibc's malloc and free took about a tenth of the table's time.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The thesis's results, checked: exact identities, rigorous constants, stated-confidence bounds.
#[derive(Debug, Parser)]
#[command(name = "ilopt-theory", version)]
struct Args {
    /// Run at the thesis's scale instead of the quick size.
    #[arg(long)]
    full: bool,
    /// Also write the JSON report (with certificates) to this file.
    #[arg(long, value_name = "FILE")]
    json: Option<std::path::PathBuf>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let profile = if args.full {
        Profile::Full
    } else {
        Profile::Quick
    };
    let rows = match whole_table(profile) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!("{}", markdown(&rows));
    if let Some(path) = args.json {
        let text = serde_json::to_string_pretty(&json(&rows)).expect("serialisable");
        if let Err(e) = std::fs::write(&path, text) {
            eprintln!("error: cannot write {}: {e}", path.display());
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}
