//! # ilopt — imitation learning as stochastic optimisation, checked
//!
//! A research kit for the thesis *Momentum-Based Variance Reduced Algorithms for Imitation
//! Learning*: the unbiased gradient oracle of eq. 3.15, the exact engine that proves identities in
//! rational arithmetic, and (in later modules) the algorithms, environments and theory checks.
//!
//! Everything numeric is generic over [`scalar::Scalar`], so the same code runs in `f64`/`f32`,
//! exact rationals, interval arithmetic, and dual numbers over any of them.
#![warn(missing_docs)]
// Index loops over states and actions mirror the equations they implement (math.md §1.4).
#![allow(clippy::needless_range_loop)]

pub mod algo;
pub mod baseline;
pub mod batched;
/// Command-line front ends (the `ilopt` binary's subcommands).
pub mod cli;
pub mod env;
pub mod exact;
/// Experts that label states (thesis ch. 4): the CartPole LQR controller and the velocity-obstacle
/// expert of eq. 4.1.
pub mod expert;
pub mod lqg;
pub mod oracle;
pub mod policy;
pub mod problem;
pub mod sampling;
pub mod scalar;
pub mod task;
pub mod tolerance;
pub mod toy;
