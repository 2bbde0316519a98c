//! The product of two intervals without switching the rounding mode: inari's result, bit for
//! bit, at a fraction of its cost on x86-64.
//!
//! inari classifies both operands by the signs of their endpoints (a nine-way case table, whose
//! branch intervals of mixed signs mispredict) and rounds the chosen endpoint products by setting
//! the rounding mode to upward around the vector multiplication. The directed roundings also
//! follow, without a branch on the signs, from the products rounded to nearest and their exact
//! residuals. For floats x, y with p = fl(x·y) and
//! r = fma(x, y, −p), r equals x·y − p exactly whenever |x·y| ≥ 2⁻⁹⁶⁹ (the error of a product is a
//! float when the exponents satisfy e_x + e_y ≥ e_min + 52; Muller et al., *Handbook of
//! Floating-Point Arithmetic*, 2nd ed., 2018, §4.2). Then x·y rounded upward is p when
//! r ≤ 0 and the float after p when r > 0; rounded downward, p when r ≥ 0 and the float before p
//! when r < 0 (past `f64::MAX` the next float is ∞, as upward rounding gives).
//!
//! [a, b]·[c, d] is [min of the four products rounded down, max of them rounded up]: inari's case
//! table picks the extremal products, and directed rounding is monotone, so the minimum of the
//! rounded products is the rounded minimum. [`mul`] computes the four in one vector register when
//! every endpoint product is finite and at least [`TINY`] in magnitude (so no endpoint is 0 or
//! infinite and neither operand is empty); every other case, and every target without AVX2 and
//! FMA, goes to inari's `*`.

use inari::Interval;

/// The smallest magnitude of an endpoint product the vector route takes: 2⁻⁹⁶⁸, above the 2⁻⁹⁶⁹
/// from which the FMA residual of a product is exact.
pub(crate) const TINY: f64 = f64::from_bits((1023 - 968) << 52);

/// `x · y`, the same interval as inari's `x * y` (module docs).
#[inline]
#[must_use]
pub fn mul(x: Interval, y: Interval) -> Interval {
    vector_route(x, y).unwrap_or_else(|| x * y)
}

/// The product by the vector route, or `None` where it does not apply (module docs).
#[inline]
fn vector_route(x: Interval, y: Interval) -> Option<Interval> {
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ))]
    {
        #[allow(unsafe_code)]
        // SAFETY: the `cfg` above admits this only where the build enables AVX2 and FMA, the
        // target features `vector::mul` needs.
        unsafe {
            vector::mul(x.inf(), x.sup(), y.inf(), y.sup())
        }
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    )))]
    {
        let _ = (x, y);
        None
    }
}

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
mod vector {
    use super::TINY;
    use core::arch::x86_64::{
        _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ, _mm_cvtsd_f64, _mm_max_pd, _mm_max_sd,
        _mm_min_pd, _mm_min_sd, _mm_unpackhi_pd, _mm256_add_epi64, _mm256_and_pd, _mm256_andnot_pd,
        _mm256_castpd_si256, _mm256_castpd256_pd128, _mm256_castsi256_pd, _mm256_cmp_pd,
        _mm256_extractf128_pd, _mm256_fmsub_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_set_pd,
        _mm256_set1_pd, _mm256_setzero_pd, _mm256_sub_epi64, _mm256_xor_si256,
    };
    use inari::Interval;

    /// [a, b]·[c, d] from the four endpoint products and their FMA residuals, or `None` where an
    /// endpoint product is not a finite float of magnitude at least [`TINY`].
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn mul(a: f64, b: f64, c: f64, d: f64) -> Option<Interval> {
        // Lanes (low to high): a·c, a·d, b·c, b·d.
        let x = _mm256_set_pd(b, b, a, a);
        let y = _mm256_set_pd(d, c, d, c);
        let p = _mm256_mul_pd(x, y);
        let magnitude = _mm256_andnot_pd(_mm256_set1_pd(-0.0), p);
        let in_range = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_GE_OQ>(magnitude, _mm256_set1_pd(TINY)),
            _mm256_cmp_pd::<_CMP_LE_OQ>(magnitude, _mm256_set1_pd(f64::MAX)),
        );
        if _mm256_movemask_pd(in_range) != 0b1111 {
            return None;
        }
        // r = x·y − p, exact here.
        let r = _mm256_fmsub_pd(x, y, p);
        let zero = _mm256_setzero_pd();
        // All ones (−1 as an integer) where p < 0, where r > 0, where r < 0.
        let negative = _mm256_castpd_si256(_mm256_cmp_pd::<_CMP_LT_OQ>(p, zero));
        let r_above = _mm256_castpd_si256(_mm256_cmp_pd::<_CMP_GT_OQ>(r, zero));
        let r_below = _mm256_castpd_si256(_mm256_cmp_pd::<_CMP_LT_OQ>(r, zero));
        // A nonzero float's neighbours are its bit pattern ± 1: away from 0 upward for p > 0 and
        // downward for p < 0. (m ^ s) − s is m for s = 0 and −m for s = −1.
        let bits = _mm256_castpd_si256(p);
        let signed = |m| _mm256_sub_epi64(_mm256_xor_si256(m, negative), negative);
        let up = _mm256_castsi256_pd(_mm256_sub_epi64(bits, signed(r_above)));
        let down = _mm256_castsi256_pd(_mm256_add_epi64(bits, signed(r_below)));
        let hi = _mm_max_pd(_mm256_castpd256_pd128(up), _mm256_extractf128_pd::<1>(up));
        let lo = _mm_min_pd(
            _mm256_castpd256_pd128(down),
            _mm256_extractf128_pd::<1>(down),
        );
        let hi = _mm_cvtsd_f64(_mm_max_sd(hi, _mm_unpackhi_pd(hi, hi)));
        let lo = _mm_cvtsd_f64(_mm_min_sd(lo, _mm_unpackhi_pd(lo, lo)));
        Interval::try_from((lo, hi)).ok()
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

    /// Endpoints of every kind: signs, zeros, infinities, magnitudes from the subnormals to the
    /// largest float, neighbours of the thresholds, and random mantissas.
    fn endpoints(rng: &mut KitRng) -> Vec<f64> {
        let mut v = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            5e-324,
            TINY,
            TINY.next_up(),
            TINY.next_down(),
            f64::MAX.sqrt(),
            f64::MAX.sqrt().next_up(),
            TINY.sqrt(),
            TINY.sqrt().next_down(),
            1.0,
            1.0 / 3.0,
            0.1,
        ];
        for _ in 0..400 {
            let m: f64 = rng.random_range(1.0..2.0);
            let e: i32 = [
                rng.random_range(-4..4),
                rng.random_range(-600..600),
                rng.random_range(-1074..1024),
            ][rng.random_range(0..3)];
            v.push(m * 2f64.powi(e));
        }
        let negated: Vec<f64> = v.iter().map(|x| -x).collect();
        v.extend(negated);
        v
    }

    /// Against inari's product, bit for bit, on intervals from every pair of endpoint kinds (and
    /// the empty and entire intervals), including the cases the vector route leaves to inari.
    #[test]
    fn the_product_is_inaris_bit_for_bit() {
        let mut rng = KitRng::seed_from_u64(3);
        let e = endpoints(&mut rng);
        let mut xs = vec![Interval::EMPTY, Interval::ENTIRE];
        for _ in 0..3000 {
            let (a, b) = (
                e[rng.random_range(0..e.len())],
                e[rng.random_range(0..e.len())],
            );
            if let Ok(x) = Interval::try_from((a.min(b), a.max(b))) {
                xs.push(x);
            }
            // Narrow intervals, as branch-and-bound boxes give.
            let a: f64 = rng.random_range(-4.0..4.0);
            let w = 2f64.powi(rng.random_range(-50..0));
            xs.push(Interval::try_from((a, a + w)).unwrap());
            xs.push(Interval::try_from((a, a)).unwrap());
        }
        let (mut checked, mut vector) = (0usize, 0usize);
        for (i, x) in xs.iter().enumerate() {
            for y in xs.iter().skip(i % 7).step_by(7) {
                let z = mul(*x, *y);
                assert!(same(z, *x * *y), "{x:?} · {y:?}: {z:?} vs {:?}", *x * *y);
                checked += 1;
                vector += usize::from(vector_route(*x, *y).is_some());
            }
        }
        assert!(checked > 1_000_000, "{checked}");
        #[cfg(all(
            target_arch = "x86_64",
            target_feature = "avx2",
            target_feature = "fma"
        ))]
        assert!(
            vector > checked / 4,
            "the vector route took {vector} of {checked}"
        );
        let _ = vector;
    }

    /// The check has power: rounding to nearest (no residual correction) gives a different
    /// interval for most products of such endpoints (three in four here; the rest are exact).
    #[test]
    fn rounding_to_nearest_would_be_caught() {
        let mut rng = KitRng::seed_from_u64(5);
        let mut differ = 0;
        for _ in 0..1000 {
            let a: f64 = rng.random_range(0.5..2.0);
            let c: f64 = rng.random_range(0.5..2.0);
            let x = Interval::try_from((a, a + 0.25)).unwrap();
            let y = Interval::try_from((c, c + 0.25)).unwrap();
            let nearest = Interval::try_from((a * c, (a + 0.25) * (c + 0.25))).unwrap();
            differ += usize::from(!same(nearest, mul(x, y)));
        }
        assert!(differ > 600, "{differ}");
    }
}
