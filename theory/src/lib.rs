//! # ilopt-theory — the thesis's results as code
//!
//! Each bound is a function of its constants ([`bounds`]); each constant is computed exactly or
//! bounded rigorously, and says which ([`constants`]); each check runs the kit's algorithms over
//! many seeded runs and decides with a stated false-alarm probability ([`stats`]). Errata of the
//! thesis are checked as stated and as corrected (math.md, errata table).
#![warn(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod bnb;
pub mod bounds;
pub mod check;
pub mod checks;
pub mod constants;
pub mod global;
pub mod recheck;
pub mod report;
pub mod schedule;
pub mod stats;
pub mod suite;
