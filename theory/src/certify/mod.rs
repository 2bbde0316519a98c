//! Rigorous constants and their certificates (math.md §7.1): the interval branch-and-bound
//! ([`bnb`]) and the exact tiling check of its partitions ([`tiling`]); the constants on a box
//! ([`box_constants`]); the two charts of ℝ ∪ {∞} ([`charts`]) over which the constants of
//! [`global`] hold on all of ℝ (ℝ² for the (A4) curvature of [`v_is`]), and those of the
//! baselined estimator in [`global_baselined`]; and the independent
//! second route that re-evaluates every certificate box by box ([`recheck`]).

pub mod bnb;
pub mod box_constants;
pub mod charts;
pub mod global;
pub mod global_baselined;
pub mod recheck;
pub mod tiling;
pub mod v_is;
