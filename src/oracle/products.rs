//! [`ScoreProducts`]: what one trajectory adds to the statistics of the variance-minimising
//! baselines, and the baselines' correction of its estimate, in one read of its scores.

use crate::scalar::Scalar;

/// One trajectory's part of the estimated baselines' bookkeeping (math.md §9), for its scored
/// decisions i = 0..n (0-based; n = `cross.len()` = `moment.len()`):
///
/// * `cross[i] += v·ψ_i` and `moment[i] += ‖ψ_i‖²` with v the trajectory's plain estimate g of
///   eq. 3.15: the statistics from which [`crate::baseline::RunningOptimum`] forms
///   `b*_i = E[g·ψ_i] / E‖ψ_i‖²`;
/// * `g −= b_i ψ_i` for the decisions `baseline` covers (i < `baseline.len()`), row by row:
///   with `g` holding v this is the baselined estimate `g_b = g − Σ_i b_i ψ_i`.
///
/// Both need every ψ_i once the plain estimate is known, so they share one pass over the
/// recorded decisions. `baseline` may be empty (statistics only; `g` is then untouched), and so
/// may `cross` and `moment` (the correction only, for every decision `baseline` covers: a
/// trajectory whose statistics are not wanted).
#[derive(Debug)]
pub struct ScoreProducts<'a, S> {
    /// v, the trajectory's plain estimate (d entries).
    pub v: &'a [S],
    /// b_i of the decisions to correct (at most n entries).
    pub baseline: &'a [S],
    /// `Σ v·ψ_i` per decision, added to.
    pub cross: &'a mut [S],
    /// `Σ ‖ψ_i‖²` per decision, added to.
    pub moment: &'a mut [S],
    /// The estimate the correction is subtracted from (d entries).
    pub g: &'a mut [S],
}

impl<S: Scalar> ScoreProducts<'_, S> {
    /// The products and the correction for the scores ψ_0, ψ_1, … that `scores` yields, as far as
    /// it and `cross` go (as far as `baseline` goes when `cross` is empty: the correction only),
    /// each in the order the fixed-dimension passes use: `cross[i]` with
    /// [`crate::scalar::dot`], `moment[i]` with [`crate::scalar::norm_sq`], then
    /// `g_j −= b_i ψ_ij` entry by entry.
    pub fn add_rows<'r>(self, scores: impl Iterator<Item = &'r [S]>)
    where
        S: 'r,
    {
        let Self {
            v,
            baseline,
            cross,
            moment,
            g,
        } = self;
        if cross.is_empty() {
            for (psi, b) in scores.zip(baseline) {
                for (gj, x) in g.iter_mut().zip(psi) {
                    *gj -= b.clone() * x;
                }
            }
            return;
        }
        let products = cross.iter_mut().zip(moment.iter_mut());
        for (i, (psi, (c, m))) in scores.zip(products).enumerate() {
            *c += crate::scalar::dot(v, psi);
            *m += crate::scalar::norm_sq(psi);
            if let Some(b) = baseline.get(i) {
                for (gj, x) in g.iter_mut().zip(psi) {
                    *gj -= b.clone() * x;
                }
            }
        }
    }
}
