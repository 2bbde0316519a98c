//! The gradient oracle of eq. 3.15 and its variants: every route against one reference (`routes` in `f64`, bit for bit where a route sums in the reference's order; `route_scalars` in exact rationals, intervals, f32 and duals), Monte-Carlo unbiasedness, golden hashes, sampling laws, task problems, the hand-specialised yardstick, baselines (the leave-one-out fast route against the reference), minibatches, the fixed-horizon objective and the trajectory loss.
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

#[path = "../common/mod.rs"]
mod common;

mod baselines;
mod batched;
mod estimated_baseline;
mod fixed_horizon;
mod leave_one_out;
mod oracle_monte_carlo;
mod oracle_reference;
mod oracle_sampling;
mod route_scalars;
mod routes;
mod specialised;
mod task_problems;
mod trajectory_loss;
