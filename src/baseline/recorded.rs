//! [`RecordedPass`]: the plain causal estimate of one trajectory with what a baseline fixed only
//! after the pass needs.

use super::DecisionTerms;
use crate::scalar::Scalar;

/// The causal estimator of eq. 3.15 on one trajectory, `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`, with
/// the per-step losses `l_t` (the absorbing tail as one more step), from which the loss-to-go of
/// decision i is `L_i = Σ_{t>i} l_t`, the number of scored decisions, and a record of the scores
/// ψ_i, so that `g_b = g − Σ_i b_i ψ_i` ([`crate::baseline`]) can be formed
/// for baselines b_i known only after every trajectory's pass — leave-one-out, where
/// `b_i^{(j)} = (Σ_{k≠j} L_i^{(k)})/(m − 1)`.
///
/// Filled by [`crate::problem::IlProblem::recorded_estimate`]; the scores are read back by
/// [`crate::problem::IlProblem::subtract_recorded`] of the same problem, in a form of its choosing
/// (rows of d entries by default, one coefficient per decision for the logistic policy). The
/// buffers are kept between uses: nothing is allocated per step once they have grown.
#[derive(Debug, Clone)]
pub struct RecordedPass<S> {
    /// g, d entries.
    pub(crate) estimate: Vec<S>,
    /// l_t per step, then the absorbing tail's `L_abs` if any.
    pub(crate) losses: Vec<S>,
    /// The number of scored decisions.
    pub(crate) decisions: usize,
    /// The scores ψ_i in the filling problem's form.
    pub(crate) scores: Vec<S>,
    /// Whether `scores` holds ψ_i as rows of d entries (the default form).
    pub(crate) score_rows: bool,
    /// Storage of the default route through [`DecisionTerms`].
    terms: DecisionTerms<S>,
}

impl<S: Scalar> Default for RecordedPass<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Scalar> RecordedPass<S> {
    /// Empty buffers.
    pub fn new() -> Self {
        Self {
            estimate: Vec::new(),
            losses: Vec::new(),
            decisions: 0,
            scores: Vec::new(),
            score_rows: true,
            terms: DecisionTerms::new(),
        }
    }

    /// The plain causal estimate g (eq. 3.15).
    pub fn estimate(&self) -> &[S] {
        &self.estimate
    }

    /// The number n of scored decisions.
    pub fn decisions(&self) -> usize {
        self.decisions
    }

    /// The per-step losses `l_t` (0-based t), steps after the last decision included: `L_i` is
    /// the sum of the entries after entry i.
    pub fn losses(&self) -> &[S] {
        &self.losses
    }

    /// The per-decision terms to fill for [`RecordedPass::fill_from_terms`].
    pub fn terms_mut(&mut self) -> &mut DecisionTerms<S> {
        &mut self.terms
    }

    /// g, the per-step losses and ψ_i as rows of d entries from the (unweighted)
    /// [`DecisionTerms`] of [`RecordedPass::terms_mut`]: `g = D + Σ_i L_i ψ_i`.
    ///
    /// # Panics
    /// If the terms carry importance weights.
    pub fn fill_from_terms(&mut self) {
        let t = &mut self.terms;
        assert!(
            t.scale().is_none() && t.prefix_weight(0).is_none(),
            "recorded pass: unweighted terms only"
        );
        self.losses.clear();
        self.losses.extend_from_slice(t.step_losses());
        self.decisions = t.decisions();
        t.finish();
        self.estimate.clear();
        self.estimate.resize(t.dim(), S::zero());
        t.estimate_into(|_| None, &mut self.estimate);
        self.scores.clear();
        for i in 0..t.decisions() {
            self.scores.extend_from_slice(t.score(i));
        }
        self.score_rows = true;
    }

    /// `g −= Σ_{i<n} b_i ψ_i` over the n scored decisions, for scores stored as rows; `b` yields
    /// `b_{n−1}, …, b_0`.
    ///
    /// # Panics
    /// If the scores are not stored as rows.
    pub fn subtract_rows(&self, b: impl Iterator<Item = S>, g: &mut [S]) {
        assert!(self.score_rows, "recorded pass: scores not stored as rows");
        crate::oracle::kernel::subtract_score_rows(
            &self.scores,
            self.estimate.len(),
            self.decisions(),
            b,
            g,
        );
    }
}
