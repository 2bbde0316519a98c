//! `paper-checks`: regenerate the thesis's chapter 4 as a reproducible appendix.
use clap::{Parser, Subcommand};
use paper_checks::config::{Profile, committed_text};
use paper_checks::pipeline::Options;
use paper_checks::shard::{Mode, Shard};
use std::path::PathBuf;
use std::process::ExitCode;

/// mimalloc instead of the system allocator: the theorem table and the dataset learners allocate
/// many short-lived buffers, and glibc's malloc and free took about a tenth of their time.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Regenerate Tables 4.1–4.4 and Figures 4.2–4.10 of the thesis, with the theorem-check and
/// errata tables, into one directory.
#[derive(Debug, Parser)]
#[command(name = "paper-checks", version)]
struct Args {
    /// Use the thesis-scale profile (`configs/full.toml`) instead of the quick one.
    #[arg(long, global = true)]
    full: bool,
    /// Use this profile file instead of the committed ones.
    #[arg(long, value_name = "FILE", conflicts_with = "full", global = true)]
    config: Option<PathBuf>,
    /// Output directory.
    #[arg(
        long,
        value_name = "DIR",
        default_value = "out/appendix",
        global = true
    )]
    out: PathBuf,
    /// Recompute configurations whose results already exist.
    #[arg(long, global = true)]
    redo: bool,
    /// Skip the PNG renderings of the figures (SVG only).
    #[arg(long, global = true)]
    no_png: bool,
    /// No progress output.
    #[arg(long, global = true)]
    quiet: bool,
    /// Run the theorem table at this size instead of the profile's `theory_profile`: `quick`,
    /// `full` (`ilopt-theory --full`) or `none`. The appendix and the provenance name the size.
    #[arg(long, value_name = "SIZE", global = true)]
    theory: Option<paper_checks::config::TheorySize>,
    /// Compute only shard K of N (e.g. `3/16`) of the tuning and report runs into the output
    /// directory's unit store; run every shard in passes until it says its report runs are
    /// stored (each pass advances every row's tuning by one rung of successive halving, and the
    /// report runs need every row's tuning: at most 1 + rungs × (extensions + 1) passes), then
    /// `paper-checks merge`. The shards leave the theorem table to `paper-checks theory`, a job
    /// that runs beside their passes.
    #[arg(long, value_name = "K/N", value_parser = Shard::parse)]
    shard: Option<Shard>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Assemble the appendix from the shards' results in the output directory, computing
    /// nothing (an error lists what is missing).
    Merge,
    /// Compute only the theorem table into the output directory's store: the sharded run's job
    /// beside the shards' passes (it shares nothing with them); `paper-checks merge` reads it.
    Theory,
}

fn main() -> ExitCode {
    let args = Args::parse();
    // The committed profiles are embedded, so an installed binary runs from any directory.
    let (path, text) = match &args.config {
        Some(p) => (
            p.clone(),
            std::fs::read_to_string(p).map_err(|e| paper_checks::Error::io(p, e)),
        ),
        None => {
            let name = if args.full { "full" } else { "quick" };
            (
                PathBuf::from(format!("configs/{name}.toml")),
                Ok(committed_text(name)
                    .expect("a committed profile")
                    .to_string()),
            )
        }
    };
    let start = std::time::Instant::now();
    let result = text.and_then(|text| {
            let mut p = Profile::from_toml(&text, &path)?;
            if let Some(t) = &args.theory {
                p.theory_profile = *t;
            }
            let mode = match (&args.command, args.shard) {
                (Some(Command::Merge | Command::Theory), Some(s)) => {
                    return Err(paper_checks::Error::experiment(
                        "--shard",
                        format!("a shard's option; `merge` and `theory` take none (got {s})"),
                    ));
                }
                (Some(Command::Merge), None) => Mode::Merge,
                (Some(Command::Theory), None) => Mode::All,
                (None, Some(s)) => Mode::Shard(s),
                (None, None) => Mode::All,
            };
            let opts = Options {
                redo: args.redo,
                progress: !args.quiet,
                mode,
                ..Options::new(args.out.clone())
            };
            if mode == Mode::Merge && args.redo {
                return Err(paper_checks::Error::experiment(
                    "merge",
                    "--redo would recompute, and a merge computes nothing",
                ));
            }
            if matches!(args.command, Some(Command::Theory)) {
                use paper_checks::pipeline::TheoryJob;
                let store = args.out.join("runs").join("theory.json");
                return Ok(match paper_checks::pipeline::run_theory(&p, &opts)? {
                    TheoryJob::Computed => format!(
                        "theory: computed the theorem table in {:.1} s into {}",
                        start.elapsed().as_secs_f64(),
                        store.display()
                    ),
                    TheoryJob::Stored => format!(
                        "theory: {} already holds this profile's theorem table",
                        store.display()
                    ),
                    TheoryJob::NotRun => "theory: the profile runs no theorem table (theory_profile = \"none\")".to_string(),
                });
            }
            if let Mode::Shard(s) = mode {
                let r = paper_checks::pipeline::run_shard(&p, &opts)?;
                return Ok(format!(
                    "shard {s}: computed {} units in {:.1} s; {}",
                    r.computed,
                    start.elapsed().as_secs_f64(),
                    if r.complete {
                        "every unit of the profile is stored: run `paper-checks merge`"
                    } else if r.tuning_complete && !r.theory_stored {
                        "this shard's report runs are stored; merge when every shard and the theory job (`paper-checks theory`) have finished"
                    } else if r.tuning_complete {
                        "this shard's report runs are stored; merge when every shard has finished"
                    } else {
                        "the tuning needs units of other shards or of the next rung: run this shard again when the other shards have finished this pass"
                    }
                ));
            }
            let r = paper_checks::regenerate(&p, &path, &text, &opts, !args.no_png)?;
            Ok(format!(
                "computed {} configurations in {:.1} s; output in {}",
                r.computed.len(),
                start.elapsed().as_secs_f64(),
                args.out.display()
            ))
        });
    match result {
        Ok(msg) => {
            eprintln!("{msg}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
