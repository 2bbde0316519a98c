//! Sums and differences of intervals without switching the rounding mode: inari's results, bit
//! for bit, at a fraction of their cost on x86-64.
//!
//! inari adds [a, b] + [c, d] as the vector sum (−a, b) + (−c, d) rounded upward, setting the
//! rounding mode around it (and subtracts as (−a, b) + (d, −c)). As for the product
//! (`interval_product`), the directed rounding also follows from the sum rounded to nearest and
//! its exact error: for floats x, y with s = fl(x + y), Møller and Knuth's 2Sum
//! (t = s − x, e = (x − (s − t)) + (y − t)) gives e = x + y − s exactly whenever nothing overflows
//! (Muller et al., *Handbook of Floating-Point Arithmetic*, 2nd ed., 2018, §4.3), which
//! |x|, |y| ≤ 2¹⁰²¹ ensures. Then x + y rounded upward is s when e ≤ 0 and the float after s when
//! e > 0. [`add`] and [`sub`] take this route when every endpoint involved and both results are
//! nonzero and the endpoints are at most 2¹⁰²¹ in magnitude (so neither operand is empty or
//! unbounded, and no zero's sign is in question); every other case, and every target other than
//! x86-64, goes to inari.

use inari::Interval;

/// The largest endpoint magnitude the vector route takes.
const BIG: f64 = f64::from_bits((1023 + 1021) << 52);

/// `x + y`, the same interval as inari's `x + y` (module docs).
#[inline]
#[must_use]
pub fn add(x: Interval, y: Interval) -> Interval {
    vector_route(x, [-y.inf(), y.sup()]).unwrap_or_else(|| x + y)
}

/// `x − y`, the same interval as inari's `x - y` (module docs).
#[inline]
#[must_use]
pub fn sub(x: Interval, y: Interval) -> Interval {
    vector_route(x, [y.sup(), -y.inf()]).unwrap_or_else(|| x - y)
}

/// (−a, b) + y rounded upward, as an interval, by the vector route; `None` where it does not
/// apply (module docs).
#[inline]
fn vector_route(x: Interval, y: [f64; 2]) -> Option<Interval> {
    #[cfg(target_arch = "x86_64")]
    {
        #[allow(unsafe_code)]
        // SAFETY: SSE2 is part of every x86-64 target, the only feature `vector::add_up` needs.
        unsafe {
            vector::add_up([-x.inf(), x.sup()], y)
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (x, y);
        None
    }
}

#[cfg(target_arch = "x86_64")]
mod vector {
    use super::BIG;
    use core::arch::x86_64::{
        __m128d, _mm_add_pd, _mm_and_pd, _mm_andnot_pd, _mm_castpd_si128, _mm_castsi128_pd,
        _mm_cmpgt_pd, _mm_cmple_pd, _mm_cmplt_pd, _mm_cmpneq_pd, _mm_cvtsd_f64, _mm_movemask_pd,
        _mm_set_pd, _mm_set1_pd, _mm_setzero_pd, _mm_sub_epi64, _mm_sub_pd, _mm_unpackhi_pd,
        _mm_xor_si128,
    };
    use inari::Interval;

    /// `x + y` lane by lane rounded upward, read as (−lower, upper); `None` where an entry or a
    /// sum is 0, non-finite or beyond [`BIG`].
    #[inline]
    #[target_feature(enable = "sse2")]
    pub(super) fn add_up(x: [f64; 2], y: [f64; 2]) -> Option<Interval> {
        let xv = _mm_set_pd(x[1], x[0]);
        let yv = _mm_set_pd(y[1], y[0]);
        let s = _mm_add_pd(xv, yv);
        let zero = _mm_setzero_pd();
        let usable = |v: __m128d| {
            let m = _mm_andnot_pd(_mm_set1_pd(-0.0), v);
            _mm_and_pd(_mm_cmple_pd(m, _mm_set1_pd(BIG)), _mm_cmpneq_pd(v, zero))
        };
        let ok = _mm_and_pd(_mm_and_pd(usable(xv), usable(yv)), _mm_cmpneq_pd(s, zero));
        if _mm_movemask_pd(ok) != 0b11 {
            return None;
        }
        // 2Sum: e = x + y − s exactly.
        let t = _mm_sub_pd(s, xv);
        let e = _mm_add_pd(_mm_sub_pd(xv, _mm_sub_pd(s, t)), _mm_sub_pd(yv, t));
        // The float after a nonzero s is its bit pattern + 1 for s > 0 and − 1 for s < 0;
        // (m ^ n) − n is m for n = 0 and −m for n = −1.
        let negative = _mm_castpd_si128(_mm_cmplt_pd(s, zero));
        let e_above = _mm_castpd_si128(_mm_cmpgt_pd(e, zero));
        let step = _mm_sub_epi64(_mm_xor_si128(e_above, negative), negative);
        let up = _mm_castsi128_pd(_mm_sub_epi64(_mm_castpd_si128(s), step));
        let lower = -_mm_cvtsd_f64(up);
        let upper = _mm_cvtsd_f64(_mm_unpackhi_pd(up, up));
        Interval::try_from((lower, upper)).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::KitRng;
    use rand::{Rng, SeedableRng};

    fn same(x: Interval, y: Interval) -> bool {
        (x.is_empty() && y.is_empty())
            || (x.inf().to_bits() == y.inf().to_bits() && x.sup().to_bits() == y.sup().to_bits())
    }

    /// Intervals of every kind: endpoints of every sign and magnitude (zeros, infinities,
    /// subnormals, the threshold's neighbours, the largest floats), narrow boxes, points, and the
    /// empty and entire intervals.
    fn intervals(rng: &mut KitRng) -> Vec<Interval> {
        let mut e = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            5e-324,
            BIG,
            BIG.next_up(),
            BIG.next_down(),
            1.0,
            0.1,
        ];
        for _ in 0..300 {
            let m: f64 = rng.random_range(1.0..2.0);
            let k: i32 = [
                rng.random_range(-4..4),
                rng.random_range(-60..60),
                rng.random_range(-1074..1024),
            ][rng.random_range(0..3)];
            e.push(m * 2f64.powi(k));
        }
        let negated: Vec<f64> = e.iter().map(|x| -x).collect();
        e.extend(negated);
        let mut xs = vec![Interval::EMPTY, Interval::ENTIRE];
        for _ in 0..2500 {
            let (a, b) = (
                e[rng.random_range(0..e.len())],
                e[rng.random_range(0..e.len())],
            );
            if let Ok(x) = Interval::try_from((a.min(b), a.max(b))) {
                xs.push(x);
            }
            let a: f64 = rng.random_range(-4.0..4.0);
            let w = 2f64.powi(rng.random_range(-50..0));
            xs.push(Interval::try_from((a, a + w)).unwrap());
            xs.push(Interval::try_from((a, a)).unwrap());
            // Sums that cancel: the negated interval, and one an ulp away.
            xs.push(Interval::try_from((-a - w, -a)).unwrap());
            xs.push(Interval::try_from(((-a).next_up(), (-a).next_up())).unwrap());
        }
        xs
    }

    /// Against inari's sum and difference, bit for bit, including the cases the vector route
    /// leaves to inari.
    #[test]
    fn sums_and_differences_are_inaris_bit_for_bit() {
        let mut rng = KitRng::seed_from_u64(9);
        let xs = intervals(&mut rng);
        let (mut checked, mut vector) = (0usize, 0usize);
        for (i, x) in xs.iter().enumerate() {
            for y in xs.iter().skip(i % 9).step_by(9) {
                let (s, d) = (add(*x, *y), sub(*x, *y));
                assert!(same(s, *x + *y), "{x:?} + {y:?}: {s:?} vs {:?}", *x + *y);
                assert!(same(d, *x - *y), "{x:?} − {y:?}: {d:?} vs {:?}", *x - *y);
                checked += 1;
                vector += usize::from(vector_route(*x, [-y.inf(), y.sup()]).is_some());
            }
        }
        assert!(checked > 1_000_000, "{checked}");
        #[cfg(target_arch = "x86_64")]
        assert!(
            vector > checked / 4,
            "the vector route took {vector} of {checked}"
        );
        let _ = vector;
    }

    /// The check has power: the sums rounded to nearest (no correction by the error) differ
    /// from inari's in most cases of inexact sums.
    #[test]
    fn rounding_to_nearest_would_be_caught() {
        let mut rng = KitRng::seed_from_u64(13);
        let mut differ = 0;
        for _ in 0..1000 {
            let a: f64 = rng.random_range(0.5..2.0);
            let c: f64 = rng.random_range(1e-9..1e-3);
            let x = Interval::try_from((a, a)).unwrap();
            let y = Interval::try_from((c, c)).unwrap();
            let nearest = Interval::try_from((a + c, a + c)).unwrap();
            differ += usize::from(!same(nearest, add(x, y)));
        }
        assert!(differ > 900, "{differ}");
    }
}
