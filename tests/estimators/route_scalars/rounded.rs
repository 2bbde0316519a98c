//! The f32 and `Dual<f64>` checks: f32 routes within a tolerance of an enclosure and bit for
//! bit the reference formed in f32 in `routes`' order; dual routes' values bit for bit the f64
//! routes', their tangents within a tolerance of the tangent of a reference in duals over
//! intervals.

use super::*;

/// How far an f32 route's value may lie from the reference, relative to the largest magnitude in
/// the quantity's reference (per vector): as [`TOLERANCE`] in f64, twice `routes`' bound between
/// two summation orders of up to [`LONG_STEPS`] terms (each within `LONG_STEPS · ε₃₂` of the
/// exact sum relative to the terms' magnitudes), for the rounding of the terms themselves. The
/// estimates with leave-one-out baselines come closest (0.4 of it: the baselines cancel most of
/// the terms).
pub(super) const F32_TOLERANCE: f64 = 4.0 * LONG_STEPS as f64 * f32::EPSILON as f64;

/// The same for the tangent of a dual route against the exact or enclosed tangent: as
/// [`TOLERANCE`], the tangent's own sums and products being of the value's length.
pub(super) const TANGENT_TOLERANCE: f64 = TOLERANCE;

/// The perturbation of the f32 failure tests, `1 + 2⁰`: the last decision's loss is as little
/// as 3·10⁻⁴ of the trajectory's loss on these trajectories (the learner ends near the goal), so
/// that only doubling it moves every sum it enters by more than [`F32_TOLERANCE`] (about 10⁻⁴;
/// the least such move is 1.5 times that), at the roll-out's θ and but for the leave-one-out
/// estimates (where the other trajectory's baselines take up most of the change).
pub(super) const F32_PERTURBATION: u32 = 0;

/// The perturbation of the dual failure tests' tangents, `1 + 2⁻²⁰`: as the interval
/// problem-level routes' ([`TANGENT_TOLERANCE`] is far below, the widest enclosure of a tangent
/// below [`MAX_WIDTH`]).
pub(super) const DUAL_PERTURBATION: u32 = 20;

/// Where a reference quantity lies, entry by entry, in f64: `[lo, hi]`.
pub(super) type Bounds = Vec<(f64, f64)>;

pub(super) fn interval_bounds(x: &Interval) -> (f64, f64) {
    (x.inf(), x.sup())
}

/// A dual's tangent: its derivative along the one seeded direction.
pub(super) fn tangent<R: Scalar>(x: &Dual<R>) -> R {
    x.gradient().first().cloned().unwrap_or_else(R::zero)
}

/// The quantities every reference forms per trajectory.
pub(super) const WANTS: [Want; 9] = [
    Want::Plain,
    Want::Full,
    Want::Loss,
    Want::Losses,
    Want::PerDecision,
    Want::Trajectory,
    Want::Baselined,
    Want::Cross,
    Want::Moment,
];

/// A reference of the f32 and dual instances, seen through [`Bounds`]: every quantity of one
/// f64 trajectory at θ towards θ_new ([`want`]; `None` where the scalar lacks the `exp` it
/// needs), and the batch references of the baseline kinds known from outside.
pub(super) trait Reference<T: Task<f64>> {
    fn wants(
        &self,
        t: &Trajectory64<T>,
        theta: &DVector<f64>,
        theta_new: &DVector<f64>,
        mode: Mode,
    ) -> Vec<(Want, Option<Bounds>)>;

    /// One entry per kind of `kinds`: the mean baselined estimate at θ on the batch `ts` for a
    /// kind known from outside ([`batch_reference`]), else `None`.
    fn batch(
        &self,
        kinds: &[Baseline],
        ts: &[Trajectory64<T>],
        theta: &DVector<f64>,
        mode: Mode,
    ) -> Vec<Option<Bounds>>;
}

/// A [`Reference`] in the scalar `R`: the terms from a policy in `R` on the trajectory and θ
/// lifted exactly, `R`'s `exp` where it has one, and what of a value is compared (the value of
/// a rational or an interval, the tangent of a dual).
pub(super) struct InScalar<'a, T: Task<f64>, R> {
    terms: Box<TermsIn<'a, T, R>>,
    exp: Option<fn(&R) -> R>,
    bounds: fn(&R) -> (f64, f64),
}

/// The terms of an f64 trajectory at θ towards θ_new in `R`.
pub(super) type TermsIn<'a, T, R> =
    dyn Fn(&Trajectory64<T>, &DVector<f64>, &DVector<f64>) -> Terms<R> + 'a;

impl<T: Task<f64>, R: Scalar> Reference<T> for InScalar<'_, T, R> {
    fn wants(
        &self,
        t: &Trajectory64<T>,
        theta: &DVector<f64>,
        theta_new: &DVector<f64>,
        mode: Mode,
    ) -> Vec<(Want, Option<Bounds>)> {
        let x = mode.apply((self.terms)(t, theta, theta_new));
        let exp = self.exp.as_ref().map(|f| f as &dyn Fn(&R) -> R);
        WANTS
            .iter()
            .map(|&w| {
                (
                    w,
                    want(w, &x, exp).map(|v| v.iter().map(self.bounds).collect()),
                )
            })
            .collect()
    }

    fn batch(
        &self,
        kinds: &[Baseline],
        ts: &[Trajectory64<T>],
        theta: &DVector<f64>,
        mode: Mode,
    ) -> Vec<Option<Bounds>> {
        let all: Vec<Terms<R>> = ts
            .iter()
            .map(|t| mode.apply((self.terms)(t, theta, theta)))
            .collect();
        kinds
            .iter()
            .map(|kind| {
                known(kind).then(|| {
                    batch_reference(kind, &all)
                        .iter()
                        .map(self.bounds)
                        .collect()
                })
            })
            .collect()
    }
}

/// A [`Reference`] from the policy `pr` in `R`, the trajectories lifted by `label` and
/// `action`, θ by `theta`.
pub(super) fn reference_in<'a, T, R, PR, LR, AR>(
    pr: PR,
    label: impl Fn(&T::Label) -> LR + 'a,
    action: impl Fn(&T::Action) -> AR + 'a,
    theta: fn(&DVector<f64>) -> DVector<R>,
    exp: Option<fn(&R) -> R>,
    bounds: fn(&R) -> (f64, f64),
) -> Box<dyn Reference<T> + 'a>
where
    T: Task<f64> + 'a,
    R: Scalar,
    PR: LikelihoodRatio<R, Action = AR> + 'a,
    LR: Borrow<PR::Label>,
{
    let terms = move |t: &Trajectory64<T>, th: &DVector<f64>, other: &DVector<f64>| {
        let tr = lift::<R, _, _, _, _>(t, &label, &action);
        terms(&pr, theta(th).as_slice(), theta(other).as_slice(), &tr)
    };
    Box::new(InScalar {
        terms: Box::new(terms),
        exp,
        bounds,
    })
}

/// θ in duals along the fixed direction `u_j = ±((j mod 3) + 1)/8`, the sign alternating with
/// j (dyadic, so that every scalar's duals carry the same direction).
pub(super) fn dual_theta<S: Scalar>(theta: &DVector<f64>) -> DVector<Dual<S>> {
    DVector::from_fn(theta.len(), |j, _| {
        let sign = if j % 2 == 0 { 1 } else { -1 };
        let u = S::from_ratio(sign * (j % 3 + 1) as i64, 8);
        Dual::new(exact(theta[j]), vec![u])
    })
}

/// Record whether every entry lies within `tolerance` of its bounds, relative to the largest
/// magnitude of the bounds (the quantity's scale); the largest relative distance of the entries
/// joins [`Tally::worst`] (against the reference) or [`Tally::least`] (perturbed).
pub(super) fn within(
    tally: &mut Tally,
    mode: Mode,
    name: &str,
    got: &[f64],
    want: &Bounds,
    tolerance: f64,
) {
    let check = lengths(name, got, want).and_then(|()| {
        let scale = want
            .iter()
            .fold(0.0f64, |m, (lo, hi)| m.max(lo.abs()).max(hi.abs()));
        let mut far = (0.0f64, 0);
        for (j, (x, (lo, hi))) in got.iter().zip(want).enumerate() {
            let distance = (lo - x).max(x - hi).max(0.0);
            let relative = if distance == 0.0 {
                0.0
            } else {
                distance / scale
            };
            if relative.is_nan() || relative > far.0 {
                far = (relative, j);
            }
        }
        match mode {
            Mode::Reference => tally.worst = tally.worst.max(far.0),
            Mode::Perturbed(_) => tally.least = Some(tally.least.map_or(far.0, |m| m.min(far.0))),
        }
        if far.0 <= tolerance {
            Ok(())
        } else {
            let (j, x, (lo, hi)) = (far.1, got[far.1], want[far.1]);
            Err(format!(
                "{name}: entry {j}: {x} is {} (relative) from [{lo}, {hi}]",
                far.0
            ))
        }
    });
    tally.record(mode, name, check);
}

/// The same f64 bits entry by entry (an f32 widened exactly).
pub(super) fn same_bits(name: &str, got: &[f64], want: &[f64]) -> Check {
    lengths(name, got, want)?;
    match got
        .iter()
        .zip(want)
        .position(|(a, b)| a.to_bits() != b.to_bits())
    {
        None => Ok(()),
        Some(j) => Err(format!(
            "{name}: entry {j}: {} != {} (bits)",
            got[j], want[j]
        )),
    }
}

/// The largest width of the bounds relative to `1 +` their magnitude.
pub(super) fn bounds_width(b: &Bounds) -> f64 {
    b.iter().fold(0.0f64, |m, (lo, hi)| {
        m.max((hi - lo) / (1.0 + lo.abs().max(hi.abs())))
    })
}

/// One route's compared part (`got`: f32 values widened, or a dual's tangents) within
/// `tolerance` of the first reference that has its quantity (the references in order: exact,
/// then enclosures); nothing is compared where none has it.
pub(super) fn check_bounds(
    tally: &mut Tally,
    mode: Mode,
    name: &str,
    what: Want,
    got: &[f64],
    refs: &[Vec<(Want, Option<Bounds>)>],
    tolerance: f64,
) {
    if matches!(mode, Mode::Perturbed(_)) && !reads_loss(what) {
        return;
    }
    let found = refs.iter().find_map(|r| {
        r.iter()
            .find(|(w, _)| *w == what)
            .and_then(|(_, b)| b.as_ref())
    });
    if let Some(b) = found {
        tally.width = tally.width.max(bounds_width(b));
        within(tally, mode, name, got, b, tolerance);
    }
}

/// The batch routes' compared parts (`part` of each route's value), each within `tolerance` of
/// its kind's batch reference where the kind is known from outside, else (against the
/// reference only) `estimate_by_terms` within `tolerance` of the oracle's `estimate` before it.
pub(super) fn check_batches<X>(
    tally: &mut Tally,
    mode: Mode,
    routes: &[(usize, usize, Route<X>)],
    part: &dyn Fn(&[X]) -> Vec<f64>,
    references: &[Vec<Option<Bounds>>],
    tolerance: f64,
) {
    for (i, (k, batch, r)) in routes.iter().enumerate() {
        let got = part(&r.value);
        if let Some(b) = &references[*batch][*k] {
            tally.width = tally.width.max(bounds_width(b));
            within(tally, mode, &r.name, &got, b, tolerance);
        } else if mode == Mode::Reference && r.name.ends_with("estimate_by_terms") {
            let before: Bounds = part(&routes[i - 1].2.value)
                .into_iter()
                .map(|x| (x, x))
                .collect();
            within(tally, mode, &r.name, &got, &before, tolerance);
        }
    }
}

/// The learner's batches of [`M`] roll-outs at θ for the baselined oracle, [`BATCHES`] of them
/// (the same as the interval instance's).
pub(super) fn batches<T, P>(
    p: &mut TaskProblem<T, P>,
    theta: &DVector<f64>,
) -> Vec<Vec<Trajectory64<T>>>
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let mut rng = KitRng::seed_from_u64(7);
    let mut cost = Cost::default();
    (0..BATCHES)
        .map(|_| {
            (0..M)
                .map(|_| {
                    p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                        .unwrap()
                })
                .collect()
        })
        .collect()
}

/// The batch references of every kind: per batch, per kind, from the first reference.
pub(super) fn batch_references<T: Task<f64>>(
    references: &[Box<dyn Reference<T> + '_>],
    batches: &[Vec<Trajectory64<T>>],
    theta: &DVector<f64>,
    mode: Mode,
) -> Vec<Vec<Option<Bounds>>> {
    let all = kinds();
    batches
        .iter()
        .map(|ts| match references.first() {
            Some(r) => r.batch(&all, ts, theta, mode),
            None => vec![None; all.len()],
        })
        .collect()
}

/// `x` rounded to the nearest f32 (finite), as an f64.
pub(super) fn to_f32(x: f64) -> f64 {
    let y = x as f32;
    assert!(y.is_finite(), "{x} overflows f32");
    f64::from(y)
}

#[allow(clippy::ptr_arg)] // the obstacle task's label and action type
pub(super) fn round_vec(v: &Vec<f64>) -> Vec<f64> {
    v.iter().map(|&x| to_f32(x)).collect()
}

pub(super) fn round_pair(v: &[f64; 2]) -> [f64; 2] {
    v.map(to_f32)
}

/// An f64 trajectory with every value rounded to f32 (features, the tail's losses, labels and
/// actions through `label` and `action`): the f32 instance's inputs, exact in every scalar.
pub(super) fn round_trajectory<T: Task<f64>>(
    t: &Trajectory64<T>,
    label: &dyn Fn(&T::Label) -> T::Label,
    action: &dyn Fn(&T::Action) -> T::Action,
) -> Trajectory64<T> {
    map_trajectory(t, &to_f32, label, action)
}

/// The reference order of a route that `routes` asserts bit for bit in f64: the plain pass
/// (`Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`, then the tail), a quantity of [`want`] formed in the
/// route's order (the full form, the losses and their sum, the weighted estimates), or the plain
/// pass with the losses shifted by the baseline as the recorded routes shift them
/// (`(l_t + b_t) − b_{t−1}`) or as `baselined_estimate` does (`l_t + (b_t − b_{t−1})`).
#[derive(Debug, Clone, Copy)]
pub(super) enum Order {
    Plain,
    Want(Want),
    Shifted,
    ShiftedGiven,
}

/// The routes that `routes` asserts bit for bit in f64, with their order; the policy's records
/// summed with the shifted losses are the pass that `estimate_recorded` takes for the
/// problem's recorded pass.
pub(super) const SAME_ORDER: [(&str, Order); 16] = [
    ("estimate_with_loss", Order::Plain),
    ("estimate_with_loss loss", Order::Want(Want::Loss)),
    ("estimate Causal", Order::Plain),
    ("estimate Full", Order::Want(Want::Full)),
    (
        "weighted_estimate PerDecision",
        Order::Want(Want::PerDecision),
    ),
    ("weighted_estimate PerDecision at θ", Order::Plain),
    (
        "weighted_estimate Trajectory",
        Order::Want(Want::Trajectory),
    ),
    ("weighted_estimate Trajectory at θ", Order::Plain),
    ("baselined_estimate, time-indexed", Order::ShiftedGiven),
    ("record_decisions + estimate_recorded", Order::Plain),
    (
        "record_decisions + estimate_recorded, shifted losses",
        Order::Shifted,
    ),
    ("causal_sum_validated", Order::Plain),
    ("causal_sum_validated loss", Order::Want(Want::Loss)),
    ("record_validated losses", Order::Want(Want::Losses)),
    ("record_validated + accumulate_recorded", Order::Plain),
    (
        "record_validated + accumulate_recorded, shifted losses",
        Order::Shifted,
    ),
];

/// The reference in `routes`' order of a route's quantity, from the terms in the route's scalar.
pub(super) fn in_order<S: Real>(order: Order, t: &Terms<S>) -> Vec<S> {
    let exp = |x: &S| x.exp();
    match order {
        Order::Plain => {
            let mut losses = t.losses.clone();
            losses.extend(t.tail.clone());
            plain_with(t, &losses)
        }
        Order::Want(what) => want(what, t, Some(&exp)).expect("an exp"),
        Order::Shifted => plain_with(t, &shifted(t.losses.iter().chain(&t.tail), t.scored, false)),
        Order::ShiftedGiven => {
            plain_with(t, &shifted(t.losses.iter().chain(&t.tail), t.scored, true))
        }
    }
}

/// The f32 instance: every problem-level route (over the [`Lifted`] task) and the kernel routes
/// on every trajectory rounded to f32 at both θ (rounded), then the baselined oracle with every
/// kind on rounded batches; each within [`F32_TOLERANCE`] of the first reference that has the
/// quantity, and, where `routes` asserts it in f64, bit for bit the reference formed in f32 in
/// the route's order ([`SAME_ORDER`]). `round_*` round the f64 labels and actions, `label` and
/// `action` lift the rounded ones to f32.
#[allow(clippy::too_many_arguments)] // the problem, the f32 policy, the roundings and lifts
pub(super) fn check_f32<T, P, P32, L32, A32>(
    p: &mut TaskProblem<T, P>,
    p32: P32,
    thetas: &[DVector<f64>; 2],
    round_label: &dyn Fn(&T::Label) -> T::Label,
    round_action: &dyn Fn(&T::Action) -> T::Action,
    label: &dyn Fn(&T::Label) -> L32,
    action: &dyn Fn(&T::Action) -> A32,
    references: &[Box<dyn Reference<T> + '_>],
    mode: Mode,
) -> Tally
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
    P32: LikelihoodRatio<f32, Action = A32> + EstimatorKernel<f32> + Clone,
    L32: Borrow<P32::Label> + Clone + Debug,
    A32: Clone + Debug,
{
    let mut p32 = lifted::<L32, A32, _>(p32, p.horizon);
    let rounded = thetas.clone().map(|th| th.map(to_f32));
    let th32 = rounded.clone().map(|th| lift_theta::<f32>(&th));
    let widen = |v: &[f32]| v.iter().map(|&x| f64::from(x)).collect::<Vec<_>>();
    let mut tally = Tally::default();
    for (seed, t) in SEEDS.into_iter().zip(rollouts(p, &thetas[0])) {
        let t = round_trajectory::<T>(&t, round_label, round_action);
        let t32 = lift::<f32, _, _, _, _>(&t, label, action);
        // Perturbed, at the roll-out's θ only: at the other, the last loss is too small a part
        // of the sums for F32_TOLERANCE to see it doubled (F32_PERTURBATION).
        let ks = if mode == Mode::Reference { 2 } else { 1 };
        for k in 0..ks {
            let refs: Vec<_> = references
                .iter()
                .map(|r| r.wants(&t, &rounded[k], &rounded[1 - k], mode))
                .collect();
            let own = terms(
                &p32.policy,
                th32[k].as_slice(),
                th32[1 - k].as_slice(),
                &t32,
            );
            let routes = problem_routes(&mut p32, &th32[k], &th32[1 - k], &t32);
            let mut bitwise = 0;
            for r in &routes {
                let name = format!("seed {seed}, θ{k}: {}", r.name);
                let got = widen(&r.value);
                check_bounds(&mut tally, mode, &name, r.what, &got, &refs, F32_TOLERANCE);
                if let Some((_, order)) = SAME_ORDER.iter().find(|(n, _)| *n == r.name) {
                    bitwise += 1;
                    let mut want = in_order(*order, &own);
                    if let (Mode::Perturbed(_), Some(x)) = (mode, want.first_mut()) {
                        *x = f32::from_bits(x.to_bits() ^ 1);
                    }
                    tally.record(mode, &name, same_bits(&name, &got, &widen(&want)));
                }
            }
            assert_eq!(bitwise, SAME_ORDER.len(), "every route of SAME_ORDER ran");
        }
    }

    let batches = batches(p, &thetas[0]);
    let batches: Vec<Vec<_>> = batches
        .iter()
        .map(|ts| {
            ts.iter()
                .map(|t| round_trajectory::<T>(t, round_label, round_action))
                .collect()
        })
        .collect();
    let batches32: Vec<Vec<_>> = batches
        .iter()
        .map(|ts| {
            ts.iter()
                .map(|t| lift::<f32, _, _, _, _>(t, label, action))
                .collect()
        })
        .collect();
    let routes = baselined_routes(&p32, &th32[0], &batches32);
    let mut refs = batch_references(references, &batches, &rounded[0], mode);
    if mode != Mode::Reference {
        // The leave-one-out estimate: the other trajectory's baselines take up most of the
        // doubled loss's part, too little remains for F32_TOLERANCE.
        let leave_one_out = kinds()
            .iter()
            .position(|k| matches!(k, Baseline::LeaveOneOut));
        for r in &mut refs {
            r[leave_one_out.unwrap()] = None;
        }
    }
    check_batches(&mut tally, mode, &routes, &widen, &refs, F32_TOLERANCE);
    tally
}

/// The `Dual<f64>` instance: every problem-level route and the kernel routes on every f64
/// trajectory at both θ, then the baselined oracle with every kind, θ seeded along
/// [`dual_theta`]'s direction. The value parts must be the f64 routes' values on the same
/// inputs, bit for bit (dual arithmetic's value is f64 arithmetic in the same order); the
/// tangents within [`TANGENT_TOLERANCE`] of the first reference that has the quantity (duals
/// over rationals or intervals). Perturbed, the f64 values are nudged by one unit in the last
/// place (first entry) and every value comparison must fail.
pub(super) fn check_dual<T, P, PD, LD, AD>(
    p: &mut TaskProblem<T, P>,
    pd: PD,
    thetas: &[DVector<f64>; 2],
    label: &dyn Fn(&T::Label) -> LD,
    action: &dyn Fn(&T::Action) -> AD,
    references: &[Box<dyn Reference<T> + '_>],
    mode: Mode,
) -> Tally
where
    T: Task<f64> + Clone,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64> + Clone,
    T::Label: Borrow<P::Label>,
    PD: LikelihoodRatio<Dual<f64>, Action = AD> + EstimatorKernel<Dual<f64>> + Clone,
    LD: Borrow<PD::Label> + Clone + Debug,
    AD: Clone + Debug,
{
    let mut pd = lifted::<LD, AD, _>(pd, p.horizon);
    let thd = [dual_theta::<f64>(&thetas[0]), dual_theta(&thetas[1])];
    let values = |v: &[Dual<f64>]| v.iter().map(|x| *x.value()).collect::<Vec<_>>();
    let tangents = |v: &[Dual<f64>]| v.iter().map(tangent).collect::<Vec<_>>();
    let mut tally = Tally::default();
    let lanes = thetas[0].len() >= DOT_LANES_FROM;
    let check_value = |tally: &mut Tally, name: &str, what: Want, got: &[Dual<f64>], f: &[f64]| {
        if lanes && what == Want::Cross {
            // `v·ψ_i` through `scalar::dot`: f64 sums it in lanes, duals left to right.
            if mode == Mode::Reference {
                let f = f.iter().map(|&x| (x, x)).collect();
                within(tally, mode, name, &values(got), &f, TOLERANCE);
                tally.in_lanes += 1;
            }
            return;
        }
        let mut f = f.to_vec();
        if let (Mode::Perturbed(_), Some(x)) = (mode, f.first_mut()) {
            *x = f64::from_bits(x.to_bits() ^ 1);
        }
        tally.record(mode, name, same_bits(name, &values(got), &f));
    };
    for (seed, t) in SEEDS.into_iter().zip(rollouts(p, &thetas[0])) {
        let td = lift::<Dual<f64>, _, _, _, _>(&t, label, action);
        for k in 0..2 {
            let refs: Vec<_> = references
                .iter()
                .map(|r| r.wants(&t, &thetas[k], &thetas[1 - k], mode))
                .collect();
            let fs = problem_routes(p, &thetas[k], &thetas[1 - k], &t);
            let ds = problem_routes(&mut pd, &thd[k], &thd[1 - k], &td);
            for (r, f) in ds.iter().zip(&fs) {
                assert_eq!(r.name, f.name, "the routes of both scalars in one order");
                let name = format!("seed {seed}, θ{k}: {}", r.name);
                check_value(&mut tally, &name, r.what, &r.value, &f.value);
                let got = tangents(&r.value);
                check_bounds(
                    &mut tally,
                    mode,
                    &name,
                    r.what,
                    &got,
                    &refs,
                    TANGENT_TOLERANCE,
                );
            }
        }
    }

    let batches = batches(p, &thetas[0]);
    let batches_d: Vec<Vec<_>> = batches
        .iter()
        .map(|ts| {
            ts.iter()
                .map(|t| lift::<Dual<f64>, _, _, _, _>(t, label, action))
                .collect()
        })
        .collect();
    let fs = baselined_routes(p, &thetas[0], &batches);
    let ds = baselined_routes(&pd, &thd[0], &batches_d);
    for ((_, _, r), (_, _, f)) in ds.iter().zip(&fs) {
        assert_eq!(r.name, f.name, "the routes of both scalars in one order");
        check_value(&mut tally, &r.name, r.what, &r.value, &f.value);
    }
    let refs = batch_references(references, &batches, &thetas[0], mode);
    check_batches(&mut tally, mode, &ds, &tangents, &refs, TANGENT_TOLERANCE);
    tally
}
