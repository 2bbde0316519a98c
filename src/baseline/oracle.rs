//! [`Baselined`]: m trajectories per oracle call, each estimate with a baseline.

use super::{Baseline, PerDecisionTerms, RunningOptimum, RunningRegression, leading_features};
use crate::batched::Batched;
use crate::oracle::{Baselines, DecisionTerms, Given, LinearBaseline, RecordedPass, ScoreProducts};
use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use crate::scalar::Scalar;
use nalgebra::DVector;

/// A baseline resolved in the scalar `S`: the kinds known before a pass carry their values, the
/// learned kinds their own state type.
#[derive(Debug, Clone)]
enum Kind<S> {
    None,
    Constant(S),
    TimeIndexed(Vec<S>),
    Estimated(Estimated<S>),
    LeaveOneOut,
    StateDependent(StateDependent<S>),
}

/// The estimated variance-minimising baseline's state: its running statistics
/// ([`RunningOptimum`]), per decision index or one constant.
#[derive(Debug, Clone)]
struct Estimated<S> {
    time_indexed: bool,
    running: RunningOptimum<S>,
}

/// The state-dependent baseline's state: which state features it reads, whether it adds the
/// decision index, and its running regression ([`RunningRegression`]).
#[derive(Debug, Clone)]
struct StateDependent<S> {
    leading: Option<usize>,
    time: bool,
    running: RunningRegression<S>,
}

/// Reused storage of one oracle call: per trajectory its [`DecisionTerms`] or its
/// [`RecordedPass`], the leave-one-out step totals or the estimated baselines, per-step losses,
/// one trajectory's plain estimate, the estimate; per trajectory its state features (k per
/// decision) and the number k, and the rows of a problem that builds them.
#[derive(Debug, Clone)]
struct Buffers<S> {
    terms: Vec<DecisionTerms<S>>,
    features: Vec<(Vec<S>, usize)>,
    rows: Vec<S>,
    products: (Vec<S>, Vec<S>),
    records: Vec<RecordedPass<S>>,
    totals: Vec<S>,
    losses: Vec<S>,
    plain: Vec<S>,
    g: Vec<S>,
}

/// The problem `inner` with m trajectories per oracle call (as [`Batched`]) and the causal
/// estimator of eq. 3.15 replaced by its baselined form `g_b = g − Σ_i b_i ψ_i` (module docs of
/// [`crate::baseline`]): `g_m(θ) = (1/m) Σ_j g_b(θ, τ_j)` with trajectory j's own baselines
/// `b^{(j)}`, unbiased for ∇F(θ) by the argument there. The importance-weighted old-point estimate
/// is the baselined one with the weight on it (trajectory weight) or the prefix weight `w_{1:i}` on
/// `b_i ψ_i` (per-decision).
///
/// With [`Baseline::None`] every call is [`Batched`]'s, bit for bit. With a baseline, the
/// [`EstimatorForm::Full`] form is refused (baselines apply to the causal form), and `inner` must
/// implement [`PerDecisionTerms::decision_terms`].
///
/// Leave-one-out: trajectory j's `b_i^{(j)} = (1/(m−1)) Σ_{k≠j} L_i^{(k)}` with `L_i^{(k)}` the
/// loss-to-go of trajectory k at its decision i (0 where k took fewer decisions; in a weighted
/// estimate the weighted loss-to-go). It is a function of the other trajectories only, which are
/// independent of τ_j. The unweighted estimate records each trajectory's decisions
/// ([`PerDecisionTerms::record_decisions`]), then sums each trajectory's estimate once with its
/// per-step losses shifted by the baseline ([`PerDecisionTerms::estimate_recorded`]). Baselines
/// known before the pass (a constant, per-decision constants) take the same route with their own
/// shifts ([`super::baselined_estimate`]). Every weighted estimate, of every kind, is assembled
/// from the trajectories' weighted [`DecisionTerms`], as [`Baselined::estimate_by_terms`]
/// assembles the unweighted ones.
///
/// Estimated optimum: the statistics of the trajectories of a call enter the baselines when the
/// next roll-out starts ([`RunningOptimum`]), so every trajectory is estimated with baselines from
/// earlier roll-outs only. The state-dependent baseline `b_i = w·φ_b(s_i)` works the same way,
/// its weights from [`RunningRegression`] and φ_b from [`PerDecisionTerms::state_features`]. This
/// assumes, as every algorithm of the kit does, that a trajectory is estimated before the next one
/// is rolled out. That state is the oracle's own, one type per learned kind, changed only through
/// `&mut self` ([`IlProblem`]'s oracle calls): a clone continues from the same statistics, and a
/// new oracle starts from none.
#[derive(Debug, Clone)]
pub struct Baselined<P, S> {
    batch: Batched<P>,
    kind: Kind<S>,
    buffers: Buffers<S>,
}

/// The error of a baseline that cannot be used.
fn invalid(msg: impl Into<String>) -> OracleError {
    OracleError::Baseline(msg.into())
}

/// A decay factor in `S`, checked to lie in [0, 1] (`None`: no decay).
fn decay_of<S: Scalar>(
    decay: Option<&crate::scalar::ConfigNumber>,
) -> Result<Option<S>, OracleError> {
    let Some(x) = decay else {
        return Ok(None);
    };
    let q = x
        .exact("baseline decay")
        .map_err(|e| invalid(e.to_string()))?;
    let zero = crate::scalar::BigRational::from_integer(0.into());
    let one = crate::scalar::BigRational::from_integer(1.into());
    if q < zero || q > one {
        return Err(invalid(format!("decay {q} is not in [0, 1]")));
    }
    Ok(Some(S::from_rational(&q)))
}

impl<P, S: Scalar> Baselined<P, S> {
    /// `m` trajectories per oracle call with `baseline`.
    ///
    /// # Errors
    /// [`OracleError::Behaviour`] if `m` is 0; [`OracleError::Baseline`] for a non-finite value,
    /// a `decay` outside [0, 1], or leave-one-out with m < 2 (one trajectory has no other to
    /// take its baseline from).
    pub fn new(inner: P, m: usize, baseline: &Baseline) -> Result<Self, OracleError> {
        let batch = Batched::new(inner, m)?;
        let num = |x: &crate::scalar::ConfigNumber, what: &'static str| {
            x.to::<S>(what).map_err(|e| invalid(e.to_string()))
        };
        let kind = match baseline {
            Baseline::None => Kind::None,
            Baseline::Constant { value } => Kind::Constant(num(value, "baseline value")?),
            Baseline::TimeIndexed { values } => Kind::TimeIndexed(
                values
                    .iter()
                    .map(|v| num(v, "baseline values"))
                    .collect::<Result<_, _>>()?,
            ),
            Baseline::Estimated {
                time_indexed,
                decay,
            } => Kind::Estimated(Estimated {
                time_indexed: *time_indexed,
                running: RunningOptimum::new(decay_of(decay.as_ref())?),
            }),
            Baseline::StateDependent {
                features,
                time,
                decay,
                ridge,
                fit_every,
            } => {
                let every = fit_every.unwrap_or(super::DEFAULT_FIT_EVERY);
                if every == 0 {
                    return Err(invalid(
                        "a state-dependent baseline takes the statistics of every e-th trajectory, e ≥ 1; got fit_every = 0",
                    ));
                }
                if *features == Some(0) {
                    return Err(invalid(
                        "a state-dependent baseline needs at least 1 state feature, got features = 0",
                    ));
                }
                let ridge = match ridge {
                    None => S::zero(),
                    Some(x) => {
                        let q = x
                            .exact("baseline ridge")
                            .map_err(|e| invalid(e.to_string()))?;
                        if q < crate::scalar::BigRational::from_integer(0.into()) {
                            return Err(invalid(format!("ridge {q} is negative")));
                        }
                        S::from_rational(&q)
                    }
                };
                Kind::StateDependent(StateDependent {
                    leading: *features,
                    time: *time,
                    running: RunningRegression::new(decay_of(decay.as_ref())?, ridge)
                        .taking_every(every),
                })
            }
            Baseline::LeaveOneOut => {
                if m < 2 {
                    return Err(invalid(format!(
                        "leave-one-out needs at least 2 trajectories per gradient, got {m}"
                    )));
                }
                Kind::LeaveOneOut
            }
        };
        Ok(Self {
            batch,
            kind,
            buffers: Buffers {
                terms: Vec::new(),
                features: Vec::new(),
                rows: Vec::new(),
                products: (Vec::new(), Vec::new()),
                records: Vec::new(),
                totals: Vec::new(),
                losses: Vec::new(),
                plain: Vec::new(),
                g: Vec::new(),
            },
        })
    }

    /// The problem each trajectory comes from.
    pub fn inner(&self) -> &P {
        self.batch.inner()
    }

    /// Trajectories per oracle call.
    pub fn size(&self) -> usize {
        self.batch.size()
    }

    /// The committed weights of a [`Baseline::StateDependent`] baseline (a copy; empty before
    /// any statistics were committed).
    pub fn state_weights(&self) -> Option<Vec<S>> {
        match &self.kind {
            Kind::StateDependent(state) => Some(state.running.weights().to_vec()),
            _ => None,
        }
    }

    /// The committed running estimates of an [`Baseline::Estimated`] baseline (a copy).
    pub fn running(&self) -> Option<RunningOptimum<S>> {
        match &self.kind {
            Kind::Estimated(state) => Some(state.running.clone()),
            _ => None,
        }
    }
}

/// The state features of the first `n` scored decisions of `t` by columns into `columns` (k of
/// n entries, k returned): the first k (all for `None`) of the problem's
/// ([`PerDecisionTerms::state_features`], its rows in `rows` if it builds them), then with `time`
/// the decision index i (as a sum of ones, exact for every index a trajectory can have) and a
/// column of ones.
fn state_columns<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    t: &P::Trajectory,
    n: usize,
    leading: Option<usize>,
    time: bool,
    columns: &mut Vec<S>,
    rows: &mut Vec<S>,
) -> Result<usize, OracleError> {
    let (data, stride) = inner.state_features(t, n, rows)?;
    let k = leading_features(stride, leading)?;
    columns.clear();
    for j in 0..k {
        columns.extend(
            data.chunks_exact(stride.max(1))
                .take(n)
                .map(|phi| phi[j].clone()),
        );
    }
    if !time {
        return Ok(k);
    }
    // By `extend` of a sized iterator: reserved once, so the running index stays in a register.
    let mut index = S::zero();
    columns.extend((0..n).map(|_| {
        let i = index.clone();
        index += S::one();
        i
    }));
    columns.extend(std::iter::repeat_n(S::one(), n));
    Ok(k + 2)
}

/// The number of trajectories of `batch`.
///
/// # Errors
/// [`OracleError::Trajectory`] for an empty minibatch.
fn batch_size<T>(batch: &[T]) -> Result<usize, OracleError> {
    if batch.is_empty() {
        return Err(OracleError::Trajectory("an empty minibatch".into()));
    }
    Ok(batch.len())
}

/// The error of a leave-one-out minibatch with fewer than two trajectories.
fn too_few_for_leave_one_out(m: usize) -> OracleError {
    invalid(format!(
        "leave-one-out needs at least 2 trajectories per gradient, got {m}"
    ))
}

/// `S_t = Σ_k l_t^{(k)}` into `totals`, step by step over the longest list of per-step losses
/// (`l_t^{(k)} = 0` beyond trajectory k's steps).
fn step_totals<'a, S: Scalar + 'a>(
    losses: impl Iterator<Item = &'a [S]> + Clone,
    totals: &mut Vec<S>,
) {
    let n = losses.clone().map(<[S]>::len).max().unwrap_or(0);
    totals.clear();
    totals.resize(n, S::zero());
    for l in losses {
        for (x, y) in totals.iter_mut().zip(l) {
            *x += y;
        }
    }
}

/// Trajectory j's per-step losses with its leave-one-out baseline folded in, into `shifted`:
/// `l'_t = l_t − (S_t − l_t)/(m − 1)` for each of its steps `own` (t < len), and on its last
/// step also `− Σ_{t≥len} S_t/(m − 1)`, the other trajectories' steps after its end (its last
/// step's score sum is the sum over all its scored decisions). Since
/// `(m − 1) b_i^{(j)} = Σ_{t>i} (S_t − l_t^{(j)})`, the estimate with these losses is
/// `g_j − Σ_i b_i^{(j)} ψ_i^{(j)}` ([`RecordedPass`]).
fn leave_one_out_losses<S: Scalar>(totals: &[S], own: &[S], others: &S, shifted: &mut Vec<S>) {
    shifted.clear();
    shifted.extend(
        own.iter()
            .zip(totals)
            .map(|(l, s)| l.clone() - (s.clone() - l) / others),
    );
    if let Some(last) = shifted.last_mut() {
        let after = totals[own.len()..].iter().fold(S::zero(), |a, s| a + s);
        *last -= after / others;
    }
}

/// The mean over `batch` of the baselined estimates with baselines known before the pass:
/// every trajectory's decisions recorded ([`PerDecisionTerms::record_decisions`]), then each
/// trajectory's estimate summed once with its losses shifted by the baseline
/// ([`super::shifted_by_given`], [`PerDecisionTerms::estimate_recorded`]), as leave-one-out's
/// are. No allocation per step.
///
/// # Errors
/// For an empty batch, the first trajectory's error, too few time-indexed baselines, and a
/// non-finite mean.
fn given_estimate<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    buffers: &mut Buffers<S>,
    theta: &DVector<S>,
    batch: &[P::Trajectory],
    given: Given<'_, S>,
    cost: &mut Cost,
) -> Result<DVector<S>, OracleError> {
    let m = batch_size(batch)?;
    let Buffers {
        records, losses, g, ..
    } = buffers;
    let records = record_batch(inner, theta, batch, records, cost)?;
    g.clear();
    g.resize(inner.dim(), S::zero());
    for (t, r) in batch.iter().zip(records.iter_mut()) {
        super::shifted_by_given(r, given, losses)?;
        inner.estimate_recorded(t, r, Some(losses), g);
    }
    checked_mean(g, &S::from_i64(m as i64))
}

/// Trajectory `t`'s plain estimate from its records ([`PerDecisionTerms::estimate_recorded`]
/// with its own losses) into `plain` (the problem's dimension), and added to `g`.
fn add_plain<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    t: &P::Trajectory,
    r: &mut RecordedPass<S>,
    plain: &mut Vec<S>,
    g: &mut [S],
) {
    plain.clear();
    plain.resize(inner.dim(), S::zero());
    inner.estimate_recorded(t, r, None, plain);
    for (gj, x) in g.iter_mut().zip(plain.iter()) {
        *gj += x;
    }
}

/// `g / m`, checked finite.
///
/// # Errors
/// [`OracleError::NonFinite`] for a non-finite entry.
fn checked_mean<S: Scalar>(g: &[S], m: &S) -> Result<DVector<S>, OracleError> {
    let mean = DVector::from_iterator(g.len(), g.iter().map(|x| x.clone() / m));
    if !mean.iter().all(Scalar::is_finite) {
        return Err(OracleError::NonFinite("the baselined gradient estimate"));
    }
    Ok(mean)
}

/// Every trajectory of `batch` recorded ([`PerDecisionTerms::record_decisions`]) into the first m
/// entries of `records`, grown to m if need be.
fn record_batch<'r, S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    theta: &DVector<S>,
    batch: &[P::Trajectory],
    records: &'r mut Vec<RecordedPass<S>>,
    cost: &mut Cost,
) -> Result<&'r mut [RecordedPass<S>], OracleError> {
    let m = batch.len();
    if records.len() < m {
        records.resize_with(m, RecordedPass::new);
    }
    let records = &mut records[..m];
    for (t, r) in batch.iter().zip(records.iter_mut()) {
        inner.record_decisions(theta, t, r, cost)?;
    }
    Ok(records)
}

impl<S: Scalar, P: PerDecisionTerms<S>> Baselined<P, S> {
    /// The mean causal estimate over `batch` assembled from every trajectory's [`DecisionTerms`]
    /// ([`PerDecisionTerms::decision_terms`]) for every kind of baseline: the reference route, with
    /// the results of [`IlProblem::estimate`] (the same mathematics; in floating point up to the
    /// order of the sums where `estimate` takes a fused pass). An estimated baseline observes the
    /// trajectories as `estimate` does.
    ///
    /// # Errors
    /// As [`IlProblem::estimate`].
    pub fn estimate_by_terms(
        &mut self,
        theta: &DVector<S>,
        batch: &[P::Trajectory],
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let inner = self.batch.inner();
        baselined(
            inner,
            &mut self.kind,
            &mut self.buffers,
            batch,
            true,
            |t, out| inner.decision_terms(theta, t, None, out, cost),
        )
    }
}

/// The mean leave-one-out estimate over `batch`, `(1/m) Σ_j [g_j − Σ_i b_i^{(j)} ψ_i^{(j)}]`
/// with `b_i^{(j)} = (1/(m − 1)) Σ_{k≠j} L_i^{(k)}`: every trajectory's decisions recorded
/// ([`PerDecisionTerms::record_decisions`]), the step totals `S_t = Σ_k l_t^{(k)}`, then each
/// trajectory's estimate summed once with the baseline folded into its per-step losses
/// (`leave_one_out_losses`, [`PerDecisionTerms::estimate_recorded`]). No allocation per step.
fn leave_one_out<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    buffers: &mut Buffers<S>,
    theta: &DVector<S>,
    batch: &[P::Trajectory],
    cost: &mut Cost,
) -> Result<DVector<S>, OracleError> {
    let m = batch_size(batch)?;
    if m < 2 {
        return Err(too_few_for_leave_one_out(m));
    }
    let Buffers {
        records,
        totals,
        losses,
        g,
        ..
    } = buffers;
    let records = record_batch(inner, theta, batch, records, cost)?;
    step_totals(records.iter().map(RecordedPass::losses), totals);
    let (others, m) = (S::from_i64(m as i64 - 1), S::from_i64(m as i64));
    g.clear();
    g.resize(inner.dim(), S::zero());
    for (t, r) in batch.iter().zip(records.iter_mut()) {
        leave_one_out_losses(totals, r.losses(), &others, losses);
        inner.estimate_recorded(t, r, Some(losses), g);
    }
    checked_mean(g, &m)
}

/// The mean estimate over `batch` with the committed variance-minimising baselines of
/// [`RunningOptimum`], which then observes the batch: every trajectory's decisions recorded
/// ([`PerDecisionTerms::record_decisions`]), its plain estimate g summed once
/// ([`PerDecisionTerms::estimate_recorded`] with its own losses, read in place), then one more read of its
/// scores for both the statistics `g·ψ_i`, `‖ψ_i‖²` and the correction `g − Σ_i b_i ψ_i`
/// ([`PerDecisionTerms::recorded_score_products`]). No allocation per step.
///
/// The committed b_i are known before the pass, yet they are not folded into shifted losses as
/// a given baseline's are ([`super::shifted_by_given`]): the statistics need g in any case, and
/// per-decision estimates jump from one decision to the next, so summation by parts would
/// multiply each jump `b_t − b_{t−1}` by the prefix sum `Σ_{i<t} ψ_i`, where the correction's
/// rounding grows with `|b_i| ‖ψ_i‖` alone (docs/architecture.md). The same holds for the
/// state-dependent baseline's `b_i = w·φ_i`.
fn estimated<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    state: &mut Estimated<S>,
    buffers: &mut Buffers<S>,
    theta: &DVector<S>,
    batch: &[P::Trajectory],
    cost: &mut Cost,
) -> Result<DVector<S>, OracleError> {
    let Estimated {
        time_indexed,
        running,
    } = state;
    let m = batch_size(batch)?;
    let Buffers {
        records,
        totals: baseline,
        plain,
        g,
        ..
    } = buffers;
    let records = record_batch(inner, theta, batch, records, cost)?;
    let d = inner.dim();
    g.clear();
    g.resize(d, S::zero());
    // The committed b_i of every decision the batch scored, before the batch's statistics.
    let n = records
        .iter()
        .map(RecordedPass::decisions)
        .max()
        .unwrap_or(0);
    baseline.clear();
    if *time_indexed {
        running.time_indexed_into(n, baseline);
    } else {
        baseline.resize(n, running.constant().unwrap_or_else(S::zero));
    }
    running.clear_pending();
    for (t, r) in batch.iter().zip(records.iter_mut()) {
        add_plain(inner, t, r, plain, g);
        let n = r.decisions();
        let (cross, moment) = running.pending_mut(n);
        let out = ScoreProducts {
            v: plain,
            baseline: Baselines::Given(&baseline[..n]),
            cross,
            moment,
            g,
        };
        inner.recorded_score_products(t, r, out);
    }
    checked_mean(g, &S::from_i64(m as i64))
}

/// The mean estimate over `batch` with the committed state-dependent baseline of
/// [`RunningRegression`], which then observes the batch, on the estimated kind's route:
/// every trajectory's decisions recorded ([`PerDecisionTerms::record_decisions`]), its
/// baselines `b_i = w·φ_i` from its state features, its plain estimate g summed once
/// ([`PerDecisionTerms::estimate_recorded`]), then one more read of its scores for the
/// products `g·ψ_i`, `‖ψ_i‖²` and the correction `g − Σ_i b_i ψ_i`
/// ([`PerDecisionTerms::recorded_score_products`]), from which the statistics are summed
/// ([`RunningRegression::observe_products`]). A trajectory whose statistics are not taken
/// ([`RunningRegression::takes_next`]) needs the correction alone: with stored feature rows,
/// one products pass given the baseline's weights and the rows
/// ([`crate::oracle::Baselines::Linear`]; the logistic policy forms each `b_i` as it reads ψ_i,
/// the others form the b_i first), else its baselines from the columns, then the products pass
/// without statistics. Every route gives the same estimate, bit for bit. No allocation per step
/// (a policy that forms the b_i before the products pass allocates them once per trajectory).
fn state_dependent<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    state: &mut StateDependent<S>,
    buffers: &mut Buffers<S>,
    theta: &DVector<S>,
    batch: &[P::Trajectory],
    cost: &mut Cost,
) -> Result<DVector<S>, OracleError> {
    let StateDependent {
        leading,
        time,
        running,
    } = state;
    let m = batch_size(batch)?;
    let Buffers {
        records,
        features,
        rows: row_scratch,
        products: (cross, moment),
        totals: baseline,
        plain,
        g,
        ..
    } = buffers;
    let records = record_batch(inner, theta, batch, records, cost)?;
    if features.is_empty() {
        features.push((Vec::new(), 0));
    }
    let (phi, _) = &mut features[0];
    let d = inner.dim();
    g.clear();
    g.resize(d, S::zero());
    running.clear_pending();
    for (t, r) in batch.iter().zip(records.iter_mut()) {
        let n = r.decisions();
        let take = running.takes_next();
        add_plain(inner, t, r, plain, g);
        // A trajectory whose statistics are not taken, when the problem stores its feature
        // rows: its correction in one products pass with the baseline's weights and the rows
        // (a policy may form each b_i in the pass that reads ψ_i). The statistics need the
        // features by columns.
        let mut from_rows = false;
        if !take
            && let Ok(rows) = inner.state_features(t, n, row_scratch)
            && let Ok(k) = leading_features(rows.1, *leading)
        {
            if let Some(b) = LinearBaseline::new(running.weights(), k, *time)
                && k <= rows.1
                && rows.0.len() >= n * rows.1
            {
                let out = ScoreProducts {
                    v: plain,
                    baseline: Baselines::Linear {
                        baseline: b,
                        rows: rows.0,
                        stride: rows.1,
                        decisions: n,
                    },
                    cross: &mut [],
                    moment: &mut [],
                    g,
                };
                inner.recorded_score_products(t, r, out);
                continue;
            }
            from_rows = running.baselines_from_rows(rows, k, *time, n, baseline);
        }
        let k = if from_rows {
            0
        } else {
            let k = state_columns(inner, t, n, *leading, *time, phi, row_scratch)?;
            running.baselines_into(phi, n, baseline);
            k
        };
        // Without statistics, the products pass makes the correction alone.
        for v in [&mut *cross, &mut *moment] {
            v.clear();
            if take {
                v.resize(n, S::zero());
            }
        }
        let out = ScoreProducts {
            v: plain,
            baseline: Baselines::Given(baseline),
            cross,
            moment,
            g,
        };
        inner.recorded_score_products(t, r, out);
        if take {
            running.observe_products(phi, k, cross, moment);
        }
    }
    checked_mean(g, &S::from_i64(m as i64))
}

/// The mean baselined estimate over `batch` for the baseline `kind`, each trajectory's terms
/// from `fill`; with `observe`, a learned baseline then takes in the batch's statistics.
fn baselined<S: Scalar, P: PerDecisionTerms<S>>(
    inner: &P,
    kind: &mut Kind<S>,
    buffers: &mut Buffers<S>,
    batch: &[P::Trajectory],
    observe: bool,
    mut fill: impl FnMut(&P::Trajectory, &mut DecisionTerms<S>) -> Result<(), OracleError>,
) -> Result<DVector<S>, OracleError> {
    let m = batch_size(batch)?;
    if m < 2 && matches!(kind, Kind::LeaveOneOut) {
        return Err(too_few_for_leave_one_out(m));
    }
    let Buffers {
        terms,
        features,
        rows,
        totals,
        g,
        ..
    } = buffers;
    if terms.len() < m {
        terms.resize_with(m, DecisionTerms::new);
    }
    for (t, out) in batch.iter().zip(terms.iter_mut()) {
        fill(t, out)?;
        out.finish();
    }
    let terms = &terms[..m];
    if let Kind::StateDependent(state) = kind {
        if features.len() < m {
            features.resize_with(m, || (Vec::new(), 0));
        }
        for ((t, out), (phi, k)) in batch.iter().zip(terms).zip(features.iter_mut()) {
            *k = state_columns(
                inner,
                t,
                out.decisions(),
                state.leading,
                state.time,
                phi,
                rows,
            )?;
        }
    }
    if observe {
        match kind {
            Kind::Estimated(state) => state.running.clear_pending(),
            Kind::StateDependent(state) => state.running.clear_pending(),
            _ => {}
        }
    }
    let d = inner.dim();
    g.clear();
    g.resize(d, S::zero());
    let mut sum = DVector::from_element(d, S::zero());
    if matches!(kind, Kind::LeaveOneOut) {
        let n = terms.iter().map(DecisionTerms::decisions).max();
        totals.clear();
        totals.resize(n.unwrap_or(0), S::zero());
        for t in terms {
            for (i, x) in totals.iter_mut().enumerate().take(t.decisions()) {
                *x += t.loss_to_go(i);
            }
        }
    }
    let others = S::from_i64(m as i64 - 1);
    for (j, t) in terms.iter().enumerate() {
        match &*kind {
            Kind::None => t.estimate_into(|_| None, g),
            Kind::Constant(b) => t.estimate_into(|_| Some(b.clone()), g),
            Kind::TimeIndexed(bs) => {
                if t.decisions() > bs.len() {
                    return Err(super::decisions::too_few_baselines(t.decisions()));
                }
                t.estimate_into(|i| Some(bs[i].clone()), g);
            }
            Kind::Estimated(state) => {
                let r = &state.running;
                if state.time_indexed {
                    t.estimate_into(|i| r.time_indexed(i), g);
                } else {
                    let b = r.constant();
                    t.estimate_into(|_| b.clone(), g);
                }
            }
            Kind::LeaveOneOut => {
                t.estimate_into(|i| Some((totals[i].clone() - t.loss_to_go(i)) / &others), g)
            }
            Kind::StateDependent(state) => {
                state
                    .running
                    .baselines_into(&features[j].0, t.decisions(), totals);
                t.estimate_into(|i| totals.get(i).cloned(), g);
            }
        }
        for (s, x) in sum.iter_mut().zip(g.iter()) {
            *s += x;
        }
    }
    if observe {
        match kind {
            Kind::Estimated(state) => {
                for t in terms {
                    state.running.observe(t);
                }
            }
            Kind::StateDependent(state) => {
                for (t, (phi, k)) in terms.iter().zip(features.iter()) {
                    if state.running.takes_next() {
                        state.running.observe(t, phi, *k);
                    }
                }
            }
            _ => {}
        }
    }
    let m = S::from_i64(m as i64);
    let g = sum.map(|x| x / &m);
    if !g.iter().all(Scalar::is_finite) {
        return Err(OracleError::NonFinite("the baselined gradient estimate"));
    }
    Ok(g)
}

impl<S: Scalar, P: PerDecisionTerms<S>> IlProblem<S> for Baselined<P, S> {
    type Trajectory = Vec<P::Trajectory>;
    type Labelled = P::Labelled;

    fn dim(&self) -> usize {
        self.batch.dim()
    }

    /// `m` roll-outs in turn from the one RNG; an estimated baseline first takes in the
    /// statistics of the previous call's trajectories.
    fn rollout(
        &mut self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<Self::Trajectory, OracleError> {
        match &mut self.kind {
            Kind::Estimated(state) => state.running.commit(),
            Kind::StateDependent(state) => state.running.commit(),
            _ => {}
        }
        self.batch.rollout(behaviour, rng, cost)
    }

    fn estimate(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let Self {
            batch,
            kind,
            buffers,
        } = self;
        match kind {
            Kind::None => batch.estimate(theta, trajectory, form, cost),
            _ if form == EstimatorForm::Full => {
                Err(invalid("baselines apply to the causal form of eq. 3.15"))
            }
            Kind::Constant(b) => given_estimate(
                batch.inner(),
                buffers,
                theta,
                trajectory,
                Given::Constant(b),
                cost,
            ),
            Kind::TimeIndexed(bs) => given_estimate(
                batch.inner(),
                buffers,
                theta,
                trajectory,
                Given::TimeIndexed(bs),
                cost,
            ),
            Kind::LeaveOneOut => leave_one_out(batch.inner(), buffers, theta, trajectory, cost),
            Kind::Estimated(state) => {
                estimated(batch.inner(), state, buffers, theta, trajectory, cost)
            }
            Kind::StateDependent(state) => {
                state_dependent(batch.inner(), state, buffers, theta, trajectory, cost)
            }
        }
    }

    /// Without a baseline, the minibatch's own (one pass per trajectory). With a baseline the
    /// estimate, which records every trajectory's decisions, then the trajectory loss read off
    /// the records where the problem can ([`RecordedPass::trajectory_loss`]; the same value),
    /// else computed again.
    fn estimate_with_loss(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<(DVector<S>, S), OracleError> {
        if matches!(self.kind, Kind::None) {
            return self.batch.estimate_with_loss(theta, trajectory, form, cost);
        }
        if form == EstimatorForm::Full {
            return crate::problem::estimate_then_loss(self, theta, trajectory, form, cost);
        }
        let g = self.estimate(theta, trajectory, form, cost)?;
        let inner = self.inner();
        let mut records = self.buffers.records.iter();
        // `Batched::trajectory_loss`'s mean, over the same per-trajectory losses.
        let loss = crate::batched::mean(trajectory, |t| {
            let recorded = records.next().and_then(RecordedPass::trajectory_loss);
            let l = match recorded {
                Some(l) => l,
                None => inner.trajectory_loss(theta, t)?,
            };
            Ok(DVector::from_element(1, l))
        })?;
        Ok((g, loss[0].clone()))
    }

    fn weighted_estimate(
        &mut self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &Self::Trajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let Self {
            batch,
            kind,
            buffers,
        } = self;
        match kind {
            Kind::None => {
                batch.weighted_estimate(theta_old, theta_new, trajectory, weighting, cost)
            }
            _ => {
                let inner = batch.inner();
                baselined(inner, kind, buffers, trajectory, false, |t, out| {
                    inner.decision_terms(theta_old, t, Some((theta_new, weighting)), out, cost)
                })
            }
        }
    }

    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
    ) -> Result<S, OracleError> {
        self.batch.trajectory_loss(theta, trajectory)
    }

    fn labelled_states(&self, trajectory: &Self::Trajectory) -> Vec<Self::Labelled> {
        self.batch.labelled_states(trajectory)
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &Self::Labelled,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError> {
        self.batch.supervised(theta, example, grad, cost)
    }
}
