//! The `ilopt` command line: each subcommand's output, contracts and errors, run as the binary
//! (`CARGO_BIN_EXE_ilopt`) or through `ilopt_cli`.
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

/// The repository root, where `examples/` and `experts/` are: the paths in the docs are relative
/// to it.
pub const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

mod env;
mod expert;
mod hostile;
mod jobs;
mod plot;
mod plugin;
mod run;
mod support;
mod toy;
