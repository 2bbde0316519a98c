//! The `ilopt` command line's subcommands, one module each: their arguments (clap), the files they
//! read (TOML configs, JSON lines) and what they print (JSON, CSV, progress). What they compute is
//! the core library's (`ilopt`). The binary (`src/main.rs`) parses the command line and dispatches
//! to these modules; errors go to stderr with a non-zero exit status (2 for usage errors, 1 for
//! failures), results to stdout as JSON.

#![warn(missing_docs)]
#![deny(unsafe_code)]

pub mod estimate;
pub mod eval;
pub mod expert;
pub mod plot;
pub mod provenance;
pub mod replay;
pub mod run;
pub mod toy;
