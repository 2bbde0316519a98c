//! Hostile input: the command line's contracts and errors, property tests over malformed input, and the fuzzers' regressions.
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

#[path = "../../fuzz/src/props/mod.rs"]
mod props;

mod cli_env;
mod cli_hostile;
mod cli_run;
mod cli_toy;
mod fuzz_regressions;
mod hostile_input;
