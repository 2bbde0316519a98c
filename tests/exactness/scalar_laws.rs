//! The field laws of every scalar type, checked with quickcheck, each law stated in the form that
//! is *true* for the type (conventions.md 10–12):
//!
//! | scalar | a law `lhs = rhs` of ℚ holds when |
//! |---|---|
//! | `BigRational`, `Dual<BigRational>` | `lhs == rhs` exactly (value and gradient) |
//! | `f64`, `Dual<f64>` | `lhs ≈ rhs` within [`DERIVATIVE_F64_REL`] on the scale `max(1, |lhs|, |rhs|)` (two f64 routes to one value), and for `f64` each side lies in the interval run of the same expression (the policy's f64 rule) |
//! | `f32` | `lhs ≈ rhs` within [`F32_REL`] on the same scale |
//! | `Interval` | *inclusion*: for every choice of rational points in the operands (endpoints, midpoint), the exact value of either side lies in both enclosures |
//!
//! Besides the field laws: the operator forms (by value, by reference, compound assignment) agree
//! exactly; `from_ratio` agrees with the exact ratio under the tolerance policy; certain
//! comparisons are answered exactly when every pair of points of the operands compares the same
//! way, and then with that answer; intervals are sub-distributive; duals obey the product, quotient
//! and chain rules against derivatives of polynomials computed from their coefficients; and the
//! num-traits identities of the scalars that implement them agree with the kit's.
//!
//! Every law can fail: wrong laws (`a − b = b − a`, `(a + b)² = a² + b²`, a comparison by
//! midpoints, super-distributivity, exact f64 associativity, the product rule `(pq)' = p'q'`)
//! are run through the same checks and must be falsified, which shows that the generators reach
//! informative values. The runs use a fixed seed, so they are reproducible.

use approx::relative_eq;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar, interval_contains_rational};
use ilopt::tolerance::{Agreement, DERIVATIVE_F64_REL, F32_REL};
use num_traits::{One, Zero};
use quickcheck::{Arbitrary, Gen, QuickCheck, TestResult, Testable};
use std::cmp::Ordering;
use std::fmt::Debug;

type Q = BigRational;

/// Cases per law: enough to falsify each wrong law below, few enough for a debug run in seconds.
const CASES: u64 = 150;
const SEED: u64 = 0x5ca1_a71a_0005;

fn quickcheck() -> QuickCheck {
    QuickCheck::new()
        .rng(Gen::from_size_and_seed(8, SEED))
        .tests(CASES)
        .max_tests(20 * CASES)
}

/// Run a property; on failure, the counterexample.
fn run<A: Testable>(prop: A) -> Result<(), String> {
    match quickcheck().quicktest(prop) {
        Ok(n) if n >= CASES / 2 => Ok(()),
        Ok(n) => Err(format!("only {n} cases were not discarded")),
        Err(failure) => Err(format!("{failure:?}")),
    }
}

// ---------------------------------------------------------------------------------------------
// Generators: newtypes, since the orphan rule forbids `Arbitrary` impls on foreign types.

/// An integer in `[-bound, bound]`.
fn int_in(g: &mut Gen, bound: i64) -> i64 {
    i64::arbitrary(g).rem_euclid(2 * bound + 1) - bound
}

/// A finite binary64 with a full 53-bit significand and `2⁻³ ≤ |x| < 2³`, or one of a few
/// special values (0, ±1, 2, 1/2, −3). Bounded above and away from zero so that every term of a
/// law, derivatives of quotients included, stays below 2¹² times the law's scale
/// `max(1, |lhs|, |rhs|)`: the rounding error of a law's short straight-line program is then
/// below 2⁻³⁷ of the scale, well inside [`DERIVATIVE_F64_REL`] = 2⁻³⁰.
fn f64_value(g: &mut Gen) -> f64 {
    if u8::arbitrary(g) % 8 == 0 {
        return *g.choose(&[0.0, 1.0, -1.0, 2.0, 0.5, -3.0]).unwrap();
    }
    let m = ((1i64 << 52) + int_in(g, (1 << 52) - 1).abs()) as f64;
    let sign = *g.choose(&[-1.0, 1.0]).unwrap();
    sign * m * 2f64.powi(int_in(g, 3).min(2) as i32 - 52)
}

/// A rational with numerator in `[-2²⁰, 2²⁰]` and denominator in `[1, 2¹²]`, or a small one.
fn rational_parts(g: &mut Gen) -> (i64, i64) {
    if u8::arbitrary(g) % 8 == 0 {
        return *g
            .choose(&[(0, 1), (1, 1), (-1, 1), (1, 2), (-1, 3), (7, 5)])
            .unwrap();
    }
    (int_in(g, 1 << 20), 1 + int_in(g, 1 << 12).abs())
}

fn shrink_f64(x: f64) -> Box<dyn Iterator<Item = f64>> {
    let candidates = [0.0, 1.0, x.trunc(), (x * 16.0).trunc() / 16.0];
    Box::new(
        candidates
            .into_iter()
            .filter(move |c| c.abs() < x.abs() || (c.abs() == x.abs() && *c != x))
            .collect::<Vec<_>>()
            .into_iter(),
    )
}

#[derive(Clone, Debug)]
struct F64(f64);

impl Arbitrary for F64 {
    fn arbitrary(g: &mut Gen) -> Self {
        F64(f64_value(g))
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        Box::new(shrink_f64(self.0).map(F64))
    }
}

/// An `f32` with a full 24-bit significand and `2⁻³ ≤ |x| < 2³`, or a special value: a law's
/// rounding error is then below 2⁻¹³ of its scale, inside [`F32_REL`] = 2⁻¹⁰.
#[derive(Clone, Debug)]
struct F32(f32);

impl Arbitrary for F32 {
    fn arbitrary(g: &mut Gen) -> Self {
        if u8::arbitrary(g) % 8 == 0 {
            return F32(*g.choose(&[0.0, 1.0, -1.0, 2.0, 0.5, -3.0]).unwrap());
        }
        let m = ((1i32 << 23) + int_in(g, (1 << 23) - 1).abs() as i32) as f32;
        let sign = *g.choose(&[-1.0, 1.0]).unwrap();
        F32(sign * m * 2f32.powi(int_in(g, 3).min(2) as i32 - 23))
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        Box::new(shrink_f64(f64::from(self.0)).map(|x| F32(x as f32)))
    }
}

/// An exact rational `n/d` with bounded numerator and denominator.
#[derive(Clone, Debug)]
struct Rat(i64, i64);

impl Arbitrary for Rat {
    fn arbitrary(g: &mut Gen) -> Self {
        let (n, d) = rational_parts(g);
        Rat(n, d)
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        Box::new(
            (self.0, self.1)
                .shrink()
                .filter(|&(_, d)| d > 0)
                .map(|(n, d)| Rat(n, d)),
        )
    }
}

impl Rat {
    fn q(&self) -> Q {
        Q::from_ratio(self.0, self.1)
    }
}

/// A bounded interval: a point (degenerate), the tight enclosure of a ratio, or the hull of two
/// floats.
#[derive(Clone)]
struct Iv(Interval);

/// `[inf, sup]`: inari's own `Debug` shows its internal representation.
fn show_interval(x: &Interval) -> String {
    format!("[{:?}, {:?}]", x.inf(), x.sup())
}

impl Debug for Iv {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&show_interval(&self.0))
    }
}

impl Arbitrary for Iv {
    fn arbitrary(g: &mut Gen) -> Self {
        let x = f64_value(g);
        Iv(match u8::arbitrary(g) % 4 {
            0 => Interval::try_from((x, x)).unwrap(),
            1 => {
                let (n, d) = rational_parts(g);
                Interval::from_ratio(n, d)
            }
            _ => {
                let y = f64_value(g);
                Interval::try_from((x.min(y), x.max(y))).unwrap()
            }
        })
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        let x = self.0;
        if x.is_singleton() {
            return Box::new(shrink_f64(x.inf()).map(|p| Iv(Interval::try_from((p, p)).unwrap())));
        }
        let ends = [x.inf(), x.sup()].map(|p| Iv(Interval::try_from((p, p)).unwrap()));
        Box::new(ends.into_iter())
    }
}

/// A dual over `S` with a gradient of 0 to 2 entries (constants broadcast against any length).
#[derive(Clone, Debug)]
struct D<W>(W, Vec<W>);

impl<W: Arbitrary> Arbitrary for D<W> {
    fn arbitrary(g: &mut Gen) -> Self {
        let n = usize::from(u8::arbitrary(g) % 3);
        D(W::arbitrary(g), (0..n).map(|_| W::arbitrary(g)).collect())
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        let v = self.0.clone();
        let g = self.1.clone();
        let shorter = (0..g.len()).map(move |k| D(v.clone(), g[..k].to_vec()));
        let g = self.1.clone();
        let values = self.0.shrink().map(move |v| D(v, g.clone()));
        Box::new(shorter.chain(values))
    }
}

// ---------------------------------------------------------------------------------------------
// How each scalar type judges a law.

/// A generated value of a scalar type, and how a law of ℚ is judged in that type.
trait LawScalar: Arbitrary + Debug {
    type S: Scalar + Agreement;
    fn get(&self) -> Self::S;
    /// Rational points of the value part: the value itself, or an interval's ends and midpoint.
    fn points(&self) -> Vec<Q>;
    /// Whether the computed sides `l` and `r` of law `L` at the operands `x` agree, in the form
    /// the law takes in this type.
    fn agree<L: Law>(x: [&Self; 3], l: &Self::S, r: &Self::S) -> bool;
    /// A value, for a failure message.
    fn show(x: &Self::S) -> String {
        format!("{x:?}")
    }
}

fn f64_close(l: f64, r: f64) -> bool {
    relative_eq!(
        l,
        r,
        epsilon = DERIVATIVE_F64_REL,
        max_relative = DERIVATIVE_F64_REL
    )
}

fn f32_close(l: f32, r: f32) -> bool {
    let tol = F32_REL as f32;
    relative_eq!(l, r, epsilon = tol, max_relative = tol)
}

fn point(x: f64) -> Interval {
    Interval::try_from((x, x)).unwrap()
}

impl LawScalar for Rat {
    type S = Q;
    fn get(&self) -> Q {
        self.q()
    }
    fn points(&self) -> Vec<Q> {
        vec![self.q()]
    }
    fn agree<L: Law>(_: [&Self; 3], l: &Q, r: &Q) -> bool {
        l == r
    }
}

impl LawScalar for F64 {
    type S = f64;
    fn get(&self) -> f64 {
        self.0
    }
    fn points(&self) -> Vec<Q> {
        vec![Q::from_float(self.0).unwrap()]
    }
    fn agree<L: Law>(x: [&Self; 3], l: &f64, r: &f64) -> bool {
        // The policy's f64 rule: the same expression in intervals encloses the f64 result.
        let enclosed = L::sides(&point(x[0].0), &point(x[1].0), &point(x[2].0))
            .is_some_and(|(li, ri)| li.contains(*l) && ri.contains(*r));
        enclosed && f64_close(*l, *r)
    }
}

impl LawScalar for F32 {
    type S = f32;
    fn get(&self) -> f32 {
        self.0
    }
    fn points(&self) -> Vec<Q> {
        vec![Q::from_float(self.0).unwrap()]
    }
    fn agree<L: Law>(_: [&Self; 3], l: &f32, r: &f32) -> bool {
        f32_close(*l, *r)
    }
}

impl LawScalar for Iv {
    type S = Interval;
    fn get(&self) -> Interval {
        self.0
    }
    fn points(&self) -> Vec<Q> {
        let lo = Q::from_float(self.0.inf()).unwrap();
        let hi = Q::from_float(self.0.sup()).unwrap();
        let mid = (lo.clone() + &hi) / Q::from_i64(2);
        vec![lo, mid, hi]
    }
    fn show(x: &Interval) -> String {
        show_interval(x)
    }
    fn agree<L: Law>(x: [&Self; 3], l: &Interval, r: &Interval) -> bool {
        let [pa, pb, pc] = x.map(Iv::points);
        pa.iter().all(|a| {
            pb.iter().all(|b| {
                pc.iter().all(|c| match L::sides(a, b, c) {
                    Some((lq, rq)) => [&lq, &rq].iter().all(|v| {
                        interval_contains_rational(*l, v) && interval_contains_rational(*r, v)
                    }),
                    // The divisor was certainly non-zero as an interval, so it is at every point.
                    None => false,
                })
            })
        })
    }
}

impl LawScalar for D<F64> {
    type S = Dual<f64>;
    fn get(&self) -> Dual<f64> {
        Dual::new(self.0.0, self.1.iter().map(|g| g.0).collect())
    }
    fn points(&self) -> Vec<Q> {
        self.0.points()
    }
    fn agree<L: Law>(_: [&Self; 3], l: &Dual<f64>, r: &Dual<f64>) -> bool {
        let n = l.gradient().len().max(r.gradient().len());
        f64_close(*l.value(), *r.value())
            && l.gradient_padded(n)
                .iter()
                .zip(r.gradient_padded(n))
                .all(|(a, b)| f64_close(*a, b))
    }
}

impl LawScalar for D<Rat> {
    type S = Dual<Q>;
    fn get(&self) -> Dual<Q> {
        Dual::new(self.0.q(), self.1.iter().map(Rat::q).collect())
    }
    fn points(&self) -> Vec<Q> {
        self.0.points()
    }
    fn agree<L: Law>(_: [&Self; 3], l: &Dual<Q>, r: &Dual<Q>) -> bool {
        l == r
    }
}

// ---------------------------------------------------------------------------------------------
// The laws: identities of ℚ, written once for every scalar.

/// An identity `lhs(a, b, c) = rhs(a, b, c)` (or, for the wrong laws, a claimed one); `None`
/// when a divisor is not certainly non-zero.
trait Law: 'static {
    const NAME: &'static str;
    fn sides<S: Scalar>(a: &S, b: &S, c: &S) -> Option<(S, S)>;
}

fn nonzero<S: Scalar>(x: &S) -> Option<()> {
    matches!(
        x.certain_cmp(&S::zero()),
        Some(Ordering::Less | Ordering::Greater)
    )
    .then_some(())
}

macro_rules! law {
    ($name:ident, $text:literal, |$a:ident, $b:ident, $c:ident| $body:expr) => {
        struct $name;
        impl Law for $name {
            const NAME: &'static str = $text;
            #[allow(unused_variables)]
            fn sides<S: Scalar>($a: &S, $b: &S, $c: &S) -> Option<(S, S)> {
                $body
            }
        }
    };
}

law!(AddAssoc, "(a + b) + c = a + (b + c)", |a, b, c| Some((
    a.clone() + b + c,
    a.clone() + (b.clone() + c)
)));
law!(MulAssoc, "(ab)c = a(bc)", |a, b, c| Some((
    a.clone() * b * c,
    a.clone() * (b.clone() * c)
)));
law!(AddComm, "a + b = b + a", |a, b, c| Some((
    a.clone() + b,
    b.clone() + a
)));
law!(MulComm, "ab = ba", |a, b, c| Some((
    a.clone() * b,
    b.clone() * a
)));
law!(Distrib, "a(b + c) = ab + ac", |a, b, c| Some((
    a.clone() * (b.clone() + c),
    a.clone() * b + a.clone() * c
)));
law!(AddZero, "a + 0 = a", |a, b, c| Some((
    a.clone() + S::zero(),
    a.clone()
)));
law!(MulOne, "a·1 = a", |a, b, c| Some((
    a.clone() * S::one(),
    a.clone()
)));
law!(AddInverse, "a + (−a) = 0", |a, b, c| Some((
    a.clone() + (-a.clone()),
    S::zero()
)));
law!(SubIsAddNeg, "a − b = a + (−b)", |a, b, c| Some((
    a.clone() - b,
    a.clone() + (-b.clone())
)));
law!(NegMul, "(−a)b = −(ab)", |a, b, c| Some((
    -a.clone() * b,
    -(a.clone() * b)
)));
law!(MulInverse, "a ≠ 0 ⇒ a·(1/a) = 1", |a, b, c| {
    nonzero(a)?;
    Some((a.clone() * (S::one() / a), S::one()))
});
law!(DivCancel, "b ≠ 0 ⇒ (a/b)·b = a", |a, b, c| {
    nonzero(b)?;
    Some((a.clone() / b * b, a.clone()))
});
law!(
    DivDistrib,
    "c ≠ 0 ⇒ (a + b)/c = a/c + b/c",
    |a, b, c| {
        nonzero(c)?;
        Some(((a.clone() + b) / c, a.clone() / c + b.clone() / c))
    }
);
law!(Square, "a.square() = a·a", |a, b, c| Some((
    a.square(),
    a.clone() * a
)));

// Wrong laws: every type's judgement must falsify them.
law!(SubCommutes, "(wrong) a − b = b − a", |a, b, c| Some((
    a.clone() - b,
    b.clone() - a
)));
law!(SquareOfSum, "(wrong) (a + b)² = a² + b²", |a, b, c| Some(
    ((a.clone() + b).square(), a.square() + b.square())
));

fn holds<W: LawScalar, L: Law>(a: W, b: W, c: W) -> TestResult {
    let x = [a.get(), b.get(), c.get()];
    match L::sides(&x[0], &x[1], &x[2]) {
        None => TestResult::discard(),
        Some((l, r)) if W::agree::<L>([&a, &b, &c], &l, &r) => TestResult::passed(),
        Some((l, r)) => TestResult::error(format!(
            "{}: lhs {}, rhs {}",
            L::NAME,
            W::show(&l),
            W::show(&r)
        )),
    }
}

fn check<W: LawScalar, L: Law>(failures: &mut Vec<String>) {
    if let Err(e) = run(holds::<W, L> as fn(W, W, W) -> TestResult) {
        failures.push(format!("{}: {e}", L::NAME));
    }
}

fn field_laws<W: LawScalar>() {
    let mut failures = Vec::new();
    check::<W, AddAssoc>(&mut failures);
    check::<W, MulAssoc>(&mut failures);
    check::<W, AddComm>(&mut failures);
    check::<W, MulComm>(&mut failures);
    check::<W, Distrib>(&mut failures);
    check::<W, AddZero>(&mut failures);
    check::<W, MulOne>(&mut failures);
    check::<W, AddInverse>(&mut failures);
    check::<W, SubIsAddNeg>(&mut failures);
    check::<W, NegMul>(&mut failures);
    check::<W, MulInverse>(&mut failures);
    check::<W, DivCancel>(&mut failures);
    check::<W, DivDistrib>(&mut failures);
    check::<W, Square>(&mut failures);
    assert!(
        failures.is_empty(),
        "{}: {failures:#?}",
        std::any::type_name::<W::S>()
    );
}

/// The deliberate mutations: each type's judgement falsifies a wrong law.
fn wrong_laws_fail<W: LawScalar>() {
    for (name, result) in [
        (
            SubCommutes::NAME,
            run(holds::<W, SubCommutes> as fn(W, W, W) -> TestResult),
        ),
        (
            SquareOfSum::NAME,
            run(holds::<W, SquareOfSum> as fn(W, W, W) -> TestResult),
        ),
    ] {
        assert!(
            result.is_err(),
            "{}: `{name}` was not falsified: the generator is not informative",
            std::any::type_name::<W::S>()
        );
    }
}

/// By-value, by-reference and compound-assignment forms of an operation are the same operation:
/// equal in every type, intervals and floats included.
fn forms_agree<W: LawScalar>(a: W, b: W) -> bool {
    let (a, b) = (a.get(), b.get());
    let mut t = a.clone();
    t += &b;
    t -= b.clone();
    t *= &a;
    t *= b.clone();
    let by_value = (a.clone() + b.clone() - b.clone()) * a.clone() * b.clone();
    let by_ref = (a.clone() + &b - &b) * &a * &b;
    let mut same = t == by_value && by_ref == by_value;
    if nonzero(&b).is_some() {
        let mut u = a.clone();
        u /= &b;
        let mut v = a.clone();
        v /= b.clone();
        same &= u == a.clone() / &b && v == a / b;
    }
    same
}

/// `from_ratio(n, d)` agrees with `n/d` under the tolerance policy (its `Agreement`), and
/// `from_rational` with `from_ratio`.
fn ratios_agree<W: LawScalar>(r: Rat) -> bool {
    let exact = r.q();
    let x = W::S::from_ratio(r.0, r.1);
    x.agrees(&exact, &Interval::from_ratio(r.0, r.1)) && W::S::from_rational(&exact) == x
}

/// A certain comparison (`cmp`) is answered exactly when every pair of points of the operands
/// compares the same way, and then with that answer; and it is antisymmetric.
fn cmp_is_certain<W: LawScalar>(
    cmp: fn(&W::S, &W::S) -> Option<Ordering>,
    a: &W,
    b: &W,
) -> Result<(), String> {
    let (pa, pb) = (a.points(), b.points());
    let pointwise: Vec<Ordering> = pa
        .iter()
        .flat_map(|x| pb.iter().map(move |y| x.cmp(y)))
        .collect();
    let unanimous = pointwise
        .iter()
        .all(|o| *o == pointwise[0])
        .then_some(pointwise[0]);
    let (x, y) = (a.get(), b.get());
    let got = cmp(&x, &y);
    if got != unanimous {
        return Err(format!("cmp = {got:?}, pointwise {pointwise:?}"));
    }
    if cmp(&y, &x) != got.map(Ordering::reverse) {
        return Err("not antisymmetric".into());
    }
    Ok(())
}

fn certain_cmp_prop<W: LawScalar>(a: W, b: W) -> TestResult {
    match cmp_is_certain::<W>(Scalar::certain_cmp, &a, &b) {
        Ok(()) => TestResult::passed(),
        Err(e) => TestResult::error(e),
    }
}

/// `positive_when_certain` is `certain_cmp` with 0, read as "greater or not" (floats override it).
fn positive_when_certain_prop<W: LawScalar>(a: W) -> bool {
    let x = a.get();
    let expected = x
        .certain_cmp(&<W::S as Scalar>::zero())
        .map(|o| o == Ordering::Greater);
    x.positive_when_certain() == expected
}

/// `all_finite` is the conjunction of `is_finite` over the entries, with and without a non-finite
/// entry (10³⁰ squared four times: an overflow in the floating types, a large number in ℚ), in
/// either order.
fn all_finite_prop<W: LawScalar>(a: W, b: W) -> bool {
    let (x, y) = (a.get(), b.get());
    let mut huge = <W::S as Scalar>::from_binary64(1e30).expect("1e30 is representable");
    for _ in 0..4 {
        huge = huge.clone() * huge;
    }
    let entries = [x, y, huge];
    (0..=entries.len()).all(|k| {
        let xs = &entries[..k];
        let rotated: Vec<W::S> = xs.iter().rev().cloned().collect();
        let expected = xs.iter().all(Scalar::is_finite);
        ilopt::scalar::all_finite(xs) == expected && ilopt::scalar::all_finite(&rotated) == expected
    })
}

/// num-traits' identities agree with the kit's, and generic num-traits code (`num_traits::pow`,
/// nalgebra's matrix products, which need `Zero + One`) runs on the scalar.
fn num_traits_prop<W: LawScalar>(a: W, b: W) -> bool
where
    W::S: Zero + One,
{
    let (x, y) = (a.get(), b.get());
    let identities = <W::S as Zero>::zero() == <W::S as Scalar>::zero()
        && <W::S as One>::one() == <W::S as Scalar>::one()
        && Zero::is_zero(&<W::S as Scalar>::zero())
        && !Zero::is_zero(&<W::S as Scalar>::one())
        && Zero::is_zero(&x) == (x == <W::S as Scalar>::zero());
    let pow = num_traits::pow(x.clone(), 3) == x.clone() * (x.clone() * x.clone());
    let m = nalgebra::DMatrix::from_row_slice(2, 2, &[x.clone(), y.clone(), y.clone(), x.clone()]);
    let id = nalgebra::DMatrix::<W::S>::identity(2, 2);
    let v = nalgebra::DVector::from_vec(vec![y.clone(), x.clone()]);
    let mv = &m * &v;
    let matrices = &id * &m == m
        && mv[0] == x.clone() * y.clone() + y.clone() * x.clone()
        && mv[1] == y.clone() * y.clone() + x.clone() * x.clone();
    identities && pow && matrices
}

macro_rules! scalar_laws {
    ($($module:ident => $w:ty),+ $(,)?) => {$(
        mod $module {
            use super::*;

            #[test]
            fn field_laws_hold() {
                field_laws::<$w>();
            }

            #[test]
            fn wrong_laws_are_falsified() {
                wrong_laws_fail::<$w>();
            }

            #[test]
            fn operator_forms_agree() {
                run(forms_agree::<$w> as fn($w, $w) -> bool).unwrap();
            }

            #[test]
            fn ratios_agree_with_the_exact_value() {
                run(ratios_agree::<$w> as fn(Rat) -> bool).unwrap();
            }

            #[test]
            fn comparisons_are_certain() {
                run(certain_cmp_prop::<$w> as fn($w, $w) -> TestResult).unwrap();
            }

            #[test]
            fn all_finite_is_every_entry_finite() {
                run(all_finite_prop::<$w> as fn($w, $w) -> bool).unwrap();
            }

            #[test]
            fn positive_when_certain_is_the_comparison_with_zero() {
                run(positive_when_certain_prop::<$w> as fn($w) -> bool).unwrap();
            }
        }
    )+};
}

scalar_laws!(
    exact_rational => Rat,
    float64 => F64,
    float32 => F32,
    interval => Iv,
    dual_float64 => D<F64>,
    dual_rational => D<Rat>,
);

/// The scalars that implement num-traits' `Zero` and `One` (all but inari's `Interval`, a foreign
/// type the kit cannot give a foreign trait).
macro_rules! num_traits_interop {
    ($($name:ident => $w:ty),+ $(,)?) => {$(
        #[test]
        fn $name() {
            run(num_traits_prop::<$w> as fn($w, $w) -> bool).unwrap();
        }
    )+};
}

num_traits_interop!(
    num_traits_rational => Rat,
    num_traits_float64 => F64,
    num_traits_float32 => F32,
    num_traits_dual_float64 => D<F64>,
    num_traits_dual_rational => D<Rat>,
);

// ---------------------------------------------------------------------------------------------
// Laws particular to one type, and their mutations.

/// An interval with endpoints `k/16`, `|k| ≤ 2¹⁰`: sums and products of three of them are exact
/// in binary64, so the laws of exact interval arithmetic hold without rounding.
#[derive(Clone)]
struct DyadicIv(Interval);

impl Debug for DyadicIv {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&show_interval(&self.0))
    }
}

impl Arbitrary for DyadicIv {
    fn arbitrary(g: &mut Gen) -> Self {
        let x = int_in(g, 1 << 10) as f64 / 16.0;
        let y = if bool::arbitrary(g) {
            x
        } else {
            int_in(g, 1 << 10) as f64 / 16.0
        };
        DyadicIv(Interval::try_from((x.min(y), x.max(y))).unwrap())
    }
}

fn sub_distributive(a: DyadicIv, b: DyadicIv, c: DyadicIv) -> bool {
    let (a, b, c) = (a.0, b.0, c.0);
    (a * (b + c)).subset(a * b + a * c)
}

fn super_distributive(a: DyadicIv, b: DyadicIv, c: DyadicIv) -> bool {
    let (a, b, c) = (a.0, b.0, c.0);
    (a * b + a * c).subset(a * (b + c))
}

/// Sub-distributivity `a(b + c) ⊆ ab + ac`, a law of exact interval arithmetic, checked where the
/// float operations are exact (with rounding, each side is only an enclosure of the exact set,
/// which the inclusion laws above check, and the two roundings need not nest); the reverse
/// inclusion is false for intervals and is falsified. And the square is tight: `a² ⊆ a·a`.
#[test]
fn intervals_are_sub_distributive() {
    type Iv3 = fn(DyadicIv, DyadicIv, DyadicIv) -> bool;
    run(sub_distributive as Iv3).unwrap();
    assert!(run(super_distributive as Iv3).is_err());
    run((|a: Iv| a.0.square().subset(a.0 * a.0)) as fn(Iv) -> bool).unwrap();
}

/// Ordering intervals by their midpoints is not a certain comparison: the law falsifies it.
#[test]
fn a_comparison_by_midpoints_is_falsified() {
    fn by_midpoints(a: Iv, b: Iv) -> bool {
        cmp_is_certain::<Iv>(|x, y| x.mid().partial_cmp(&y.mid()), &a, &b).is_ok()
    }
    assert!(run(by_midpoints as fn(Iv, Iv) -> bool).is_err());
}

/// Exact associativity is false in f64 (which is why the f64 laws carry a tolerance): the
/// generator reaches values that round.
#[test]
fn exact_f64_associativity_is_falsified() {
    fn exact(a: F64, b: F64, c: F64) -> bool {
        (a.0 + b.0) + c.0 == a.0 + (b.0 + c.0)
    }
    assert!(run(exact as fn(F64, F64, F64) -> bool).is_err());
}

// Polynomials over ℚ, for derivatives by an independent route (their coefficients).

#[derive(Clone, Debug)]
struct Poly(Vec<Rat>);

impl Arbitrary for Poly {
    fn arbitrary(g: &mut Gen) -> Self {
        let n = 1 + usize::from(u8::arbitrary(g) % 4);
        Poly((0..n).map(|_| Rat::arbitrary(g)).collect())
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        Box::new(self.0.shrink().filter(|c| !c.is_empty()).map(Poly))
    }
}

fn coefficients(p: &Poly) -> Vec<Q> {
    p.0.iter().map(Rat::q).collect()
}

/// Horner's scheme, in any scalar.
fn eval<S: Scalar>(c: &[Q], x: &S) -> S {
    c.iter()
        .rev()
        .fold(S::zero(), |acc, k| acc * x + S::from_rational(k))
}

fn derivative(c: &[Q]) -> Vec<Q> {
    c.iter()
        .enumerate()
        .skip(1)
        .map(|(k, ck)| Q::from_i64(k as i64) * ck)
        .collect()
}

fn product(p: &[Q], q: &[Q]) -> Vec<Q> {
    let mut out = vec![<Q as Zero>::zero(); p.len() + q.len() - 1];
    for (i, a) in p.iter().enumerate() {
        for (j, b) in q.iter().enumerate() {
            out[i + j] += a.clone() * b;
        }
    }
    out
}

/// The coefficients of `p(q(x))`.
fn compose(p: &[Q], q: &[Q]) -> Vec<Q> {
    p.iter().rev().fold(vec![<Q as Zero>::zero()], |acc, k| {
        let mut next = product(&acc, q);
        next[0] += k;
        next
    })
}

/// The derivative at `x` of `f`, evaluated through `Dual<Q>` arithmetic.
fn dual_derivative(f: impl Fn(&Dual<Q>) -> Dual<Q>, x: &Q) -> Q {
    f(&Dual::variable(x.clone(), 0, 1)).gradient_padded(1)[0].clone()
}

/// The product, quotient and chain rules, exactly, against derivatives from coefficients.
fn derivative_rules(p: Poly, q: Poly, x: Rat) -> TestResult {
    let (p, q, x) = (coefficients(&p), coefficients(&q), x.q());
    let product_rule = dual_derivative(|t| eval(&p, t) * eval(&q, t), &x)
        == eval(&derivative(&product(&p, &q)), &x);
    let chain_rule =
        dual_derivative(|t| eval(&p, &eval(&q, t)), &x) == eval(&derivative(&compose(&p, &q)), &x);
    let qx = eval(&q, &x);
    let quotient_rule = qx.is_zero()
        || dual_derivative(|t| eval(&p, t) / eval(&q, t), &x)
            == (eval(&derivative(&p), &x) * &qx - eval(&p, &x) * eval(&derivative(&q), &x))
                / (qx.clone() * &qx);
    let values = *Dual::constant(eval(&p, &x)).value() == eval::<Q>(&p, &x);
    TestResult::from_bool(product_rule && chain_rule && quotient_rule && values)
}

#[test]
fn dual_derivatives_obey_the_product_quotient_and_chain_rules() {
    run(derivative_rules as fn(Poly, Poly, Rat) -> TestResult).unwrap();
    // The wrong product rule (pq)' = p'q' is falsified.
    fn wrong_product_rule(p: Poly, q: Poly, x: Rat) -> bool {
        let (p, q, x) = (coefficients(&p), coefficients(&q), x.q());
        dual_derivative(|t| eval(&p, t) * eval(&q, t), &x)
            == eval(&derivative(&p), &x) * eval(&derivative(&q), &x)
    }
    assert!(run(wrong_product_rule as fn(Poly, Poly, Rat) -> bool).is_err());
}
