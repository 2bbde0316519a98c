//! [`RecordedPass`]: the decisions of one trajectory recorded for the causal estimator, to be
//! summed with losses chosen after the pass.

use super::{DecisionTerms, ScoreProducts};
use crate::scalar::Scalar;

/// One trajectory's decisions recorded for the causal estimator of eq. 3.15,
/// `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`: the per-step losses `l_t` (the absorbing tail as one
/// more step), from which the loss-to-go of decision i is `L_i = Σ_{t>i} l_t`, the number of
/// scored decisions, and a record of the decisions from which the estimate can be summed with
/// *other* per-step losses `l'_t` — a baseline known only after every trajectory's pass enters
/// that way ([`crate::baseline`]): leave-one-out's `b_i^{(j)} = (Σ_{k≠j} L_i^{(k)})/(m − 1)`
/// is `l'_t = l_t − (S_t − l_t)/(m − 1)` with `S_t` the step's total over the m trajectories,
/// since `Σ_i b_i ψ_i = Σ_t (b_{t−1} − b_t) Σ_{i<t} ψ_i`.
///
/// Filled by [`crate::baseline::PerDecisionTerms::record_decisions`] and summed by
/// [`crate::baseline::PerDecisionTerms::estimate_recorded`] of the same problem, in a form of its
/// choosing (by default the plain estimate and the scores ψ_i as rows of d entries; the real
/// tasks keep their policy's own records). The buffers are kept between uses: nothing is allocated per
/// step once they have grown.
#[derive(Debug, Clone)]
pub struct RecordedPass<S> {
    /// The plain estimate g, d entries (the default form only).
    pub(crate) estimate: Vec<S>,
    /// l_t per step, then the absorbing tail's `L_abs` if any.
    pub(crate) losses: Vec<S>,
    /// The number of scored decisions.
    pub(crate) decisions: usize,
    /// The decisions' records in the filling problem's form (ψ_i as rows in the default form).
    pub(crate) scores: Vec<S>,
    /// Whether this is the default form: `estimate` and ψ_i as rows of d entries in `scores`.
    pub(crate) score_rows: bool,
    /// Whether the last entry of `losses` is the absorbing tail's `L_abs`.
    pub(crate) tail: bool,
    /// Working storage of the summing pass.
    pub(crate) work: Vec<S>,
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
            tail: false,
            work: Vec::new(),
            terms: DecisionTerms::new(),
        }
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

    /// The trajectory's loss `Σ_t l_t` read off the policy's own records (the real tasks'
    /// [`crate::task::TaskProblem`]): the absorbing tail (recorded last) first, then the per-step
    /// losses in order, as [`crate::problem::IlProblem::trajectory_loss`] adds them, so the same
    /// value bit for bit; `None` for records of the default form, whose losses come from the
    /// problem's per-decision terms and whose trajectory loss the caller computes.
    pub fn trajectory_loss(&self) -> Option<S> {
        if self.score_rows {
            return None;
        }
        let (steps, mut total) = match (self.tail, self.losses.split_last()) {
            (true, Some((tail, steps))) => (steps, tail.clone()),
            _ => (&self.losses[..], S::zero()),
        };
        for l in steps {
            total += l;
        }
        Some(total)
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
        self.tail = false;
    }

    /// [`ScoreProducts`] of the default form's rows.
    ///
    /// # Panics
    /// If the scores are not stored as rows.
    pub(crate) fn score_row_products(&self, out: ScoreProducts<'_, S>) {
        assert!(self.score_rows, "recorded pass: scores not stored as rows");
        let d = self.estimate.len().max(1);
        out.add_rows(self.scores.chunks_exact(d));
    }

    /// `g += Σ_t [∇l_t + l'_t Σ_{i<min(t, s)} ψ_i]` (s scored decisions) for the default form,
    /// with one loss `l'_t` per entry of [`RecordedPass::losses`] (`None`: the recorded `l_t`): the
    /// plain estimate minus `Σ_{i<s} b_i ψ_i` with `b_i = −Σ_{t>i} (l'_t − l_t)` (summation by
    /// parts).
    ///
    /// # Panics
    /// If the scores are not stored as rows.
    pub(crate) fn sum_rows(&self, losses: Option<&[S]>, g: &mut [S]) {
        assert!(self.score_rows, "recorded pass: scores not stored as rows");
        let losses = losses.unwrap_or(&self.losses);
        for (gj, x) in g.iter_mut().zip(&self.estimate) {
            *gj += x;
        }
        // b_i for i = s − 1, …, 0: the shifts of the steps after i, summed from the last step.
        let shifts = losses
            .iter()
            .zip(&self.losses)
            .map(|(new, old)| new.clone() - old);
        let shift: Vec<S> = shifts.collect();
        let s = self.decisions;
        let after: S = shift[(s + 1).min(shift.len())..]
            .iter()
            .fold(S::zero(), |a, x| a + x);
        let b = shift[..(s + 1).min(shift.len())]
            .iter()
            .skip(1)
            .rev()
            .scan(after, |acc, x| {
                *acc += x;
                Some(-acc.clone())
            });
        crate::oracle::kernel::subtract_score_rows(&self.scores, self.estimate.len(), s, b, g);
    }
}
