//! inari [`Interval`]s: rigorous enclosures.
//!
//! Every operation returns an interval that contains the exact result for every choice of points in
//! the operands (IEEE 1788 outward rounding). Constants built from integer ratios are enclosed, not
//! rounded: `Interval::from_ratio(1, 3)` is the tightest float interval around 1/3.

use super::{BigRational, Scalar, Sqrt};
use inari::Interval;
use num_bigint::BigInt;
use num_traits::{FromPrimitive, ToPrimitive};
use std::cmp::Ordering;

/// The tightest pair of floats around an integer (a singleton when the integer is a float).
fn enclose_bigint(n: &BigInt) -> Interval {
    let f = n.to_f64().unwrap_or(f64::NAN);
    if f.is_finite() && BigInt::from_f64(f).as_ref() == Some(n) {
        return Interval::try_from((f, f)).expect("finite singleton");
    }
    if f.is_nan() {
        return Interval::ENTIRE;
    }
    // |n| beyond f64::MAX rounds to ±∞; the enclosure then reaches to infinity.
    let lo = if f.is_finite() {
        f.next_down()
    } else if f > 0.0 {
        f64::MAX
    } else {
        f64::NEG_INFINITY
    };
    let hi = if f.is_finite() {
        f.next_up()
    } else if f > 0.0 {
        f64::INFINITY
    } else {
        f64::MIN
    };
    Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE)
}

/// An interval that contains the rational `q` (a singleton when `q` is a float).
pub fn enclose_rational(q: &BigRational) -> Interval {
    enclose_bigint(q.numer()) / enclose_bigint(q.denom())
}

/// Exact test `q ∈ x` (the comparison is done in rationals, so it cannot be fooled by rounding).
pub fn interval_contains_rational(x: Interval, q: &BigRational) -> bool {
    if x.is_empty() {
        return false;
    }
    let above_inf =
        x.inf() == f64::NEG_INFINITY || BigRational::from_float(x.inf()).is_some_and(|lo| lo <= *q);
    let below_sup =
        x.sup() == f64::INFINITY || BigRational::from_float(x.sup()).is_some_and(|hi| *q <= hi);
    above_inf && below_sup
}

impl Scalar for Interval {
    fn zero() -> Self {
        Interval::try_from((0.0, 0.0)).expect("[0, 0]")
    }
    fn one() -> Self {
        Interval::try_from((1.0, 1.0)).expect("[1, 1]")
    }
    fn from_ratio(num: i64, den: i64) -> Self {
        assert!(den != 0, "from_ratio: zero denominator");
        const EXACT: u64 = 1 << 53;
        if num.unsigned_abs() <= EXACT && den.unsigned_abs() <= EXACT {
            let point = |x: i64| Interval::try_from((x as f64, x as f64)).expect("exact point");
            // Outward-rounded division of exact points encloses num/den.
            return point(num) / point(den);
        }
        enclose_rational(&BigRational::new(num.into(), den.into()))
    }
    fn from_rational(q: &BigRational) -> Self {
        enclose_rational(q)
    }
    fn to_f64(&self) -> f64 {
        self.mid()
    }
    /// inari's product, bit for bit, from the endpoint products' FMA residuals where the
    /// endpoints allow (see `interval_product`).
    #[inline]
    fn product(&self, other: &Self) -> Self {
        super::interval_product::mul(*self, *other)
    }
    #[inline]
    fn product_assign(&mut self, other: &Self) {
        *self = super::interval_product::mul(*self, *other);
    }
    fn from_binary64(x: f64) -> Option<Self> {
        if x.is_finite() {
            Interval::try_from((x, x)).ok()
        } else {
            None
        }
    }
    fn certain_cmp(&self, other: &Self) -> Option<Ordering> {
        if self.is_empty() || other.is_empty() {
            None
        } else if self.sup() < other.inf() {
            Some(Ordering::Less)
        } else if self.inf() > other.sup() {
            Some(Ordering::Greater)
        } else if self.is_singleton() && self == other {
            Some(Ordering::Equal)
        } else {
            None
        }
    }
    fn is_finite(&self) -> bool {
        !self.is_empty() && self.inf().is_finite() && self.sup().is_finite()
    }
    /// inari's `sqr`: the tight enclosure of {x² : x ∈ X} (x·x would give [−1, 1]·[−1, 1] = [−1, 1]).
    fn square(&self) -> Self {
        self.sqr()
    }
}

impl Sqrt for Interval {
    fn sqrt(&self) -> Self {
        Interval::sqrt(*self)
    }
}

#[cfg(feature = "mpfr")]
impl super::Real for Interval {
    fn exp(&self) -> Self {
        Interval::exp(*self)
    }
    fn ln(&self) -> Self {
        Interval::ln(*self)
    }
    fn sin(&self) -> Self {
        Interval::sin(*self)
    }
    fn cos(&self) -> Self {
        Interval::cos(*self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thirds_are_enclosed_tightly() {
        let x = Interval::from_ratio(1, 3);
        let q = BigRational::from_ratio(1, 3);
        assert!(interval_contains_rational(x, &q));
        assert!(!x.is_singleton());
        assert_eq!(x.sup().next_down(), x.inf(), "not the tightest enclosure");
        assert!(Interval::from_ratio(1, 4).is_singleton());
    }

    #[test]
    fn huge_integers_are_enclosed() {
        let n = BigInt::from(2u8).pow(80) + 1;
        let x = enclose_bigint(&n);
        assert!(interval_contains_rational(x, &BigRational::from_integer(n)));
    }

    #[test]
    fn straddling_intervals_do_not_compare() {
        let a = Interval::try_from((0.0, 2.0)).unwrap();
        let b = Interval::one();
        assert_eq!(a.certain_cmp(&b), None);
        assert_eq!(Interval::zero().certain_cmp(&b), Some(Ordering::Less));
        assert_eq!(b.certain_cmp(&b), Some(Ordering::Equal));
        assert!(!Scalar::is_finite(&(b / Interval::zero())));
    }

    #[test]
    fn squares_are_tight() {
        let x = Interval::try_from((-2.0, 3.0)).unwrap();
        assert_eq!(x.square(), Interval::try_from((0.0, 9.0)).unwrap());
    }
}
