//! The kit's samplers: every random draw of a roll-out goes through one of these, built exactly in
//! every scalar from the `f64`/`u64` output of the [`KitRng`], so that one seed gives one path in
//! `f64`, in rationals and in intervals (as long as interval comparisons stay decidable).
//!
//! * [`dyadic_uniform`]: `u = k/2⁵³ ∈ [0, 1)`, the uniform of every categorical draw;
//! * [`sample_categorical`] and its two-action form [`sample_binary`]: the first action whose
//!   cumulative probability certainly exceeds `u`;
//! * [`standard_normal`]: `ε ∼ N(0, 1)`, the noise of the Gaussian policies and the LQG system.

use crate::problem::KitRng;
use crate::scalar::{Scalar, Undecidable, certainly_less};

/// `2⁵³`: the denominator of [`dyadic_uniform`].
pub const UNIFORM_DENOMINATOR: i64 = 1 << 53;

/// A uniform draw on `[0, 1)` as the dyadic rational `k / 2⁵³` (k from the top 53 bits of one
/// `u64`), built exactly in every scalar: the same seed gives the same number in `f64`, in
/// rationals and in intervals (a singleton). Every categorical sampler of the kit draws through
/// it, so runs in different scalars with one seed follow the same path.
#[inline]
pub fn dyadic_uniform<S: Scalar>(rng: &mut KitRng) -> S {
    use rand::RngCore;
    let k = (rng.next_u64() >> 11) as i64;
    S::from_ratio(k, UNIFORM_DENOMINATOR)
}

/// The category drawn by the uniform `u` from the probabilities `probs`: the first action `a`
/// with `P(a) ≠ 0` whose cumulative probability `Σ_{b≤a} P(b)` certainly exceeds `u`, and the
/// last action of non-zero probability if none does (so rounding in the cumulative sums never
/// yields an impossible action).
///
/// # Errors
/// [`Undecidable`] when interval arithmetic cannot order `u` and a cumulative probability.
#[inline]
pub fn sample_categorical<S: Scalar>(probs: &[S], u: &S) -> Result<usize, Undecidable> {
    let last = probs
        .iter()
        .rposition(|p| !p.is_certainly_zero())
        .unwrap_or(probs.len() - 1);
    let mut cum = S::zero();
    for (a, p) in probs.iter().enumerate().take(last) {
        cum += p;
        if !p.is_certainly_zero() && certainly_less(u, &cum, "categorical sampling")? {
            return Ok(a);
        }
    }
    Ok(last)
}

/// [`sample_categorical`] on the two probabilities `[q, p]`, written out for two actions (the same
/// decisions and errors, with fewer branches): action 0 iff `q ≠ 0` and (`p = 0` or certainly
/// `u < q`), otherwise 1. The last action of positive probability is the fallback; the comparison
/// is undecidable (an error) only when it is needed, with both probabilities non-zero.
///
/// `sample_categorical` compares `u` with the running sum `0 + q`; adding an exact zero changes no
/// comparison in any of the kit's scalars (`f64` comparisons treat `−0` and `+0` alike, interval
/// and rational sums with 0 are exact, a dual compares its value), so the sum, a dependent
/// addition on the roll-out's latency chain, is left out.
///
/// # Errors
/// [`Undecidable`] when both probabilities are non-zero and `u < q` cannot be decided.
#[inline]
pub fn sample_binary<S: Scalar>(u: &S, q: S, p: &S) -> Result<usize, Undecidable> {
    let q_zero = q.is_certainly_zero();
    let p_zero = p.is_certainly_zero();
    // Compared unconditionally (the result is used only when both are non-zero): the decision is
    // one expression of three flags, with no branch but the error's.
    let cmp = u.certain_cmp(&q);
    if cmp.is_none() & !q_zero & !p_zero {
        return Err(undecidable_sample());
    }
    let zero = !q_zero & (p_zero | (cmp == Some(std::cmp::Ordering::Less)));
    Ok(usize::from(!zero))
}

#[cold]
#[inline(never)]
fn undecidable_sample() -> Undecidable {
    Undecidable {
        what: "categorical sampling",
    }
}

/// A standard normal draw `ε ∼ N(0, 1)` as an exact scalar: rand_distr's ziggurat in `f64`, then
/// the exact value of that double in `S` ([`Scalar::from_binary64`]).
pub fn standard_normal<S: Scalar>(rng: &mut KitRng) -> S {
    let x: f64 = rand::Rng::sample(rng, rand_distr::StandardNormal);
    // The ziggurat only returns finite values.
    S::from_binary64(x).unwrap_or_else(S::zero)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Interval;

    /// `sample_binary` is `sample_categorical` on `[q, p]`: same actions, same errors.
    #[test]
    fn sample_binary_is_the_two_action_categorical() {
        let points = [
            0.0,
            0.25,
            0.5,
            0.75,
            1.0,
            f64::MIN_POSITIVE,
            1.0 - f64::EPSILON / 2.0,
        ];
        for &p in &points {
            for &u in &points {
                let q = 1.0 - p;
                assert_eq!(
                    sample_binary(&u, q, &p),
                    sample_categorical(&[q, p], &u),
                    "p = {p}, u = {u}"
                );
            }
        }
        // Both probabilities zero, and intervals: decided, undecidable.
        assert_eq!(
            sample_binary(&0.5, 0.0, &0.0),
            sample_categorical(&[0.0, 0.0], &0.5)
        );
        let iv = |a: f64, b: f64| Interval::try_from((a, b)).unwrap();
        for (u, q) in [
            (iv(0.1, 0.1), iv(0.4, 0.5)),
            (iv(0.45, 0.45), iv(0.4, 0.5)),
            (iv(0.6, 0.6), iv(0.4, 0.5)),
            (iv(0.3, 0.3), iv(0.0, 0.0)),
        ] {
            let p = Interval::one() - q;
            assert_eq!(sample_binary(&u, q, &p), sample_categorical(&[q, p], &u));
        }
        assert!(sample_binary(&iv(0.45, 0.45), iv(0.4, 0.5), &iv(0.5, 0.6)).is_err());
    }
}
