//! `paper-checks`: regenerate the thesis's chapter 4 as a reproducible appendix.
use clap::Parser;
use paper_checks::config::Profile;
use paper_checks::pipeline::Options;
use std::path::PathBuf;
use std::process::ExitCode;

/// Regenerate Tables 4.1–4.4 and Figures 4.2–4.10 of the thesis, with the theorem-check and
/// errata tables, into one directory.
#[derive(Debug, Parser)]
#[command(name = "paper-checks", version)]
struct Args {
    /// Use the thesis-scale profile (`configs/full.toml`) instead of the quick one.
    #[arg(long)]
    full: bool,
    /// Use this profile file instead of the committed ones.
    #[arg(long, value_name = "FILE", conflicts_with = "full")]
    config: Option<PathBuf>,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/appendix")]
    out: PathBuf,
    /// Recompute configurations whose results already exist.
    #[arg(long)]
    redo: bool,
    /// Skip the PNG renderings of the figures (SVG only).
    #[arg(long)]
    no_png: bool,
    /// No progress output.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let path = args.config.clone().unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("configs")
            .join(if args.full { "full.toml" } else { "quick.toml" })
    });
    let start = std::time::Instant::now();
    let result = std::fs::read_to_string(&path)
        .map_err(|e| paper_checks::Error::io(&path, e))
        .and_then(|text| {
            let p = Profile::from_toml(&text, &path)?;
            let opts = Options {
                redo: args.redo,
                progress: !args.quiet,
                ..Options::new(args.out.clone())
            };
            paper_checks::regenerate(&p, &path, &text, &opts, !args.no_png).map(|r| (p, r))
        });
    match result {
        Ok((_p, r)) => {
            eprintln!(
                "computed {} configurations in {:.1} s; output in {}",
                r.computed.len(),
                start.elapsed().as_secs_f64(),
                args.out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
