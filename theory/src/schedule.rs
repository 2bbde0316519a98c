//! The STORM schedule (3.43) and erratum E7, decided rigorously (math.md §§3.1–3.2).
//!
//! With y_k = (7/(k+7))^{1/3}, the schedule is η_k = y_k/(4L) and a_{k+1} = y_k². Then
//! * (C1) Lη_k ≤ 1/2 ⟺ y_k ≤ 2;
//! * (C2) 4L²η_k² + (1 − a_{k+1})² ≤ η_k/η_{k−1} ⟺ a/4 + (1 − a)² ≤ ((k+6)/(k+7))^{1/3};
//! * the thesis's own route (E7) needs 1 − a/4 + a²/2 + a³/4 ≤ ((k+6)/(k+7))^{1/3}, which fails for
//!   k = 1..23.
//!
//! Cube roots are enclosed in rationals by bisection (lo³ ≤ q ≤ hi³), so every verdict is a proof,
//! not a float comparison; when the enclosure is too coarse to decide, it is refined.

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};
use serde::{Deserialize, Serialize};

/// Rational bounds `lo ≤ q^{1/3} ≤ hi` for q ≥ 0, of width ≤ 2^{−bits}·max(1, q)
/// ([`root_enclosure`] of degree 3).
pub fn cbrt_enclosure(q: &BigRational, bits: u32) -> (BigRational, BigRational) {
    root_enclosure(q, 3, bits)
}

/// Rational bounds `lo ≤ q^{1/n} ≤ hi` for q ≥ 0 and a degree n ≥ 1, of width
/// ≤ 2^{−bits}·max(1, q): `bits` steps of bisection of `[0, max(1, q)]`, keeping
/// `loⁿ ≤ q ≤ hiⁿ`.
///
/// Every midpoint is `H·j/2^b` with `H = max(1, q) = n_H/d_H` and an integer j, so with
/// `q = n/d` the test `midⁿ ≤ q` is the integer comparison `n_Hⁿ jⁿ d ≤ n d_Hⁿ 2^{nb}`: the same
/// bisection as in rationals, without a gcd per step.
pub fn root_enclosure(q: &BigRational, degree: u32, bits: u32) -> (BigRational, BigRational) {
    let h = q.clone().max(BigRational::one());
    let (n, d) = (q.numer(), q.denom());
    let (nh, dh) = (h.numer(), h.denom());
    // midⁿ ≤ q ⟺ jⁿ · (n_Hⁿ d) ≤ (n d_Hⁿ) · 2^{nb} at depth b.
    let left = nh.pow(degree) * d;
    let right = n * dh.pow(degree);
    let (mut lo, mut hi) = (BigInt::zero(), BigInt::one());
    for b in 1..=bits {
        // The interval [lo, hi]/2^{b−1} halved: [2lo, 2hi]/2^b, midpoint lo + hi.
        let mid = lo.clone() + &hi;
        lo <<= 1;
        hi <<= 1;
        if mid.pow(degree) * &left <= right.clone() << ((degree * b) as usize) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let scale = BigInt::one() << bits as usize;
    let at = |j: BigInt| BigRational::new(j, scale.clone()) * &h;
    (at(lo), at(hi))
}

/// A decided inequality `lhs ≤ rhs`, or undecided at the precision tried.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Proved to hold.
    Holds,
    /// Proved to fail.
    Fails,
    /// Not decided (equality or beyond the precision tried).
    Undecided,
}

fn ratio(n: u64, d: u64) -> BigRational {
    BigRational::new(BigInt::from(n), BigInt::from(d))
}

/// Decide `f(a) ≤ r` where `a = (7/(k+7))^{2/3}`, `r = ((k+6)/(k+7))^{1/3}`, from a function
/// giving (lower, upper) bounds of f over a rational interval [a_lo, a_hi] ⊂ [0, 1].
fn decide_at(
    k: u64,
    bounds: impl Fn(&BigRational, &BigRational) -> (BigRational, BigRational),
) -> Verdict {
    for bits in [24u32, 48, 96] {
        let (ylo, yhi) = cbrt_enclosure(&ratio(7, k + 7), bits);
        let (rlo, rhi) = cbrt_enclosure(&ratio(k + 6, k + 7), bits);
        let (alo, ahi) = (
            ylo.clone() * &ylo,
            (yhi.clone() * &yhi).min(BigRational::one()),
        );
        let (flo, fhi) = bounds(&alo, &ahi);
        if fhi <= rlo {
            return Verdict::Holds;
        }
        if flo > rhi {
            return Verdict::Fails;
        }
    }
    Verdict::Undecided
}

/// (C2) at step k: `a/4 + (1 − a)² ≤ ((k+6)/(k+7))^{1/3}`.
pub fn c2(k: u64) -> Verdict {
    let four = ratio(4, 1);
    decide_at(k, |alo, ahi| {
        let one = BigRational::one();
        let lo = alo.clone() / &four + (one.clone() - ahi) * (one.clone() - ahi);
        let hi = ahi.clone() / &four + (one.clone() - alo) * (one - alo);
        (lo, hi)
    })
}

/// The thesis's condition after (3.58)/(3.59) (erratum E7) at step k:
/// `1 − a/4 + a²/2 + a³/4 ≤ ((k+6)/(k+7))^{1/3}`.
pub fn thesis_route(k: u64) -> Verdict {
    decide_at(k, |alo, ahi| {
        let one = BigRational::one();
        let (two, four) = (ratio(2, 1), ratio(4, 1));
        let poly = |neg: &BigRational, pos: &BigRational| {
            one.clone() - neg.clone() / &four
                + pos.clone() * pos / &two
                + pos.clone() * pos * pos / &four
        };
        (poly(ahi, alo), poly(alo, ahi))
    })
}

/// (C1) at step k for the schedule (3.43): Lη_k = y_k/4 ≤ 1/2 ([`c1_scaled`] with s = 1/4).
pub fn c1(k: u64) -> Verdict {
    c1_scaled(k, &ratio(1, 4))
}

/// (C1) at step k for a step Lη_k = s·y_k, y_k = (7/(k+7))^{1/3}: proved to hold when
/// s·hi ≤ 1/2 and to fail when s·lo > 1/2, for the cube-root enclosure [lo, hi] ∋ y_k, refined
/// as in (C2). With s = 1 (the schedule without its 1/4 factor) (C1) is false exactly for
/// 7/(k+7) > 1/8, i.e. k ≤ 48 (at k = 49, y_k = 1/2 and it holds with equality).
pub fn c1_scaled(k: u64, s: &BigRational) -> Verdict {
    let half = ratio(1, 2);
    for bits in [24u32, 48, 96] {
        let (ylo, yhi) = cbrt_enclosure(&ratio(7, k + 7), bits);
        if yhi * s <= half {
            return Verdict::Holds;
        }
        if ylo * s > half {
            return Verdict::Fails;
        }
    }
    Verdict::Undecided
}

/// Every k ≤ k_max where (C1) is proved false for the step Lη_k = s·y_k ([`c1_scaled`]), and
/// every k where it is undecided.
pub fn c1_scaled_failures(k_max: u64, s: &BigRational) -> (Vec<u64>, Vec<u64>) {
    let (mut fails, mut undecided) = (vec![], vec![]);
    for k in 1..=k_max {
        match c1_scaled(k, s) {
            Verdict::Fails => fails.push(k),
            Verdict::Undecided => undecided.push(k),
            Verdict::Holds => {}
        }
    }
    (fails, undecided)
}

/// What the schedule checks found for k = 1..=k_max.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScheduleReport {
    /// Largest k checked.
    pub k_max: u64,
    /// Every k where (C1) was not proved.
    pub c1_not_proved: Vec<u64>,
    /// Every k where (C2) was not proved.
    pub c2_not_proved: Vec<u64>,
    /// Every k where the thesis's route was proved to fail.
    pub thesis_route_fails: Vec<u64>,
    /// Every k where the thesis's route was not decided.
    pub thesis_route_undecided: Vec<u64>,
}

/// Check (C1), (C2) and the thesis route for k = 1..=k_max.
pub fn check_schedule(k_max: u64) -> ScheduleReport {
    let mut r = ScheduleReport {
        k_max,
        c1_not_proved: vec![],
        c2_not_proved: vec![],
        thesis_route_fails: vec![],
        thesis_route_undecided: vec![],
    };
    for k in 1..=k_max {
        if c1(k) != Verdict::Holds {
            r.c1_not_proved.push(k);
        }
        if c2(k) != Verdict::Holds {
            r.c2_not_proved.push(k);
        }
        match thesis_route(k) {
            Verdict::Fails => r.thesis_route_fails.push(k),
            Verdict::Undecided => r.thesis_route_undecided.push(k),
            Verdict::Holds => {}
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bisection in rationals, step by step: the reference the integer route must equal.
    fn cbrt_by_rational_bisection(q: &BigRational, bits: u32) -> (BigRational, BigRational) {
        let (mut lo, mut hi) = (BigRational::zero(), q.clone().max(BigRational::one()));
        let two = ratio(2, 1);
        for _ in 0..bits {
            let mid = (lo.clone() + &hi) / &two;
            if mid.clone() * &mid * &mid <= *q {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (lo, hi)
    }

    /// The integer route returns exactly the rational bisection's bounds, for q below, at and
    /// above 1 (where the bisection starts from [0, q]), perfect cubes included.
    #[test]
    fn integer_bisection_equals_rational_bisection() {
        let mut qs: Vec<BigRational> = (1..=60).map(|k| ratio(7, k + 7)).collect();
        qs.extend((1..=60).map(|k| ratio(k + 6, k + 7)));
        qs.extend([
            ratio(0, 1),
            ratio(1, 1),
            ratio(27, 8),
            ratio(8, 27),
            ratio(1000, 3),
        ]);
        qs.extend([ratio(64, 1), ratio(1, 64), ratio(123_456_789, 1_000)]);
        for q in &qs {
            for bits in [1u32, 2, 7, 24, 48, 96] {
                assert_eq!(
                    cbrt_enclosure(q, bits),
                    cbrt_by_rational_bisection(q, bits),
                    "q = {q}, bits = {bits}"
                );
            }
        }
    }

    #[test]
    fn cube_roots_are_enclosed() {
        let (lo, hi) = cbrt_enclosure(&ratio(27, 8), 40);
        assert!(lo <= ratio(3, 2) && ratio(3, 2) <= hi);
        let (lo, hi) = cbrt_enclosure(&ratio(7, 8), 40);
        assert!(lo.clone() * &lo * &lo <= ratio(7, 8) && ratio(7, 8) <= hi.clone() * &hi * &hi);
        assert!(hi - lo <= ratio(1, 1 << 39));
    }

    /// Square roots (degree 2) are enclosed the same way, above and below 1.
    #[test]
    fn square_roots_are_enclosed() {
        for (n, d) in [(9, 4), (2, 1), (1, 3), (50, 1)] {
            let x = ratio(n, d);
            let (lo, hi) = root_enclosure(&x, 2, 40);
            assert!(lo.clone() * &lo <= x && x <= hi.clone() * &hi, "{x}");
            assert!(hi - lo <= ratio(n.max(d), d) * ratio(1, 1 << 39), "{x}");
        }
    }

    /// E7 (math.md §3.1): the thesis route fails exactly for k = 1..23; (C1), (C2) hold throughout.
    #[test]
    fn erratum_e7_and_the_corrected_conditions() {
        let r = check_schedule(400);
        assert_eq!(r.thesis_route_fails, (1..=23).collect::<Vec<_>>());
        assert!(r.thesis_route_undecided.is_empty());
        assert!(r.c1_not_proved.is_empty() && r.c2_not_proved.is_empty());
    }

    /// The (C1) check can report failure: for the step without its 1/4 factor
    /// (Lη_k = (7/(k+7))^{1/3}) it proves (C1) false exactly for k = 1..48; k = 49 (Lη_k = 1/2
    /// exactly, a perfect cube) is left undecided, and from k = 50 on (C1) is proved.
    #[test]
    fn c1_is_refuted_for_the_step_without_its_quarter() {
        let (fails, undecided) = c1_scaled_failures(400, &ratio(1, 1));
        assert_eq!(fails, (1..=48).collect::<Vec<_>>());
        assert_eq!(undecided, vec![49]);
        assert_eq!(c1(1), Verdict::Holds);
        assert_eq!(c1_scaled(1, &ratio(1, 1)), Verdict::Fails);
    }

    /// The decision procedure can report failure: the thesis route is proved false at k = 1
    /// (LHS ≈ 1.38 against RHS ≈ 0.956, math.md §3.1) and proved true at k = 24.
    #[test]
    fn the_procedure_reports_both_outcomes() {
        assert_eq!(thesis_route(1), Verdict::Fails);
        assert_eq!(thesis_route(24), Verdict::Holds);
    }
}
