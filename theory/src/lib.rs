//! # ilopt-theory — the thesis's results as code
//!
//! Each bound is a function of its constants ([`bounds`]); each constant is computed exactly or
//! bounded rigorously, and says which ([`certify`]); each check runs the kit's algorithms over
//! many seeded runs and decides with a stated false-alarm probability ([`stats`]). Errata of the
//! thesis are checked as stated and as corrected (math.md, errata table).
//!
//! The table's rows are built in [`checks`] under the sizes of [`protocol`], assembled by
//! [`suite`] and rendered by [`report`]; the rows, constants and certificates are plain records
//! ([`record`]).
#![warn(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod bounds;
pub mod certify;
pub mod checks;
pub mod input_rows;
pub mod inputs;
pub mod perturbation;
pub mod protocol;
pub mod record;
pub mod report;
pub mod reuse;
pub mod schedule;
pub mod stage;
pub mod stats;
pub mod suite;

/// The table's row records ([`record::check`]).
pub mod check {
    pub use crate::record::check::{
        Check, CheckBuilder, Expected, Measured, Method, Role, Verdict,
    };
}

/// The constant records ([`record::constant`]).
pub mod constants {
    pub use crate::record::constant::{Constant, Provenance};
}
