//! The properties checked by the fuzz targets, shared word for word with the proptest suites
//! (`tests/inputs/hostile_input.rs`) and the regression tests (`tests/inputs/fuzz_regressions.rs`), which include
//! this module with `#[path = "../../fuzz/src/props/mod.rs"] mod props;`.
//!
//! Every `check_*` function panics (a fuzzer "crash") exactly when a property is violated; a clean
//! error from the library is never a violation. The inputs are plain structs so that the fuzz crate
//! can implement `arbitrary::Arbitrary` for them and the proptest suites can build them from
//! strategies; they only need `ilopt`'s own dependencies.
#![allow(dead_code)]

mod cartpole;
mod config;
mod differential;
mod oracle;
mod toy;
mod vo;

pub use cartpole::*;
pub use config::*;
pub use differential::*;
pub use oracle::*;
pub use toy::*;
pub use vo::*;
