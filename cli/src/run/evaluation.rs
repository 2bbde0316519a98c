//! The seeds of `ilopt run`'s evaluation episodes: episode j of a seed's evaluation draws from an
//! RNG seeded by (seed, j) only ([`episode_seed`]), so every checkpoint of a run meets the same
//! episodes (common random numbers). The evaluation itself (the policy's deterministic action on
//! those episodes, a toy MDP's exact objective) is the kit's
//! [`TaskLearner::evaluate`](ilopt::evaluate::builtin::TaskLearner::evaluate).

pub use ilopt::evaluate::Evaluation;
use ilopt::seeding::splitmix64;

/// The RNG seed of evaluation episode `j` of `seed` (SplitMix64 of both, with a tag that keeps
/// it apart from the run's own seed).
pub fn episode_seed(seed: u64, j: u64) -> u64 {
    splitmix64(splitmix64(seed ^ 0x6576_616c_7561_7465) ^ j)
}
