//! [`Setting`]: the exact inputs of Algorithm 5 for one candidate of the search, which the walk
//! over the blocks' paths reads.

use ilopt::algo::o2nc::O2ncParameters;
use ilopt::scalar::BigRational;

/// The exact inputs of Algorithm 5 for a candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// Δ₀ = F(θ₁).
    pub delta0: BigRational,
    /// δ = xΔ₀/(GN).
    pub delta: BigRational,
    /// G.
    pub g: BigRational,
    /// T, K, M and D, from the kit's
    /// [`O2ncConfig::parameters`](ilopt::algo::o2nc::O2ncConfig::parameters).
    pub params: O2ncParameters,
}
