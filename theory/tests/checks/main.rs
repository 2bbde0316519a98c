//! The theory crate's tests, one binary: each module is a family of checks of the table.

mod baselined_storm;
mod certificates;
mod common;
mod exact_checks;
mod l_tilde;
mod mc_checks;
mod power;
mod real_env;
mod real_env_explore;
mod storm_checks;
mod tracking;
