//! [`RecordedPass`]: the plain causal estimate of one trajectory with what a baseline fixed only
//! after the pass needs.

use super::DecisionTerms;
use crate::scalar::Scalar;

/// The causal estimator of eq. 3.15 on one trajectory, `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`, with
/// the loss-to-go `L_i = Σ_{t>i} l_t` of every scored decision (the absorbing tail included) and a
/// record of the scores ψ_i, so that `g_b = g − Σ_i b_i ψ_i` ([`crate::baseline`]) can be formed
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
    /// L_1, …, L_n of the scored decisions.
    pub(crate) loss_to_go: Vec<S>,
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
            loss_to_go: Vec::new(),
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
        self.loss_to_go.len()
    }

    /// `L_i = Σ_{t>i} l_t` (0-based `i`), the absorbing tail included.
    pub fn loss_to_go(&self, i: usize) -> &S {
        &self.loss_to_go[i]
    }

    /// The per-decision terms to fill for [`RecordedPass::fill_from_terms`].
    pub fn terms_mut(&mut self) -> &mut DecisionTerms<S> {
        &mut self.terms
    }

    /// g, every `L_i` and ψ_i as rows of d entries from the (unweighted) [`DecisionTerms`] of
    /// [`RecordedPass::terms_mut`]: `g = D + Σ_i L_i ψ_i`.
    ///
    /// # Panics
    /// If the terms carry importance weights.
    pub fn fill_from_terms(&mut self) {
        let t = &mut self.terms;
        assert!(
            t.scale().is_none() && t.prefix_weight(0).is_none(),
            "recorded pass: unweighted terms only"
        );
        t.finish();
        self.estimate.clear();
        self.estimate.resize(t.dim(), S::zero());
        t.estimate_into(|_| None, &mut self.estimate);
        self.loss_to_go.clear();
        self.loss_to_go
            .extend((0..t.decisions()).map(|i| t.loss_to_go(i)));
        self.scores.clear();
        for i in 0..t.decisions() {
            self.scores.extend_from_slice(t.score(i));
        }
        self.score_rows = true;
    }

    /// `g −= Σ_{i<n} b(i) ψ_i` over the n scored decisions, for scores stored as rows.
    ///
    /// # Panics
    /// If the scores are not stored as rows.
    pub fn subtract_rows(&self, b: impl FnMut(usize) -> S, g: &mut [S]) {
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
