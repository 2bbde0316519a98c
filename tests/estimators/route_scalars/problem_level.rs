//! The problem-level routes and the baselined oracle in any [`Real`] scalar, and the interval
//! instance over them (with the `mpfr` feature, through which intervals are [`Real`]).

use super::*;

/// Every problem-level route of one trajectory at θ (estimated towards θ_new where weighted),
/// then the policy's kernel routes: the causal estimate with its loss, the trajectory loss,
/// the full form, the weighted estimates (towards θ_new, and at θ itself where every weight
/// is 1), the per-decision terms (weighted; unweighted with the baseline), the baselined
/// estimate with the baseline given, the recorded passes (recorded and filled from the
/// terms) with the recorded and the baselined losses, and the recorded score products.
pub(super) fn problem_routes<S, T, P>(
    p: &mut TaskProblem<T, P>,
    theta: &DVector<S>,
    theta_new: &DVector<S>,
    t: &TaskTrajectory<S, T::Label, T::Action>,
) -> Vec<Route<S>>
where
    S: Real,
    T: Task<S>,
    P: LikelihoodRatio<S, Action = T::Action> + EstimatorKernel<S>,
    T::Label: Borrow<P::Label>,
{
    let mut cost = Cost::default();
    let d = theta.len();
    let scored = if t.absorbed.is_some() {
        t.len()
    } else {
        t.len() - 1
    };
    let b = |i: usize| shift_baseline::<S>(i, scored);
    let mut out = vec![];
    let (g, loss) = p
        .estimate_with_loss(theta, t, EstimatorForm::Causal, &mut cost)
        .unwrap();
    out.push(route(
        "estimate_with_loss",
        Want::Plain,
        g.as_slice().to_vec(),
    ));
    out.push(route("estimate_with_loss loss", Want::Loss, vec![loss]));
    let loss = p.trajectory_loss(theta, t).unwrap();
    out.push(route("trajectory_loss", Want::Loss, vec![loss]));
    for (form, what) in [
        (EstimatorForm::Causal, Want::Plain),
        (EstimatorForm::Full, Want::Full),
    ] {
        let g = p.estimate(theta, t, form, &mut cost).unwrap();
        out.push(route(
            format!("estimate {form:?}"),
            what,
            g.as_slice().to_vec(),
        ));
    }
    for (weighting, what) in [
        (Weighting::PerDecision, Want::PerDecision),
        (Weighting::Trajectory, Want::Trajectory),
    ] {
        let g = p
            .weighted_estimate(theta, theta_new, t, weighting, &mut cost)
            .unwrap();
        out.push(route(
            format!("weighted_estimate {weighting:?}"),
            what,
            g.as_slice().to_vec(),
        ));
        let g = p
            .weighted_estimate(theta, theta, t, weighting, &mut cost)
            .unwrap();
        out.push(route(
            format!("weighted_estimate {weighting:?} at θ"),
            Want::Plain,
            g.as_slice().to_vec(),
        ));
        let mut dt = DecisionTerms::new();
        p.decision_terms(theta, t, Some((theta_new, weighting)), &mut dt, &mut cost)
            .unwrap();
        dt.finish();
        let mut g = vec![S::zero(); d];
        dt.estimate_into(|_| None, &mut g);
        out.push(route(format!("decision_terms {weighting:?}"), what, g));
    }
    let mut dt = DecisionTerms::new();
    p.decision_terms(theta, t, None, &mut dt, &mut cost)
        .unwrap();
    dt.finish();
    let mut g = vec![S::zero(); d];
    dt.estimate_into(|_| None, &mut g);
    out.push(route("decision_terms", Want::Plain, g));
    let mut g = vec![S::zero(); d];
    dt.estimate_into(|i| Some(b(i)), &mut g);
    out.push(route("decision_terms with b", Want::Baselined, g));
    let bs: Vec<S> = (0..scored).map(b).collect();
    let g = baselined_estimate(p, theta, t, Given::TimeIndexed(&bs), &mut cost).unwrap();
    out.push(route(
        "baselined_estimate, time-indexed",
        Want::Baselined,
        g.as_slice().to_vec(),
    ));
    let mut rec = RecordedPass::new();
    p.record_decisions(theta, t, &mut rec, &mut cost).unwrap();
    let mut rows = RecordedPass::new();
    p.decision_terms(theta, t, None, rows.terms_mut(), &mut cost)
        .unwrap();
    rows.fill_from_terms();
    let shifted = shifted(rec.losses().iter(), scored, false);
    for (name, r) in [
        ("record_decisions", &mut rec),
        ("fill_from_terms", &mut rows),
    ] {
        let mut g = vec![S::zero(); d];
        p.estimate_recorded(t, r, None, &mut g);
        out.push(route(format!("{name} + estimate_recorded"), Want::Plain, g));
        let mut g = vec![S::zero(); d];
        p.estimate_recorded(t, r, Some(&shifted), &mut g);
        out.push(route(
            format!("{name} + estimate_recorded, shifted losses"),
            Want::Baselined,
            g,
        ));
    }
    let v = out[0].value.clone();
    let given: Vec<S> = (0..scored).map(b).collect();
    for (name, r) in [("record_decisions", &rec), ("fill_from_terms", &rows)] {
        let (mut cross, mut moment) = (vec![S::zero(); scored], vec![S::zero(); scored]);
        let mut g = v.clone();
        p.recorded_score_products(
            t,
            r,
            ScoreProducts {
                v: &v,
                baseline: Baselines::Given(&given),
                cross: &mut cross,
                moment: &mut moment,
                g: &mut g,
            },
        );
        out.push(route(
            format!("{name} + recorded_score_products g"),
            Want::Baselined,
            g,
        ));
        out.push(route(
            format!("{name} + recorded_score_products cross"),
            Want::Cross,
            cross,
        ));
        out.push(route(
            format!("{name} + recorded_score_products moment"),
            Want::Moment,
            moment,
        ));
    }
    out.extend(kernel_routes(&p.policy, theta.as_slice(), t));
    out
}

/// Every kind of baseline, as `routes`'.
pub(super) fn kinds() -> Vec<Baseline> {
    super::super::routes::baseline_kinds()
}

/// The baselined oracle's routes for every kind on the same batches at θ: `estimate`,
/// `estimate_by_terms`, and (where the baselines are known from outside and not
/// leave-one-out) the weighted estimates at θ itself. One entry per kind, batch and route.
pub(super) fn baselined_routes<S, T, P>(
    p: &TaskProblem<T, P>,
    theta: &DVector<S>,
    batches: &[Vec<Trajectory<S, T>>],
) -> Vec<(usize, usize, Route<S>)>
where
    S: Real,
    T: Task<S> + Clone,
    P: LikelihoodRatio<S, Action = T::Action> + EstimatorKernel<S> + Clone,
    T::Label: Borrow<P::Label>,
{
    let mut out = vec![];
    for (k, kind) in kinds().iter().enumerate() {
        let mut b = Baselined::new(p.clone(), M, kind).unwrap();
        let mut cost = Cost::default();
        for (batch, ts) in batches.iter().enumerate() {
            let name = |r: &str| format!("{kind:?}, batch {batch}: {r}");
            let g = b
                .estimate(theta, ts, EstimatorForm::Causal, &mut cost)
                .unwrap();
            out.push((
                k,
                batch,
                route(name("estimate"), Want::Baselined, g.as_slice().to_vec()),
            ));
            let g = b.estimate_by_terms(theta, ts, &mut cost).unwrap();
            out.push((
                k,
                batch,
                route(
                    name("estimate_by_terms"),
                    Want::Baselined,
                    g.as_slice().to_vec(),
                ),
            ));
            if known(kind) && !matches!(kind, Baseline::LeaveOneOut) {
                for weighting in [Weighting::PerDecision, Weighting::Trajectory] {
                    let g = b
                        .weighted_estimate(theta, theta, ts, weighting, &mut cost)
                        .unwrap();
                    out.push((
                        k,
                        batch,
                        route(
                            name(&format!("weighted {weighting:?} at θ")),
                            Want::Baselined,
                            g.as_slice().to_vec(),
                        ),
                    ));
                }
            }
        }
    }
    out
}

/// Whether the kind's baselines are known from outside the oracle (so that the reference
/// can form them): none, constants, leave-one-out.
pub(super) fn known(kind: &Baseline) -> bool {
    matches!(
        kind,
        Baseline::None
            | Baseline::Constant { .. }
            | Baseline::TimeIndexed { .. }
            | Baseline::LeaveOneOut
    )
}

/// The mean baselined estimate `(1/M) Σ_j [g_j − Σ_{i<s_j} b_i^{(j)} ψ_i^{(j)}]` of a known
/// kind from each trajectory's terms: b = 0, the constant 1/2, the time-indexed values, or
/// the other trajectory's loss-to-go `L_i = Σ_{t>i} l_t` (its tail included; 0 past its
/// end) for leave-one-out.
pub(super) fn batch_reference<S: Scalar>(kind: &Baseline, all: &[Terms<S>]) -> Vec<S> {
    let to_go: Vec<Vec<S>> = all
        .iter()
        .map(|x| {
            let mut after = x.tail.clone().unwrap_or_else(S::zero);
            let mut out = vec![S::zero(); x.losses.len()];
            for i in (0..x.losses.len()).rev() {
                out[i] = after.clone();
                after += &x.losses[i];
            }
            out
        })
        .collect();
    let d = all[0].grads[0].len();
    let mut mean = vec![S::zero(); d];
    for (j, x) in all.iter().enumerate() {
        let b = |i: usize| match kind {
            Baseline::None => S::zero(),
            Baseline::Constant { .. } => S::from_ratio(1, 2),
            Baseline::TimeIndexed { .. } => exact(super::super::routes::time_indexed(i)),
            Baseline::LeaveOneOut => to_go[1 - j].get(i).cloned().unwrap_or_else(S::zero),
            _ => unreachable!("a kind known from outside"),
        };
        for (m, g) in mean.iter_mut().zip(reference(x, None, &b)) {
            *m += g;
        }
    }
    let m = S::from_i64(all.len() as i64);
    mean.into_iter().map(|x| x / &m).collect()
}

/// A batch reference: exact, or an enclosure.
#[cfg(feature = "mpfr")]
enum BatchReference {
    Exact(Vec<BigRational>),
    Interval(Vec<Interval>),
}

#[cfg(feature = "mpfr")]
pub(super) fn interval_exp(x: &Interval) -> Interval {
    Real::exp(x)
}

/// The interval instance with the `mpfr` feature: every problem-level route (over the
/// [`Lifted`] task) and the kernel routes on every lifted trajectory at both θ, then the
/// baselined oracle with every kind on lifted batches; each against the exact reference
/// (`exact`) or the interval reference, and the f64 problem's routes near them.
#[cfg(feature = "mpfr")]
#[allow(clippy::too_many_arguments)] // the problem, the lifted policy and its lifts
pub(super) fn check_interval_problem<T, P, PI, LI, AI>(
    p: &mut TaskProblem<T, P>,
    pi: PI,
    thetas: &[DVector<f64>; 2],
    label: &dyn Fn(&T::Label) -> LI,
    action: &dyn Fn(&T::Action) -> AI,
    exact: Option<&ExactTerms<'_, T>>,
    mode: Mode,
) -> Tally
where
    T: Task<f64> + Clone,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64> + Clone,
    T::Label: Borrow<P::Label>,
    PI: LikelihoodRatio<Interval, Action = AI> + EstimatorKernel<Interval> + Clone,
    LI: Borrow<PI::Label> + Clone + Debug,
    AI: Clone + Debug,
{
    let mut pint = lifted::<LI, AI, _>(pi, p.horizon);
    let thetas_i = [lift_theta(&thetas[0]), lift_theta(&thetas[1])];
    let mut tally = Tally::default();
    for (seed, t) in SEEDS.into_iter().zip(rollouts(p, &thetas[0])) {
        let ti = lift::<Interval, _, _, _, _>(&t, label, action);
        for k in 0..2 {
            let (th, other) = (&thetas_i[k], &thetas_i[1 - k]);
            let refs = IntervalRefs {
                exact: exact
                    .map(|e| Wants::new(mode.apply(e(&t, &thetas[k], &thetas[1 - k])), None)),
                interval: Wants::new(
                    mode.apply(terms(&pint.policy, th.as_slice(), other.as_slice(), &ti)),
                    Some(&interval_exp),
                ),
            };
            let fs = problem_routes(p, &thetas[k], &thetas[1 - k], &t);
            let is = problem_routes(&mut pint, th, other, &ti);
            for (r, f) in is.iter().zip(&fs) {
                let context = format!("seed {seed}, θ{k}");
                check_interval_route(&mut tally, mode, &refs, r, f, &context);
            }
        }
    }

    // The baselined oracle on batches of M trajectories.
    let batches = batches(p, &thetas[0]);
    let batches_i: Vec<Vec<_>> = batches
        .iter()
        .map(|ts| {
            ts.iter()
                .map(|t| lift::<Interval, _, _, _, _>(t, label, action))
                .collect()
        })
        .collect();
    let fs = baselined_routes(p, &thetas[0], &batches);
    let is = baselined_routes(&pint, &thetas_i[0], &batches_i);
    let all_kinds = kinds();
    // Each batch's terms once (exact where the policy is rational, and in intervals), and
    // each known kind's reference once per batch.
    let exact_terms: Option<Vec<Vec<Terms<BigRational>>>> = exact.map(|e| {
        batches
            .iter()
            .map(|ts| {
                ts.iter()
                    .map(|t| mode.apply(e(t, &thetas[0], &thetas[0])))
                    .collect()
            })
            .collect()
    });
    let interval_terms: Vec<Vec<Terms<Interval>>> = batches_i
        .iter()
        .map(|ts| {
            let th = thetas_i[0].as_slice();
            ts.iter()
                .map(|t| mode.apply(terms(&pint.policy, th, th, t)))
                .collect()
        })
        .collect();
    let mut references: Vec<((usize, usize), BatchReference)> = vec![];
    for (i, ((k, batch, r), (_, _, f))) in is.iter().zip(&fs).enumerate() {
        assert_eq!(r.name, f.name, "the routes of both scalars in one order");
        tally.width = tally.width.max(relative_width(&r.value));
        let kind = &all_kinds[*k];
        let check = if known(kind) {
            let at = references.iter().position(|(key, _)| *key == (*k, *batch));
            let at = at.unwrap_or_else(|| {
                let reference = match &exact_terms {
                    Some(x) => BatchReference::Exact(batch_reference(kind, &x[*batch])),
                    None => {
                        BatchReference::Interval(batch_reference(kind, &interval_terms[*batch]))
                    }
                };
                references.push(((*k, *batch), reference));
                references.len() - 1
            });
            match &references[at].1 {
                BatchReference::Exact(q) => contains(&r.name, &r.value, q),
                BatchReference::Interval(w) => meets(&r.name, &r.value, w),
            }
        } else if mode == Mode::Reference && r.name.ends_with("estimate_by_terms") {
            // The estimated baselines: the oracle's estimate and its route by terms
            // enclose the same real number.
            meets(&r.name, &r.value, &is[i - 1].2.value)
        } else {
            Ok(())
        };
        if mode == Mode::Reference || known(kind) {
            tally.record(mode, &r.name, check);
        }
        if mode == Mode::Reference {
            tally.record(mode, &r.name, near(&r.name, &f.value, &r.value));
        }
    }
    tally
}
