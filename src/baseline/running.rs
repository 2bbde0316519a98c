//! [`RunningOptimum`]: the variance-minimising baselines estimated from earlier iterations only.

use crate::oracle::DecisionTerms;
use crate::oracle::{Baselines, ScoreProducts};
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
    /// `Σ_i` of `cross` and of `moment`.
    totals: (S, S),
    /// The committed baselines: b_i (0 where not formed), whether b_i is formed (its `Σ ‖ψ_i‖²`
    /// was not zero when it was last formed), and the one constant.
    per_decision: Vec<S>,
    formed: Vec<bool>,
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
            totals: (S::zero(), S::zero()),
            per_decision: Vec::new(),
            formed: Vec::new(),
            constant: None,
            g: Vec::new(),
        }
    }

    /// The committed time-indexed baseline `b_i` (0-based i); `None` (b_i = 0) where no earlier
    /// trajectory had a decision i with a nonzero score.
    pub fn time_indexed(&self, i: usize) -> Option<S> {
        self.formed
            .get(i)
            .is_some_and(|&f| f)
            .then(|| self.per_decision[i].clone())
    }

    /// The committed time-indexed baselines of decisions `0..n` into `out` (cleared first):
    /// [`RunningOptimum::time_indexed`] with 0 for `None`, copied from the stored values.
    pub fn time_indexed_into(&self, n: usize, out: &mut Vec<S>) {
        out.clear();
        let known = n.min(self.per_decision.len());
        out.extend_from_slice(&self.per_decision[..known]);
        out.resize(n, S::zero());
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
        let statistics = ScoreProducts {
            v: &g,
            baseline: Baselines::Given(&[]),
            cross,
            moment,
            g: &mut [],
        };
        statistics.add_rows((0..n).map(|i| terms.score(i)));
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

    /// Move the pending statistics into the estimates (see the type docs for when): every sum
    /// times the decay, plus the pending one.
    ///
    /// The decay scales `Σ g·ψ_i` and `Σ ‖ψ_i‖²` alike, so a baseline `b_i` with nothing pending is
    /// unchanged by it and keeps its value; only the pending decisions' `b_i` are formed again
    /// (all of them when the decay is 0, which empties the sums). The constant's sums over i are
    /// kept beside them, the pending values added in four partial sums (for floats a
    /// rounding other than left to right, with the same error bound; exact types get the exact
    /// sum). Each loop runs over whole slices with no carried dependence, so for floats it runs
    /// in vector lanes; a commit costs one division per pending decision.
    pub fn commit(&mut self) {
        let n = self.pending_cross.len();
        if self.cross.len() < n {
            self.cross.resize(n, S::zero());
            self.moment.resize(n, S::zero());
            self.per_decision.resize(n, S::zero());
            self.formed.resize(n, false);
        }
        let mut reformed = n;
        if let Some(decay) = self.decay.clone() {
            // A local decay (not a field the loop could write) lets the loops run in lanes.
            for x in &mut self.cross {
                *x *= &decay;
            }
            for x in &mut self.moment {
                *x *= &decay;
            }
            self.totals.0 *= &decay;
            self.totals.1 *= &decay;
            if decay.is_certainly_zero() {
                reformed = self.cross.len();
            }
        }
        for (x, p) in self.cross.iter_mut().zip(&self.pending_cross) {
            *x += p;
        }
        for (x, p) in self.moment.iter_mut().zip(&self.pending_moment) {
            *x += p;
        }
        self.totals.0 += &lane_sum(&self.pending_cross);
        self.totals.1 += &lane_sum(&self.pending_moment);
        let (cross, moment) = (&self.cross[..reformed], &self.moment[..reformed]);
        for (((b, f), c), m) in self.per_decision[..reformed]
            .iter_mut()
            .zip(&mut self.formed[..reformed])
            .zip(cross)
            .zip(moment)
        {
            *f = !m.is_certainly_zero();
            *b = if *f { c.clone() / m } else { S::zero() };
        }
        self.clear_pending();
        let (num, den) = &self.totals;
        self.constant = (!den.is_certainly_zero()).then(|| num.clone() / den);
    }
}

/// Partial sums in [`lane_sum`].
const LANES: usize = 4;

/// `Σ xᵢ` as [`LANES`] partial sums over `i mod LANES`, added at the end: the exact sum for
/// exact types, an enclosure for intervals, for floats a rounding whose error is bounded like
/// the left-to-right sum's (`γ_n Σ|xᵢ|`) and whose loop runs in lanes.
fn lane_sum<S: Scalar>(xs: &[S]) -> S {
    let mut lanes: [S; LANES] = std::array::from_fn(|_| S::zero());
    let mut chunks = xs.chunks_exact(LANES);
    for c in &mut chunks {
        for (l, x) in lanes.iter_mut().zip(c) {
            *l += x;
        }
    }
    for (l, x) in lanes.iter_mut().zip(chunks.remainder()) {
        *l += x;
    }
    let [a, b, c, d] = lanes;
    (a + b) + (c + d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::BigRational;
    use rand::{Rng, SeedableRng};

    fn q(n: i64, d: i64) -> BigRational {
        BigRational::new(n.into(), d.into())
    }

    /// The baselines from every commit's sums recomputed from scratch, as the definition reads:
    /// `C_i ← decay·C_i + pending_i` for every i, then `b_i = C_i / M_i` and
    /// `b = Σ C_i / Σ M_i` (None where the denominator is 0).
    struct Eager {
        decay: BigRational,
        cross: Vec<BigRational>,
        moment: Vec<BigRational>,
    }

    impl Eager {
        fn commit(&mut self, cross: &[BigRational], moment: &[BigRational]) {
            let n = cross.len().max(self.cross.len());
            self.cross.resize(n, q(0, 1));
            self.moment.resize(n, q(0, 1));
            for i in 0..n {
                self.cross[i] = &self.decay * &self.cross[i] + cross.get(i).unwrap_or(&q(0, 1));
                self.moment[i] = &self.decay * &self.moment[i] + moment.get(i).unwrap_or(&q(0, 1));
            }
        }

        fn ratio(c: &BigRational, m: &BigRational) -> Option<BigRational> {
            (*m != q(0, 1)).then(|| c / m)
        }

        fn time_indexed(&self, i: usize) -> Option<BigRational> {
            Self::ratio(self.cross.get(i)?, &self.moment[i])
        }

        fn constant(&self) -> Option<BigRational> {
            let total = |xs: &[BigRational]| xs.iter().fold(q(0, 1), |a, x| a + x);
            Self::ratio(&total(&self.cross), &total(&self.moment))
        }
    }

    /// Commits of pending statistics of random lengths (zero scores included), with the decays
    /// 1, 9/10 and 0: the kept baselines of the decisions with nothing pending equal the
    /// recomputed ones exactly.
    #[test]
    fn commit_equals_the_recomputed_baselines() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for decay in [q(1, 1), q(9, 10), q(0, 1)] {
            let mut running = RunningOptimum::new(Some(decay.clone()));
            let mut eager = Eager {
                decay,
                cross: Vec::new(),
                moment: Vec::new(),
            };
            for _ in 0..40 {
                let n = rng.random_range(0..12);
                let cross: Vec<_> = (0..n).map(|_| q(rng.random_range(-20..20), 7)).collect();
                let moment: Vec<_> = (0..n)
                    .map(|_| q(rng.random_range(0..3) * rng.random_range(1..20), 5))
                    .collect();
                let (c, m) = running.pending_mut(n);
                c.clone_from_slice(&cross);
                m.clone_from_slice(&moment);
                running.commit();
                eager.commit(&cross, &moment);
                for i in 0..14 {
                    assert_eq!(running.time_indexed(i), eager.time_indexed(i), "b_{i}");
                }
                // The copies the estimates read: 0 where no baseline is formed.
                let mut copied = Vec::new();
                running.time_indexed_into(14, &mut copied);
                for i in 0..14 {
                    let b = eager.time_indexed(i).unwrap_or_else(|| q(0, 1));
                    assert_eq!(copied[i], b, "copied b_{i}");
                }
                assert_eq!(running.constant(), eager.constant());
            }
        }
    }
}
