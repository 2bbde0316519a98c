//! [`ScoreProducts`]: what one trajectory adds to the statistics of the variance-minimising
//! baselines, and the baselines' correction of its estimate, in one read of its scores.

use super::linear_baseline::LinearBaseline;
use crate::scalar::Scalar;

/// The b_i of the correction `g −= Σ_i b_i ψ_i` that a [`ScoreProducts`] makes.
#[derive(Debug, Clone, Copy)]
pub enum Baselines<'a, S> {
    /// Given, one per decision to correct (decisions i < the slice's length; empty: none).
    Given(&'a [S]),
    /// The linear state-dependent baseline's, `b_i` = [`LinearBaseline::next`] on decision i's
    /// state features, for the first `decisions` decisions: row i starts at `rows[i·stride]`
    /// (at least `decisions` rows of `stride` entries, stride at least the baseline's k).
    /// A policy may form each b_i in the pass that reads ψ_i.
    Linear {
        /// The committed weights.
        baseline: LinearBaseline<'a, S>,
        /// The state features, by rows.
        rows: &'a [S],
        /// Entries per row.
        stride: usize,
        /// Decisions to correct.
        decisions: usize,
    },
}

impl<S: Scalar> Baselines<'_, S> {
    /// The b_i as a slice: the given ones, or the linear baseline's formed row by row into
    /// `buf` (the values of [`crate::baseline::RunningRegression::baselines_from_rows`], bit for
    /// bit: every route sums b_i in [`LinearBaseline`]'s order).
    pub fn values<'b>(&'b self, buf: &'b mut Vec<S>) -> &'b [S] {
        match self {
            Baselines::Given(b) => b,
            Baselines::Linear {
                baseline,
                rows,
                stride,
                decisions,
            } => {
                buf.clear();
                let mut index = S::zero();
                buf.extend(
                    rows.chunks_exact((*stride).max(1))
                        .take(*decisions)
                        .map(|phi| baseline.next(phi, &mut index)),
                );
                buf
            }
        }
    }

    /// Whether there is no correction to make.
    pub fn is_empty(&self) -> bool {
        match self {
            Baselines::Given(b) => b.is_empty(),
            Baselines::Linear { decisions, .. } => *decisions == 0,
        }
    }
}

/// One trajectory's part of the estimated baselines' bookkeeping (math.md §9), for its scored
/// decisions i = 0..n (0-based; n = `cross.len()` = `moment.len()`):
///
/// * `cross[i] += v·ψ_i` and `moment[i] += ‖ψ_i‖²` with v the trajectory's plain estimate g of
///   eq. 3.15: the statistics from which [`crate::baseline::RunningOptimum`] forms
///   `b*_i = E[g·ψ_i] / E‖ψ_i‖²`;
/// * `g −= b_i ψ_i` for the decisions `baseline` covers ([`Baselines`]: given b_i, or the linear
///   state-dependent baseline's), row by row: with `g` holding v this is the baselined estimate
///   `g_b = g − Σ_i b_i ψ_i`.
///
/// Both need every ψ_i once the plain estimate is known, so they share one pass over the
/// recorded decisions. `baseline` may be empty (statistics only; `g` is then untouched), and so
/// may `cross` and `moment` (the correction only, for every decision `baseline` covers: a
/// trajectory whose statistics are not wanted).
#[derive(Debug)]
pub struct ScoreProducts<'a, S> {
    /// v, the trajectory's plain estimate (d entries).
    pub v: &'a [S],
    /// b_i of the decisions to correct (at most n).
    pub baseline: Baselines<'a, S>,
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
        let mut buf = Vec::new();
        let baseline = baseline.values(&mut buf);
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
