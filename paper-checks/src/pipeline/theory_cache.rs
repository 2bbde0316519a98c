//! The cached theorem table and its renderings beside the appendix.

use crate::error::Error;
use crate::storage::{to_json, write_atomic};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The cached theorem table (`runs/theory.json`): the check records and the key they were
/// computed under.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TheoryCache {
    /// The cache key of the profile's theorem table and of the code that computed the checks.
    pub key_hash: String,
    /// Every check of the table, in table order.
    pub checks: Vec<ilopt_theory::check::Check>,
}

/// Write `ilopt-theory`'s renderings of `checks` beside the appendix: its Markdown table
/// (`theory.md`) and its JSON report (`theory.json`).
pub(super) fn write_theory_copies(
    markdown_file: &Path,
    json_file: &Path,
    checks: &[ilopt_theory::check::Check],
) -> Result<(), Error> {
    write_atomic(
        json_file,
        &to_json("theory", &ilopt_theory::report::json(checks))?,
    )?;
    write_atomic(
        markdown_file,
        ilopt_theory::report::markdown(checks).as_bytes(),
    )
}
