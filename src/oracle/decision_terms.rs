//! [`DecisionTerms`]: the per-decision parts of the causal estimator of eq. 3.15 on one trajectory,
//! from which the estimator with any baseline is assembled.

use crate::scalar::Scalar;

/// The causal estimator of eq. 3.15 on one trajectory, kept apart decision by decision:
///
/// `g = c · (D + Σ_{i=1}^{n} ψ_i L_i)`, and with baselines b_i
/// `g_b = c · (D + Σ_{i=1}^{n} ψ_i (L_i − w_{1:i} b_i))`,
///
/// where `D = Σ_t w_{1:t−1} ∇l_t` (the direct part), ψ_i = ∇log π_θ(a_i|s_i) the score of the
/// i-th scored decision, `L_i = Σ_{t>i} w_{1:t−1} l_t` its (weighted) loss-to-go, and
///
/// * without importance weights: every `w = 1` and `c = 1` (eq. 3.15 itself);
/// * with the per-decision weights of the old-point estimate (math.md §4): `w_{1:t−1} =
///   Π_{i<t} π_old(a_i|s_i)/π_new(a_i|s_i)`, and the baseline term of decision i carries the
///   prefix weight `w_{1:i}` (`c = 1`);
/// * with the whole-trajectory weight: `w = 1` inside and `c = Π_i π_old(a_i|s_i)/π_new(a_i|s_i)`
///   multiplies the baselined estimate.
///
/// Why each stays unbiased is in the module docs of [`crate::baseline`]. Decision i is taken at
/// step i (the same 0-based index), so `L_i` sums the losses of the steps after it; steps after
/// the last decision (absorbing steps, the absorbing tail) carry losses only.
///
/// The buffers are kept between uses: refilled with [`DecisionTerms::begin`] and the `push_*`
/// calls, a trajectory of n steps allocates at most once per buffer (reserved in `begin`), and
/// nothing per step.
#[derive(Debug, Clone)]
pub struct DecisionTerms<S> {
    d: usize,
    direct: Vec<S>,
    /// ψ_1, …, ψ_n, `d` entries each.
    scores: Vec<S>,
    /// n, the number of scores.
    decisions: usize,
    /// Per step its (weighted) loss.
    losses: Vec<S>,
    /// After [`DecisionTerms::finish`], the suffix sums `Σ_{u≥t} l_u`.
    suffix: Vec<S>,
    /// `w_{1:i}` per decision; empty when every weight is 1.
    prefix_weights: Vec<S>,
    scale: Option<S>,
    finished: bool,
}

impl<S: Scalar> Default for DecisionTerms<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Scalar> DecisionTerms<S> {
    /// Empty buffers.
    pub fn new() -> Self {
        Self {
            d: 0,
            direct: Vec::new(),
            scores: Vec::new(),
            decisions: 0,
            losses: Vec::new(),
            suffix: Vec::new(),
            prefix_weights: Vec::new(),
            scale: None,
            finished: false,
        }
    }

    /// Start a trajectory of about `steps` steps with θ of dimension `d`: `D = 0`, no decisions.
    pub fn begin(&mut self, d: usize, steps: usize) {
        self.d = d;
        self.direct.clear();
        self.direct.resize(d, S::zero());
        self.scores.clear();
        self.scores.reserve(steps * d);
        self.decisions = 0;
        self.losses.clear();
        self.losses.reserve(steps + 1);
        self.prefix_weights.clear();
        self.scale = None;
        self.finished = false;
    }

    /// The direct part `D`, to add `w_{1:t−1} ∇l_t` into.
    pub fn direct_mut(&mut self) -> &mut [S] {
        &mut self.direct
    }

    /// The next step's (weighted) loss `w_{1:t−1} l_t`.
    #[inline]
    pub fn push_loss(&mut self, loss: S) {
        debug_assert!(!self.finished);
        self.losses.push(loss);
    }

    /// The next decision's score row, zeroed, to be filled with ψ_i; `prefix_weight` is `w_{1:i}`
    /// (`None`: 1). Decision i must be pushed after the loss of step i, or with it pending.
    ///
    /// # Panics
    /// If some decisions carry a prefix weight and others do not.
    #[inline]
    pub fn push_score(&mut self, prefix_weight: Option<S>) -> &mut [S] {
        let i = self.decisions();
        self.push_prefix_weight(i, prefix_weight);
        self.scores.resize((i + 1) * self.d, S::zero());
        &mut self.scores[i * self.d..]
    }

    /// The next decision's score ψ_i, copied from `score` (d entries), with its prefix weight as
    /// in [`DecisionTerms::push_score`].
    ///
    /// # Panics
    /// As [`DecisionTerms::push_score`], and if `score` does not have d entries.
    #[inline]
    pub fn push_score_from(&mut self, prefix_weight: Option<S>, score: &[S]) {
        assert_eq!(score.len(), self.d, "push_score_from: a score of d entries");
        let i = self.decisions();
        self.push_prefix_weight(i, prefix_weight);
        self.scores.extend_from_slice(score);
    }

    /// Decision i's prefix weight, with the check that every decision has one or none does.
    #[inline]
    fn push_prefix_weight(&mut self, i: usize, prefix_weight: Option<S>) {
        self.decisions += 1;
        match prefix_weight {
            Some(w) => {
                assert_eq!(
                    self.prefix_weights.len(),
                    i,
                    "prefix weights on every decision"
                );
                self.prefix_weights.push(w);
            }
            None => assert!(
                self.prefix_weights.is_empty(),
                "prefix weights on every decision"
            ),
        }
    }

    /// The whole-trajectory weight `c` that multiplies the estimate.
    pub fn set_scale(&mut self, c: S) {
        self.scale = Some(c);
    }

    /// Close the trajectory: the loss-to-go of every decision becomes available. Idempotent (a
    /// second call before the next [`DecisionTerms::begin`] does nothing).
    ///
    /// # Panics
    /// If there are more decisions than steps.
    pub fn finish(&mut self) {
        if self.finished {
            return;
        }
        assert!(
            self.decisions() <= self.losses.len(),
            "a decision without its step"
        );
        self.suffix.clear();
        self.suffix.resize(self.losses.len(), S::zero());
        let mut acc = S::zero();
        for (l, s) in self.losses.iter().zip(self.suffix.iter_mut()).rev() {
            acc += l;
            *s = acc.clone();
        }
        self.finished = true;
    }

    /// The dimension d of θ.
    pub fn dim(&self) -> usize {
        self.d
    }

    /// The number n of scored decisions.
    pub fn decisions(&self) -> usize {
        self.decisions
    }

    /// ψ_i (0-based `i`).
    pub fn score(&self, i: usize) -> &[S] {
        &self.scores[i * self.d..(i + 1) * self.d]
    }

    /// `L_i = Σ_{t>i} w_{1:t−1} l_t` (0-based `i`).
    ///
    /// # Panics
    /// Before [`DecisionTerms::finish`].
    pub fn loss_to_go(&self, i: usize) -> S {
        assert!(self.finished, "loss-to-go before finish");
        self.suffix.get(i + 1).cloned().unwrap_or_else(S::zero)
    }

    /// The per-step (weighted) losses, steps after the last decision included: `L_i` is the sum
    /// of the entries after entry i.
    pub fn step_losses(&self) -> &[S] {
        &self.losses
    }

    /// `w_{1:i}` (0-based `i`), `None` when it is 1.
    pub fn prefix_weight(&self, i: usize) -> Option<&S> {
        self.prefix_weights.get(i)
    }

    /// The whole-trajectory weight `c`, `None` when it is 1.
    pub fn scale(&self) -> Option<&S> {
        self.scale.as_ref()
    }

    /// `g_b = c · (D + Σ_i ψ_i (L_i − w_{1:i} b_i))` into `out` (length d), with `b_i =
    /// baseline(i)` (0-based i; `None`: no baseline at that decision, b_i = 0 skipped).
    ///
    /// # Panics
    /// Before [`DecisionTerms::finish`], or if `out` has the wrong length.
    pub fn estimate_into(&self, mut baseline: impl FnMut(usize) -> Option<S>, out: &mut [S]) {
        assert!(self.finished, "estimate before finish");
        assert_eq!(out.len(), self.d, "estimate: wrong output length");
        out.clone_from_slice(&self.direct);
        for i in 0..self.decisions() {
            let mut coef = self.suffix.get(i + 1).cloned().unwrap_or_else(S::zero);
            if let Some(b) = baseline(i) {
                match self.prefix_weights.get(i) {
                    Some(w) => coef -= w.clone() * b,
                    None => coef -= b,
                }
            }
            for (o, p) in out.iter_mut().zip(self.score(i)) {
                *o += coef.clone() * p;
            }
        }
        if let Some(c) = &self.scale {
            for o in out.iter_mut() {
                *o *= c;
            }
        }
    }
}
