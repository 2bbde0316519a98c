//! Hostile input: property tests over malformed input, and the fuzzers' regressions (the command
//! line's contracts and errors are tested in `cli/tests/commands`).
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

#[path = "../../fuzz/src/props/mod.rs"]
mod props;

mod fuzz_regressions;
mod hostile_input;
