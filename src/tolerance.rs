//! The kit's one tolerance policy (STYLE.md 12): how a value computed in scalar `S` is judged
//! against the exact value of the same quantity.
//!
//! | scalar | passes when | why this is justified |
//! |---|---|---|
//! | `BigRational` | equal to the exact value | no rounding at all |
//! | `Interval` | the enclosure contains the exact value | outward rounding makes this a theorem |
//! | `f64` | lies inside the interval computed by the **same code** | every f64 operation rounds to nearest, which lies between the outward-rounded bounds of the same interval operation, so by induction the f64 result is inside; no tolerance is chosen |
//! | `f32` | within relative error 2⁻¹⁰ (plus absolute 2⁻²⁰) of the exact value | a smoke check: f32 is used only for speed, and the small problems here chain at most a few hundred operations of relative error 2⁻²⁴ each |
//! | `Dual<S>` | its value part passes for `S` | derivatives are checked separately |
//!
//! The f64 rule needs identical operation sequences and correctly rounded elementary functions;
//! the kit's generic code guarantees the first, and the toy engine uses only field operations.

use crate::scalar::{BigRational, Dual, Interval, Scalar, interval_contains_rational};

/// A scalar whose computed value can be judged against the exact one.
pub trait Agreement: Scalar {
    /// Does `self` agree with `exact`, given `enclosure` (the same computation in intervals)?
    fn agrees(&self, exact: &BigRational, enclosure: &Interval) -> bool;
}

impl Agreement for BigRational {
    fn agrees(&self, exact: &BigRational, _enclosure: &Interval) -> bool {
        self == exact
    }
}

impl Agreement for Interval {
    fn agrees(&self, exact: &BigRational, _enclosure: &Interval) -> bool {
        interval_contains_rational(*self, exact)
    }
}

impl Agreement for f64 {
    fn agrees(&self, _exact: &BigRational, enclosure: &Interval) -> bool {
        self.is_finite() && enclosure.contains(*self)
    }
}

impl Agreement for f32 {
    fn agrees(&self, exact: &BigRational, _enclosure: &Interval) -> bool {
        let e = Scalar::to_f64(exact);
        let x = f64::from(*self);
        x.is_finite() && (x - e).abs() <= e.abs() * 2f64.powi(-10) + 2f64.powi(-20)
    }
}

impl<S: Agreement> Agreement for Dual<S> {
    fn agrees(&self, exact: &BigRational, enclosure: &Interval) -> bool {
        self.value().agrees(exact, enclosure)
    }
}

/// Element-wise [`Agreement`] of vectors of equal length.
pub fn all_agree<S: Agreement>(xs: &[S], exact: &[BigRational], enclosure: &[Interval]) -> bool {
    xs.len() == exact.len()
        && xs.len() == enclosure.len()
        && xs
            .iter()
            .zip(exact)
            .zip(enclosure)
            .all(|((x, e), i)| x.agrees(e, i))
}
