//! [`LinearBaseline`]: the linear state-dependent baseline `b_i = w·φ_b(s_i)` evaluated off
//! feature rows, one decision after another.

use crate::scalar::Scalar;

/// The committed weights of a linear state-dependent baseline ([`crate::baseline`], math.md §9)
/// split by what they weigh: `b_i = Σ_{j<k} w_j φ_ij`, and with the time features also
/// `+ w_k·i + w_{k+1}·1` (i the decision's index from 0). Every b_i is summed from 0 in this
/// order, the order of the features by columns
/// ([`crate::baseline::RunningRegression::baselines_into`]), so that every route gives the same
/// value bit for bit.
#[derive(Debug, Clone, Copy)]
pub struct LinearBaseline<'w, S> {
    state: &'w [S],
    time: Option<(&'w S, &'w S)>,
}

impl<'w, S: Scalar> LinearBaseline<'w, S> {
    /// The weights of k state features, with `time` those of the index and the constant after
    /// them; `None` unless `weights` holds exactly that many (before any statistics were
    /// committed it holds none).
    pub fn new(weights: &'w [S], k: usize, time: bool) -> Option<Self> {
        if weights.len() != k + if time { 2 } else { 0 } {
            return None;
        }
        let (state, extra) = weights.split_at(k);
        let time = match extra {
            [w_index, w_one] => Some((w_index, w_one)),
            _ => None,
        };
        Some(Self { state, time })
    }

    /// The same baseline with k = K known at compile time (a row's products unroll); `None`
    /// when k is not K.
    pub fn fixed<const K: usize>(&self) -> Option<FixedLinearBaseline<'w, S, K>> {
        Some(FixedLinearBaseline {
            state: self.state.try_into().ok()?,
            time: self.time,
        })
    }

    /// b_i of the decision with state features `phi` (its first k entries) and index `index`,
    /// which then moves on to the next decision's.
    ///
    /// # Panics
    /// If `phi` has fewer than k entries.
    #[inline]
    pub fn next(&self, phi: &[S], index: &mut S) -> S {
        value(self.state, &phi[..self.state.len()], self.time, index)
    }
}

/// A [`LinearBaseline`] with K state features known at compile time.
#[derive(Debug, Clone, Copy)]
pub struct FixedLinearBaseline<'w, S, const K: usize> {
    state: &'w [S; K],
    time: Option<(&'w S, &'w S)>,
}

impl<S: Scalar, const K: usize> FixedLinearBaseline<'_, S, K> {
    /// [`LinearBaseline::next`] for a row of K entries: the same value, bit for bit.
    #[inline(always)]
    pub fn next(&self, phi: &[S; K], index: &mut S) -> S {
        value(self.state, phi, self.time, index)
    }
}

/// `b = Σ_j w_j φ_j`, summed from 0 in the order of j, then with the time features
/// `b += w_index·i + w_one·1` for the decision whose index `index` holds, which then moves on to
/// the next. The product with 1 is kept: the columns route multiplies the column of ones.
/// Inlined, so that a caller's compile-time length unrolls the sum.
#[inline(always)]
fn value<S: Scalar>(w: &[S], phi: &[S], time: Option<(&S, &S)>, index: &mut S) -> S {
    let mut b = S::zero();
    for (w, x) in w.iter().zip(phi) {
        b += w.clone() * x;
    }
    if let Some((w_index, w_one)) = time {
        b += w_index.clone() * &*index;
        b += w_one.clone() * S::one();
        *index += S::one();
    }
    b
}
