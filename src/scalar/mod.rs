//! The scalar layer: one generic core, many number types (conventions.md, "The spine").
//!
//! Traits are layered like simba/nalgebra, each layer as small as it can be:
//!
//! | trait | adds | implemented for |
//! |---|---|---|
//! | [`Scalar`] | field operations (by value and by reference), exact construction from integer ratios, lossy [`Scalar::to_f64`], *certain* comparison | `f64`, `f32`, [`BigRational`], [`Interval`], [`Dual<S>`] |
//! | [`Roots`] | the capability query [`Roots::HAS_ROOTS`] and `try_sqrt`/`try_cbrt`, which a scalar without roots declines with `None`; a supertrait of [`Scalar`] | every scalar: roots in `f64`, `f32`, [`Interval`] (outward-rounded) and `Dual<S>` when `S` has them; none in [`BigRational`] |
//! | [`Sqrt`] | `sqrt` | `f64`, `f32`, [`Interval`], `Dual<S: Sqrt>` |
//! | [`Real`] | `exp`, `ln`, `sin`, `cos` | `f64`, `f32`, `Dual<S: Real>`, and [`Interval`] with the `mpfr` feature |
//!
//! Rationals are not [`Sqrt`]: a square root of a rational is rarely rational, and the kit never
//! rounds an exact computation silently. [`Roots`] lets code bounded by [`Scalar`] alone use roots
//! where the scalar has them and reject, when it is built, a configuration that needs them where
//! it has not (the algorithms' `AlgoError::NeedsRoots`).
//!
//! Comparison is tri-state ([`Scalar::certain_cmp`]): an interval that straddles a threshold cannot be
//! ordered, and generic code that branches on such a comparison returns [`Undecidable`] instead of
//! guessing (conventions.md 3).

mod config_number;
mod dual;
mod float;
mod interval;
mod interval_product;
mod rational;
mod report;
mod roots;

pub use config_number::{ConfigNumber, NonFiniteNumber};
pub use dual::Dual;
pub use inari::Interval;
pub use interval::{enclose_rational, interval_contains_rational};
pub use num_rational::BigRational;
pub use rational::{MAX_DIGITS, MAX_EXPONENT, ParseExactError, parse_exact, parse_exact_list};
pub use report::JsonScalar;
pub use roots::Roots;

use std::cmp::Ordering;
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A number type the generic core can compute with: an (approximate, exact or enclosing) field.
///
/// Laws hold exactly for [`BigRational`], up to rounding for floats, and as *enclosures* for
/// [`Interval`] (the result contains every exact result for points in the operands).
pub trait Scalar:
    Clone
    + PartialEq
    + Debug
    + Send
    + Sync
    + 'static
    + Roots
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + for<'a> Add<&'a Self, Output = Self>
    + for<'a> Sub<&'a Self, Output = Self>
    + for<'a> Mul<&'a Self, Output = Self>
    + for<'a> Div<&'a Self, Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + for<'a> AddAssign<&'a Self>
    + for<'a> SubAssign<&'a Self>
    + for<'a> MulAssign<&'a Self>
    + for<'a> DivAssign<&'a Self>
{
    /// Whether `a + b`, `a − b` and `a · b` are non-finite whenever `a` or `b` is (so that a dot
    /// product `θ·φ` with a finite θ is non-finite whenever some φⱼ is, and one test of the result
    /// checks the whole of φ). True for IEEE floats (∞ and NaN propagate through sums and
    /// products, `∞ − ∞` and `0·∞` are NaN) and, vacuously, for rationals (always finite); false
    /// for intervals (`[0, 0]·[1, +∞] = [0, 0]`) and, conservatively, the default.
    const NON_FINITE_PROPAGATES: bool = false;
    /// Whether the type is IEEE binary64 itself: its operations are `f64`'s, bit for bit, so that
    /// a computation in `f64` (a faster pre-test of a decision) decides as the same computation in
    /// this type does. True for `f64` only; false by default.
    const IS_BINARY64: bool = false;
    /// The additive identity.
    fn zero() -> Self;
    /// The multiplicative identity.
    fn one() -> Self;
    /// `num / den`: exact for rationals, an enclosure for intervals, correctly rounded for `f64`
    /// (and `f64`-then-`f32` rounded for `f32`).
    ///
    /// # Panics
    /// If `den == 0` (a programming error: callers construct constants).
    fn from_ratio(num: i64, den: i64) -> Self;
    /// A rational number, with the same guarantees as [`Scalar::from_ratio`].
    fn from_rational(q: &BigRational) -> Self;
    /// The lossy conversion used for reporting (midpoint for intervals, value part for duals).
    fn to_f64(&self) -> f64;
    /// Comparison that is only answered when it is certain: `None` for an interval that overlaps
    /// the other operand (unless both are the same point) and for NaN.
    fn certain_cmp(&self, other: &Self) -> Option<Ordering>;
    /// `false` for NaN/±∞ floats and for unbounded or empty intervals: a result that must not be
    /// reported as a number.
    fn is_finite(&self) -> bool;

    /// The value of a finite binary64 number (a random draw, a datum read as `f64`, a trained
    /// weight) — never for decimal literals, which are not what they look like. Exact in `f64`,
    /// rationals, intervals (a singleton) and duals over them; rounded in `f32`. `None` for NaN
    /// or ±∞. The default goes through [`BigRational::from_float`]; fast types override it.
    fn from_binary64(x: f64) -> Option<Self> {
        BigRational::from_float(x).map(|q| Self::from_rational(&q))
    }
    /// A key that identifies the value bit for bit, for types whose values a few bits name (the
    /// floats: their bits widened to `f64`, so that 0 and −0 differ): `None` for every other type
    /// (the default). Caches keyed by θ use it (the toy problem's recent policy tables).
    fn bit_key(&self) -> Option<u64> {
        None
    }
    /// An integer, exactly where the type can hold it.
    fn from_i64(n: i64) -> Self {
        Self::from_ratio(n, 1)
    }
    /// `self * self`.
    fn square(&self) -> Self {
        self.clone() * self
    }
    /// `self * other`: the same value as the operator; a type may compute it by a faster route
    /// (an [`Interval`] from its endpoint products' FMA residuals, without inari's case table on
    /// the operands' signs and its rounding-mode switches). Hot generic kernels (the dual
    /// numbers' products, the exact forward pass, the toy policies' tables) multiply with it.
    #[inline]
    fn product(&self, other: &Self) -> Self {
        self.clone() * other
    }
    /// `self *= other` by the route of [`Scalar::product`] (in place, for the types whose
    /// operator works in place).
    #[inline]
    fn product_assign(&mut self, other: &Self) {
        *self *= other;
    }
    /// Certainly `self > 0`.
    fn is_certainly_positive(&self) -> bool {
        self.certain_cmp(&Self::zero()) == Some(Ordering::Greater)
    }
    /// Whether `self > 0`, where that is certain: `Some(true)` where [`Scalar::certain_cmp`]
    /// with 0 gives `Greater`, `Some(false)` where it gives `Less` or `Equal`, `None` where it
    /// gives no answer. Floats override it with one comparison and a NaN test (the same answers
    /// as `partial_cmp` and a match, in fewer instructions on a roll-out's hot path).
    fn positive_when_certain(&self) -> Option<bool> {
        self.certain_cmp(&Self::zero())
            .map(|o| o == Ordering::Greater)
    }
    /// Certainly `self ≥ 0`.
    fn is_certainly_nonnegative(&self) -> bool {
        matches!(
            self.certain_cmp(&Self::zero()),
            Some(Ordering::Greater | Ordering::Equal)
        )
    }
    /// Certainly `self = 0` (for intervals: the degenerate interval [0, 0]).
    fn is_certainly_zero(&self) -> bool {
        self.certain_cmp(&Self::zero()) == Some(Ordering::Equal)
    }
    /// `Σ xᵢ yᵢ` over equally long slices ([`dot`] checks the lengths). The default adds the
    /// products left to right from 0; exact types give the exact sum, intervals an enclosure.
    /// Floats override it for long slices with [`DOT_LANES`] partial sums added at the end
    /// (a different rounding, the same error bound `γ_n Σ|xᵢyᵢ|`), so that the loop runs in
    /// vector registers; below [`DOT_LANES_FROM`] terms they keep the left-to-right order.
    #[inline]
    fn dot_slices(x: &[Self], y: &[Self]) -> Self {
        x.iter()
            .zip(y)
            .fold(Self::zero(), |acc, (a, b)| acc + a.clone() * b)
    }
}

/// Partial sums of the floats' [`Scalar::dot_slices`] (two AVX2 registers of `f64`).
pub const DOT_LANES: usize = 8;

/// The length from which the floats' [`Scalar::dot_slices`] uses [`DOT_LANES`] partial sums:
/// shorter products (CartPole's five features, the PPO expert's four inputs) keep the
/// left-to-right order, bit for bit.
pub const DOT_LANES_FROM: usize = 16;

/// A [`Scalar`] with a square root (enclosing for intervals).
pub trait Sqrt: Scalar {
    /// The principal square root.
    fn sqrt(&self) -> Self;
}

/// A [`Scalar`] with the elementary functions the environments and the smooth policies need.
pub trait Real: Sqrt {
    /// `eˣ`.
    fn exp(&self) -> Self;
    /// Natural logarithm.
    fn ln(&self) -> Self;
    /// Sine (radians).
    fn sin(&self) -> Self;
    /// Cosine (radians).
    fn cos(&self) -> Self;
}

/// A comparison that generic code needed to branch on could not be decided (an interval straddles
/// the threshold). Carries what was being decided.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("undecidable comparison in {what}: the interval enclosure straddles the threshold")]
pub struct Undecidable {
    /// What the comparison decided.
    pub what: &'static str,
}

/// `a < b`, certainly true, certainly false, or undecidable.
///
/// # Errors
/// [`Undecidable`] when [`Scalar::certain_cmp`] cannot order the operands.
#[inline]
pub fn certainly_less<S: Scalar>(a: &S, b: &S, what: &'static str) -> Result<bool, Undecidable> {
    match a.certain_cmp(b) {
        Some(o) => Ok(o == Ordering::Less),
        None => Err(Undecidable { what }),
    }
}

/// Whether every entry is finite ([`Scalar::is_finite`]), without an early exit: one branch-free
/// pass that runs in vector lanes for floats, for the checks of whole parameter vectors that
/// every oracle call and every inner-optimiser step makes.
#[inline]
pub fn all_finite<S: Scalar>(xs: &[S]) -> bool {
    xs.iter().fold(true, |ok, x| ok & x.is_finite())
}

/// Sum of a sequence of scalars (zero when empty).
pub fn sum<'a, S: Scalar>(xs: impl IntoIterator<Item = &'a S>) -> S {
    xs.into_iter().fold(S::zero(), |acc, x| acc + x)
}

/// Dot product `Σ xᵢ yᵢ` of two equally long slices.
///
/// # Panics
/// If the lengths differ.
#[inline]
pub fn dot<S: Scalar>(x: &[S], y: &[S]) -> S {
    assert_eq!(x.len(), y.len(), "dot: length mismatch");
    S::dot_slices(x, y)
}

/// `xⁿ` by binary powering: `r = 1`, then for each bit of `n` from the lowest, `r ← r·x` if the
/// bit is set and `x ← x²` while bits remain. Exact in exact scalars, an enclosure in intervals;
/// in floats the same operations in the same order as `f64::powi` (compiler-rt's `__powidf2`), so
/// the two agree bit for bit.
pub fn powi<S: Scalar>(x: &S, n: u32) -> S {
    let (mut base, mut n, mut r) = (x.clone(), n, S::one());
    loop {
        if n & 1 == 1 {
            r *= &base;
        }
        n >>= 1;
        if n == 0 {
            return r;
        }
        base = base.clone() * &base;
    }
}

/// Squared Euclidean norm `Σ xᵢ²`.
pub fn norm_sq<S: Scalar>(x: &[S]) -> S {
    x.iter().fold(S::zero(), |acc, a| acc + a.square())
}
