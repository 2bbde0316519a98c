//! # ilopt — imitation learning as stochastic optimisation, checked
//!
//! A research kit for the thesis *Momentum-Based Variance Reduced Algorithms for Imitation
//! Learning*: the unbiased gradient oracle of eq. 3.15, the exact engine that proves identities in
//! rational arithmetic, and (in later modules) the algorithms, environments and theory checks.
//!
//! Everything numeric is generic over [`scalar::Scalar`], so the same code runs in `f64`/`f32`,
//! exact rationals, interval arithmetic, and dual numbers over any of them.
#![warn(missing_docs)]

/// Command-line entry points (`ilopt expert vo`, …).
pub mod cli;
/// Environments (the obstacle-avoidance task of thesis §4.1.1, …).
pub mod env;
/// Experts that label states (the velocity-obstacle expert of thesis eq. 4.1, …).
pub mod expert;
pub mod problem;
pub mod scalar;
