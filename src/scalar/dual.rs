//! `Dual<S>`: forward-mode automatic differentiation over any [`Scalar`].
//!
//! A dual number is a value `v ∈ S` with a gradient `g ∈ Sᵈ`; arithmetic follows the chain rule
//! (`(a·b)' = a'b + ab'`, `(a/b)' = (a' − (a/b)·b')/b`). Because `Dual<S>` is itself a [`Scalar`],
//! duals nest: `Dual<Dual<BigRational>>` carries exact second derivatives (the Hessian is the
//! gradient of the gradient).
//!
//! The gradient may be stored shorter than `d`: missing trailing entries are zero. Constants
//! (`Dual::constant`, `zero()`, `one()`) store an empty gradient, so they combine with duals of any
//! dimension.
//!
//! Up to two gradient entries are stored inline (no allocation): the jets the rigorous constants
//! nest three deep have at most two variables per level, and a heap allocation per value would
//! dominate their arithmetic. Longer gradients spill to the heap; the arithmetic is the same.

use super::{BigRational, Real, Scalar, Sqrt};
use smallvec::SmallVec;
use std::cmp::Ordering;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The gradient's storage: up to two entries inline, more on the heap (module docs).
type Gradient<S> = SmallVec<[S; 2]>;

/// A value with its gradient (forward-mode derivative with respect to `d` seeded variables).
#[derive(Clone, Debug)]
pub struct Dual<S> {
    v: S,
    g: Gradient<S>,
}

impl<S: Scalar> Dual<S> {
    /// A dual with an explicit gradient.
    pub fn new(value: S, gradient: Vec<S>) -> Self {
        Self {
            v: value,
            g: Gradient::from_vec(gradient),
        }
    }
    /// A constant (zero gradient).
    pub fn constant(value: S) -> Self {
        Self {
            v: value,
            g: Gradient::new(),
        }
    }
    /// The `i`-th of `n` independent variables, with value `value` (gradient `eᵢ`).
    ///
    /// # Panics
    /// If `i >= n`.
    pub fn variable(value: S, i: usize, n: usize) -> Self {
        assert!(i < n, "variable index {i} out of {n}");
        let mut g = Gradient::from_elem(S::zero(), n);
        g[i] = S::one();
        Self { v: value, g }
    }
    /// Seed every entry of `values` as an independent variable.
    pub fn variables(values: &[S]) -> Vec<Self> {
        let n = values.len();
        values
            .iter()
            .enumerate()
            .map(|(i, x)| Self::variable(x.clone(), i, n))
            .collect()
    }
    /// The value part.
    pub fn value(&self) -> &S {
        &self.v
    }
    /// The stored gradient (possibly shorter than the number of variables; missing entries are 0).
    pub fn gradient(&self) -> &[S] {
        &self.g
    }
    /// The gradient padded with zeros to length `n`.
    pub fn gradient_padded(&self, n: usize) -> Vec<S> {
        let mut g = self.g.to_vec();
        g.resize(n.max(g.len()), S::zero());
        g
    }
    /// Split into value and gradient padded to length `n`.
    pub fn into_parts(self, n: usize) -> (S, Vec<S>) {
        let g = self.gradient_padded(n);
        (self.v, g)
    }

    /// Apply a scalar function with known derivative: `f(self)` with gradient `f'(v)·g`.
    pub(super) fn chain(&self, value: S, derivative: S) -> Self {
        Self {
            v: value,
            g: self.g.iter().map(|gi| derivative.clone() * gi).collect(),
        }
    }

    /// The square root given `root = √v`: derivative `g / (2√v)` (both [`Sqrt`] and
    /// [`super::Roots`] take it from here).
    pub(super) fn sqrt_from(&self, root: S) -> Self {
        let d = S::one() / (S::from_i64(2) * &root);
        self.chain(root, d)
    }
}

// The arithmetic works in place on the left operand's storage: a nested dual
// (`Dual<Dual<Dual<Interval>>>`, hundreds of bytes) would otherwise be copied through an iterator
// for every entry of every result. Each entry is computed by the same operations, in the same
// order, as the chain rules in the module docs (up to the order of a product's or a sum's two
// operands, which IEEE arithmetic, intervals and ℚ do not see), so the results are the same bits.

/// `a += b`: values and gradients entrywise (missing entries are zero).
fn add_assign_ref<S: Scalar>(a: &mut Dual<S>, b: &Dual<S>) {
    a.v += &b.v;
    for (x, y) in a.g.iter_mut().zip(&b.g) {
        *x += y;
    }
    if b.g.len() > a.g.len() {
        let n = a.g.len();
        a.g.extend(b.g[n..].iter().cloned());
    }
}

/// `a −= b`: values and gradients entrywise (missing entries are zero).
fn sub_assign_ref<S: Scalar>(a: &mut Dual<S>, b: &Dual<S>) {
    a.v -= &b.v;
    for (x, y) in a.g.iter_mut().zip(&b.g) {
        *x -= y;
    }
    if b.g.len() > a.g.len() {
        let n = a.g.len();
        a.g.extend(b.g[n..].iter().map(|y| -y.clone()));
    }
}

/// `a ·= b`: value `a·b`, gradient `b·a′ + a·b′`.
fn mul_assign_ref<S: Scalar>(a: &mut Dual<S>, b: &Dual<S>) {
    let Dual { v, g } = a;
    for (i, x) in g.iter_mut().enumerate() {
        x.product_assign(&b.v);
        if let Some(y) = b.g.get(i) {
            *x += v.product(y);
        }
    }
    if b.g.len() > g.len() {
        let n = g.len();
        g.extend(b.g[n..].iter().map(|y| v.product(y)));
    }
    v.product_assign(&b.v);
}

/// `a /= b`: value `q = a/b`, gradient `(a′ − q·b′)/b`.
fn div_assign_ref<S: Scalar>(a: &mut Dual<S>, b: &Dual<S>) {
    a.v /= &b.v;
    let Dual { v: q, g } = a;
    for (i, x) in g.iter_mut().enumerate() {
        if let Some(y) = b.g.get(i) {
            *x -= q.product(y);
        }
        *x /= &b.v;
    }
    if b.g.len() > g.len() {
        let n = g.len();
        g.extend(b.g[n..].iter().map(|y| -q.product(y) / &b.v));
    }
}

macro_rules! dual_binop {
    ($Op:ident, $op:ident, $OpAssign:ident, $op_assign:ident, $f:ident) => {
        impl<S: Scalar> $Op for Dual<S> {
            type Output = Dual<S>;
            fn $op(mut self, rhs: Dual<S>) -> Dual<S> {
                $f(&mut self, &rhs);
                self
            }
        }
        impl<'a, S: Scalar> $Op<&'a Dual<S>> for Dual<S> {
            type Output = Dual<S>;
            fn $op(mut self, rhs: &'a Dual<S>) -> Dual<S> {
                $f(&mut self, rhs);
                self
            }
        }
        impl<'a, S: Scalar> $Op<Dual<S>> for &'a Dual<S> {
            type Output = Dual<S>;
            fn $op(self, rhs: Dual<S>) -> Dual<S> {
                let mut out = self.clone();
                $f(&mut out, &rhs);
                out
            }
        }
        impl<'a, 'b, S: Scalar> $Op<&'b Dual<S>> for &'a Dual<S> {
            type Output = Dual<S>;
            fn $op(self, rhs: &'b Dual<S>) -> Dual<S> {
                let mut out = self.clone();
                $f(&mut out, rhs);
                out
            }
        }
        impl<S: Scalar> $OpAssign for Dual<S> {
            fn $op_assign(&mut self, rhs: Dual<S>) {
                $f(self, &rhs);
            }
        }
        impl<'a, S: Scalar> $OpAssign<&'a Dual<S>> for Dual<S> {
            fn $op_assign(&mut self, rhs: &'a Dual<S>) {
                $f(self, rhs);
            }
        }
    };
}

dual_binop!(Add, add, AddAssign, add_assign, add_assign_ref);
dual_binop!(Sub, sub, SubAssign, sub_assign, sub_assign_ref);
dual_binop!(Mul, mul, MulAssign, mul_assign, mul_assign_ref);
dual_binop!(Div, div, DivAssign, div_assign, div_assign_ref);

impl<S: Scalar> Neg for Dual<S> {
    type Output = Dual<S>;
    fn neg(self) -> Dual<S> {
        Dual {
            v: -self.v,
            g: self.g.into_iter().map(|x| -x).collect(),
        }
    }
}

impl<S: Scalar> PartialEq for Dual<S> {
    /// Equal values and equal gradients, missing entries counting as zero.
    fn eq(&self, other: &Self) -> bool {
        let zero = S::zero();
        self.v == other.v
            && (0..self.g.len().max(other.g.len()))
                .all(|i| self.g.get(i).unwrap_or(&zero) == other.g.get(i).unwrap_or(&zero))
    }
}

impl<S: Scalar> Scalar for Dual<S> {
    fn zero() -> Self {
        Self::constant(S::zero())
    }
    fn one() -> Self {
        Self::constant(S::one())
    }
    fn from_ratio(num: i64, den: i64) -> Self {
        Self::constant(S::from_ratio(num, den))
    }
    fn from_rational(q: &BigRational) -> Self {
        Self::constant(S::from_rational(q))
    }
    fn to_f64(&self) -> f64 {
        self.v.to_f64()
    }
    fn from_binary64(x: f64) -> Option<Self> {
        S::from_binary64(x).map(Self::constant)
    }
    /// Orders by value only (the gradient does not take part).
    fn certain_cmp(&self, other: &Self) -> Option<Ordering> {
        self.v.certain_cmp(&other.v)
    }
    fn is_finite(&self) -> bool {
        self.v.is_finite() && self.g.iter().all(Scalar::is_finite)
    }
    /// `v²` through the value type's own `square` (tight for intervals), derivative `2v·g`.
    fn square(&self) -> Self {
        let two_v = S::from_i64(2) * &self.v;
        self.chain(self.v.square(), two_v)
    }
}

/// num-traits' additive identity, so that generic code written against num-traits (nalgebra's
/// matrix products and `identity`, `num_traits::pow`) runs on duals. Agrees with
/// [`Scalar::zero`]; `is_zero` means a zero value and a zero gradient.
impl<S: Scalar> num_traits::Zero for Dual<S> {
    fn zero() -> Self {
        <Self as Scalar>::zero()
    }
    fn is_zero(&self) -> bool {
        *self == <Self as Scalar>::zero()
    }
}

/// num-traits' multiplicative identity (see the [`num_traits::Zero`] impl); agrees with
/// [`Scalar::one`].
impl<S: Scalar> num_traits::One for Dual<S> {
    fn one() -> Self {
        <Self as Scalar>::one()
    }
    fn is_one(&self) -> bool {
        *self == <Self as Scalar>::one()
    }
}

impl<S: Sqrt> Sqrt for Dual<S> {
    /// `√v`, with derivative `g / (2√v)`.
    fn sqrt(&self) -> Self {
        self.sqrt_from(self.v.sqrt())
    }
}

impl<S: Real> Real for Dual<S> {
    fn exp(&self) -> Self {
        let e = self.v.exp();
        self.chain(e.clone(), e)
    }
    fn ln(&self) -> Self {
        self.chain(self.v.ln(), S::one() / &self.v)
    }
    fn sin(&self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn cos(&self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Q = BigRational;
    fn q(n: i64, d: i64) -> Q {
        Q::from_ratio(n, d)
    }

    /// f(x, y) = (x² y − 3) / (x + y): gradient by hand, compared exactly.
    #[test]
    fn rational_quotient_rule_is_exact() {
        let (x0, y0) = (q(1, 2), q(-3, 1));
        let v = Dual::variables(&[x0.clone(), y0.clone()]);
        let (x, y) = (&v[0], &v[1]);
        let f = (x * x * y - Dual::from_i64(3)) / (x + y);
        let den = x0.clone() + &y0;
        let num = x0.clone() * &x0 * &y0 - q(3, 1);
        let fx = (q(2, 1) * &x0 * &y0 * &den - &num) / (den.clone() * &den);
        let fy = (x0.clone() * &x0 * &den - &num) / (den.clone() * &den);
        assert_eq!(*f.value(), num / den);
        assert_eq!(f.gradient(), &[fx, fy]);
    }

    /// Nested duals give the exact Hessian of x³y.
    #[test]
    fn nested_duals_give_second_derivatives() {
        let (x0, y0) = (q(2, 3), q(5, 7));
        let inner = Dual::variables(&[x0.clone(), y0.clone()]);
        let outer: Vec<Dual<Dual<Q>>> = inner
            .iter()
            .enumerate()
            .map(|(i, d)| Dual::variable(d.clone(), i, 2))
            .collect();
        let (x, y) = (&outer[0], &outer[1]);
        let f = x * x * x * y;
        let h: Vec<Vec<Q>> = f
            .gradient()
            .iter()
            .map(|gi| gi.gradient_padded(2))
            .collect();
        let hxx = q(6, 1) * &x0 * &y0;
        let hxy = q(3, 1) * &x0 * &x0;
        assert_eq!(h, vec![vec![hxx, hxy.clone()], vec![hxy, q(0, 1)]]);
    }

    #[test]
    fn constants_broadcast_against_any_dimension() {
        let v = Dual::variables(&[q(1, 1), q(2, 1), q(3, 1)]);
        let s = Dual::one() + &v[2] - Dual::from_i64(1);
        assert_eq!(s.gradient_padded(3), vec![q(0, 1), q(0, 1), q(1, 1)]);
        assert_eq!(
            Dual::constant(q(1, 1)),
            Dual::new(q(1, 1), vec![q(0, 1); 4])
        );
    }

    /// Every operation, with either operand's gradient stored shorter than the other's and
    /// through every operator form (owned, borrowed, assigning), against the chain rules written
    /// out entrywise on the zero-padded gradients (`(a·b)′ = b·a′ + a·b′`, `(a/b)′ = (a′ − q·b′)/b`).
    /// In ℚ this is the mathematics; in `f64`, intervals and nested duals it is also the claim that
    /// the in-place arithmetic rounds as the chain rules do (the same operations, their operands
    /// in another order, which none of these arithmetics sees).
    fn short_gradients_follow_the_chain_rules<S: Scalar>() {
        let r = |n, d| S::from_ratio(n, d);
        let short = Dual::new(r(3, 2), vec![r(1, 3)]);
        let long = Dual::new(r(-5, 7), vec![r(2, 1), r(-1, 4), r(7, 9)]);
        for (a, b) in [(&short, &long), (&long, &short)] {
            let (av, bv) = (a.value().clone(), b.value().clone());
            let (ag, bg) = (a.gradient_padded(3), b.gradient_padded(3));
            let quotient = av.clone() / &bv;
            let entry = |op: usize, x: &S, y: &S| match op {
                0 => x.clone() + y,
                1 => x.clone() - y,
                2 => bv.clone() * x + av.clone() * y,
                _ => (x.clone() - quotient.clone() * y) / &bv,
            };
            for op in 0..4 {
                let value = [
                    av.clone() + &bv,
                    av.clone() - &bv,
                    av.clone() * &bv,
                    quotient.clone(),
                ][op]
                    .clone();
                let grad: Vec<S> = (0..3).map(|i| entry(op, &ag[i], &bg[i])).collect();
                let forms = match op {
                    0 => [a + b, a.clone() + b, a + b.clone(), {
                        let mut c = a.clone();
                        c += b;
                        c
                    }],
                    1 => [a - b, a.clone() - b, a - b.clone(), {
                        let mut c = a.clone();
                        c -= b;
                        c
                    }],
                    2 => [a * b, a.clone() * b, a * b.clone(), {
                        let mut c = a.clone();
                        c *= b;
                        c
                    }],
                    _ => [a / b, a.clone() / b, a / b.clone(), {
                        let mut c = a.clone();
                        c /= b;
                        c
                    }],
                };
                for got in forms {
                    assert_eq!(got.value(), &value, "op {op}");
                    assert_eq!(got.gradient(), grad.as_slice(), "op {op}");
                }
            }
        }
    }

    macro_rules! chain_rule_tests {
        ($($name:ident => $s:ty),+ $(,)?) => {$(
            #[test]
            fn $name() {
                short_gradients_follow_the_chain_rules::<$s>();
            }
        )+};
    }

    chain_rule_tests!(
        short_gradients_rational => Q,
        short_gradients_f64 => f64,
        short_gradients_interval => super::super::Interval,
        short_gradients_nested_f64 => Dual<f64>,
    );

    #[test]
    fn float_chain_rules() {
        let x = Dual::variable(0.7_f64, 0, 1);
        let y = (x.sin() * x.exp() + x.ln() * x.cos()).sqrt();
        let f = |t: f64| (t.sin() * t.exp() + t.ln() * t.cos()).sqrt();
        let h = 1e-6;
        let fd = (f(0.7 + h) - f(0.7 - h)) / (2.0 * h);
        approx::assert_abs_diff_eq!(y.gradient()[0], fd, epsilon = 1e-8);
    }
}
