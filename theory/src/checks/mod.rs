//! The checks of the theorem table, each a function returning [`crate::record::check::Check`] rows.

pub mod attained;
pub mod baselined_sgd;
pub mod baselined_storm;
pub mod constants;
pub mod errata;
pub mod estimated;
pub mod montecarlo;
pub mod o2nc_formula;
pub mod proof_o2nc;
pub mod proof_sgd;
pub mod proof_step;
pub mod proof_storm;
pub mod real_env;
pub mod schedule;
pub mod second_toy;
pub mod statistical;
pub mod storm;
pub mod storm_stability;
pub mod thm31;
pub mod tight;
pub mod tracking;
pub mod unbiased;
pub mod unchecked;
