//! The estimator's per-decision kernel: the loss, sampling and causal accumulation of eq. 3.15 for
//! inputs the oracle has validated once per trajectory, so that a policy may skip its per-call
//! checks and fuse the per-decision work.
//!
//! Every method has a default built on [`Policy`]'s checked, allocation-free methods; a policy
//! opts in by implementing [`EstimatorKernel`] (an empty `impl` takes the defaults). The logistic
//! policy overrides the causal passes with fixed-dimension loops (module `logistic`); the softmax
//! and linear-Gaussian policies override the per-decision methods with their checked methods'
//! work after the θ and φ checks the oracle has made, and the loss without its gradient; the
//! softmax policy notes the probabilities it samples from, and the estimate at the same θ reads
//! them ([`EstimatorKernel::sample_noting`], the `notes` of
//! [`EstimatorKernel::causal_sum_validated`]). Every override returns the default's values bit
//! for bit and the default's first error, except the logistic policy's `score_products`, which
//! forms the same products in another order (equal up to rounding). For each policy the recorded
//! sum ([`EstimatorKernel::accumulate_recorded`]) makes the plain pass's operations in its order,
//! with the losses it is given: one summation order for the plain and every baselined estimate.

use super::products::ScoreProducts;
use crate::policy::{
    ActionVector, LinearGaussian, MlpGaussian, MlpSoftmax, Policy, PolicyError, Softmax,
    SpeedLimitedGaussian,
};
use crate::problem::KitRng;
use crate::scalar::{Real, Scalar, Sqrt};
use std::borrow::Borrow;

/// The per-decision operations of the gradient oracle (eq. 3.15, math.md §1.1) on validated
/// inputs: θ has [`Policy::param_dim`] finite entries (checked once per roll-out or estimate), and
/// where stated φ has [`Policy::feature_dim`] finite entries (checked once per trajectory).
///
/// For validated inputs every method returns exactly the values and errors of its default; for
/// other inputs the outcome is unspecified (an error, a panic or a meaningless value, never
/// undefined behaviour).
pub trait EstimatorKernel<S: Scalar>: Policy<S> {
    /// The loss `l(s, θ)` of [`Policy::loss_into`] without its gradient, for a validated θ and φ.
    /// `scratch` has [`Policy::param_dim`] entries; its contents afterwards are unspecified.
    ///
    /// The default calls [`Policy::loss_into`] (the gradient is computed and discarded).
    ///
    /// # Errors
    /// As [`Policy::loss_into`].
    fn loss_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        scratch: &mut [S],
    ) -> Result<S, PolicyError> {
        self.loss_into(theta, phi, label, scratch)
    }

    /// `a ∼ π_θ(·|s)` as [`Policy::sample`] for a validated θ; φ is still checked (length and
    /// finiteness) exactly as [`Policy::sample`] checks it: the oracle relies on this to mark a
    /// learner's roll-out as having finite features.
    ///
    /// The default calls [`Policy::sample`].
    ///
    /// # Errors
    /// As [`Policy::sample`].
    #[inline]
    fn sample_validated(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<Self::Action, PolicyError> {
        self.sample(theta, phi, rng)
    }

    /// One decision of the unit-weight causal estimator of eq. 3.15 on a validated θ and φ:
    /// returns `l_t`, adds `∇_θ l_t + l_t Σ_{i<t} ψ_i` to `g` entry by entry, then `ψ_t` to
    /// `score_sum` (which holds `Σ_{i<t} ψ_i` on entry). `grad` and `score` are scratch of length
    /// [`Policy::param_dim`].
    ///
    /// The default is [`Policy::loss_score_into`] then `accumulate` with unit weight.
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`].
    #[allow(clippy::too_many_arguments)] // the estimator's whole per-decision state
    #[inline]
    fn causal_step_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &Self::Label,
        action: &Self::Action,
        grad: &mut [S],
        score: &mut [S],
        g: &mut [S],
        score_sum: &mut [S],
    ) -> Result<S, PolicyError> {
        let l = self.loss_score_into(theta, phi, label, action, grad, score)?;
        accumulate(g, None, &l, grad, score, score_sum);
        Ok(l)
    }

    /// The unit-weight causal estimator of eq. 3.15 over one trajectory,
    /// `g += Σ_t [∇_θ l_t + l_t Σ_{i<t} ψ_i] + L Σ_{i≤n} ψ_i`, on validated inputs: `features`
    /// holds φ(s_1), …, φ(s_n) row after row, `labels` and `actions` one entry per row, and `end`
    /// the losses L after the last decision that weigh every score (an absorbing tail's
    /// `L_abs`), or `None` (L = 0, no term). A baseline enters through the recorded route
    /// ([`EstimatorKernel::record_validated`], then [`EstimatorKernel::accumulate_recorded`] with
    /// shifted losses), which sums in this pass's order.
    ///
    /// With `loss`, every decision's `l_t` is added to it in the order of the rows (the
    /// unshifted losses: the trajectory loss of [`crate::problem::IlProblem::trajectory_loss`],
    /// summed in its order when `loss` starts at the absorbing tail's value, or 0).
    ///
    /// `notes` are the entries [`EstimatorKernel::sample_noting`] noted while the trajectory was
    /// sampled at this θ ([`EstimatorKernel::note_len`] per row of `features`), or `None`: a
    /// policy that notes something (the softmax policy's probabilities) reads them instead of
    /// recomputing them, with the same values and errors; the caller guarantees that θ, the
    /// features and the notes are those of the roll-out. Every other policy ignores them.
    ///
    /// `scratch` is working storage the implementation sizes as it needs (the default:
    /// `3 ·` [`Policy::param_dim`] entries; the logistic policy's fixed-dimension loop needs
    /// none). The default runs [`EstimatorKernel::causal_step_validated`] decision after decision
    /// (`causal_sum_by_steps`) and ignores the notes.
    ///
    /// # Errors
    /// As [`EstimatorKernel::causal_step_validated`] at the first failing decision.
    #[allow(clippy::too_many_arguments)] // the trajectory, its notes and the output
    #[inline]
    fn causal_sum_validated<L: Borrow<Self::Label>>(
        &self,
        theta: &[S],
        features: &[S],
        notes: Option<&[S]>,
        labels: &[L],
        actions: &[Self::Action],
        end: Option<&S>,
        g: &mut [S],
        loss: Option<&mut S>,
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let _ = notes;
        causal_sum_by_steps(
            self, theta, features, labels, actions, end, g, loss, scratch,
        )
    }

    /// Entries per decision that [`EstimatorKernel::sample_noting`] notes for the estimate at the
    /// same θ; 0 (the default): it notes nothing, and the estimate recomputes what it needs.
    fn note_len(&self) -> usize {
        0
    }

    /// [`EstimatorKernel::sample_validated`] (the same action, draws and errors), appending to
    /// `notes` the [`EstimatorKernel::note_len`] entries of this decision that
    /// [`EstimatorKernel::causal_sum_validated`] reads instead of recomputing them (the softmax
    /// policy's probabilities). The default notes nothing.
    ///
    /// # Errors
    /// As [`EstimatorKernel::sample_validated`]; `notes` then holds at most this decision's
    /// entries more.
    #[inline]
    fn sample_noting(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
        notes: &mut Vec<S>,
    ) -> Result<Self::Action, PolicyError> {
        let _ = notes;
        self.sample_validated(theta, phi, rng)
    }

    /// The decisions of one trajectory recorded for the causal estimator of eq. 3.15, without
    /// summing it (the inputs of [`EstimatorKernel::causal_sum_validated`]): every decision's
    /// loss `l_t` into `losses` (one entry per row) and into `records` what
    /// [`EstimatorKernel::accumulate_recorded`] needs to form `Σ_t [∇_θ l_t + l'_t Σ_{i<t} ψ_i]`
    /// for losses `l'_t` chosen afterwards, in a form of the policy's choosing. It serves
    /// baselines, which enter as shifted losses ([`crate::baseline`]): leave-one-out's b_i depends
    /// on every trajectory's losses, an estimated baseline's on the plain estimate.
    ///
    /// `notes` are the roll-out's notes at this θ, or `None`, as for
    /// [`EstimatorKernel::causal_sum_validated`]: a policy that notes something reads them
    /// instead of recomputing them, with the same records and errors.
    ///
    /// `losses` and `records` are cleared, then refilled: kept between calls, they allocate
    /// nothing per decision once grown. The default records `∇_θ l_t` and ψ_t per decision, as
    /// rows of 2 · [`Policy::param_dim`] entries, with [`Policy::loss_score_into`] per decision
    /// (`record_rows`), and ignores the notes.
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`] at the first failing decision; `losses` and `records` are
    /// then unspecified.
    #[allow(clippy::too_many_arguments)] // the trajectory, its notes and the records
    fn record_validated<L: Borrow<Self::Label>>(
        &self,
        theta: &[S],
        features: &[S],
        notes: Option<&[S]>,
        labels: &[L],
        actions: &[Self::Action],
        losses: &mut Vec<S>,
        records: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let _ = notes;
        record_rows(self, theta, features, labels, actions, losses, records)
    }

    /// `g += Σ_{t<n} [∇_θ l_t + l'_t Σ_{i<t} ψ_i] + l'_n Σ_{i<n} ψ_i` over the n decisions that
    /// [`EstimatorKernel::record_validated`] recorded in `records` for the same `features`, with
    /// the losses `l'` given: n entries, or n + 1 when one more loss (an absorbing tail, a
    /// baseline's weight after the last decision) weighs every score. Decision by decision it
    /// makes the operations of the policy's [`EstimatorKernel::causal_sum_validated`] in the
    /// same order with `l'_t` in place of `l_t`: with the recorded losses it is the plain causal
    /// estimate bit for bit (floats), and every baselined estimate, whose baseline enters as
    /// shifted losses, is summed in that one order.
    ///
    /// `scratch` is working storage the implementation sizes as it needs (the default:
    /// [`Policy::param_dim`] entries for `Σ_{i<t} ψ_i`; the logistic policy's fixed-dimension
    /// loop needs none). The default reads the rows of `record_rows` (`accumulate_rows`).
    fn accumulate_recorded(
        &self,
        features: &[S],
        records: &[S],
        losses: &[S],
        g: &mut [S],
        scratch: &mut Vec<S>,
    ) {
        let _ = features;
        accumulate_rows(records, self.param_dim(), losses, g, scratch);
    }

    /// [`ScoreProducts`] for the decisions that [`EstimatorKernel::record_validated`] recorded in
    /// `records` for the same `features`: the statistics of the variance-minimising baseline
    /// ([`crate::baseline::RunningOptimum`]) and the baseline's correction of the estimate, with
    /// b_i given or the linear state-dependent baseline's ([`super::Baselines`]), which a policy
    /// may form in the pass that reads ψ_i. The default reads the rows of `record_rows`
    /// ([`ScoreProducts::add_rows`], the linear baseline's b_i formed first).
    fn score_products(&self, features: &[S], records: &[S], out: ScoreProducts<'_, S>) {
        let _ = features;
        out.add_rows(score_rows(records, self.param_dim()));
    }
}

/// The default [`EstimatorKernel::record_validated`]: per decision [`Policy::loss_score_into`]
/// (with the policy's checks), its loss appended to `losses` and the row `∇_θ l_t`, ψ_t (2d
/// entries) to `records` (through [`record_by_steps`]).
pub(crate) fn record_rows<S, P, L>(
    policy: &P,
    theta: &[S],
    features: &[S],
    labels: &[L],
    actions: &[P::Action],
    losses: &mut Vec<S>,
    records: &mut Vec<S>,
) -> Result<(), PolicyError>
where
    S: Scalar,
    P: Policy<S> + ?Sized,
    L: Borrow<P::Label>,
{
    record_rows_with(
        policy,
        features,
        labels,
        actions,
        losses,
        records,
        |phi, y, a, grad, score| policy.loss_score_into(theta, phi, y, a, grad, score),
    )
}

/// `record_rows` with the per-decision [`Policy::loss_score_into`] replaced by
/// `loss_score(φ_t, y_t, a_t, ∇l_t, ψ_t)`, which writes the same gradient and score and returns
/// the same loss (a policy's version without checks the oracle has made).
pub(crate) fn record_rows_with<S, P, L>(
    policy: &P,
    features: &[S],
    labels: &[L],
    actions: &[P::Action],
    losses: &mut Vec<S>,
    records: &mut Vec<S>,
    mut loss_score: impl FnMut(
        &[S],
        &P::Label,
        &P::Action,
        &mut [S],
        &mut [S],
    ) -> Result<S, PolicyError>,
) -> Result<(), PolicyError>
where
    S: Scalar,
    P: Policy<S> + ?Sized,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let mut buf = vec![S::zero(); 2 * d];
    let (grad, score) = buf.split_at_mut(d);
    let x = policy.feature_dim();
    record_by_steps(
        features,
        x,
        labels,
        actions,
        losses,
        records,
        2 * d,
        |phi, y, a, records| {
            let l = loss_score(phi, y.borrow(), a, grad, score)?;
            records.extend_from_slice(grad);
            records.extend_from_slice(score);
            Ok(l)
        },
    )
}

/// The default [`EstimatorKernel::accumulate_recorded`] for the `records` of `record_rows` (per
/// decision the row `∇_θ l_t`, ψ_t of `2d` entries): per decision [`accumulate`] with `l'_t` (the
/// default causal pass's operations in its order), then `g += l'_n Σ_{i<n} ψ_i` for an
/// (n + 1)-th loss.
pub(crate) fn accumulate_rows<S: Scalar>(
    records: &[S],
    d: usize,
    losses: &[S],
    g: &mut [S],
    scratch: &mut Vec<S>,
) {
    scratch.clear();
    scratch.resize(d, S::zero());
    let score_sum = &mut scratch[..];
    let rows = records.chunks_exact(2 * d.max(1));
    let n = rows.len();
    for (row, l) in rows.zip(losses) {
        let (grad, score) = row.split_at(d);
        accumulate(g, None, l, grad, score, score_sum);
    }
    if let Some(end) = losses.get(n) {
        for (gj, sj) in g.iter_mut().zip(score_sum.iter()) {
            *gj += end.clone() * sj;
        }
    }
}

/// The scores ψ_t of the records of `record_rows`, one row of `d` entries per decision.
fn score_rows<S>(records: &[S], d: usize) -> impl Iterator<Item = &[S]> {
    records.chunks_exact(2 * d.max(1)).map(move |row| &row[d..])
}

/// Every decision of a trajectory recorded, as [`EstimatorKernel::record_validated`] records
/// them: `losses` and `scores` are cleared (with room reserved once for `n` losses and
/// `n · score_len` record entries), then for each row φ_t of `features` (`feature_dim`
/// entries), its label and its action, `step(φ_t, y_t, a_t, scores)` appends the decision's
/// record to `scores` and returns `l_t`, which is appended to `losses`.
///
/// # Errors
/// The first error of `step`; the records are then unspecified.
#[allow(clippy::too_many_arguments)] // the trajectory, the records and the step
pub(crate) fn record_by_steps<S, Y, A>(
    features: &[S],
    feature_dim: usize,
    labels: &[Y],
    actions: &[A],
    losses: &mut Vec<S>,
    scores: &mut Vec<S>,
    score_len: usize,
    mut step: impl FnMut(&[S], &Y, &A, &mut Vec<S>) -> Result<S, PolicyError>,
) -> Result<(), PolicyError> {
    let n = actions.len();
    losses.clear();
    losses.reserve(n);
    scores.clear();
    scores.reserve(n * score_len);
    let rows = features.chunks_exact(feature_dim.max(1));
    for ((phi, y), a) in rows.zip(labels).zip(actions) {
        let l = step(phi, y, a, scores)?;
        losses.push(l);
    }
    Ok(())
}

/// `g −= Σ_{i<n} b_i ψ_i` for ψ_i stored as consecutive rows of `d` entries, `b` yielding
/// `b_{n−1}, …, b_0` (decisions it has no item for are left out).
pub(crate) fn subtract_score_rows<S: Scalar>(
    scores: &[S],
    d: usize,
    n: usize,
    b: impl Iterator<Item = S>,
    g: &mut [S],
) {
    for (row, bi) in scores.chunks_exact(d.max(1)).take(n).rev().zip(b) {
        for (gj, x) in g.iter_mut().zip(row) {
            *gj -= bi.clone() * x;
        }
    }
}

/// The default [`EstimatorKernel::causal_sum_validated`]: per decision
/// [`EstimatorKernel::causal_step_validated`], with `scratch` resized to
/// `3 · param_dim` zeros and split into `∇l_t`, `ψ_t` and `Σ_{i<t} ψ_i`; then `g += L Σ_{i≤n} ψ_i`
/// for an `end` L; with `loss`, each `l_t` added to it in order.
#[allow(clippy::too_many_arguments)] // the method's arguments and the policy
#[inline]
pub(crate) fn causal_sum_by_steps<S, P, L>(
    policy: &P,
    theta: &[S],
    features: &[S],
    labels: &[L],
    actions: &[P::Action],
    end: Option<&S>,
    g: &mut [S],
    loss: Option<&mut S>,
    scratch: &mut Vec<S>,
) -> Result<(), PolicyError>
where
    S: Scalar,
    P: EstimatorKernel<S> + ?Sized,
    L: Borrow<P::Label>,
{
    causal_sum_with_steps(
        policy,
        features,
        labels,
        actions,
        end,
        g,
        loss,
        scratch,
        |_, phi, y, a, grad, score, g, score_sum| {
            policy.causal_step_validated(theta, phi, y, a, grad, score, g, score_sum)
        },
    )
}

/// `causal_sum_by_steps` with the per-decision step given: `step(t, φ_t, y_t, a_t, ∇l_t, ψ_t,
/// g, Σ_{i<t} ψ_i)` does what [`EstimatorKernel::causal_step_validated`] does for decision t
/// (0-based) and returns `l_t`.
#[allow(clippy::too_many_arguments)] // the trajectory, the output and the step
#[inline]
pub(crate) fn causal_sum_with_steps<S, P, L>(
    policy: &P,
    features: &[S],
    labels: &[L],
    actions: &[P::Action],
    end: Option<&S>,
    g: &mut [S],
    mut loss: Option<&mut S>,
    scratch: &mut Vec<S>,
    mut step: impl FnMut(
        usize,
        &[S],
        &P::Label,
        &P::Action,
        &mut [S],
        &mut [S],
        &mut [S],
        &mut [S],
    ) -> Result<S, PolicyError>,
) -> Result<(), PolicyError>
where
    S: Scalar,
    P: EstimatorKernel<S> + ?Sized,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    scratch.clear();
    scratch.resize(3 * d, S::zero());
    let (grad, rest) = scratch.split_at_mut(d);
    let (score, score_sum) = rest.split_at_mut(d);
    let rows = features.chunks_exact(policy.feature_dim().max(1));
    for (t, ((phi, y), a)) in rows.zip(labels).zip(actions).enumerate() {
        let l = step(t, phi, y.borrow(), a, grad, score, g, score_sum)?;
        if let Some(total) = loss.as_deref_mut() {
            *total += l;
        }
    }
    if let Some(end) = end {
        for (gj, sj) in g.iter_mut().zip(score_sum.iter()) {
            *gj += end.clone() * sj;
        }
    }
    Ok(())
}

/// One decision's terms of the causal estimator (eq. 3.15; math.md §4 for the weight):
/// `g += w ∇l_t + w l_t Σ_{i<t} ψ_i` entry by entry, then `Σ_{i<t} ψ_i += ψ_t`. `w = None`: the
/// weight is exactly 1, and `1·x = x` in every scalar, so the multiplication is skipped. A
/// function of its own so that the compiler knows the slices do not overlap.
#[inline]
pub(crate) fn accumulate<S: Scalar>(
    g: &mut [S],
    w: Option<&S>,
    l: &S,
    grad: &[S],
    score: &[S],
    score_sum: &mut [S],
) {
    let terms = g.iter_mut().zip(grad).zip(score_sum.iter());
    match w {
        Some(w) => {
            let wl = w.clone() * l;
            for ((gj, dj), sj) in terms {
                *gj += w.clone() * dj + wl.clone() * sj;
            }
        }
        None => {
            for ((gj, dj), sj) in terms {
                *gj += dj.clone() + l.clone() * sj;
            }
        }
    }
    for (sj, pj) in score_sum.iter_mut().zip(score) {
        *sj += pj;
    }
}

/// `causal_step_validated` and `record_validated` of a policy with a `loss_score_validated`:
/// [`Policy::loss_score_into`]'s work after the θ and φ checks (the same values and, for
/// validated θ and φ, the same errors), then the default's accumulation or records (with
/// `noted`, `record_validated` is left to the policy).
macro_rules! steps_by_validated {
    ($label:ty, $action:ty, noted) => {
        #[inline]
        fn causal_step_validated(
            &self,
            theta: &[S],
            phi: &[S],
            label: &$label,
            action: &$action,
            grad: &mut [S],
            score: &mut [S],
            g: &mut [S],
            score_sum: &mut [S],
        ) -> Result<S, PolicyError> {
            let l = self.loss_score_validated(theta, phi, label, action, grad, score)?;
            accumulate(g, None, &l, grad, score, score_sum);
            Ok(l)
        }
    };
    ($label:ty, $action:ty) => {
        steps_by_validated!($label, $action, noted);

        fn record_validated<L: Borrow<$label>>(
            &self,
            theta: &[S],
            features: &[S],
            _notes: Option<&[S]>,
            labels: &[L],
            actions: &[$action],
            losses: &mut Vec<S>,
            records: &mut Vec<S>,
        ) -> Result<(), PolicyError> {
            record_rows_with(
                self,
                features,
                labels,
                actions,
                losses,
                records,
                |phi, y, a, grad, score| self.loss_score_validated(theta, phi, y, a, grad, score),
            )
        }
    };
}

/// The per-decision methods without the checks of θ and φ that the oracle has made once (the
/// same operations after them, so the defaults' values and errors), and the loss without the
/// gradient.
impl<S: Real> EstimatorKernel<S> for Softmax {
    fn loss_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        _scratch: &mut [S],
    ) -> Result<S, PolicyError> {
        self.loss_only_validated(theta, phi, *label)
    }

    #[inline]
    fn sample_validated(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
    ) -> Result<usize, PolicyError> {
        self.sample_validated_theta(theta, phi, rng)
    }

    steps_by_validated!(usize, usize, noted);

    /// With notes, each decision's loss and score from its noted probabilities (as the causal
    /// sum's); without, after the θ and φ checks the oracle has made.
    fn record_validated<L: Borrow<usize>>(
        &self,
        theta: &[S],
        features: &[S],
        notes: Option<&[S]>,
        labels: &[L],
        actions: &[usize],
        losses: &mut Vec<S>,
        records: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let Some(notes) = notes else {
            return record_rows_with(
                self,
                features,
                labels,
                actions,
                losses,
                records,
                |phi, y, a, grad, score| self.loss_score_validated(theta, phi, y, a, grad, score),
            );
        };
        let k = self.actions();
        let mut rows = notes.chunks_exact(k.max(1));
        record_rows_with(
            self,
            features,
            labels,
            actions,
            losses,
            records,
            |phi, y, a, grad, score| {
                let probs = rows.next().unwrap_or_default();
                self.noted_loss_score(probs, phi, *y, *a, grad, score)
            },
        )
    }

    /// The probabilities π_θ(·|s_t): A entries per decision.
    fn note_len(&self) -> usize {
        self.actions()
    }

    #[inline]
    fn sample_noting(
        &self,
        theta: &[S],
        phi: &[S],
        rng: &mut KitRng,
        notes: &mut Vec<S>,
    ) -> Result<usize, PolicyError> {
        self.sample_noting_probs(theta, phi, rng, notes)
    }

    /// With notes, each decision's step from its noted probabilities, not from θ (two actions'
    /// copied into a two-entry array, so that the loops over the actions unroll); without, the
    /// default's steps from θ.
    fn causal_sum_validated<L: Borrow<usize>>(
        &self,
        theta: &[S],
        features: &[S],
        notes: Option<&[S]>,
        labels: &[L],
        actions: &[usize],
        end: Option<&S>,
        g: &mut [S],
        loss: Option<&mut S>,
        scratch: &mut Vec<S>,
    ) -> Result<(), PolicyError> {
        let Some(notes) = notes else {
            return causal_sum_by_steps(
                self, theta, features, labels, actions, end, g, loss, scratch,
            );
        };
        let k = self.actions();
        causal_sum_with_steps(
            self,
            features,
            labels,
            actions,
            end,
            g,
            loss,
            scratch,
            |t, phi, y, a, grad, score, g, score_sum| {
                let probs = &notes[t * k..(t + 1) * k];
                let l = self.noted_loss_score(probs, phi, *y, *a, grad, score)?;
                accumulate(g, None, &l, grad, score, score_sum);
                Ok(l)
            },
        )
    }
}

impl Softmax {
    /// One decision's loss and score from its noted probabilities
    /// ([`Softmax::loss_score_from_probs`]), two actions' copied into a two-entry array so that
    /// the loops over the actions unroll.
    #[inline]
    fn noted_loss_score<S: Real>(
        &self,
        probs: &[S],
        phi: &[S],
        label: usize,
        action: usize,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        if let [p0, p1] = probs {
            let two = [p0.clone(), p1.clone()];
            self.loss_score_from_probs(&two, phi, label, action, grad, score)
        } else {
            self.loss_score_from_probs(probs, phi, label, action, grad, score)
        }
    }
}

impl<S: Real> EstimatorKernel<S> for MlpSoftmax {}

impl<S: Real> EstimatorKernel<S> for MlpGaussian<S> {}

/// The loss without the gradient, and every per-decision method without the θ, φ checks the
/// oracle has made once (the same operations after them, so the defaults' values and errors).
impl<S: Scalar, A: ActionVector<S>> EstimatorKernel<S> for LinearGaussian<S, A> {
    fn loss_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        _scratch: &mut [S],
    ) -> Result<S, PolicyError> {
        self.loss_only_validated(theta, phi, label)
    }

    #[inline]
    fn sample_validated(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<A, PolicyError> {
        self.sample_validated_theta(theta, phi, rng)
    }

    steps_by_validated!([S], A);
}

/// The loss without the gradient, and every per-decision method without the θ, φ checks the
/// oracle has made once (sampling is the linear-Gaussian policy's).
impl<S: Sqrt, A: ActionVector<S>> EstimatorKernel<S> for SpeedLimitedGaussian<S, A> {
    fn loss_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        scratch: &mut [S],
    ) -> Result<S, PolicyError> {
        self.loss_only_validated(theta, phi, label, scratch)
    }

    #[inline]
    fn sample_validated(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<A, PolicyError> {
        self.inner().sample_validated_theta(theta, phi, rng)
    }

    steps_by_validated!([S], A);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::LinearGaussian;
    use crate::scalar::Dual;
    use rand::{Rng, SeedableRng};
    use std::fmt::Debug;

    /// Equal, and for floats the same bits.
    fn same<S: Scalar>(a: &S, b: &S) -> bool {
        a == b && a.bit_key() == b.bit_key()
    }

    fn same_all<S: Scalar>(a: &[S], b: &[S]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same(x, y))
    }

    fn same_result<S: Scalar>(a: &Result<S, PolicyError>, b: &Result<S, PolicyError>) -> bool {
        match (a, b) {
            (Ok(x), Ok(y)) => same(x, y),
            (Err(x), Err(y)) => x == y,
            _ => false,
        }
    }

    /// A policy's kernel against the defaults built on its checked methods, for a θ and
    /// features the oracle has validated (finite, the right lengths) and any labels and
    /// actions: the same values bit for bit (floats) and the same errors; sampling still
    /// rejects `bad_phi` (a non-finite feature) as φ's error. Returns whether the first
    /// decision's causal step succeeded.
    #[allow(clippy::too_many_arguments)] // a trajectory and its variations
    fn assert_kernel_as_defaults<S, P, L>(
        pi: &P,
        theta: &[S],
        rows: &[S],
        labels: &[L],
        actions: &[P::Action],
        bad_phi: &[S],
        seed: u64,
    ) -> bool
    where
        S: Scalar,
        P: EstimatorKernel<S>,
        P::Action: PartialEq + Debug,
        L: Borrow<P::Label>,
    {
        assert!(theta.iter().chain(rows).all(Scalar::is_finite), "validated");
        let d = pi.param_dim();
        let phi = &rows[..pi.feature_dim()];
        let (mut r1, mut r2) = (KitRng::seed_from_u64(seed), KitRng::seed_from_u64(seed));
        let a1 = pi.sample_validated(theta, phi, &mut r1);
        let a2 = pi.sample(theta, phi, &mut r2);
        assert_eq!((a1, &r1), (a2, &r2));
        let mut r = KitRng::seed_from_u64(seed);
        assert_eq!(
            pi.sample_validated(theta, bad_phi, &mut r).err(),
            Some(PolicyError::NonFinite { param: "phi" })
        );
        let (y, a) = (labels[0].borrow(), &actions[0]);
        let mut scratch = vec![S::zero(); d];
        let mut grad = vec![S::zero(); d];
        assert!(same_result(
            &pi.loss_validated(theta, phi, y, &mut scratch),
            &pi.loss_into(theta, phi, y, &mut grad),
        ));
        // One causal step from the same non-zero running sums.
        let start: Vec<S> = (0..d).map(|j| S::from_i64(j as i64 - 2)).collect();
        let run = |validated: bool| {
            let (mut g, mut ss) = (start.clone(), start.clone());
            let (mut gr, mut sc) = (vec![S::zero(); d], vec![S::zero(); d]);
            let l = if validated {
                pi.causal_step_validated(theta, phi, y, a, &mut gr, &mut sc, &mut g, &mut ss)
            } else {
                pi.loss_score_into(theta, phi, y, a, &mut gr, &mut sc)
                    .inspect(|l| accumulate(&mut g, None, l, &gr, &sc, &mut ss))
            };
            (l, g, ss)
        };
        let ((step, g1, s1), (l2, g2, s2)) = (run(true), run(false));
        assert!(same_result(&step, &l2), "{step:?} {l2:?}");
        assert!(same_all(&g1, &g2) && same_all(&s1, &s2));
        let record = |validated: bool| {
            let (mut losses, mut records) = (vec![], vec![]);
            let r = if validated {
                pi.record_validated(
                    theta,
                    rows,
                    None,
                    labels,
                    actions,
                    &mut losses,
                    &mut records,
                )
            } else {
                record_rows(pi, theta, rows, labels, actions, &mut losses, &mut records)
            };
            (r, losses, records)
        };
        let ((r1, l1, c1), (r2, l2, c2)) = (record(true), record(false));
        assert_eq!(r1, r2);
        if r1.is_ok() {
            assert!(same_all(&l1, &l2) && same_all(&c1, &c2));
        }
        step.is_ok()
    }

    /// Random inputs for `actions × features` parameters and `n` decisions: θ scaled by one of
    /// `scales`, features in [−1, 1], and `nan` as the bad feature.
    fn inputs<S: Scalar>(
        rng: &mut KitRng,
        from: &impl Fn(f64) -> S,
        d: usize,
        features: usize,
        n: usize,
        scale: f64,
    ) -> (Vec<S>, Vec<S>, Vec<S>) {
        let theta = (0..d)
            .map(|_| from(scale * (rng.random::<f64>() - 0.5)))
            .collect();
        let rows: Vec<S> = (0..n * features)
            .map(|_| from(rng.random::<f64>() * 2.0 - 1.0))
            .collect();
        let mut bad = rows[..features].to_vec();
        bad[rng.random_range(0..features)] = from(f64::NAN);
        (theta, rows, bad)
    }

    /// The softmax policy's kernel: labels and actions now and then out of range, and θ scaled
    /// by `big` so that logits overflow in `S` while θ stays finite.
    fn softmax_kernel_matches_the_defaults<S: Real>(big: f64, from: impl Fn(f64) -> S) {
        let mut rng = KitRng::seed_from_u64(11);
        let mut outcomes = [0usize; 2];
        for &(actions, features) in &[(2, 5), (3, 4), (17, 2)] {
            let pi = Softmax::new(actions, features).unwrap();
            for trial in 0..40 {
                let scale = [0.1, 1.0, 30.0, big][trial % 4];
                let d = actions * features;
                let (theta, rows, bad) = inputs(&mut rng, &from, d, features, 4, scale);
                let pick = |rng: &mut KitRng| {
                    if rng.random::<f64>() < 0.1 {
                        actions
                    } else {
                        rng.random_range(0..actions)
                    }
                };
                let labels: Vec<usize> = (0..4).map(|_| pick(&mut rng)).collect();
                let acts: Vec<usize> = (0..4).map(|_| pick(&mut rng)).collect();
                let seed = rng.random();
                let ok = assert_kernel_as_defaults(&pi, &theta, &rows, &labels, &acts, &bad, seed);
                outcomes[usize::from(ok)] += 1;
                noted_sum_as_validated(&pi, &theta, &rows, &labels, &acts, from(0.75), seed);
            }
        }
        // Both outcomes occur: values, and errors (overflowing logits, labels out of range).
        assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
    }

    /// Sampling every row with notes draws as `sample_validated` does and notes `note_len`
    /// entries per row; the causal sum from those notes is the validated sum's, bit for bit
    /// (floats), with its errors, with an absorbing tail's losses `end` and the summed loss; so
    /// are the records from those notes.
    #[allow(clippy::too_many_arguments)] // a trajectory
    fn noted_sum_as_validated<S: Real>(
        pi: &Softmax,
        theta: &[S],
        rows: &[S],
        labels: &[usize],
        actions: &[usize],
        end: S,
        seed: u64,
    ) {
        let (mut ra, mut rb) = (KitRng::seed_from_u64(seed), KitRng::seed_from_u64(seed));
        let mut notes = vec![];
        let mut sampled = true;
        let n = Policy::<S>::feature_dim(pi);
        let k = EstimatorKernel::<S>::note_len(pi);
        for row in rows.chunks_exact(n) {
            let a = pi.sample_noting(theta, row, &mut ra, &mut notes);
            assert_eq!((&a, &ra), (&pi.sample_validated(theta, row, &mut rb), &rb));
            sampled &= a.is_ok();
        }
        if !sampled {
            return;
        }
        assert_eq!(notes.len(), k * rows.len() / n);
        let d = Policy::<S>::param_dim(pi);
        let run = |noted: bool| {
            let (mut g, mut loss, mut scratch) = (vec![S::zero(); d], S::zero(), vec![]);
            let r = pi.causal_sum_validated(
                theta,
                rows,
                noted.then_some(&notes[..]),
                labels,
                actions,
                Some(&end),
                &mut g,
                Some(&mut loss),
                &mut scratch,
            );
            (r, g, loss)
        };
        let ((r1, g1, l1), (r2, g2, l2)) = (run(true), run(false));
        assert_eq!(r1, r2);
        if r1.is_ok() {
            assert!(same_all(&g1, &g2) && same(&l1, &l2));
        }
        let record = |noted: bool| {
            let (mut losses, mut records) = (vec![], vec![]);
            let notes = noted.then_some(&notes[..]);
            let r = pi.record_validated(
                theta,
                rows,
                notes,
                labels,
                actions,
                &mut losses,
                &mut records,
            );
            (r, losses, records)
        };
        let ((r1, l1, c1), (r2, l2, c2)) = (record(true), record(false));
        assert_eq!(r1, r2);
        if r1.is_ok() {
            assert!(same_all(&l1, &l2) && same_all(&c1, &c2));
        }
    }

    /// The linear-Gaussian policies' kernels (P3 and P3 with the speed limit, both branches of
    /// the limit): labels now and then non-finite, and θ scaled by `big` so that the loss
    /// overflows in `S`.
    fn gaussian_kernels_match_the_defaults<S: Sqrt>(big: f64, from: impl Fn(f64) -> S) {
        let mut rng = KitRng::seed_from_u64(12);
        let mut outcomes = [0usize; 2];
        let features = 6;
        let sigma = from(0.1);
        let lg = LinearGaussian::new(2, features, sigma)
            .unwrap()
            .with_actions::<[S; 2]>()
            .unwrap();
        let slg = SpeedLimitedGaussian::new(lg.clone(), from(0.5)).unwrap();
        for trial in 0..80 {
            let scale = [0.1, 1.0, 30.0, big][trial % 4];
            let (theta, rows, bad) = inputs(&mut rng, &from, 2 * features, features, 4, scale);
            let coordinate = |rng: &mut KitRng| {
                if rng.random::<f64>() < 0.05 {
                    from(f64::INFINITY)
                } else {
                    from(rng.random::<f64>() - 0.5)
                }
            };
            let labels: Vec<Vec<S>> = (0..4)
                .map(|_| vec![coordinate(&mut rng), coordinate(&mut rng)])
                .collect();
            let acts: Vec<[S; 2]> = (0..4)
                .map(|_| [coordinate(&mut rng), coordinate(&mut rng)])
                .collect();
            let seed = rng.random();
            let labels: Vec<&[S]> = labels.iter().map(Vec::as_slice).collect();
            let ok = if trial % 2 == 0 {
                assert_kernel_as_defaults(&lg, &theta, &rows, &labels, &acts, &bad, seed)
            } else {
                assert_kernel_as_defaults(&slg, &theta, &rows, &labels, &acts, &bad, seed)
            };
            outcomes[usize::from(ok)] += 1;
        }
        assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
    }

    macro_rules! kernel_tests {
        ($($softmax:ident, $gaussian:ident: $s:ty = $big:expr, $from:expr;)*) => {$(
            #[test]
            fn $softmax() {
                softmax_kernel_matches_the_defaults::<$s>($big, $from);
            }

            #[test]
            fn $gaussian() {
                gaussian_kernels_match_the_defaults::<$s>($big, $from);
            }
        )*};
    }

    kernel_tests! {
        softmax_kernel_f64, gaussian_kernels_f64: f64 = 1e306, |x| x;
        softmax_kernel_f32, gaussian_kernels_f32: f32 = 3e38, |x| x as f32;
        softmax_kernel_dual, gaussian_kernels_dual: Dual<f64> = 1e306, |x| Dual::variable(x, 0, 1);
    }

    /// Intervals: the softmax policy with the `mpfr` feature (its `exp`). A non-finite interval
    /// feature is the whole line (no interval is NaN).
    #[cfg(feature = "mpfr")]
    #[test]
    fn softmax_kernel_interval() {
        use crate::scalar::Interval;
        softmax_kernel_matches_the_defaults::<Interval>(1e306, |x| {
            Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE)
        });
    }

    #[test]
    fn gaussian_kernels_interval() {
        use crate::scalar::Interval;
        gaussian_kernels_match_the_defaults::<Interval>(1e306, |x| {
            Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE)
        });
    }
}
