//! Identities proved in exact arithmetic and agreement across scalar types: exact identities, STORM's mean linearisation, scalar agreement, the scalar field laws (quickcheck), policy derivatives and features, and the toy-MDP format and termination.
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

#[path = "../common/mod.rs"]
mod common;

mod exact_identities;
mod policy_derivatives;
mod policy_features;
mod scalar_agreement;
mod scalar_laws;
mod storm_stability;
mod toy_format;
mod toy_termination;
