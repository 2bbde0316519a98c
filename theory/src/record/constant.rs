//! A constant of a bound with its value, its exact rational form and how it was obtained (exact,
//! rigorous with a certificate, or estimated), math.md §7.1.

use crate::record::certificate::{ChartBound, SupBound};
use ilopt::scalar::{BigRational, Scalar};
use serde::{Deserialize, Serialize};

/// How a constant was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Provenance {
    /// Computed exactly in rationals.
    Exact,
    /// A rigorous upper bound (interval branch-and-bound; certificate attached).
    Rigorous,
    /// A statistical or sampled estimate — never a certificate.
    Estimate,
}

/// A named constant with its value and provenance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Constant {
    /// Name as in math.md (L_F, σ², …).
    pub name: String,
    /// The value used by the bound (an upper bound unless exact).
    pub value: f64,
    /// The same value as an exact rational string (the f64 above is exactly this rational).
    pub rational: String,
    /// Exact, rigorous or estimate.
    pub provenance: Provenance,
    /// How it was obtained (domain, tolerance, boxes).
    pub how: String,
    /// The branch-and-bound certificate, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certificate: Option<SupBound>,
    /// For a constant bounded over all of ℝ^d: one certificate per chart region
    /// ([`crate::certify::global`]); empty otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub charts: Vec<ChartBound>,
    /// For a rigorous constant: the largest value of the quantity actually attained at a point the
    /// branch-and-bound evaluated, in the constant's own units (e.g. `√ sup ‖g‖²` for G_∞, not the
    /// squared quantity the search bounds). It is a lower bound on the true supremum, so
    /// `attained ≤ value` and the gap shows how tight the bound is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attained: Option<f64>,
}

/// The exact rational an `f64` is, as text (`inf` for a non-finite value).
fn rational_form(value: f64) -> String {
    BigRational::from_float(value).map_or_else(|| "inf".into(), |q| q.to_string())
}

impl Provenance {
    /// The certificate kind as the tables print it.
    pub fn name(self) -> &'static str {
        match self {
            Provenance::Exact => "exact",
            Provenance::Rigorous => "rigorous upper bound",
            Provenance::Estimate => "ESTIMATE (not a certificate)",
        }
    }
}

impl Constant {
    /// An exact rational constant.
    pub fn exact(name: &str, q: &BigRational, how: &str) -> Self {
        Self {
            name: name.into(),
            value: Scalar::to_f64(q),
            rational: q.to_string(),
            provenance: Provenance::Exact,
            how: how.into(),
            certificate: None,
            charts: vec![],
            attained: None,
        }
    }
    /// A rigorous upper bound `value` from one branch-and-bound certificate; `transform` maps the
    /// supremum of the enclosed function to the constant (e.g. a square root) and gives the
    /// attained value from the certificate's best lower value.
    pub fn rigorous(
        name: &str,
        bound: SupBound,
        value: f64,
        transform: impl Fn(f64) -> f64,
        how: String,
    ) -> Self {
        let attained = Some(transform(bound.lower));
        Self {
            name: name.into(),
            value,
            rational: rational_form(value),
            provenance: Provenance::Rigorous,
            how,
            certificate: Some(bound),
            charts: vec![],
            attained,
        }
    }
    /// A rigorous upper bound `value` over all of ℝ (ℝ²) with one certificate per chart region
    /// ([`ChartBound`]); `attained` is the largest value of the quantity at a point the
    /// branch-and-bound evaluated, in the constant's units.
    pub fn over_charts(
        name: &str,
        value: f64,
        how: String,
        regions: Vec<ChartBound>,
        attained: f64,
    ) -> Self {
        Self {
            name: name.into(),
            value,
            rational: rational_form(value),
            provenance: Provenance::Rigorous,
            how,
            certificate: None,
            charts: regions,
            attained: Some(attained),
        }
    }
    /// A statistical or sampled estimate: no exact rational form, never a certificate.
    pub fn estimate(name: &str, value: f64, how: String) -> Self {
        Self {
            name: name.into(),
            value,
            rational: "—".into(),
            provenance: Provenance::Estimate,
            how,
            certificate: None,
            charts: vec![],
            attained: None,
        }
    }
}
