//! [`RunningOptimum`]: the variance-minimising baselines estimated from earlier iterations only.

use super::DecisionTerms;
use crate::scalar::Scalar;

/// Running estimates of `b*_i = E[g·ψ_i] / E‖ψ_i‖²` (time-indexed) and of
/// `b*_const = Σ_i E[g·ψ_i] / Σ_i E‖ψ_i‖²` (one constant) from the plain estimates g of
/// eq. 3.15 seen so far (math.md §9).
///
/// Unbiasedness needs the baseline of a trajectory to be independent of it, so what a trajectory
/// contributes is held back ([`RunningOptimum::observe`] into a pending sum) and enters the
/// estimates only at [`RunningOptimum::commit`], which the oracle calls when it rolls out the
/// *next* trajectory. Every estimate formed on a trajectory (STORM forms two on one) thus uses
/// a baseline built from strictly earlier trajectories: a function of data independent of the
/// current one, as the unbiasedness argument requires.
///
/// `decay` ∈ [0, 1] multiplies the committed sums at each commit (1: a plain running sum; below 1
/// forgets old iterates' statistics geometrically, as the policy moves).
#[derive(Debug, Clone)]
pub struct RunningOptimum<S> {
    decay: Option<S>,
    /// Σ g·ψ_i and Σ ‖ψ_i‖² over committed trajectories.
    cross: Vec<S>,
    moment: Vec<S>,
    /// Their values from the trajectories observed since the last commit.
    pending_cross: Vec<S>,
    pending_moment: Vec<S>,
    /// The committed baselines: b_i, and the one constant.
    per_decision: Vec<Option<S>>,
    constant: Option<S>,
    g: Vec<S>,
}

impl<S: Scalar> RunningOptimum<S> {
    /// No data yet (every baseline 0); `decay` as in the type docs (`None`: 1).
    pub fn new(decay: Option<S>) -> Self {
        Self {
            decay,
            cross: Vec::new(),
            moment: Vec::new(),
            pending_cross: Vec::new(),
            pending_moment: Vec::new(),
            per_decision: Vec::new(),
            constant: None,
            g: Vec::new(),
        }
    }

    /// The committed time-indexed baseline `b_i` (0-based i); `None` (b_i = 0) where no earlier
    /// trajectory had a decision i with a nonzero score.
    pub fn time_indexed(&self, i: usize) -> Option<S> {
        self.per_decision.get(i).cloned().flatten()
    }

    /// The committed constant baseline; `None` (0) before any nonzero score was seen.
    pub fn constant(&self) -> Option<S> {
        self.constant.clone()
    }

    /// Forget the pending statistics (a new estimate on the current trajectories replaces them).
    pub fn clear_pending(&mut self) {
        self.pending_cross.clear();
        self.pending_moment.clear();
    }

    /// Add one trajectory's `g·ψ_i` and `‖ψ_i‖²` (g the plain estimate of `terms`) to the pending
    /// statistics.
    pub fn observe(&mut self, terms: &DecisionTerms<S>) {
        let n = terms.decisions();
        self.g.clear();
        self.g.resize(terms.dim(), S::zero());
        terms.estimate_into(|_| None, &mut self.g);
        let g = std::mem::take(&mut self.g);
        let (cross, moment) = self.pending_mut(n);
        let scores = (0..n).map(|i| terms.score(i));
        crate::oracle::kernel::add_score_products(scores, &g, cross, moment);
        self.g = g;
    }

    /// The pending sums `Σ g·ψ_i` and `Σ ‖ψ_i‖²` of decisions 0..n (grown to n entries), for a
    /// trajectory's statistics added in place, as [`RunningOptimum::observe`] adds them.
    pub(crate) fn pending_mut(&mut self, n: usize) -> (&mut [S], &mut [S]) {
        if self.pending_cross.len() < n {
            self.pending_cross.resize(n, S::zero());
            self.pending_moment.resize(n, S::zero());
        }
        (&mut self.pending_cross[..n], &mut self.pending_moment[..n])
    }

    /// Move the pending statistics into the estimates (see the type docs for when).
    pub fn commit(&mut self) {
        if let Some(decay) = &self.decay {
            for x in self.cross.iter_mut().chain(self.moment.iter_mut()) {
                *x *= decay;
            }
        }
        let n = self.pending_cross.len();
        if self.cross.len() < n {
            self.cross.resize(n, S::zero());
            self.moment.resize(n, S::zero());
        }
        for i in 0..n {
            self.cross[i] += &self.pending_cross[i];
            self.moment[i] += &self.pending_moment[i];
        }
        self.clear_pending();
        let ratio = |num: &S, den: &S| (!den.is_certainly_zero()).then(|| num.clone() / den);
        self.per_decision = self
            .cross
            .iter()
            .zip(&self.moment)
            .map(|(c, m)| ratio(c, m))
            .collect();
        let total = |xs: &[S]| xs.iter().fold(S::zero(), |acc, x| acc + x);
        self.constant = ratio(&total(&self.cross), &total(&self.moment));
    }
}
