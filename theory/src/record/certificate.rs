//! The data of a rigorous supremum bound: the certificate a branch-and-bound leaves (a partition
//! of the domain with an enclosure of the function on each box) and, for a constant bounded over
//! all of ℝ or ℝ², one certificate per chart region. Plain records: the search that produces them
//! is [`crate::certify`].

use serde::{Deserialize, Serialize};

/// One box of the final partition and the enclosure of f on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CertifiedBox {
    /// [lo, hi] per dimension.
    pub bounds: Vec<[f64; 2]>,
    /// [inf, sup] of the enclosure of f on the box.
    pub enclosure: [f64; 2],
}

/// A rigorous upper bound with its certificate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SupBound {
    /// Upper bound on the supremum (max of the boxes' enclosure sups).
    pub upper: f64,
    /// A value f attains (certified lower end of an enclosure at a point): sup f ≥ lower.
    pub lower: f64,
    /// The partition of the domain with enclosures.
    pub certificate: Vec<CertifiedBox>,
}

/// A chart of ℝ ∪ {∞} (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Chart {
    /// θ ∈ [−R, R].
    Core,
    /// θ = 1/u, u ∈ [−1/R, 1/R].
    Tail,
}

/// The core radius R (a power of two, so 1/R is exact).
pub const CORE_RADIUS: f64 = 4.0;

impl Chart {
    /// The chart's coordinate domain.
    pub fn domain(self) -> [f64; 2] {
        match self {
            Chart::Core => [-CORE_RADIUS, CORE_RADIUS],
            Chart::Tail => [-1.0 / CORE_RADIUS, 1.0 / CORE_RADIUS],
        }
    }
}

/// A supremum bound on one region (a product of charts), with its branch-and-bound certificate in
/// the charts' coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChartBound {
    /// The chart of each coordinate.
    pub charts: Vec<Chart>,
    /// The region in chart coordinates.
    pub domain: Vec<[f64; 2]>,
    /// The bound and its partition.
    pub bound: SupBound,
}
