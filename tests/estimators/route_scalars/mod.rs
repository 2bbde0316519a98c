//! The contract of `routes` in other scalars: every route to the causal estimate of eq. 3.15 that
//! compiles for a scalar, on f64 trajectories lifted to it exactly, against a reference built
//! from `Policy`'s in-place methods in that scalar and the sums of eq. 3.15 written out
//! (math.md §1.1, §4): an exact or rigorous check where the scalar is exact or encloses
//! (rationals, intervals), a tolerance against such a reference where it rounds (f32, the
//! tangents of duals over f64), and bit-for-bit equalities where the rounding is `routes`'.
//!
//! Every f64 is a dyadic rational, so a trajectory rolled out in f64 (features, actions, labels,
//! the absorbing tail's losses) and θ are represented exactly by [`BigRational`]s and by point
//! [`Interval`]s: the routes of every scalar then estimate the same real number.
//!
//! * [`BigRational`]: the linear-Gaussian policy (both action kinds), whose loss, score and
//!   log-ratio are rational functions (σ = 1/16). [`TaskProblem`] and [`Baselined`] need a
//!   [`Real`](ilopt::scalar::Real) scalar, so only the policy's kernel routes run; each must
//!   equal the exact reference.
//! * [`Interval`] without the `mpfr` feature: the same kernel routes of the linear-Gaussian and
//!   speed-limited policies (no `exp`/`ln` needed).
//! * [`Interval`] with the `mpfr` feature: every policy, every problem-level route over a task
//!   that carries the lifted trajectories' types ([`Lifted`]), the kernel routes, and
//!   [`Baselined`] with every baseline kind. Each enclosure must contain the exact value where
//!   it is known (the linear-Gaussian policies' rational reference, for every quantity without
//!   an `exp`), else intersect the interval reference (both enclose the same real number); the
//!   f64 route's value must lie within [`TOLERANCE`] of the enclosure.
//! * f32: every policy, every problem-level route, the kernel routes and [`Baselined`] with every
//!   kind, on the f64 trajectories and θ rounded to f32 (whose values every scalar holds
//!   exactly). Each value must lie within [`F32_TOLERANCE`] of the interval reference (relative
//!   to the quantity's largest magnitude), and every route that `routes` asserts bit for bit in
//!   f64 must equal, bit for bit, the reference formed in f32 in that route's order
//!   ([`SAME_ORDER`]). Without `mpfr` the policies whose terms need `exp` (and the weighted
//!   estimates towards another θ) have no interval reference: their routes run with the
//!   bit-for-bit checks only.
//! * `Dual<f64>`: the same routes, θ seeded along a fixed dyadic direction ([`dual_theta`]). The
//!   value parts must equal the f64 routes' values on the same inputs bit for bit (but the score
//!   products' `v·ψ_i` over at least [`DOT_LANES_FROM`] entries: f64's `dot` sums those in
//!   lanes, the duals' left to right, so that they are compared within [`TOLERANCE`]); the
//!   tangents must lie within [`TANGENT_TOLERANCE`] of the tangent of the reference in duals over
//!   intervals (with the same gaps as f32 without `mpfr`).
//!
//! The f32 and dual references are intervals, not rationals, for the linear-Gaussian policies
//! too: their checks are tolerances, which an enclosure below [`MAX_WIDTH`] serves as well, and
//! rational (dual) references would cost seconds per instance.
//!
//! The fixed horizons are `routes`' ([`STEPS`]) but the MLP-Gaussian policy's, shortened to
//! [`LONG_STEPS`] for the intervals' cost; the enclosures stay below 10⁻⁹ of their size.
//!
//! The failure tests feed the same comparisons, on the same trajectories, the reference with the
//! last decision's loss scaled by `1 + 2⁻ᵉ`, and require every comparison of a quantity that
//! loss enters to fail: e = 40 in rationals, 30 for the intervals' kernel routes (containment
//! of the exact value), 20 for the problem-level routes (where the reference is itself an
//! enclosure, so that a wrong value is seen only when the two enclosures are disjoint), 20 for
//! the dual tangents, and 0 (the loss doubled) for f32, at the roll-out's θ only (at the other
//! θ the last loss is too small a part of the sums it enters). The bit-for-bit checks (f32 against its
//! own reference, dual values against f64) are fed the same value with its first entry one unit
//! in the last place off, and must fail.

use ilopt::baseline::{Baseline, Baselined, PerDecisionTerms, baselined_estimate};
use ilopt::oracle::{Baselines, EstimatorKernel, ScoreProducts};
use ilopt::oracle::{DecisionTerms, Given, RecordedPass};
use ilopt::policy::{
    ActionVector, LikelihoodRatio, LinearGaussian, Logistic, Mlp, MlpGaussian, MlpSoftmax, Softmax,
    SpeedLimitedGaussian,
};
use ilopt::problem::{Behaviour, Cost, IlProblem, KitRng};
use ilopt::problem::{EstimatorForm, OracleError, Weighting};
use ilopt::scalar::{BigRational, Interval, Scalar, interval_contains_rational};
use ilopt::scalar::{DOT_LANES_FROM, Dual, Real};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, Task, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use std::borrow::Borrow;
use std::cell::RefCell;
use std::fmt::Debug;
use std::marker::PhantomData;

mod lifted_instances;
#[cfg(feature = "mpfr")]
mod mpfr_instances;
mod policies;
mod problem_level;
mod rounded;

use super::routes::{Terms, plain_with, terms};
use lifted_instances::*;
#[cfg(feature = "mpfr")]
use mpfr_instances::*;
use policies::*;
#[cfg(feature = "mpfr")]
use problem_level::check_interval_problem;
use problem_level::{baselined_routes, batch_reference, kinds, known, problem_routes};
use rounded::*;

/// Decisions of a fixed-horizon stream (the absorbing tail follows an episode that ends sooner).
const STEPS: usize = 40;

/// Decisions of the MLP-Gaussian policy's fixed-horizon streams: its episodes outlast [`STEPS`]
/// (`routes` runs 600; 200 keep the interval instance within a second or two).
const LONG_STEPS: usize = 200;

/// The θ the kernel-only instances estimate at: the roll-out's. The kernel routes take no
/// second θ, and the Gaussian policies note nothing when they sample, so another θ exercises
/// nothing more there, while every rational decision costs milliseconds (the exact sums'
/// denominators run to hundreds of bits). The problem-level instances estimate at both.
const KERNEL_THETAS: usize = 1;

/// The seeds of the trajectories rolled out per instance: on the
/// obstacle task at a fixed horizon of [`STEPS`], one trajectory that runs to the horizon and
/// two whose episodes end before it (an absorbing tail, or a reset); episodic, one long episode
/// and two short ones.
const SEEDS: [u64; 3] = [2, 5, 7];

/// Trajectories per batch and batches per baseline kind (as `routes`).
const M: usize = 2;
const BATCHES: usize = 3;

/// σ_π of the Gaussian policies: dyadic, so that σ² and the score's division are exact in
/// rationals.
const SIGMA: f64 = 1.0 / 16.0;

/// How far an f64 route's value may lie from the interval enclosure of the same route, relative
/// to `1 +` the enclosure's largest magnitude: twice `routes`' tolerance between two summation
/// orders of up to 600 terms, for the f64 rounding of the terms themselves (and of the weights'
/// `exp`) that the enclosure does not share.
const TOLERANCE: f64 = 4.0 * 600.0 * f64::EPSILON;

/// The widest enclosure accepted, relative to `1 +` its magnitude: wider, it would hide the
/// kernel failure tests' perturbation (2⁻³⁰ ≈ 10⁻⁹ of one loss).
const MAX_WIDTH: f64 = 1e-9;

/// The perturbation of the rational failure tests: one decision's loss times `1 + 2⁻⁴⁰` (any
/// change fails an exact comparison; this one is far below any f64 tolerance).
const RATIONAL_PERTURBATION: u32 = 40;

/// The perturbation of the interval failure tests of the kernel routes, `1 + 2⁻³⁰`: the
/// enclosures are up to about 10⁻¹¹ wide (relative), which hides a change of one loss by 2⁻⁴⁰.
const KERNEL_PERTURBATION: u32 = 30;

/// The perturbation of the interval failure tests of the problem-level routes, `1 + 2⁻²⁰`:
/// where the reference is itself an enclosure (the weights towards another θ, every policy but
/// the linear-Gaussian one), a wrong value is seen only when the two enclosures are disjoint,
/// and the estimates weighted along a trajectory are up to 10⁶ in size.
#[cfg(feature = "mpfr")]
const PROBLEM_PERTURBATION: u32 = 20;

/// `x` exactly, in a scalar that holds every finite f64 (rationals, intervals, f64).
fn exact<S: Scalar>(x: f64) -> S {
    S::from_binary64(x).expect("a finite f64")
}

/// The baseline `b_i = 1/4 + i/128` of the shifted routes for scored decisions (`i < scored`),
/// 0 after: dyadic, so the same real number in every scalar.
fn shift_baseline<S: Scalar>(i: usize, scored: usize) -> S {
    if i < scored {
        S::from_ratio(32 + i as i64, 128)
    } else {
        S::zero()
    }
}

/// The per-step losses `losses` (the absorbing tail's last, if any) shifted by
/// [`shift_baseline`]: `(l_t + b_t) − b_{t−1}` as the recorded routes here shift them, or,
/// `grouped`, `l_t + (b_t − b_{t−1})` as `baselined_estimate` does (b_{−1} = 0).
fn shifted<'a, S: Scalar + 'a>(
    losses: impl Iterator<Item = &'a S>,
    scored: usize,
    grouped: bool,
) -> Vec<S> {
    let b = |i: usize| shift_baseline::<S>(i, scored);
    losses
        .enumerate()
        .map(|(i, l)| {
            let before = if i == 0 { S::zero() } else { b(i - 1) };
            if grouped {
                l.clone() + (b(i) - before)
            } else {
                l.clone() + b(i) - before
            }
        })
        .collect()
}

/// A task that only names a scalar's label and action types: the problem-level routes estimate
/// from lifted trajectories and never roll out, so that a [`TaskProblem`] over intervals exists
/// for tasks implemented in f64 only (the obstacle task).
#[derive(Debug)]
struct Lifted<L, A>(PhantomData<fn() -> (L, A)>);

impl<L, A> Clone for Lifted<L, A> {
    fn clone(&self) -> Self {
        Lifted(PhantomData)
    }
}

impl<L, A> Lifted<L, A> {
    fn new() -> Self {
        Lifted(PhantomData)
    }
}

impl<S: Scalar, L: Clone + Debug, A: Clone + Debug> Task<S> for Lifted<L, A> {
    type Episode = ();
    type Label = L;
    type Action = A;

    fn start(&self, _: &mut KitRng) -> Result<(), OracleError> {
        Err(OracleError::Environment(
            "lifted trajectories only: no roll-outs".into(),
        ))
    }
    fn features(&self, _: &()) -> Vec<S> {
        unreachable!("no roll-outs")
    }
    fn expert(&self, _: &()) -> Result<(L, A), OracleError> {
        unreachable!("no roll-outs")
    }
    fn advance(&self, _: &mut (), _: &A) -> Result<bool, OracleError> {
        unreachable!("no roll-outs")
    }
}

/// An f64 trajectory with every value mapped by `value` (features, the absorbing tail's losses),
/// labels and actions by `label` and `action`, and the resets kept.
fn map_trajectory<S: Scalar, L, A, L2, A2>(
    t: &TaskTrajectory<f64, L, A>,
    value: &dyn Fn(f64) -> S,
    label: &dyn Fn(&L) -> L2,
    action: &dyn Fn(&A) -> A2,
) -> TaskTrajectory<S, L2, A2> {
    let features = t
        .features()
        .iter()
        .map(|row| row.iter().map(|&x| value(x)).collect())
        .collect();
    let mut out = TaskTrajectory::from_parts(
        features,
        t.actions.iter().map(action).collect(),
        t.labels.iter().map(label).collect(),
    )
    .unwrap();
    out.absorbed = t.absorbed.map(value);
    out.resets = t.resets;
    out
}

/// An f64 trajectory in the scalar `S`, exactly: features, the absorbing tail's losses, labels
/// and actions (through `label` and `action`), and the resets.
fn lift<S: Scalar, L, A, L2, A2>(
    t: &TaskTrajectory<f64, L, A>,
    label: &dyn Fn(&L) -> L2,
    action: &dyn Fn(&A) -> A2,
) -> TaskTrajectory<S, L2, A2> {
    map_trajectory(t, &exact, label, action)
}

/// The problem of `policy` over the [`Lifted`] task with the labels `L` and actions `A` of
/// lifted trajectories, at `horizon`.
fn lifted<L, A, P>(policy: P, horizon: Horizon) -> TaskProblem<Lifted<L, A>, P> {
    TaskProblem {
        task: Lifted::new(),
        policy,
        horizon,
    }
}

fn lift_theta<S: Scalar>(theta: &DVector<f64>) -> DVector<S> {
    theta.map(exact)
}

/// An f64 vector action or label lifted entry by entry.
fn lift_vec<S: Scalar, V: Borrow<[f64]>>(v: &V) -> Vec<S> {
    v.borrow().iter().map(|&x| exact(x)).collect()
}

fn lift_pair<S: Scalar>(v: &[f64; 2]) -> [S; 2] {
    v.map(exact)
}

/// What a route estimates, for one trajectory at one θ (the reference of each: [`want`]).
/// The weighted forms and eq. 3.16 are estimated by problem-level routes only (`mpfr`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Want {
    /// Eq. 3.15 unweighted, no baseline.
    Plain,
    /// Eq. 3.16.
    Full,
    /// `L_abs + Σ_t l_t` (one entry).
    Loss,
    /// `l_t` per decision.
    Losses,
    /// Eq. 3.15 with the per-decision prefix weights towards the other θ.
    PerDecision,
    /// Eq. 3.15 times the trajectory's weight towards the other θ.
    Trajectory,
    /// Eq. 3.15 with the baseline [`shift_baseline`].
    Baselined,
    /// `v·ψ_i` per scored decision, v the plain estimate.
    Cross,
    /// `‖ψ_i‖²` per scored decision.
    Moment,
}

/// `Σ_t [w_{1:t−1} ∇l_t + w_{1:t−1} l_t Σ_{i<t} ψ_i] + w_{1:n} L_abs Σ_{i≤n} ψ_i
/// − Σ_{i<s} w_{1:i} b_i ψ_i` with `w_{1:i} = exp(Σ_{j≤i} log-ratio_j)` (`exp` given) or every
/// weight 1 (`None`), as `routes`' reference.
#[allow(clippy::needless_range_loop)] // the sums' indices, as written
fn reference<S: Scalar>(
    t: &Terms<S>,
    exp: Option<&dyn Fn(&S) -> S>,
    b: &dyn Fn(usize) -> S,
) -> Vec<S> {
    let d = t.grads.first().map_or(0, Vec::len);
    let n = t.losses.len();
    let (mut g, mut score_sum) = (vec![S::zero(); d], vec![S::zero(); d]);
    let mut log_w = S::zero();
    let mut w = S::one();
    for step in 0..n {
        let wl = w.clone() * &t.losses[step];
        for j in 0..d {
            g[j] += w.clone() * &t.grads[step][j] + wl.clone() * &score_sum[j];
        }
        for j in 0..d {
            score_sum[j] += &t.scores[step][j];
        }
        if step < t.scored {
            log_w += &t.log_ratios[step];
            if let Some(exp) = exp {
                w = exp(&log_w);
            }
            let c = w.clone() * b(step);
            for j in 0..d {
                g[j] -= c.clone() * &t.scores[step][j];
            }
        }
    }
    if let Some(tail) = &t.tail {
        for j in 0..d {
            g[j] += w.clone() * tail * &score_sum[j];
        }
    }
    g
}

/// The reference of `what` from the terms; `exp` is the scalar's exponential where it has one.
/// `None` where the value needs an `exp` the scalar lacks (a weight towards another θ).
#[allow(clippy::needless_range_loop)] // the sums' indices, as written
fn want<S: Scalar>(what: Want, t: &Terms<S>, exp: Option<&dyn Fn(&S) -> S>) -> Option<Vec<S>> {
    let none = |_: usize| S::zero();
    let b = |i: usize| shift_baseline::<S>(i, t.scored);
    let total = || {
        t.losses
            .iter()
            .fold(t.tail.clone().unwrap_or_else(S::zero), |a, l| a + l)
    };
    Some(match what {
        Want::Plain => reference(t, None, &none),
        Want::Baselined => reference(t, None, &b),
        Want::PerDecision => reference(t, Some(exp?), &none),
        Want::Trajectory => {
            let log_w = t.log_ratios[..t.scored]
                .iter()
                .fold(S::zero(), |a, x| a + x);
            let w = exp?(&log_w);
            reference(t, None, &none)
                .into_iter()
                .map(|x| x * &w)
                .collect()
        }
        Want::Full => {
            let d = t.grads.first().map_or(0, Vec::len);
            let total = total();
            let mut g = vec![S::zero(); d];
            for step in 0..t.losses.len() {
                for j in 0..d {
                    g[j] += &t.grads[step][j];
                    if step < t.scored {
                        g[j] += total.clone() * &t.scores[step][j];
                    }
                }
            }
            g
        }
        Want::Loss => vec![total()],
        Want::Losses => t.losses.clone(),
        Want::Cross => {
            let v = reference(t, None, &none);
            t.scores[..t.scored]
                .iter()
                .map(|psi| {
                    v.iter()
                        .zip(psi)
                        .fold(S::zero(), |a, (x, y)| a + x.clone() * y)
                })
                .collect()
        }
        Want::Moment => t.scores[..t.scored]
            .iter()
            .map(|psi| psi.iter().fold(S::zero(), |a, x| a + x.clone() * x))
            .collect(),
    })
}

/// The references of one trajectory at one θ ([`want`] of its terms), each formed once.
struct Wants<'a, S> {
    terms: Terms<S>,
    exp: Option<&'a dyn Fn(&S) -> S>,
    formed: RefCell<Vec<(Want, Option<Vec<S>>)>>,
}

impl<'a, S: Scalar> Wants<'a, S> {
    fn new(terms: Terms<S>, exp: Option<&'a dyn Fn(&S) -> S>) -> Self {
        Wants {
            terms,
            exp,
            formed: RefCell::new(vec![]),
        }
    }

    fn get(&self, what: Want) -> Option<Vec<S>> {
        let mut formed = self.formed.borrow_mut();
        if let Some((_, w)) = formed.iter().find(|(x, _)| *x == what) {
            return w.clone();
        }
        let w = want(what, &self.terms, self.exp);
        formed.push((what, w.clone()));
        w
    }
}

/// The terms with the last decision's loss times `1 + 2⁻ᵉ`: the loss that weighs the longest
/// sum of scores `Σ_{i<n} ψ_i`, with the latest per-decision weight `w_{1:n−1}` (a loss early
/// in a trajectory is drowned in an estimate whose weights grow along it).
fn perturbed<S: Scalar>(t: &Terms<S>, e: u32) -> Terms<S> {
    let mut t = t.clone();
    let k = t.losses.len() - 1;
    let one_plus = S::from_ratio((1 << e) + 1, 1 << e);
    t.losses[k] *= one_plus;
    t
}

/// One route's output, named, with what it estimates.
struct Route<S> {
    name: String,
    what: Want,
    value: Vec<S>,
}

fn route<S>(name: impl Into<String>, what: Want, value: Vec<S>) -> Route<S> {
    Route {
        name: name.into(),
        what,
        value,
    }
}

/// The policy's kernel routes on one trajectory at θ, in any scalar: the causal sum with its
/// loss, the records summed with the recorded losses (and the tail) and with the
/// baselined losses `l'_t = l_t + b_t − b_{t−1}` (the tail's `L_abs − b_{n−1}`), and the score
/// products with `b_i` given (`g = v − Σ_{i<s} b_i ψ_i`, `v·ψ_i`, `‖ψ_i‖²`).
fn kernel_routes<S, P, L>(
    policy: &P,
    theta: &[S],
    t: &TaskTrajectory<S, L, P::Action>,
) -> Vec<Route<S>>
where
    S: Scalar,
    P: EstimatorKernel<S>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let n = t.len();
    let tail = t.absorbed.as_ref();
    let scored = if tail.is_some() { n } else { n - 1 };
    let labels: Vec<&P::Label> = t.labels.iter().map(Borrow::borrow).collect();
    let mut out = vec![];
    let (mut g, mut scratch) = (vec![S::zero(); d], vec![]);
    let mut loss = tail.cloned().unwrap_or_else(S::zero);
    policy
        .causal_sum_validated(
            theta,
            t.feature_data(),
            None,
            &labels,
            &t.actions,
            tail,
            &mut g,
            Some(&mut loss),
            &mut scratch,
        )
        .unwrap();
    out.push(route("causal_sum_validated", Want::Plain, g.clone()));
    out.push(route("causal_sum_validated loss", Want::Loss, vec![loss]));
    let (mut losses, mut records) = (vec![], vec![]);
    policy
        .record_validated(
            theta,
            t.feature_data(),
            None,
            &labels,
            &t.actions,
            &mut losses,
            &mut records,
        )
        .unwrap();
    out.push(route(
        "record_validated losses",
        Want::Losses,
        losses.clone(),
    ));
    let mut with_tail = losses.clone();
    with_tail.extend(tail.cloned());
    let mut acc = vec![S::zero(); d];
    policy.accumulate_recorded(
        t.feature_data(),
        &records,
        &with_tail,
        &mut acc,
        &mut scratch,
    );
    out.push(route(
        "record_validated + accumulate_recorded",
        Want::Plain,
        acc,
    ));
    let shifted = shifted(losses.iter().chain(tail), scored, false);
    let mut acc = vec![S::zero(); d];
    policy.accumulate_recorded(t.feature_data(), &records, &shifted, &mut acc, &mut scratch);
    out.push(route(
        "record_validated + accumulate_recorded, shifted losses",
        Want::Baselined,
        acc,
    ));
    let given: Vec<S> = (0..scored)
        .map(|i| shift_baseline::<S>(i, scored))
        .collect();
    let (mut cross, mut moment) = (vec![S::zero(); scored], vec![S::zero(); scored]);
    let mut corrected = g.clone();
    policy.score_products(
        t.feature_data(),
        &records,
        ScoreProducts {
            v: &g,
            baseline: Baselines::Given(&given),
            cross: &mut cross,
            moment: &mut moment,
            g: &mut corrected,
        },
    );
    out.push(route("score_products g", Want::Baselined, corrected));
    out.push(route("score_products cross", Want::Cross, cross));
    out.push(route("score_products moment", Want::Moment, moment));
    out
}

/// The outcome of one comparison: `Err` names the route and the entry that failed.
type Check = Result<(), String>;

fn lengths<A, B>(name: &str, got: &[A], want: &[B]) -> Check {
    if got.len() == want.len() {
        Ok(())
    } else {
        Err(format!(
            "{name}: {} entries, want {}",
            got.len(),
            want.len()
        ))
    }
}

/// Exact equality with the rational reference.
fn equal(name: &str, got: &[BigRational], want: &[BigRational]) -> Check {
    lengths(name, got, want)?;
    match got.iter().zip(want).position(|(a, b)| a != b) {
        None => Ok(()),
        Some(j) => Err(format!("{name}: entry {j}: {} != {}", got[j], want[j])),
    }
}

/// Every enclosure contains the exact value.
fn contains(name: &str, got: &[Interval], want: &[BigRational]) -> Check {
    lengths(name, got, want)?;
    match got
        .iter()
        .zip(want)
        .position(|(x, q)| !interval_contains_rational(*x, q))
    {
        None => Ok(()),
        Some(j) => Err(format!(
            "{name}: entry {j}: {:?} excludes {}",
            got[j],
            Scalar::to_f64(&want[j])
        )),
    }
}

/// Every enclosure meets the reference's enclosure of the same real number.
fn meets(name: &str, got: &[Interval], want: &[Interval]) -> Check {
    lengths(name, got, want)?;
    match got
        .iter()
        .zip(want)
        .position(|(x, y)| x.intersection(*y).is_empty())
    {
        None => Ok(()),
        Some(j) => Err(format!(
            "{name}: entry {j}: {:?} and the reference {:?} are disjoint",
            got[j], want[j]
        )),
    }
}

/// Every f64 value lies within [`TOLERANCE`] (relative to `1 +` the largest magnitude) of the
/// enclosure of the same route.
fn near(name: &str, got: &[f64], enclosure: &[Interval]) -> Check {
    lengths(name, got, enclosure)?;
    let scale = 1.0 + enclosure.iter().fold(0.0f64, |m, x| m.max(x.mag()));
    for (j, (x, e)) in got.iter().zip(enclosure).enumerate() {
        let distance = if *x < e.inf() {
            e.inf() - x
        } else if *x > e.sup() {
            x - e.sup()
        } else {
            0.0
        };
        if distance.is_nan() || distance > TOLERANCE * scale {
            return Err(format!(
                "{name}: entry {j}: f64 {x} is {distance} from {e:?} (scale {scale})"
            ));
        }
    }
    Ok(())
}

/// The largest width of the enclosures relative to `1 +` their magnitude.
fn relative_width(xs: &[Interval]) -> f64 {
    xs.iter()
        .fold(0.0f64, |m, x| m.max(x.wid() / (1.0 + x.mag())))
}

/// Whether the checks run against the reference (every comparison must pass) or against a
/// perturbed one (every comparison of a route that reads the perturbed loss must fail).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    Reference,
    /// One decision's loss times `1 + 2⁻ᵉ` ([`perturbed`]).
    Perturbed(u32),
}

impl Mode {
    /// The terms the reference is built from in this mode.
    fn apply<S: Scalar>(self, t: Terms<S>) -> Terms<S> {
        match self {
            Mode::Reference => t,
            Mode::Perturbed(e) => perturbed(&t, e),
        }
    }
}

/// Tallies of one instance: comparisons made, failures seen in [`Mode::Perturbed`], and the
/// widest enclosure.
#[derive(Debug, Default)]
struct Tally {
    checks: usize,
    rejected: usize,
    width: f64,
    /// The largest distance of an f32 value or a dual tangent from its reference, relative to
    /// the quantity's scale.
    worst: f64,
    /// Perturbed, the least such distance of a quantity (its largest over the entries).
    least: Option<f64>,
    /// Dual values compared within [`TOLERANCE`] rather than bit for bit: the score products'
    /// `v·ψ_i` over at least [`DOT_LANES_FROM`] entries, which f64 sums in lanes.
    in_lanes: usize,
}

impl Tally {
    /// Record one comparison: in [`Mode::Reference`] it must pass; in [`Mode::Perturbed`] (made
    /// only for quantities the perturbed loss enters: [`reads_loss`]) it must fail.
    #[track_caller]
    fn record(&mut self, mode: Mode, name: &str, check: Check) {
        self.checks += 1;
        match (mode, check) {
            (Mode::Reference, Err(e)) => panic!("{e}"),
            (Mode::Perturbed(_), Ok(())) => panic!("{name}: a perturbed reference passed"),
            (Mode::Perturbed(_), Err(_)) => self.rejected += 1,
            (Mode::Reference, Ok(())) => {}
        }
    }
}

/// Whether the perturbation of one decision's loss changes the quantity: every one but the
/// scores' squared norms.
fn reads_loss(what: Want) -> bool {
    !matches!(what, Want::Moment)
}

/// The rational instance: the kernel routes of a rational policy on every lifted trajectory,
/// at both θ, equal to the exact reference (or, perturbed, different from it).
fn check_rational<T, P, PQ, LQ, AQ>(
    p: &mut TaskProblem<T, P>,
    pq: &PQ,
    thetas: &[DVector<f64>; 2],
    label: &dyn Fn(&T::Label) -> LQ,
    action: &dyn Fn(&T::Action) -> AQ,
    mode: Mode,
) -> Tally
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
    PQ: LikelihoodRatio<BigRational, Action = AQ> + EstimatorKernel<BigRational>,
    LQ: Borrow<PQ::Label>,
{
    let mut tally = Tally::default();
    for (seed, t) in SEEDS.into_iter().zip(rollouts(p, &thetas[0])) {
        let tq = lift::<BigRational, _, _, _, _>(&t, label, action);
        for k in 0..KERNEL_THETAS {
            let (th, other) = (lift_theta(&thetas[k]), lift_theta(&thetas[1 - k]));
            let x = Wants::new(
                mode.apply(terms(pq, th.as_slice(), other.as_slice(), &tq)),
                None,
            );
            for r in kernel_routes(pq, th.as_slice(), &tq) {
                let w = x.get(r.what).unwrap();
                let name = format!("seed {seed}, θ{k}: {}", r.name);
                if mode == Mode::Reference || reads_loss(r.what) {
                    tally.record(mode, &name, equal(&name, &r.value, &w));
                }
            }
        }
    }
    tally
}

/// The learner's roll-outs at θ, one per seed of [`SEEDS`]; on a fixed horizon whose early ends
/// absorb, at least one of them absorbs.
fn rollouts<T, P>(p: &mut TaskProblem<T, P>, theta: &DVector<f64>) -> Vec<Trajectory64<T>>
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let mut cost = Cost::default();
    let ts: Vec<_> = SEEDS
        .iter()
        .map(|&seed| {
            let mut rng = KitRng::seed_from_u64(seed);
            p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .unwrap()
        })
        .collect();
    if matches!(
        p.horizon,
        Horizon::Fixed {
            after_end: AfterEnd::Absorb,
            ..
        }
    ) {
        assert!(
            ts.iter().any(|t| t.absorbed.is_some()),
            "no absorbing tail among the trajectories"
        );
    }
    ts
}

/// A trajectory of the task `T` in `S`.
type Trajectory<S, T> = TaskTrajectory<S, <T as Task<S>>::Label, <T as Task<S>>::Action>;

/// An f64 trajectory of the task `T`.
type Trajectory64<T> = TaskTrajectory<f64, <T as Task<f64>>::Label, <T as Task<f64>>::Action>;

/// The exact terms of an f64 trajectory at θ towards θ_new, from a rational policy.
type ExactTerms<'a, T> =
    dyn Fn(&Trajectory64<T>, &DVector<f64>, &DVector<f64>) -> Terms<BigRational> + 'a;

/// [`ExactTerms`] of the rational policy `pq`, the trajectory lifted by `label` and `action`.
fn exact_terms<'a, T, PQ, LQ, AQ>(
    pq: &'a PQ,
    label: &'a dyn Fn(&T::Label) -> LQ,
    action: &'a dyn Fn(&T::Action) -> AQ,
) -> impl Fn(&Trajectory64<T>, &DVector<f64>, &DVector<f64>) -> Terms<BigRational> + 'a
where
    T: Task<f64>,
    PQ: LikelihoodRatio<BigRational, Action = AQ>,
    LQ: Borrow<PQ::Label>,
{
    move |t, theta, theta_new| {
        let tq = lift::<BigRational, _, _, _, _>(t, label, action);
        terms(
            pq,
            lift_theta(theta).as_slice(),
            lift_theta(theta_new).as_slice(),
            &tq,
        )
    }
}

/// The references of one trajectory at one θ for the interval checks: the exact terms where the
/// policy is rational, the interval terms, and the intervals' `exp` where the scalar has one.
struct IntervalRefs<'a> {
    exact: Option<Wants<'a, BigRational>>,
    interval: Wants<'a, Interval>,
}

/// One interval route against its references: containment of the exact value where the
/// rational reference has it, else a common point with the interval reference; the f64 route of
/// the same name within [`TOLERANCE`] of the enclosure (against the reference only).
fn check_interval_route(
    tally: &mut Tally,
    mode: Mode,
    refs: &IntervalRefs<'_>,
    r: &Route<Interval>,
    f: &Route<f64>,
    context: &str,
) {
    assert_eq!(r.name, f.name, "the routes of both scalars in one order");
    tally.width = tally.width.max(relative_width(&r.value));
    let name = format!("{context}: {}", r.name);
    if matches!(mode, Mode::Perturbed(_)) && !reads_loss(r.what) {
        return;
    }
    let exact = refs.exact.as_ref().and_then(|x| x.get(r.what));
    let check = match exact {
        Some(q) => contains(&name, &r.value, &q),
        None => {
            let w = refs.interval.get(r.what).expect("a reference in intervals");
            meets(&name, &r.value, &w)
        }
    };
    tally.record(mode, &name, check);
    if mode == Mode::Reference {
        tally.record(mode, &name, near(&name, &f.value, &r.value));
    }
}

/// The interval instance without the `mpfr` feature: the kernel routes of an interval policy
/// (one that needs no `exp`) on every lifted trajectory at both θ, against the exact reference
/// (`exact`) or the interval reference, and the f64 policy's kernel routes near them.
#[allow(clippy::too_many_arguments)] // the problem, the lifted policy and its lifts
fn check_interval_kernel<T, P, PI, LI, AI>(
    p: &mut TaskProblem<T, P>,
    pi: &PI,
    thetas: &[DVector<f64>; 2],
    label: &dyn Fn(&T::Label) -> LI,
    action: &dyn Fn(&T::Action) -> AI,
    exact: Option<&ExactTerms<'_, T>>,
    mode: Mode,
) -> Tally
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
    PI: LikelihoodRatio<Interval, Action = AI> + EstimatorKernel<Interval>,
    LI: Borrow<PI::Label>,
{
    let mut tally = Tally::default();
    for (seed, t) in SEEDS.into_iter().zip(rollouts(p, &thetas[0])) {
        let ti = lift::<Interval, _, _, _, _>(&t, label, action);
        for k in 0..KERNEL_THETAS {
            let (th, other) = (lift_theta(&thetas[k]), lift_theta(&thetas[1 - k]));
            let refs = IntervalRefs {
                exact: exact
                    .map(|e| Wants::new(mode.apply(e(&t, &thetas[k], &thetas[1 - k])), None)),
                interval: Wants::new(
                    mode.apply(terms(pi, th.as_slice(), other.as_slice(), &ti)),
                    None,
                ),
            };
            let fs = kernel_routes(&p.policy, thetas[k].as_slice(), &t);
            let is = kernel_routes(pi, th.as_slice(), &ti);
            for (r, f) in is.iter().zip(&fs) {
                let context = format!("seed {seed}, θ{k}");
                check_interval_route(&mut tally, mode, &refs, r, f, &context);
            }
        }
    }
    tally
}

/// One test per instance (policy × scalar) × horizon kind: episodic; a fixed horizon whose
/// early ends absorb; one whose early ends reset. Every comparison must pass, and the interval
/// enclosures stay narrower than [`MAX_WIDTH`].
macro_rules! scalar_contract {
    ($($(#[$attr:meta])* $instance:ident: $episodic:ident, $absorbing:ident, $reset:ident;)*) => {$(
        $(#[$attr])*
        #[test]
        fn $episodic() {
            run(stringify!($episodic), $instance(None, Mode::Reference));
        }

        $(#[$attr])*
        #[test]
        fn $absorbing() {
            run(stringify!($absorbing), $instance(Some(AfterEnd::Absorb), Mode::Reference));
        }

        $(#[$attr])*
        #[test]
        fn $reset() {
            run(stringify!($reset), $instance(Some(AfterEnd::Reset), Mode::Reference));
        }
    )*};
}

/// The tally of one instance: some comparisons made, the enclosures narrow.
fn run(name: &str, tally: Tally) {
    eprintln!("{name}: {tally:?}");
    assert!(tally.checks > 0, "{name}: nothing compared");
    assert!(
        tally.width <= MAX_WIDTH,
        "{name}: enclosures {} wide",
        tally.width
    );
}

scalar_contract! {
    linear_gaussian_rational: linear_gaussian_rational_episodic, linear_gaussian_rational_fixed_absorbing, linear_gaussian_rational_fixed_reset;
    linear_gaussian_inline_rational: linear_gaussian_inline_rational_episodic, linear_gaussian_inline_rational_fixed_absorbing, linear_gaussian_inline_rational_fixed_reset;
    linear_gaussian_interval: linear_gaussian_interval_kernel_episodic, linear_gaussian_interval_kernel_fixed_absorbing, linear_gaussian_interval_kernel_fixed_reset;
    linear_gaussian_inline_interval: linear_gaussian_inline_interval_kernel_episodic, linear_gaussian_inline_interval_kernel_fixed_absorbing, linear_gaussian_inline_interval_kernel_fixed_reset;
    speed_limited_interval: speed_limited_interval_kernel_episodic, speed_limited_interval_kernel_fixed_absorbing, speed_limited_interval_kernel_fixed_reset;
    #[cfg(feature = "mpfr")]
    logistic_interval: logistic_interval_episodic, logistic_interval_fixed_absorbing, logistic_interval_fixed_reset;
    #[cfg(feature = "mpfr")]
    softmax_interval: softmax_interval_episodic, softmax_interval_fixed_absorbing, softmax_interval_fixed_reset;
    #[cfg(feature = "mpfr")]
    mlp_softmax_interval: mlp_softmax_interval_episodic, mlp_softmax_interval_fixed_absorbing, mlp_softmax_interval_fixed_reset;
    #[cfg(feature = "mpfr")]
    linear_gaussian_interval_problem: linear_gaussian_interval_episodic, linear_gaussian_interval_fixed_absorbing, linear_gaussian_interval_fixed_reset;
    #[cfg(feature = "mpfr")]
    linear_gaussian_inline_interval_problem: linear_gaussian_inline_interval_episodic, linear_gaussian_inline_interval_fixed_absorbing, linear_gaussian_inline_interval_fixed_reset;
    #[cfg(feature = "mpfr")]
    speed_limited_interval_problem: speed_limited_interval_episodic, speed_limited_interval_fixed_absorbing, speed_limited_interval_fixed_reset;
    #[cfg(feature = "mpfr")]
    mlp_gaussian_interval: mlp_gaussian_interval_episodic, mlp_gaussian_interval_fixed_absorbing, mlp_gaussian_interval_fixed_reset;
    linear_gaussian_f32: linear_gaussian_f32_episodic, linear_gaussian_f32_fixed_absorbing, linear_gaussian_f32_fixed_reset;
    linear_gaussian_inline_f32: linear_gaussian_inline_f32_episodic, linear_gaussian_inline_f32_fixed_absorbing, linear_gaussian_inline_f32_fixed_reset;
    speed_limited_f32: speed_limited_f32_episodic, speed_limited_f32_fixed_absorbing, speed_limited_f32_fixed_reset;
    logistic_f32: logistic_f32_episodic, logistic_f32_fixed_absorbing, logistic_f32_fixed_reset;
    softmax_f32: softmax_f32_episodic, softmax_f32_fixed_absorbing, softmax_f32_fixed_reset;
    mlp_softmax_f32: mlp_softmax_f32_episodic, mlp_softmax_f32_fixed_absorbing, mlp_softmax_f32_fixed_reset;
    mlp_gaussian_f32: mlp_gaussian_f32_episodic, mlp_gaussian_f32_fixed_absorbing, mlp_gaussian_f32_fixed_reset;
    linear_gaussian_dual: linear_gaussian_dual_episodic, linear_gaussian_dual_fixed_absorbing, linear_gaussian_dual_fixed_reset;
    linear_gaussian_inline_dual: linear_gaussian_inline_dual_episodic, linear_gaussian_inline_dual_fixed_absorbing, linear_gaussian_inline_dual_fixed_reset;
    speed_limited_dual: speed_limited_dual_episodic, speed_limited_dual_fixed_absorbing, speed_limited_dual_fixed_reset;
    logistic_dual: logistic_dual_episodic, logistic_dual_fixed_absorbing, logistic_dual_fixed_reset;
    softmax_dual: softmax_dual_episodic, softmax_dual_fixed_absorbing, softmax_dual_fixed_reset;
    mlp_softmax_dual: mlp_softmax_dual_episodic, mlp_softmax_dual_fixed_absorbing, mlp_softmax_dual_fixed_reset;
    mlp_gaussian_dual: mlp_gaussian_dual_episodic, mlp_gaussian_dual_fixed_absorbing, mlp_gaussian_dual_fixed_reset;
}

/// One failure test per instance: on a fixed horizon whose early ends absorb (the tail and
/// every kind of decision present), the reference with the last decision's loss times
/// `1 + 2⁻ᵉ` ([`perturbed`]; e per scalar and kind of route) must be rejected by every
/// comparison of a quantity that loss enters.
macro_rules! failure_demonstration {
    ($($(#[$attr:meta])* $instance:ident($e:expr): $test:ident;)*) => {$(
        $(#[$attr])*
        #[test]
        fn $test() {
            let tally = $instance(Some(AfterEnd::Absorb), Mode::Perturbed($e));
            eprintln!("{}: {tally:?}", stringify!($test));
            assert!(tally.rejected > 0 && tally.rejected == tally.checks, "{tally:?}");
        }
    )*};
}

failure_demonstration! {
    linear_gaussian_rational(RATIONAL_PERTURBATION): linear_gaussian_rational_rejects_a_perturbed_reference;
    linear_gaussian_inline_rational(RATIONAL_PERTURBATION): linear_gaussian_inline_rational_rejects_a_perturbed_reference;
    linear_gaussian_interval(KERNEL_PERTURBATION): linear_gaussian_interval_kernel_rejects_a_perturbed_reference;
    speed_limited_interval(KERNEL_PERTURBATION): speed_limited_interval_kernel_rejects_a_perturbed_reference;
    #[cfg(feature = "mpfr")]
    logistic_interval(PROBLEM_PERTURBATION): logistic_interval_rejects_a_perturbed_reference;
    #[cfg(feature = "mpfr")]
    softmax_interval(PROBLEM_PERTURBATION): softmax_interval_rejects_a_perturbed_reference;
    #[cfg(feature = "mpfr")]
    mlp_softmax_interval(PROBLEM_PERTURBATION): mlp_softmax_interval_rejects_a_perturbed_reference;
    #[cfg(feature = "mpfr")]
    linear_gaussian_interval_problem(PROBLEM_PERTURBATION): linear_gaussian_interval_rejects_a_perturbed_reference;
    #[cfg(feature = "mpfr")]
    speed_limited_interval_problem(PROBLEM_PERTURBATION): speed_limited_interval_rejects_a_perturbed_reference;
    #[cfg(feature = "mpfr")]
    mlp_gaussian_interval(PROBLEM_PERTURBATION): mlp_gaussian_interval_rejects_a_perturbed_reference;
    linear_gaussian_f32(F32_PERTURBATION): linear_gaussian_f32_rejects_a_perturbed_reference;
    linear_gaussian_inline_f32(F32_PERTURBATION): linear_gaussian_inline_f32_rejects_a_perturbed_reference;
    speed_limited_f32(F32_PERTURBATION): speed_limited_f32_rejects_a_perturbed_reference;
    logistic_f32(F32_PERTURBATION): logistic_f32_rejects_a_perturbed_reference;
    softmax_f32(F32_PERTURBATION): softmax_f32_rejects_a_perturbed_reference;
    mlp_softmax_f32(F32_PERTURBATION): mlp_softmax_f32_rejects_a_perturbed_reference;
    mlp_gaussian_f32(F32_PERTURBATION): mlp_gaussian_f32_rejects_a_perturbed_reference;
    linear_gaussian_dual(DUAL_PERTURBATION): linear_gaussian_dual_rejects_a_perturbed_reference;
    linear_gaussian_inline_dual(DUAL_PERTURBATION): linear_gaussian_inline_dual_rejects_a_perturbed_reference;
    speed_limited_dual(DUAL_PERTURBATION): speed_limited_dual_rejects_a_perturbed_reference;
    logistic_dual(DUAL_PERTURBATION): logistic_dual_rejects_a_perturbed_reference;
    softmax_dual(DUAL_PERTURBATION): softmax_dual_rejects_a_perturbed_reference;
    mlp_softmax_dual(DUAL_PERTURBATION): mlp_softmax_dual_rejects_a_perturbed_reference;
    mlp_gaussian_dual(DUAL_PERTURBATION): mlp_gaussian_dual_rejects_a_perturbed_reference;
}
