//! [`PerDecisionTerms`]: what a problem offers the baselines beyond [`IlProblem`] — eq. 3.15's
//! causal estimator decision by decision, and the faster passes built on it.
//!
//! A problem opts in by implementing [`PerDecisionTerms::decision_terms`]; every other method has
//! a default built on it, which a problem overrides with a faster pass of the same mathematics
//! (the real tasks' [`crate::task::TaskProblem`] records the decisions with its policy's
//! [`crate::oracle::EstimatorKernel`], whose sum with the baseline's shifted losses makes the
//! plain pass's operations in its order). The algorithms see only [`IlProblem`]; [`crate::baseline::Baselined`] needs this
//! trait of the problem it wraps.

use crate::oracle::{DecisionTerms, Given, RecordedPass, ScoreProducts};
use crate::problem::{Cost, IlProblem, OracleError, Weighting};
use crate::scalar::Scalar;
use nalgebra::DVector;

/// The per-decision access to eq. 3.15's causal estimator that [`crate::baseline::Baselined`]
/// assembles its estimates from (module docs).
pub trait PerDecisionTerms<S: Scalar>: IlProblem<S> {
    /// The causal estimator of eq. 3.15 at θ on one trajectory, decision by decision, into `out`
    /// ([`DecisionTerms`]: the direct part `Σ_t w_{1:t−1} ∇l_t`, every scored decision's score ψ_i
    /// and loss-to-go, the weights), from which [`crate::baseline::Baselined`] assembles the
    /// baselined estimate `g_b = g − Σ_i b_i ψ_i`. With `weights = Some((θ_new, weighting))` the
    /// terms are those of the importance-weighted old-point estimate of
    /// [`IlProblem::weighted_estimate`] (θ = θ_old, τ sampled at θ_new); the baseline term of
    /// decision i then carries the prefix weight `w_{1:i}` (per-decision) or the trajectory's
    /// weight (whole trajectory), which keeps it mean-zero (module docs of [`crate::baseline`]).
    /// The caller calls [`DecisionTerms::finish`] (idempotent) before reading `out`. Counts the
    /// same gradient evaluations as [`IlProblem::estimate`].
    ///
    /// # Errors
    /// As [`IlProblem::weighted_estimate`].
    fn decision_terms(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        weights: Option<(&DVector<S>, Weighting)>,
        out: &mut DecisionTerms<S>,
        cost: &mut Cost,
    ) -> Result<(), OracleError>;

    /// The decisions of one trajectory at θ recorded for the causal estimator of eq. 3.15
    /// ([`RecordedPass`]): every step's loss `l_t` (the absorbing tail as one more), the number of
    /// scored decisions, and what [`PerDecisionTerms::estimate_recorded`] needs to sum the estimate
    /// with per-step losses chosen afterwards — how a baseline known only after every trajectory's
    /// pass enters (leave-one-out in [`crate::baseline::Baselined`]). Counts the same gradient
    /// evaluations as [`IlProblem::estimate`].
    ///
    /// The default fills `out` from [`PerDecisionTerms::decision_terms`] (the plain estimate and
    /// ψ_i as rows of d entries); a problem may override it with a faster pass, together with
    /// [`PerDecisionTerms::estimate_recorded`].
    ///
    /// # Errors
    /// As [`PerDecisionTerms::decision_terms`].
    fn record_decisions(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        out: &mut RecordedPass<S>,
        cost: &mut Cost,
    ) -> Result<(), OracleError> {
        record_by_terms(self, theta, trajectory, out, cost)
    }

    /// `g += Σ_t [∇l_t + l'_t Σ_{i<min(t, s)} ψ_i]` on `trajectory` from what
    /// [`PerDecisionTerms::record_decisions`] recorded there (s its scored decisions), with
    /// per-step losses `l'` in place of the recorded ones: one per entry of
    /// [`RecordedPass::losses`] (`losses` must have that length), or `None` for the recorded
    /// losses themselves (read in place, not copied). With the recorded losses it is the causal
    /// estimate of eq. 3.15; with `l'_t = l_t + b_t − b_{t−1}` (b_t = 0 from the first
    /// unscored step on) it is the baselined `g − Σ_i b_i ψ_i` ([`crate::baseline`], summation by
    /// parts). The default sums the rows of the default form.
    fn estimate_recorded(
        &self,
        trajectory: &Self::Trajectory,
        recorded: &mut RecordedPass<S>,
        losses: Option<&[S]>,
        g: &mut [S],
    ) {
        let _ = trajectory;
        recorded.sum_rows(losses, g);
    }

    /// [`ScoreProducts`] for the scored decisions of `trajectory`, from what
    /// [`PerDecisionTerms::record_decisions`] recorded there: the statistics of the
    /// variance-minimising baseline ([`crate::baseline::RunningOptimum`]) and its correction
    /// `g −= Σ_i b_i ψ_i`, with b_i given or the linear state-dependent baseline's on the rows of
    /// [`PerDecisionTerms::state_features`] ([`crate::oracle::Baselines`]). The default reads
    /// the rows of the default form.
    fn recorded_score_products(
        &self,
        trajectory: &Self::Trajectory,
        recorded: &RecordedPass<S>,
        out: ScoreProducts<'_, S>,
    ) {
        let _ = trajectory;
        recorded.score_row_products(out);
    }

    /// The state features φ_b(s_i) of the first n = `decisions` scored decisions of `trajectory`,
    /// for the state-dependent baseline `b_i = w·φ_b(s_i)`
    /// ([`crate::baseline::Baseline::StateDependent`]), by rows: `(rows, stride)` with decision
    /// i's features starting at `rows[i·stride]` (n rows; stride: the features available). A
    /// problem returns the rows it stores (borrowed from the trajectory) or builds them in
    /// `scratch` (cleared first). The features must be a function of s_i alone (nothing from a_i
    /// on), which keeps the baseline unbiased.
    ///
    /// The default offers none.
    ///
    /// # Errors
    /// [`OracleError::Baseline`] when the problem offers no state features;
    /// [`OracleError::Trajectory`] when the trajectory holds fewer than n states.
    fn state_features<'a>(
        &self,
        trajectory: &'a Self::Trajectory,
        decisions: usize,
        scratch: &'a mut Vec<S>,
    ) -> Result<(&'a [S], usize), OracleError> {
        let _ = (trajectory, decisions, scratch);
        Err(OracleError::Baseline(
            "this problem offers no state features for a state-dependent baseline".into(),
        ))
    }
}

/// The number of leading state features to use out of `available`: all for `None`.
///
/// # Errors
/// [`OracleError::Baseline`] when more are asked for than there are, or none.
pub(crate) fn leading_features(
    available: usize,
    leading: Option<usize>,
) -> Result<usize, OracleError> {
    match leading {
        None => Ok(available),
        Some(0) => Err(OracleError::Baseline(
            "a state-dependent baseline needs at least 1 state feature, got features = 0".into(),
        )),
        Some(k) if k > available => Err(OracleError::Baseline(format!(
            "a state-dependent baseline asks for {k} state features; the problem has {available}"
        ))),
        Some(k) => Ok(k),
    }
}

/// The error of a time-indexed baseline list shorter than a trajectory's scored decisions.
pub(crate) fn too_few_baselines(decisions: usize) -> OracleError {
    OracleError::Baseline(format!(
        "too few time-indexed baselines: a trajectory has {decisions} scored decisions"
    ))
}

/// [`PerDecisionTerms::record_decisions`]'s default: `out` filled from
/// [`PerDecisionTerms::decision_terms`] (the plain estimate and ψ_i as rows of d entries), also
/// the checked route of a problem whose own records need validated inputs.
///
/// # Errors
/// As [`PerDecisionTerms::decision_terms`].
pub(crate) fn record_by_terms<S: Scalar, P: PerDecisionTerms<S> + ?Sized>(
    problem: &P,
    theta: &DVector<S>,
    trajectory: &P::Trajectory,
    out: &mut RecordedPass<S>,
    cost: &mut Cost,
) -> Result<(), OracleError> {
    problem.decision_terms(theta, trajectory, None, out.terms_mut(), cost)?;
    out.fill_from_terms();
    Ok(())
}

/// The baselined causal estimator `g_b = g − Σ_i b_i ψ_i` ([`crate::baseline`]) at θ on one
/// trajectory of `problem`, for baselines fixed before the pass: unbiased for ∇F(θ) when
/// τ ∼ p(·; θ), since b_i does not depend on τ. By summation by parts
/// (`Σ_i b_i ψ_i = Σ_t (b_{t−1} − b_t) Σ_{i<t} ψ_i`): the decisions recorded
/// ([`PerDecisionTerms::record_decisions`]), then summed once
/// ([`PerDecisionTerms::estimate_recorded`]) with the per-step losses
/// `l'_t = l_t + (b_t − b_{t−1})` (b_{−1} = 0, b_t = 0 from the first unscored step on) — the route
/// of every unweighted baseline fixed before the pass in [`crate::baseline::Baselined`], for
/// every problem, in the plain pass's order. Its rounding grows with
/// `Σ_t |b_t − b_{t−1}| ‖Σ_{i<t} ψ_i‖`: small for baselines that move slowly from step to step; a
/// list that jumps at every step is summed more accurately from the terms
/// ([`crate::baseline::Baselined::estimate_by_terms`]). Counts the same gradient evaluations as
/// [`IlProblem::estimate`].
///
/// # Errors
/// As [`PerDecisionTerms::record_decisions`]; [`OracleError::Baseline`] when a time-indexed list
/// is shorter than the scored decisions; [`OracleError::NonFinite`] for a non-finite estimate.
pub fn baselined_estimate<S: Scalar, P: PerDecisionTerms<S> + ?Sized>(
    problem: &P,
    theta: &DVector<S>,
    trajectory: &P::Trajectory,
    baseline: Given<'_, S>,
    cost: &mut Cost,
) -> Result<DVector<S>, OracleError> {
    let mut recorded = RecordedPass::new();
    problem.record_decisions(theta, trajectory, &mut recorded, cost)?;
    let mut shifted = Vec::new();
    shifted_by_given(&recorded, baseline, &mut shifted)?;
    let mut g = vec![S::zero(); problem.dim()];
    problem.estimate_recorded(trajectory, &mut recorded, Some(&shifted), &mut g);
    if !g.iter().all(Scalar::is_finite) {
        return Err(OracleError::NonFinite("the baselined gradient estimate"));
    }
    Ok(DVector::from_vec(g))
}

/// The recorded per-step losses with a baseline known before the pass folded in, into
/// `shifted`: `l'_t = l_t + (b_t − b_{t−1})` (b_{−1} = 0, b_t = 0 from the first unscored step
/// on, so the absorbing tail's entry, if any, carries `−b_{n−1}`), with which
/// [`PerDecisionTerms::estimate_recorded`] sums `g − Σ_i b_i ψ_i`.
///
/// # Errors
/// [`OracleError::Baseline`] when a time-indexed list is shorter than the scored decisions.
pub(crate) fn shifted_by_given<S: Scalar>(
    recorded: &RecordedPass<S>,
    baseline: Given<'_, S>,
    shifted: &mut Vec<S>,
) -> Result<(), OracleError> {
    let scored = recorded.decisions();
    if !baseline.covers(scored) {
        return Err(too_few_baselines(scored));
    }
    let mut previous = S::zero();
    shifted.clear();
    shifted.extend(recorded.losses().iter().enumerate().map(|(t, l)| {
        let bt = (t < scored)
            .then(|| baseline.at(t).cloned())
            .flatten()
            .unwrap_or_else(S::zero);
        let shift = bt.clone() - &previous;
        previous = bt;
        l.clone() + shift
    }));
    Ok(())
}
