//! [`RunningRegression`]: the variance-minimising state-dependent baseline `b(s) = w·φ_b(s)`,
//! its weights estimated from earlier iterations only.

use crate::oracle::{DecisionTerms, LinearBaseline, by_feature_count};
use crate::scalar::{Scalar, dot, norm_sq};

/// Running estimates of the weights of the variance-minimising linear state-dependent baseline
/// `b_i = w·φ_i` (φ_i = φ_b(s_i), k state features of decision i's state; [`crate::baseline`]):
///
/// `E‖g_b‖² = E‖g‖² − 2 wᵀc + wᵀA w` with `c = E[Σ_i (g·ψ_i) φ_i]` and
/// `A = E[Σ_i ‖ψ_i‖² φ_i φ_iᵀ]` (the cross terms `E[b_i ψ_i · b_j ψ_j]`, i ≠ j, vanish as for
/// constants: condition on the later decision's history, of which the earlier term and the later
/// state are functions), minimised by the solutions of `A w = c`: a weighted least-squares fit of
/// `(g·ψ_i)/‖ψ_i‖²` on φ_i with weights `‖ψ_i‖²`. One constant feature gives the constant
/// `b*_const`; one-hot decision indices give the time-indexed `b*_i`.
///
/// As [`crate::baseline::RunningOptimum`], a trajectory's statistics are held back
/// ([`RunningRegression::observe`]) and enter the weights at [`RunningRegression::commit`],
/// which the oracle calls when it rolls out the next trajectory: every baseline is a function of
/// the decision's state and of strictly earlier trajectories, so the estimate stays unbiased
/// whatever the weights are. `decay` multiplies the committed sums at each commit; `ridge` λ ≥ 0
/// is added to A's diagonal before the solve ([`solve_symmetric`]).
///
/// The statistics may be taken from every e-th trajectory only ([`RunningRegression::taking_every`],
/// [`RunningRegression::takes_next`]): which trajectories enter depends only on how many were
/// offered before, never on a trajectory's own actions, so the baselines stay functions of
/// earlier trajectories and the estimate stays unbiased; the weights then rest on a 1/e share of
/// the data. The statistics take k(k + 3)/2 multiply-adds per decision (k of them from `c`), the
/// baselines k.
#[derive(Debug, Clone)]
pub struct RunningRegression<S> {
    decay: Option<S>,
    ridge: S,
    /// Features per decision (0 before the first observation).
    k: usize,
    /// Σ ‖ψ_i‖² φ_i φ_iᵀ (k × k, row-major, the upper triangle only) and Σ (g·ψ_i) φ_i over
    /// committed trajectories.
    a: Vec<S>,
    c: Vec<S>,
    /// Their values from the trajectories observed since the last commit.
    pending_a: Vec<S>,
    pending_c: Vec<S>,
    pending: bool,
    /// The committed weights w (empty before any statistics).
    w: Vec<S>,
    /// Working storage: one trajectory's plain estimate, its products `g·ψ_i` and `‖ψ_i‖²`, the
    /// solve's augmented matrix.
    g: Vec<S>,
    products: (Vec<S>, Vec<S>),
    work: Vec<S>,
    /// One trajectory's state features by columns weighted by ‖ψ_i‖².
    weighted: Vec<S>,
    /// Statistics from every `every`-th trajectory offered ([`RunningRegression::takes_next`]).
    every: u64,
    /// Trajectories offered in committed batches, and since the last commit.
    offered: u64,
    pending_offered: u64,
}

impl<S: Scalar> RunningRegression<S> {
    /// No data yet (every baseline 0); `decay` as for [`crate::baseline::RunningOptimum`]
    /// (`None`: 1), `ridge` λ ≥ 0 on A's diagonal.
    pub fn new(decay: Option<S>, ridge: S) -> Self {
        Self {
            decay,
            ridge,
            k: 0,
            a: Vec::new(),
            c: Vec::new(),
            pending_a: Vec::new(),
            pending_c: Vec::new(),
            pending: false,
            w: Vec::new(),
            g: Vec::new(),
            products: (Vec::new(), Vec::new()),
            work: Vec::new(),
            weighted: Vec::new(),
            every: 1,
            offered: 0,
            pending_offered: 0,
        }
    }

    /// Take the statistics of every `every`-th trajectory offered only (the first, the
    /// (every + 1)-th, …; 1: every trajectory, as [`RunningRegression::new`] does).
    ///
    /// # Panics
    /// If `every` is 0.
    #[must_use]
    pub fn taking_every(mut self, every: u64) -> Self {
        assert!(every >= 1, "statistics from every e-th trajectory, e ≥ 1");
        self.every = every;
        self
    }

    /// Offer the next trajectory: whether its statistics are to be observed. The n-th
    /// trajectory offered since the start (counting from 0, committed batches and the pending
    /// one) is taken when n is a multiple of `every`; offering the same batch again after
    /// [`RunningRegression::clear_pending`] takes the same trajectories.
    pub fn takes_next(&mut self) -> bool {
        let n = self.offered + self.pending_offered;
        self.pending_offered += 1;
        n.is_multiple_of(self.every)
    }

    /// The committed weights w; empty before any trajectory's statistics were committed.
    pub fn weights(&self) -> &[S] {
        &self.w
    }

    /// The committed baselines `b_i = w·φ_i` of n decisions whose features are given by columns
    /// (`columns[j·n + i]` feature j of decision i) into `out` (cleared first), summed column by
    /// column (for each i the order of `w·φ_i`'s terms); nothing before any statistics were
    /// committed (every b_i = 0).
    ///
    /// # Panics
    /// If `columns` does not hold k columns of n entries (k the number of weights).
    pub fn baselines_into(&self, columns: &[S], n: usize, out: &mut Vec<S>) {
        out.clear();
        if self.w.is_empty() {
            return;
        }
        assert_eq!(columns.len(), self.w.len() * n, "k columns of n entries");
        out.resize(n, S::zero());
        for (j, w) in self.w.iter().enumerate() {
            for (b, x) in out.iter_mut().zip(column(columns, j, n)) {
                *b += w.clone() * x;
            }
        }
    }

    /// The same baselines as [`RunningRegression::baselines_into`], bit for bit, from features
    /// stored by rows (`rows[i·stride + j]` feature j of decision i, its first `k` used) with,
    /// when `time`, the decision index and 1 after them, as the state-dependent oracle appends
    /// them: each `w·φ_i` summed in the columns' order. Returns false, writing nothing, when the
    /// committed weights are not k (+ 2 with `time`) many; `out` is cleared first and stays empty
    /// before any statistics were committed. One pass; for 1 to 8 state features a row's
    /// products run over a compile-time length ([`crate::oracle::FixedLinearBaseline`]: the loop
    /// unrolls).
    pub fn baselines_from_rows(
        &self,
        (rows, stride): (&[S], usize),
        k: usize,
        time: bool,
        n: usize,
        out: &mut Vec<S>,
    ) -> bool {
        out.clear();
        if self.w.is_empty() {
            return true;
        }
        let Some(baseline) = LinearBaseline::new(&self.w, k, time) else {
            return false;
        };
        if k > stride || rows.len() < n * stride {
            return false;
        }
        out.resize(n, S::zero());
        let rows = rows.chunks_exact(stride);
        by_feature_count!(k, K => add_row_baselines::<S, K>(&baseline, rows, out), _ => {
            let mut index = S::zero();
            for (b, phi) in out.iter_mut().zip(rows) {
                *b = baseline.next(phi, &mut index);
            }
        });
        true
    }

    /// Forget the pending statistics (a new estimate on the current trajectories replaces them).
    pub fn clear_pending(&mut self) {
        self.pending = false;
        self.pending_offered = 0;
        for x in self.pending_a.iter_mut().chain(&mut self.pending_c) {
            *x = S::zero();
        }
    }

    /// Add one trajectory's `Σ_i (g·ψ_i) φ_i` and `Σ_i ‖ψ_i‖² φ_i φ_iᵀ` (g the plain estimate of
    /// `terms`, φ_i given by k columns of n entries, n its scored decisions:
    /// `columns[j·n + i]` is feature j of decision i) to the pending statistics.
    ///
    /// # Panics
    /// If `columns` does not hold k columns of n entries, or k differs from earlier
    /// observations' (the problem fixes it).
    pub fn observe(&mut self, terms: &DecisionTerms<S>, columns: &[S], k: usize) {
        let n = terms.decisions();
        self.g.clear();
        self.g.resize(terms.dim(), S::zero());
        terms.estimate_into(|_| None, &mut self.g);
        let (mut cross, mut moment) = std::mem::take(&mut self.products);
        cross.clear();
        cross.extend((0..n).map(|i| dot(&self.g, terms.score(i))));
        moment.clear();
        moment.extend((0..n).map(|i| norm_sq(terms.score(i))));
        self.observe_products(columns, k, &cross, &moment);
        self.products = (cross, moment);
    }

    /// Add one trajectory's statistics from its products: `Σ_i cross_i φ_i` and
    /// `Σ_i moment_i φ_i φ_iᵀ` with `cross_i = g·ψ_i`, `moment_i = ‖ψ_i‖²` (as
    /// [`crate::oracle::ScoreProducts`] computes them) for its n = `cross.len()` decisions, φ_i
    /// given by k columns of n entries. Each sum over the decisions is one dot product of
    /// contiguous columns (in vector lanes for floats); A is symmetric, so only its upper
    /// triangle is summed (the solve reads it mirrored).
    ///
    /// # Panics
    /// As [`RunningRegression::observe`], or if `moment` is shorter than `cross`.
    pub fn observe_products(&mut self, columns: &[S], k: usize, cross: &[S], moment: &[S]) {
        if self.k == 0 {
            self.k = k;
            for v in [&mut self.a, &mut self.pending_a] {
                v.resize(k * k, S::zero());
            }
            for v in [&mut self.c, &mut self.pending_c] {
                v.resize(k, S::zero());
            }
        }
        assert_eq!(k, self.k, "state features per decision changed");
        let n = cross.len();
        assert!(moment.len() >= n, "a moment per decision");
        assert_eq!(columns.len(), n * k, "k columns of {n} entries");
        // The columns weighted by ‖ψ_i‖².
        let weighted = &mut self.weighted;
        weighted.clear();
        for j in 0..k {
            weighted.extend(
                column(columns, j, n)
                    .iter()
                    .zip(moment)
                    .map(|(x, m)| m.clone() * x),
            );
        }
        for (j, c) in self.pending_c.iter_mut().enumerate() {
            *c += dot(cross, column(columns, j, n));
        }
        for j in 0..k {
            for l in j..k {
                self.pending_a[j * k + l] += dot(column(weighted, j, n), column(columns, l, n));
            }
        }
        self.pending = true;
    }

    /// Move the pending statistics into the sums (every sum times the decay, plus the pending
    /// one) and solve `(A + λI) w = c` for the weights ([`solve_symmetric`]); the trajectories
    /// offered since the last commit count as committed. Nothing else changes before the first
    /// observation. A commit that adds no statistics keeps the weights when λ = 0 (the decayed
    /// system `d·A w = d·c` has the same solutions).
    pub fn commit(&mut self) {
        self.offered += self.pending_offered;
        self.pending_offered = 0;
        if self.k == 0 {
            return;
        }
        if let Some(decay) = &self.decay {
            for x in self.a.iter_mut().chain(&mut self.c) {
                *x *= decay;
            }
        }
        let added = self.pending;
        if added {
            for (x, p) in self.a.iter_mut().zip(&self.pending_a) {
                *x += p;
            }
            for (x, p) in self.c.iter_mut().zip(&self.pending_c) {
                *x += p;
            }
        }
        self.clear_pending();
        // Without new statistics and without a ridge, the (decayed) system has the same
        // solutions: the weights stand.
        if !added && !self.w.is_empty() && self.ridge.is_certainly_zero() {
            return;
        }
        let k = self.k;
        self.work.clear();
        for r in 0..k {
            // The upper triangle, mirrored.
            self.work
                .extend((0..k).map(|l| self.a[r.min(l) * k + r.max(l)].clone()));
            self.work.push(self.c[r].clone());
        }
        for j in 0..k {
            self.work[j * (k + 1) + j] += &self.ridge;
        }
        self.w.resize(k, S::zero());
        solve_symmetric(&mut self.work, k, &mut self.w);
    }
}

/// Column j (n entries) of features stored by columns.
pub(crate) fn column<S>(v: &[S], j: usize, n: usize) -> &[S] {
    &v[j * n..(j + 1) * n]
}

/// A pivot counts only above this fraction of its diagonal entry ([`solve_symmetric`]).
const PIVOT_FRACTION: (i64, i64) = (1, 10_000_000_000);

/// Solve `M w = c` for a symmetric positive semi-definite k × k matrix M, given as the
/// augmented k × (k + 1) matrix `[M | c]` (row-major, overwritten), into `w`: Gaussian
/// elimination in the natural order (no row exchanges, which a positive semi-definite matrix
/// does not need). A pivot that is not certainly above 10⁻¹⁰ of its original diagonal entry
/// (a direction with no data, or one the earlier features already span) is skipped: its weight
/// is 0 and its column takes no part. When c lies in M's range (as the baseline's statistics do:
/// every `(g·ψ_i) φ_i` with ψ_i ≠ 0 is in the span of `‖ψ_i‖² φ_i φ_iᵀ`) and only exactly null
/// directions are skipped, w solves the system exactly; otherwise it is the solution with the
/// skipped weights fixed at 0. Any w leaves the baseline unbiased.
pub fn solve_symmetric<S: Scalar>(m: &mut [S], k: usize, w: &mut [S]) {
    let cols = k + 1;
    assert_eq!(m.len(), k * cols, "an augmented k × (k + 1) matrix");
    assert_eq!(w.len(), k, "k weights");
    let fraction = S::from_ratio(PIVOT_FRACTION.0, PIVOT_FRACTION.1);
    let original: Vec<S> = (0..k).map(|j| m[j * cols + j].clone()).collect();
    let mut used = vec![false; k];
    for j in 0..k {
        let pivot = m[j * cols + j].clone();
        let threshold = fraction.clone() * &original[j];
        used[j] = pivot.is_certainly_positive()
            && pivot.certain_cmp(&threshold) == Some(std::cmp::Ordering::Greater);
        if !used[j] {
            continue;
        }
        for r in j + 1..k {
            let f = m[r * cols + j].clone() / &pivot;
            if f.is_certainly_zero() {
                continue;
            }
            for l in j..cols {
                let x = f.clone() * &m[j * cols + l];
                m[r * cols + l] -= x;
            }
        }
    }
    for j in (0..k).rev() {
        if !used[j] {
            w[j] = S::zero();
            continue;
        }
        let mut rhs = m[j * cols + k].clone();
        for l in j + 1..k {
            rhs -= m[j * cols + l].clone() * &w[l];
        }
        w[j] = rhs / &m[j * cols + j];
    }
}

/// `out[i] = b_i` for the rows φ_i of `rows` (their first K entries), with K known at compile
/// time so that the products of a row unroll ([`crate::oracle::FixedLinearBaseline::next`]).
fn add_row_baselines<'r, S: Scalar + 'r, const K: usize>(
    baseline: &LinearBaseline<'_, S>,
    rows: impl Iterator<Item = &'r [S]>,
    out: &mut [S],
) {
    let baseline = baseline.fixed::<K>().expect("K state features");
    let mut index = S::zero();
    for (b, phi) in out.iter_mut().zip(rows) {
        *b = baseline.next(
            phi[..K].try_into().expect("rows of at least K entries"),
            &mut index,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::baseline::{PerDecisionTerms, RunningOptimum};
    use crate::problem::{Behaviour, Cost, IlProblem, KitRng};
    use crate::scalar::{BigRational, Dual, Interval};
    use crate::tolerance::Agreement;
    use crate::toy::{ToyMdp, ToyProblem};
    use nalgebra::DVector;
    use rand::{Rng, SeedableRng};

    /// `A = B Bᵀ` (k × k, rank ≤ r) from small random integers, and `c = A x`: `[A | c]` in
    /// rationals, with x.
    fn system(rng: &mut KitRng, k: usize, r: usize) -> (Vec<BigRational>, Vec<BigRational>) {
        let int = |rng: &mut KitRng| BigRational::from_integer(rng.random_range(-4i64..=4).into());
        let b: Vec<Vec<BigRational>> = (0..k).map(|_| (0..r).map(|_| int(rng)).collect()).collect();
        let x: Vec<BigRational> = (0..k).map(|_| int(rng)).collect();
        let a = |i: usize, j: usize| crate::scalar::dot(&b[i], &b[j]);
        let mut m = Vec::new();
        for i in 0..k {
            let row: Vec<BigRational> = (0..k).map(|j| a(i, j)).collect();
            let c = crate::scalar::dot(&row, &x);
            m.extend(row);
            m.push(c);
        }
        (m, x)
    }

    /// `A w − c` for the augmented `[A | c]`.
    fn residual(m: &[BigRational], k: usize, w: &[BigRational]) -> Vec<BigRational> {
        m.chunks_exact(k + 1)
            .map(|row| crate::scalar::dot(&row[..k], w) - &row[k])
            .collect()
    }

    /// Full rank: every scalar's solution agrees with the exact one (equal in ℚ, enclosed in
    /// intervals, inside the same code's interval run in `f64`); rank-deficient systems are solved
    /// exactly in ℚ with the dependent directions' weights 0.
    fn solves<S: Agreement>() {
        let mut rng = KitRng::seed_from_u64(5);
        let mut full = 0;
        for case in 0..300usize {
            let k = 1 + case % 6;
            let r = if case % 3 == 0 {
                k.saturating_sub(1).max(1)
            } else {
                k + 2
            };
            let (m, _) = system(&mut rng, k, r);
            let mut exact = m.clone();
            let mut w = vec![BigRational::from_integer(0.into()); k];
            solve_symmetric(&mut exact, k, &mut w);
            assert!(
                residual(&m, k, &w).iter().all(|x| x.is_certainly_zero()),
                "case {case}: A w ≠ c in ℚ"
            );
            // Nonsingular: the solution is unique; compare every scalar with it.
            let mut check = m.clone();
            let mut skipped = vec![BigRational::from_integer(0.into()); k];
            solve_symmetric(&mut check, k, &mut skipped);
            let singular = (0..k).any(|j| check[j * (k + 1) + j].is_certainly_zero());
            if singular {
                continue;
            }
            full += 1;
            let mut ms: Vec<S> = m.iter().map(S::from_rational).collect();
            let mut ws = vec![S::zero(); k];
            solve_symmetric(&mut ms, k, &mut ws);
            let mut mi: Vec<Interval> = m.iter().map(Interval::from_rational).collect();
            let mut wi = vec![Interval::zero(); k];
            solve_symmetric(&mut mi, k, &mut wi);
            for j in 0..k {
                assert!(
                    ws[j].agrees(&w[j], &wi[j]),
                    "case {case}, w_{j}: {:?} vs {} in {:?} ({})",
                    ws[j].to_f64(),
                    w[j],
                    wi[j],
                    std::any::type_name::<S>()
                );
            }
        }
        assert!(full > 100, "only {full} nonsingular systems");
    }

    #[test]
    fn the_solver_agrees_with_the_exact_solution_in_every_scalar() {
        solves::<BigRational>();
        solves::<Interval>();
        solves::<f64>();
        // Not f32: its rule (a fixed relative error) presumes no amplification, and a solve
        // amplifies rounding by the system's condition number.
        solves::<Dual<f64>>();
    }

    /// A skipped direction: a duplicated feature leaves the second copy's weight 0 and the
    /// system solved exactly; a ridge makes every pivot count.
    #[test]
    fn a_duplicated_feature_is_skipped_and_a_ridge_is_not() {
        let q = |n: i64| BigRational::from_integer(n.into());
        // A = [[2, 2], [2, 2]], c = [6, 6]: w = (3, 0).
        let mut m = vec![q(2), q(2), q(6), q(2), q(2), q(6)];
        let mut w = vec![q(0); 2];
        solve_symmetric(&mut m, 2, &mut w);
        assert_eq!(w, vec![q(3), q(0)]);
        // With λ = 1: [[3, 2], [2, 3]] w = (6, 6): w = (6/5, 6/5).
        let mut m = vec![q(3), q(2), q(6), q(2), q(3), q(6)];
        solve_symmetric(&mut m, 2, &mut w);
        assert_eq!(w, vec![BigRational::new(6.into(), 5.into()); 2]);
    }

    /// `baselines_from_rows` (rows of any stride, every fixed-dimension arm and the fallback)
    /// against `baselines_into` on the same features by columns, with and without the time
    /// features: the same values to the last bit (compared by their `Debug` text, which tells
    /// −0 from +0), in every scalar.
    fn rows_give_the_columns_baselines<S: Scalar + std::fmt::Debug>() {
        let mut rng = KitRng::seed_from_u64(17);
        let value = |rng: &mut KitRng| {
            let q = BigRational::new(
                rng.random_range(-40i64..=40).into(),
                rng.random_range(1i64..=9).into(),
            );
            S::from_rational(&q)
        };
        let mut compared = 0;
        for k in 1..=10 {
            for time in [false, true] {
                for (stride, n) in [(k, 0), (k, 1), (k + 2, 9), (k + 1, 40)] {
                    let mut r = RunningRegression::<S>::new(None, S::zero());
                    r.w = (0..k + if time { 2 } else { 0 })
                        .map(|_| value(&mut rng))
                        .collect();
                    let rows: Vec<S> = (0..n * stride).map(|_| value(&mut rng)).collect();
                    let mut columns: Vec<S> = (0..k)
                        .flat_map(|j| (0..n).map(move |i| i * stride + j))
                        .map(|at| rows[at].clone())
                        .collect();
                    if time {
                        columns.extend((0..n).map(|i| S::from_i64(i as i64)));
                        columns.extend((0..n).map(|_| S::one()));
                    }
                    let (mut by_rows, mut by_columns) = (Vec::new(), Vec::new());
                    assert!(r.baselines_from_rows((&rows, stride), k, time, n, &mut by_rows));
                    r.baselines_into(&columns, n, &mut by_columns);
                    assert_eq!(
                        format!("{by_rows:?}"),
                        format!("{by_columns:?}"),
                        "k = {k}, time = {time}, stride = {stride}, n = {n} ({})",
                        std::any::type_name::<S>()
                    );
                    compared += n;
                    // Weights for another number of features are refused, writing nothing.
                    assert!(!r.baselines_from_rows((&rows, stride), k + 1, time, n, &mut by_rows));
                    assert!(by_rows.is_empty());
                }
            }
        }
        assert_eq!(compared, 2 * 50 * 10);
    }

    #[test]
    fn baselines_from_rows_are_those_from_columns_in_every_scalar() {
        rows_give_the_columns_baselines::<f64>();
        rows_give_the_columns_baselines::<f32>();
        rows_give_the_columns_baselines::<BigRational>();
        rows_give_the_columns_baselines::<Interval>();
        rows_give_the_columns_baselines::<Dual<f64>>();
    }

    /// Two routes to the same baselines: a constant feature φ = 1 gives
    /// [`RunningOptimum`]'s constant `Σ_i g·ψ_i / Σ_i ‖ψ_i‖²`, one-hot decision indices give its
    /// time-indexed `b*_i`, after commits of the same trajectories (decay 9/10), exactly.
    #[test]
    fn one_constant_feature_is_the_estimated_constant() {
        let mdp = ToyMdp::from_json_str(include_str!("../../examples/toy/three-state.json"))
            .expect("valid toy file");
        let mut p = ToyProblem::<BigRational>::new(&mdp);
        let theta =
            DVector::from_vec(crate::scalar::parse_exact_list("-1/2,3,1/4,-7/2,1/3,1").expect("θ"));
        let decay = Some(BigRational::new(9.into(), 10.into()));
        let mut optimum = RunningOptimum::new(decay.clone());
        let mut constant =
            RunningRegression::new(decay.clone(), BigRational::from_integer(0.into()));
        let mut indexed = RunningRegression::new(decay, BigRational::from_integer(0.into()));
        let mut rng = KitRng::seed_from_u64(9);
        let mut cost = Cost::default();
        let mut terms = DecisionTerms::new();
        let n = mdp.horizon - 2;
        let mut checked = 0;
        for _ in 0..12 {
            let t = p
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
                .expect("roll-out");
            p.decision_terms(&theta, &t, None, &mut terms, &mut cost)
                .expect("terms");
            terms.finish();
            let d = terms.decisions();
            let ones = vec![BigRational::from_integer(1.into()); d];
            // Column j marks decision j (the n possible indices; d of them taken).
            let onehot = |d: usize| -> Vec<BigRational> {
                (0..n)
                    .flat_map(|j| {
                        (0..d).map(move |i| BigRational::from_integer(i64::from(i == j).into()))
                    })
                    .collect()
            };
            optimum.observe(&terms);
            constant.observe(&terms, &ones, 1);
            indexed.observe(&terms, &onehot(d), n);
            optimum.commit();
            constant.commit();
            indexed.commit();
            let mut b = Vec::new();
            constant.baselines_into(&[BigRational::from_integer(1.into())], 1, &mut b);
            if let Some(c) = optimum.constant() {
                assert_eq!(b, vec![c]);
            }
            // Every index at once: the n × n identity by columns.
            indexed.baselines_into(&onehot(n), n, &mut b);
            for (i, bi) in b.iter().enumerate() {
                if let Some(want) = optimum.time_indexed(i) {
                    assert_eq!(bi, &want, "b_{i}");
                    checked += 1;
                }
            }
        }
        assert!(
            checked > 10,
            "only {checked} time-indexed baselines compared"
        );
    }
}
