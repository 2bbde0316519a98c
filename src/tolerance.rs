//! The kit's one tolerance policy (conventions.md 12): how a value computed in scalar `S` is judged
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
        x.is_finite() && (x - e).abs() <= e.abs() * F32_REL + F32_ABS
    }
}

/// The relative part, 2⁻¹⁰, of the `f32` rule above: a smoke check (see the table for why).
pub const F32_REL: f64 = 9.765_625e-4; // 2^-10

/// The absolute part, 2⁻²⁰, of the `f32` rule above, for exact values at or near zero.
pub const F32_ABS: f64 = 9.536_743_164_062_5e-7; // 2^-20

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

/// Relative tolerance for comparing two `f64` evaluations of the same derivative by different
/// routes: an analytic gradient (hand-derived formula, back-propagation) against forward-mode
/// [`Dual<f64>`] derivatives of the value code. Used by [`derivative_f64_agrees`].
///
/// Why 2⁻³⁰ (≈ 9.3·10⁻¹⁰) is justified. Neither route is exact and they round differently, so
/// the interval rule above does not apply. Each route is a straight-line program of at most a few
/// hundred operations on the domains tested (≤ 4 features, ≤ 6 hidden units, ≤ 4 actions,
/// |θ|, |φ| ≤ 4), each with relative error ≤ u = 2⁻⁵³ (`exp`/`ln` within 1 ulp). Standard
/// forward error analysis bounds each route's error by about `k·u·Σ|terms|` with k ≲ 2⁹, and
/// the intermediate terms (probabilities in [0, 1], tanh in [−1, 1], weights and features ≤ 4,
/// exponentials of shifted logits ≤ 1) are at most about 2⁸ times the scale
/// `1 + max(‖a‖∞, ‖b‖∞)` by which [`derivative_f64_error`] divides. That gives ≈ 2⁻³⁶; the
/// constant adds a factor 2⁶ of margin. It is still far below any error a wrong formula makes
/// (a missing term changes the gradient by O(1) of the scale), and the test suite measures the
/// largest observed error and requires it to be at least 2⁸ below this constant. The two sides of
/// a field law evaluated in `f64` (the scalar-law tests) are two such routes to one value, on
/// operands bounded so that the same analysis applies.
pub const DERIVATIVE_F64_REL: f64 = 9.313_225_746_154_785e-10; // 2^-30

/// The scaled disagreement `max_j |a_j − b_j| / (1 + max(‖a‖∞, ‖b‖∞))` of two `f64` gradients;
/// `+∞` if the lengths differ or a value is not finite.
pub fn derivative_f64_error(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() || !a.iter().chain(b).all(|x| x.is_finite()) {
        return f64::INFINITY;
    }
    let scale = 1.0 + a.iter().chain(b).fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// Do two `f64` evaluations of one gradient agree within [`DERIVATIVE_F64_REL`]?
pub fn derivative_f64_agrees(a: &[f64], b: &[f64]) -> bool {
    derivative_f64_error(a, b) <= DERIVATIVE_F64_REL
}
