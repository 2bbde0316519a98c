//! The environments and experts: CartPole bit-for-bit against Gymnasium, the obstacle task, the velocity-obstacle expert and the PPO expert.
//!
//! One test binary of several modules, so that a fresh `cargo test` links the crate a few times
//! rather than once per file.

mod cartpole;
mod obstacle;
mod ppo;
mod vo_expert;
