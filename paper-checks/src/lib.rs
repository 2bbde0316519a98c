//! `paper-checks`: regenerates the thesis's chapter 4 (Figs. 4.2–4.10, Tables 4.1–4.4) with many
//! seeds and 95% confidence intervals, next to the thesis's own numbers, plus the theorem-check
//! table of `ilopt-theory` and the errata table, as a reproducible appendix (Markdown, LaTeX,
//! SVG/PNG figures, per-seed CSV/JSON, provenance).
//!
//! The binary (`cargo run --release -p paper-checks`) reads a committed TOML profile
//! ([`config::Profile`]), selects every row's hyper-parameters by the pre-registered [`protocol`]
//! protocol (grids on tuning seeds disjoint from the report seeds), runs the [`experiment`]s
//! through the [`pipeline`] (budgets in gradient calls, sustained convergence, diverged runs as
//! data; seeds in parallel, results independent of the thread count, finished configurations
//! reused) and writes the [`report`].

pub mod build_info;
pub mod config;
pub mod error;
pub mod experiment;
pub mod gradient_error;
pub mod grid;
pub mod naming;
pub mod pipeline;
pub mod progress;
pub mod protocol;
pub mod provenance;
pub mod report;
pub mod results;
pub mod shard;
pub mod stats;
pub mod storage;
pub mod storm_stability;
pub mod verdict;

pub use error::Error;

use std::path::Path;

/// Run the whole appendix: load nothing, run the pipeline for `profile`, write data, figures,
/// reports and provenance into `opts.out`. Returns the results.
///
/// # Errors
/// Any failure of the pipeline, the report or the provenance.
pub fn regenerate(
    profile: &config::Profile,
    profile_file: &Path,
    profile_text: &str,
    opts: &pipeline::Options,
    png: bool,
) -> Result<results::Results, Error> {
    let start = std::time::Instant::now();
    let r = pipeline::run(profile, opts)?;
    let stages = progress::Progress::new(0, opts.progress);
    stages.stage("figures and documents", || {
        report::write(profile, &r, &opts.out, png)
    })?;
    stages.finish();
    provenance::write(
        profile,
        profile_file,
        profile_text,
        &r,
        opts,
        start.elapsed().as_secs_f64(),
    )?;
    Ok(r)
}
