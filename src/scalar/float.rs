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
            fn from_binary64(x: f64) -> Option<Self> {
                x.is_finite().then_some(x as $t)
            }
            #[inline]
            fn certain_cmp(&self, other: &Self) -> Option<Ordering> {
                self.partial_cmp(other)
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
