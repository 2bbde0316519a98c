//! [`Roots`]: square and cube roots as a capability that every scalar declares.
//!
//! Every [`super::Scalar`] implements [`Roots`], so generic code bounded by `Scalar` alone can ask
//! for a root; a scalar without roots (exact rationals, and duals over them) declines with
//! `None`. Code that needs roots checks [`Roots::HAS_ROOTS`] once, when it is built, and rejects a
//! configuration it cannot run before the first step.

use super::{BigRational, Dual, Scalar};
use inari::Interval;

/// Square and cube roots, where the scalar has them.
///
/// | scalar | `√x`, `∛x` |
/// |---|---|
/// | `f64`, `f32` | the IEEE square root and the libm cube root |
/// | [`Interval`] | certified enclosures (outward rounding) |
/// | [`Dual<S>`] | the value's root with the chain rule, when `S` has roots |
/// | [`BigRational`] | none: a root of a rational is rarely rational, and an exact computation is never rounded silently |
pub trait Roots: Sized {
    /// Whether [`Roots::try_sqrt`] and [`Roots::try_cbrt`] return a value.
    const HAS_ROOTS: bool;
    /// The principal square root `√x` (an enclosure for intervals); `None` without roots.
    fn try_sqrt(&self) -> Option<Self>;
    /// The real cube root `∛x` (an enclosure for intervals); `None` without roots.
    fn try_cbrt(&self) -> Option<Self>;
}

macro_rules! float_roots {
    ($t:ty) => {
        impl Roots for $t {
            const HAS_ROOTS: bool = true;
            #[inline]
            fn try_sqrt(&self) -> Option<Self> {
                Some(<$t>::sqrt(*self))
            }
            #[inline]
            fn try_cbrt(&self) -> Option<Self> {
                Some(<$t>::cbrt(*self))
            }
        }
    };
}

float_roots!(f64);
float_roots!(f32);

impl Roots for BigRational {
    const HAS_ROOTS: bool = false;
    fn try_sqrt(&self) -> Option<Self> {
        None
    }
    fn try_cbrt(&self) -> Option<Self> {
        None
    }
}

fn point(x: f64) -> Interval {
    Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE)
}

/// A float `c` with `c³ ≤ x` (`lower`) or `c³ ≥ x`, certified by evaluating `c³` in interval
/// arithmetic and stepping one ulp outwards until the bound holds (at most 8 steps, then ∓∞).
fn cbrt_bound(x: f64, lower: bool) -> f64 {
    if !x.is_finite() {
        return x;
    }
    let mut c = x.cbrt();
    for _ in 0..8 {
        let p = point(c);
        let cube = p * p * p;
        if lower && cube.sup() <= x {
            return c;
        }
        if !lower && cube.inf() >= x {
            return c;
        }
        c = if lower { c.next_down() } else { c.next_up() };
    }
    if lower {
        f64::NEG_INFINITY
    } else {
        f64::INFINITY
    }
}

impl Roots for Interval {
    const HAS_ROOTS: bool = true;
    /// inari's square root: the tight enclosure of `{√x : x ∈ self, x ≥ 0}`.
    fn try_sqrt(&self) -> Option<Self> {
        Some(Interval::sqrt(*self))
    }
    /// An enclosure of `{∛x : x ∈ self}`: the cube root is increasing, so certified outward
    /// bounds at the two endpoints suffice.
    fn try_cbrt(&self) -> Option<Self> {
        if self.is_empty() {
            return Some(*self);
        }
        let lo = cbrt_bound(self.inf(), true);
        let hi = cbrt_bound(self.sup(), false);
        Some(Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE))
    }
}

impl<S: Scalar> Roots for Dual<S> {
    const HAS_ROOTS: bool = S::HAS_ROOTS;
    /// `√v` with derivative `g / (2√v)`.
    fn try_sqrt(&self) -> Option<Self> {
        Some(self.sqrt_from(self.value().try_sqrt()?))
    }
    /// `∛v` with derivative `g / (3 ∛v²)`.
    fn try_cbrt(&self) -> Option<Self> {
        let r = self.value().try_cbrt()?;
        let d = S::one() / (S::from_i64(3) * r.square());
        Some(self.chain(r, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rationals_decline_roots() {
        let q = BigRational::from_ratio(4, 1);
        const { assert!(!BigRational::HAS_ROOTS) };
        assert_eq!(q.try_sqrt(), None);
        assert_eq!(q.try_cbrt(), None);
        const { assert!(!<Dual<BigRational>>::HAS_ROOTS) };
        assert!(Dual::variable(q, 0, 1).try_cbrt().is_none());
    }

    #[test]
    fn interval_cube_root_encloses_the_exact_root() {
        for x in [2.0, 3.0, 10.0, 1e-300, 7e300, -5.0] {
            let c = point(x).try_cbrt().unwrap();
            let (lo, hi) = (point(c.inf()), point(c.sup()));
            assert!((lo * lo * lo).sup() <= x, "{x}");
            assert!((hi * hi * hi).inf() >= x, "{x}");
        }
    }

    /// The dual roots against central finite differences of the `f64` roots.
    #[test]
    fn dual_roots_match_finite_differences() {
        let h = 1e-6;
        for x0 in [0.3_f64, 2.0, 17.5] {
            let x = Dual::variable(x0, 0, 1);
            let y = x.clone() * &x + Dual::from_i64(1);
            let f = |t: f64| (t * t + 1.0).sqrt();
            let fd = (f(x0 + h) - f(x0 - h)) / (2.0 * h);
            approx::assert_abs_diff_eq!(y.try_sqrt().unwrap().gradient()[0], fd, epsilon = 1e-7);
            let g = |t: f64| (t * t + 1.0).cbrt();
            let fd = (g(x0 + h) - g(x0 - h)) / (2.0 * h);
            approx::assert_abs_diff_eq!(y.try_cbrt().unwrap().gradient()[0], fd, epsilon = 1e-7);
        }
    }

    /// Over exact-valued duals of intervals the derivative of ∛(x³) = x is enclosed around 1.
    #[test]
    fn dual_cube_root_of_a_cube_has_derivative_one() {
        let x = Dual::variable(point(2.0), 0, 1);
        let c = (x.clone() * &x * &x).try_cbrt().unwrap();
        assert!(c.value().contains(2.0));
        assert!(c.gradient()[0].contains(1.0));
    }
}
