//! `f64` and `f32`: the fast scalars of the experiments.

use super::{BigRational, DOT_LANES, Real, Scalar, Sqrt};
use num_traits::ToPrimitive;
use std::cmp::Ordering;

/// The floats' [`Scalar::dot_slices`] from [`super::DOT_LANES_FROM`] terms on: [`DOT_LANES`]
/// partial sums over the chunks, added pairwise ((0+1) + (2+3), …), then the tail added left to
/// right. Out of line so that the short products, the common case in the roll-outs, stay inlined
/// at their call sites.
#[inline(never)]
fn dot_in_lanes<T>(x: &[T], y: &[T]) -> T
where
    T: Copy + Default + std::ops::Add<Output = T> + std::ops::Mul<Output = T> + std::ops::AddAssign,
{
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &y[..n]);
    let mut acc = [T::default(); DOT_LANES];
    for (cx, cy) in x.chunks_exact(DOT_LANES).zip(y.chunks_exact(DOT_LANES)) {
        for l in 0..DOT_LANES {
            acc[l] += cx[l] * cy[l];
        }
    }
    let full = n - n % DOT_LANES;
    let tail = x[full..]
        .iter()
        .zip(&y[full..])
        .fold(T::default(), |acc, (&a, &b)| acc + a * b);
    let mut width = DOT_LANES;
    while width > 1 {
        width /= 2;
        for l in 0..width {
            acc[l] += acc[l + width];
        }
    }
    acc[0] + tail
}

macro_rules! impl_float {
    ($t:ty) => {
        impl Scalar for $t {
            const NON_FINITE_PROPAGATES: bool = true;
            const IS_BINARY64: bool = <$t>::MANTISSA_DIGITS == f64::MANTISSA_DIGITS;
            #[inline]
            fn zero() -> Self {
                0.0
            }
            #[inline]
            fn one() -> Self {
                1.0
            }
            #[inline]
            fn from_ratio(num: i64, den: i64) -> Self {
                assert!(den != 0, "from_ratio: zero denominator");
                const EXACT: u64 = 1 << 53;
                if num.unsigned_abs() <= EXACT && den.unsigned_abs() <= EXACT {
                    // Both operands are exact doubles, so IEEE division rounds the true quotient once.
                    return (num as f64 / den as f64) as $t;
                }
                Self::from_rational(&BigRational::new(num.into(), den.into()))
            }
            #[inline]
            fn from_rational(q: &BigRational) -> Self {
                // num-rational's to_f64 is correctly rounded for large numerators/denominators too.
                ToPrimitive::to_f64(q).unwrap_or(f64::NAN) as $t
            }
            #[inline]
            fn to_f64(&self) -> f64 {
                f64::from(*self)
            }
            #[inline]
            fn bit_key(&self) -> Option<u64> {
                Some(f64::from(*self).to_bits())
            }
            #[inline]
            fn from_binary64(x: f64) -> Option<Self> {
                x.is_finite().then_some(x as $t)
            }
            #[inline]
            fn certain_cmp(&self, other: &Self) -> Option<Ordering> {
                self.partial_cmp(other)
            }
            #[inline]
            fn positive_when_certain(&self) -> Option<bool> {
                if self.is_nan() {
                    None
                } else {
                    Some(*self > 0.0)
                }
            }
            #[inline]
            fn is_finite(&self) -> bool {
                <$t>::is_finite(*self)
            }
            #[inline]
            fn dot_slices(x: &[Self], y: &[Self]) -> Self {
                use super::DOT_LANES_FROM;
                let n = x.len().min(y.len());
                let (x, y) = (&x[..n], &y[..n]);
                if n < DOT_LANES_FROM {
                    return x.iter().zip(y).fold(0.0, |acc, (a, b)| acc + a * b);
                }
                dot_in_lanes(x, y)
            }
        }

        impl Sqrt for $t {
            #[inline]
            fn sqrt(&self) -> Self {
                <$t>::sqrt(*self)
            }
        }

        impl Real for $t {
            #[inline]
            fn exp(&self) -> Self {
                <$t>::exp(*self)
            }
            #[inline]
            fn ln(&self) -> Self {
                <$t>::ln(*self)
            }
            #[inline]
            fn sin(&self) -> Self {
                <$t>::sin(*self)
            }
            #[inline]
            fn cos(&self) -> Self {
                <$t>::cos(*self)
            }
        }
    };
}

impl_float!(f64);
impl_float!(f32);

#[cfg(test)]
mod tests {
    use super::*;

    /// The floats' `positive_when_certain` against `partial_cmp` with 0 on the special values
    /// (NaN, ±∞, ±0, the smallest subnormals and normals) in both widths.
    #[test]
    fn positive_when_certain_is_partial_cmp_with_zero() {
        fn check<T: Scalar + PartialOrd + Copy + std::fmt::Debug>(values: &[T]) {
            for x in values {
                let expected = x.partial_cmp(&T::zero()).map(|o| o == Ordering::Greater);
                assert_eq!(x.positive_when_certain(), expected, "at {x:?}");
            }
        }
        let f64s = [
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            f64::MIN,
        ];
        check(&f64s);
        check(&f64s.map(|x| x as f32));
    }

    /// `scalar::powi` against the standard library's `f64::powi` (bit for bit, over exponents
    /// from 0 to 10⁵ and bases of every magnitude), and in exact rationals against the product
    /// of n factors.
    #[test]
    fn powi_is_f64_powi_bit_for_bit_and_exact_in_rationals() {
        use crate::scalar::powi;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for _ in 0..2000 {
            let x: f64 = rng.random_range(-2.0..2.0) * 10f64.powi(rng.random_range(-3..4));
            let n: u32 = if rng.random_bool(0.5) {
                rng.random_range(0..64)
            } else {
                rng.random_range(0..100_000)
            };
            let std = x.powi(i32::try_from(n).unwrap());
            assert_eq!(powi(&x, n).to_bits(), std.to_bits(), "{x}^{n}");
        }
        // Adam's β's at a run-time step count (a compile-time exponent may be folded by
        // another route: `0.9f64.powi(7)` written with literals differs in the last bit).
        for (b1, t) in [(0.9f64, 7u32), (0.999, 4000)] {
            let t = std::hint::black_box(t);
            assert_eq!(powi(&b1, t).to_bits(), f64::powi(b1, t as i32).to_bits());
        }
        let q = BigRational::new((-7).into(), 5.into());
        for n in 0..40u32 {
            let product = (0..n).fold(BigRational::from_integer(1.into()), |acc, _| acc * &q);
            assert_eq!(powi(&q, n), product, "n = {n}");
        }
    }

    #[test]
    fn ratios_round_correctly() {
        assert_eq!(f64::from_ratio(1, 3), 1.0 / 3.0);
        assert_eq!(f32::from_ratio(-7, 2), -3.5);
        assert_eq!(f64::from_ratio(i64::MAX, 1), i64::MAX as f64);
    }

    #[test]
    fn nan_is_not_ordered() {
        assert_eq!(f64::NAN.certain_cmp(&0.0), None);
        assert!(!Scalar::is_finite(&f64::INFINITY));
    }
}
