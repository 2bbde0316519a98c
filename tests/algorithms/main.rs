//! The algorithms of the thesis run end to end: exact unit steps, the toy MDP M1, seeded runs against stored references, and the linear-quadratic-Gaussian toy.
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

#[path = "../common/mod.rs"]
mod common;

#[path = "../common/fixture.rs"]
mod fixture;

mod algo_m1;
mod algo_runs;
mod algo_units;
mod lqg;
