//! The appendix: aggregated tables (kit vs thesis), claim verdicts, figures, CSV/JSON data, the
//! theorem-check and errata tables, Markdown and LaTeX.
//!
//! Confidence intervals are Student-t 95% intervals over seeds ([`crate::stats::Summary`]).
//! Verdicts are computed from the numbers by the rules stated next to each claim; nothing is
//! tuned.

use crate::config::Profile;
use crate::error::Error;
use crate::results::Results;
use std::path::Path;

pub mod aggregate;
pub mod beyond;
pub mod blocks;
pub mod claims;
pub mod data;
pub mod document;
pub mod figures;
pub mod protocol_section;
pub mod sensitivity;
pub mod speedup;
pub mod storm_divergence;
pub mod tex;
pub mod theory;
pub mod thesis;

pub use crate::verdict::Verdict;
pub use aggregate::{ConvergenceRow, num};
pub use claims::Claim;
pub use document::latex_standalone;
pub use thesis::{ERRATA, THESIS_T41, THESIS_T42, THESIS_T43, THESIS_T44};

/// Write everything: CSV/JSON data, figures, `appendix.md` and `appendix.tex`.
///
/// # Errors
/// I/O, serialisation or plotting failures.
pub fn write(profile: &Profile, r: &Results, out: &Path, png: bool) -> Result<(), Error> {
    let fig_dir = out.join("figures");
    std::fs::create_dir_all(&fig_dir).map_err(|e| Error::io(&fig_dir, e))?;
    data::write_per_seed(r, out)?;
    let obs: Vec<ConvergenceRow> = r
        .obstacle
        .iter()
        .map(|c| aggregate::convergence_row(&c.0))
        .collect();
    let cp: Vec<ConvergenceRow> = r
        .cartpole
        .iter()
        .map(|c| aggregate::convergence_row(&c.0))
        .collect();
    let cl = claims::claims(r, profile);
    let tcl = claims::timing_claims(r, profile);
    data::write_tables(out, &obs, &cp, &cl)?;
    let figs = figures::figures(profile, r);
    let png_ok = figures::write_figures(&figs, &fig_dir, png)?;
    let machine = crate::provenance::Machine::current();
    let blocks = document::document(&document::Inputs {
        profile,
        results: r,
        obstacle_rows: &obs,
        cartpole_rows: &cp,
        claims: &cl,
        timing_claims: &tcl,
        figures: &figs,
        png: png_ok,
        machine: &machine,
    });
    let sensitivity = sensitivity::write(r, &fig_dir, png_ok)?;
    let mut blocks = blocks;
    let at = blocks
        .iter()
        .position(|b| matches!(b, blocks::Block::Table(t) if t.label == "tab:pc-sensitivity"))
        .map_or(blocks.len(), |i| i + 1);
    let mut inserted = sensitivity;
    inserted.extend(storm_divergence::blocks());
    blocks.splice(at..at, inserted);
    crate::storage::write_atomic(
        &out.join("results.md"),
        document::results_page(&cl, &tcl).as_bytes(),
    )?;
    document::write_documents(&blocks, out)
}
