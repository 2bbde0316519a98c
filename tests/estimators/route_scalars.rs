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

/// An f64 trajectory in the scalar `S`, exactly: features, the absorbing tail's losses, labels
/// and actions (through `label` and `action`), and the resets.
fn lift<S: Scalar, L, A, L2, A2>(
    t: &TaskTrajectory<f64, L, A>,
    label: &dyn Fn(&L) -> L2,
    action: &dyn Fn(&A) -> A2,
) -> TaskTrajectory<S, L2, A2> {
    let features = t
        .features()
        .iter()
        .map(|row| row.iter().map(|&x| exact(x)).collect())
        .collect();
    let mut out = TaskTrajectory::from_parts(
        features,
        t.actions.iter().map(action).collect(),
        t.labels.iter().map(label).collect(),
    )
    .unwrap();
    out.absorbed = t.absorbed.map(exact);
    out.resets = t.resets;
    out
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

/// One trajectory's per-decision terms from the policy's in-place methods in `S`: losses, loss
/// gradients, scores, and the log-ratios `log π_θ(a|s) − log π_θnew(a|s)`; with the absorbing
/// tail's losses and the number of scored decisions (n − 1, or n with an absorbing tail).
#[derive(Clone)]
struct Terms<S> {
    losses: Vec<S>,
    grads: Vec<Vec<S>>,
    scores: Vec<Vec<S>>,
    log_ratios: Vec<S>,
    tail: Option<S>,
    scored: usize,
}

fn terms<S, P, L>(
    policy: &P,
    theta: &[S],
    theta_new: &[S],
    t: &TaskTrajectory<S, L, P::Action>,
) -> Terms<S>
where
    S: Scalar,
    P: LikelihoodRatio<S>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let n = t.len();
    let mut out = Terms {
        losses: vec![],
        grads: vec![],
        scores: vec![],
        log_ratios: vec![],
        tail: t.absorbed.clone(),
        scored: if t.absorbed.is_some() { n } else { n - 1 },
    };
    for ((phi, a), y) in t.feature_rows().zip(&t.actions).zip(&t.labels) {
        let (mut grad, mut score) = (vec![S::zero(); d], vec![S::zero(); d]);
        out.losses
            .push(policy.loss_into(theta, phi, y.borrow(), &mut grad).unwrap());
        policy.score_into(theta, phi, a, &mut score).unwrap();
        out.grads.push(grad);
        out.scores.push(score);
        out.log_ratios.push(
            policy
                .log_likelihood_ratio(theta, theta_new, phi, a)
                .unwrap(),
        );
    }
    out
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
    let b = |i: usize| shift_baseline::<S>(i, scored);
    let mut shifted: Vec<S> = losses
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let before = if i == 0 { S::zero() } else { b(i - 1) };
            l.clone() + b(i) - before
        })
        .collect();
    shifted.extend(tail.map(|l| l.clone() - b(n - 1)));
    let mut acc = vec![S::zero(); d];
    policy.accumulate_recorded(t.feature_data(), &records, &shifted, &mut acc, &mut scratch);
    out.push(route(
        "record_validated + accumulate_recorded, shifted losses",
        Want::Baselined,
        acc,
    ));
    let given: Vec<S> = (0..scored).map(b).collect();
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

/// The problem-level routes and the baselined oracle in any [`Real`] scalar, and the interval
/// instance over them (with the `mpfr` feature, through which intervals are [`Real`]).
mod problem_level {
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
        let shifted: Vec<S> = rec
            .losses()
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let before = if i == 0 { S::zero() } else { b(i - 1) };
                l.clone() + b(i) - before
            })
            .collect();
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
        let mut pint = TaskProblem {
            task: Lifted::<LI, AI>::new(),
            policy: pi,
            horizon: p.horizon,
        };
        let thetas_i = [lift_theta(&thetas[0]), lift_theta(&thetas[1])];
        let mut tally = Tally::default();
        let mut cost = Cost::default();
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
        let mut rng = KitRng::seed_from_u64(7);
        let batches: Vec<Vec<_>> = (0..BATCHES)
            .map(|_| {
                (0..M)
                    .map(|_| {
                        p.rollout(&Behaviour::Learner(&thetas[0]), &mut rng, &mut cost)
                            .unwrap()
                    })
                    .collect()
            })
            .collect();
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
}

#[cfg(feature = "mpfr")]
use problem_level::check_interval_problem;

use problem_level::{baselined_routes, batch_reference, kinds, known, problem_routes};

/// How far an f32 route's value may lie from the reference, relative to the largest magnitude in
/// the quantity's reference (per vector): as [`TOLERANCE`] in f64, twice `routes`' bound between
/// two summation orders of up to [`LONG_STEPS`] terms (each within `LONG_STEPS · ε₃₂` of the
/// exact sum relative to the terms' magnitudes), for the rounding of the terms themselves. The
/// estimates with leave-one-out baselines come closest (0.4 of it: the baselines cancel most of
/// the terms).
const F32_TOLERANCE: f64 = 4.0 * LONG_STEPS as f64 * f32::EPSILON as f64;

/// The same for the tangent of a dual route against the exact or enclosed tangent: as
/// [`TOLERANCE`], the tangent's own sums and products being of the value's length.
const TANGENT_TOLERANCE: f64 = TOLERANCE;

/// The perturbation of the f32 failure tests, `1 + 2⁰`: the last decision's loss is as little
/// as 3·10⁻⁴ of the trajectory's loss on these trajectories (the learner ends near the goal), so
/// that only doubling it moves every sum it enters by more than [`F32_TOLERANCE`] (about 10⁻⁴;
/// the least such move is 1.5 times that), at the roll-out's θ and but for the leave-one-out
/// estimates (where the other trajectory's baselines take up most of the change).
const F32_PERTURBATION: u32 = 0;

/// The perturbation of the dual failure tests' tangents, `1 + 2⁻²⁰`: as the interval
/// problem-level routes' ([`TANGENT_TOLERANCE`] is far below, the widest enclosure of a tangent
/// below [`MAX_WIDTH`]).
const DUAL_PERTURBATION: u32 = 20;

/// Where a reference quantity lies, entry by entry, in f64: `[lo, hi]`.
type Bounds = Vec<(f64, f64)>;

fn interval_bounds(x: &Interval) -> (f64, f64) {
    (x.inf(), x.sup())
}

/// A dual's tangent: its derivative along the one seeded direction.
fn tangent<R: Scalar>(x: &Dual<R>) -> R {
    x.gradient().first().cloned().unwrap_or_else(R::zero)
}

/// The quantities every reference forms per trajectory.
const WANTS: [Want; 9] = [
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
trait Reference<T: Task<f64>> {
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
struct InScalar<'a, T: Task<f64>, R> {
    terms: Box<TermsIn<'a, T, R>>,
    exp: Option<fn(&R) -> R>,
    bounds: fn(&R) -> (f64, f64),
}

/// The terms of an f64 trajectory at θ towards θ_new in `R`.
type TermsIn<'a, T, R> = dyn Fn(&Trajectory64<T>, &DVector<f64>, &DVector<f64>) -> Terms<R> + 'a;

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
fn reference_in<'a, T, R, PR, LR, AR>(
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
fn dual_theta<S: Scalar>(theta: &DVector<f64>) -> DVector<Dual<S>> {
    DVector::from_fn(theta.len(), |j, _| {
        let sign = if j % 2 == 0 { 1 } else { -1 };
        let u = S::from_ratio(sign * (j % 3 + 1) as i64, 8);
        Dual::new(exact(theta[j]), vec![u])
    })
}

/// Record whether every entry lies within `tolerance` of its bounds, relative to the largest
/// magnitude of the bounds (the quantity's scale); the largest relative distance of the entries
/// joins [`Tally::worst`] (against the reference) or [`Tally::least`] (perturbed).
fn within(tally: &mut Tally, mode: Mode, name: &str, got: &[f64], want: &Bounds, tolerance: f64) {
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
fn same_bits(name: &str, got: &[f64], want: &[f64]) -> Check {
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
fn bounds_width(b: &Bounds) -> f64 {
    b.iter().fold(0.0f64, |m, (lo, hi)| {
        m.max((hi - lo) / (1.0 + lo.abs().max(hi.abs())))
    })
}

/// One route's compared part (`got`: f32 values widened, or a dual's tangents) within
/// `tolerance` of the first reference that has its quantity (the references in order: exact,
/// then enclosures); nothing is compared where none has it.
fn check_bounds(
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
fn check_batches<X>(
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
fn batches<T, P>(p: &mut TaskProblem<T, P>, theta: &DVector<f64>) -> Vec<Vec<Trajectory64<T>>>
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
fn batch_references<T: Task<f64>>(
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
fn to_f32(x: f64) -> f64 {
    let y = x as f32;
    assert!(y.is_finite(), "{x} overflows f32");
    f64::from(y)
}

#[allow(clippy::ptr_arg)] // the obstacle task's label and action type
fn round_vec(v: &Vec<f64>) -> Vec<f64> {
    v.iter().map(|&x| to_f32(x)).collect()
}

fn round_pair(v: &[f64; 2]) -> [f64; 2] {
    v.map(to_f32)
}

/// An f64 trajectory with every value rounded to f32 (features, the tail's losses, labels and
/// actions through `label` and `action`): the f32 instance's inputs, exact in every scalar.
fn round_trajectory<T: Task<f64>>(
    t: &Trajectory64<T>,
    label: &dyn Fn(&T::Label) -> T::Label,
    action: &dyn Fn(&T::Action) -> T::Action,
) -> Trajectory64<T> {
    let features = t
        .features()
        .iter()
        .map(|row| row.iter().map(|&x| to_f32(x)).collect())
        .collect();
    let mut out = TaskTrajectory::from_parts(
        features,
        t.actions.iter().map(action).collect(),
        t.labels.iter().map(label).collect(),
    )
    .unwrap();
    out.absorbed = t.absorbed.map(to_f32);
    out.resets = t.resets;
    out
}

/// The reference order of a route that `routes` asserts bit for bit in f64: the plain pass
/// (`Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`, then the tail), a quantity of [`want`] formed in the
/// route's order (the full form, the losses and their sum, the weighted estimates), or the plain
/// pass with the losses shifted by the baseline as the recorded routes shift them
/// (`(l_t + b_t) − b_{t−1}`) or as `baselined_estimate` does (`l_t + (b_t − b_{t−1})`).
#[derive(Debug, Clone, Copy)]
enum Order {
    Plain,
    Want(Want),
    Shifted,
    ShiftedGiven,
}

/// The routes that `routes` asserts bit for bit in f64, with their order; the policy's records
/// summed with the shifted losses are the pass that `estimate_recorded` takes for the
/// problem's recorded pass.
const SAME_ORDER: [(&str, Order); 16] = [
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

/// `Σ_t [∇l_t + l'_t Σ_{i<t} ψ_i]`, then `l'_n Σ_{i≤n} ψ_i` for an (n + 1)-th loss: `routes`'
/// plain pass with the losses `l'`.
#[allow(clippy::needless_range_loop)] // the sums' indices, as written
fn plain_with<S: Scalar>(t: &Terms<S>, losses: &[S]) -> Vec<S> {
    let d = t.grads.first().map_or(0, Vec::len);
    let n = t.losses.len();
    let (mut g, mut score_sum) = (vec![S::zero(); d], vec![S::zero(); d]);
    for step in 0..n {
        for j in 0..d {
            g[j] += t.grads[step][j].clone() + losses[step].clone() * &score_sum[j];
        }
        for j in 0..d {
            score_sum[j] += &t.scores[step][j];
        }
    }
    if let Some(end) = losses.get(n) {
        for j in 0..d {
            g[j] += end.clone() * &score_sum[j];
        }
    }
    g
}

/// The losses and the tail shifted by [`shift_baseline`], `grouped` as `baselined_estimate`
/// groups them (`l + (b_t − b_{t−1})`), else as the routes here (`(l + b_t) − b_{t−1}`).
fn shifted_losses<S: Scalar>(t: &Terms<S>, grouped: bool) -> Vec<S> {
    let b = |i: usize| shift_baseline::<S>(i, t.scored);
    t.losses
        .iter()
        .chain(&t.tail)
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

/// The reference in `routes`' order of a route's quantity, from the terms in the route's scalar.
fn in_order<S: Real>(order: Order, t: &Terms<S>) -> Vec<S> {
    let exp = |x: &S| x.exp();
    match order {
        Order::Plain => {
            let mut losses = t.losses.clone();
            losses.extend(t.tail.clone());
            plain_with(t, &losses)
        }
        Order::Want(what) => want(what, t, Some(&exp)).expect("an exp"),
        Order::Shifted => plain_with(t, &shifted_losses(t, false)),
        Order::ShiftedGiven => plain_with(t, &shifted_losses(t, true)),
    }
}

/// The f32 instance: every problem-level route (over the [`Lifted`] task) and the kernel routes
/// on every trajectory rounded to f32 at both θ (rounded), then the baselined oracle with every
/// kind on rounded batches; each within [`F32_TOLERANCE`] of the first reference that has the
/// quantity, and, where `routes` asserts it in f64, bit for bit the reference formed in f32 in
/// the route's order ([`SAME_ORDER`]). `round_*` round the f64 labels and actions, `label` and
/// `action` lift the rounded ones to f32.
#[allow(clippy::too_many_arguments)] // the problem, the f32 policy, the roundings and lifts
fn check_f32<T, P, P32, L32, A32>(
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
    let mut p32 = TaskProblem {
        task: Lifted::<L32, A32>::new(),
        policy: p32,
        horizon: p.horizon,
    };
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
fn check_dual<T, P, PD, LD, AD>(
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
    let mut pd = TaskProblem {
        task: Lifted::<LD, AD>::new(),
        policy: pd,
        horizon: p.horizon,
    };
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

/// Two θ of `d` entries: `base` plus independent uniform noise of half-width `spread` (as
/// `routes`).
fn two_thetas(d: usize, base: impl Fn(usize) -> f64, spread: f64) -> [DVector<f64>; 2] {
    let mut rng = KitRng::seed_from_u64(d as u64);
    let mut one = || {
        DVector::from_fn(d, |i, _| {
            base(i) + spread * (2.0 * rng.random::<f64>() - 1.0)
        })
    };
    [one(), one()]
}

/// A pull towards the goal (rows of `n` features), with noise.
fn obstacle_theta(n: usize) -> [DVector<f64>; 2] {
    two_thetas(
        2 * n,
        |i| if i == 0 || i == n + 1 { 0.05 } else { 0.0 },
        0.01,
    )
}

fn with_horizon<T, P>(task: T, policy: P, horizon: Option<AfterEnd>) -> TaskProblem<T, P> {
    match horizon {
        Some(after_end) => TaskProblem::fixed(task, policy, STEPS, after_end).unwrap(),
        None => TaskProblem::episodic(task, policy),
    }
}

/// The linear-Gaussian policy (P3) of the obstacle task in `S`, σ = [`SIGMA`].
fn gaussian<S: Scalar>() -> LinearGaussian<S> {
    LinearGaussian::new(2, obstacle::FEATURES, exact(SIGMA)).unwrap()
}

/// The same with actions stored inline.
fn gaussian_pair<S: Scalar>() -> LinearGaussian<S, [S; 2]> {
    gaussian().with_actions::<[S; 2]>().unwrap()
}

/// The obstacle task with the actions of `A`.
fn obstacle_task<A: ActionVector<f64>>() -> ObstacleTask<A> {
    ObstacleTask::thesis().unwrap().with_actions::<A>()
}

fn linear_gaussian_rational(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let lift = lift_vec::<BigRational, Vec<f64>>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_rational(&mut p, &gaussian(), &thetas, &lift, &lift, mode)
}

fn linear_gaussian_inline_rational(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let lift = lift_pair::<BigRational>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_rational(&mut p, &gaussian_pair(), &thetas, &lift, &lift, mode)
}

fn linear_gaussian_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let (lq, li) = (
        lift_vec::<BigRational, Vec<f64>>,
        lift_vec::<Interval, Vec<f64>>,
    );
    let pq = gaussian();
    let exact = exact_terms::<ObstacleTask, _, _, _>(&pq, &lq, &lq);
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_kernel(&mut p, &gaussian(), &thetas, &li, &li, Some(&exact), mode)
}

fn linear_gaussian_inline_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let (lq, li) = (lift_pair::<BigRational>, lift_pair::<Interval>);
    let pq = gaussian_pair();
    let exact = exact_terms::<ObstacleTask<[f64; 2]>, _, _, _>(&pq, &lq, &lq);
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_kernel(
        &mut p,
        &gaussian_pair(),
        &thetas,
        &li,
        &li,
        Some(&exact),
        mode,
    )
}

/// The speed-limited linear-Gaussian policy, with a limit below the pull's speed at the start
/// so that both branches of the loss occur (as `routes`); its loss needs a square root, so it
/// has no rational reference.
fn speed_limited<S: ilopt::scalar::Sqrt>() -> SpeedLimitedGaussian<S, [S; 2]> {
    SpeedLimitedGaussian::new(gaussian_pair(), exact(0.1)).unwrap()
}

fn speed_limited_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
    let li = lift_pair::<Interval>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_kernel(&mut p, &speed_limited(), &thetas, &li, &li, None, mode)
}

/// The instances with the `mpfr` feature: every policy of `routes` over intervals.
fn cartpole_task() -> CartPoleTask<f64> {
    CartPoleTask::with_lqr().unwrap()
}

fn cartpole_theta(d: usize) -> [DVector<f64>; 2] {
    two_thetas(d, |_| 0.0, 2.0)
}

/// The network's initial weights, and the same scaled by 1.001 (as `routes`).
fn mlp_theta(net: &Mlp) -> [DVector<f64>; 2] {
    let theta = DVector::from_vec(net.init::<f64>(&mut KitRng::seed_from_u64(5)));
    let near = theta.map(|x| 1.001 * x);
    [theta, near]
}

fn same(x: &usize) -> usize {
    *x
}

/// The MLP-Gaussian policy's θ, as `routes`': the linear pull through the tanh layer.
fn mlp_gaussian_theta(net: &Mlp, n: usize, h: usize) -> [DVector<f64>; 2] {
    mlp_theta(net).map(|theta| {
        let mut theta = theta.map(|x| 0.01 * x);
        theta[0] = 0.1;
        theta[n + 1] = 0.1;
        theta[h * n + h] = 0.5;
        theta[h * n + h + h + 1] = 0.5;
        theta
    })
}

/// The MLP-Gaussian problem, on fixed streams of [`LONG_STEPS`] decisions.
fn mlp_gaussian_problem(
    horizon: Option<AfterEnd>,
) -> (
    TaskProblem<ObstacleTask, MlpGaussian<f64>>,
    [DVector<f64>; 2],
) {
    let (n, h) = (obstacle::FEATURES, 4);
    let policy = MlpGaussian::new(n, h, 2, SIGMA).unwrap();
    let thetas = mlp_gaussian_theta(policy.net(), n, h);
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), policy, horizon);
    if let Some(after_end) = horizon {
        p.horizon = Horizon::fixed(LONG_STEPS, after_end);
    }
    (p, thetas)
}

#[cfg(feature = "mpfr")]
mod mpfr_instances {
    use super::*;

    pub(super) fn logistic_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = Logistic::new(cartpole::FEATURES).unwrap();
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        let thetas = cartpole_theta(cartpole::FEATURES);
        check_interval_problem(&mut p, policy, &thetas, &same, &same, None, mode)
    }

    pub(super) fn softmax_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = Softmax::new(2, cartpole::FEATURES).unwrap();
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        let thetas = cartpole_theta(2 * cartpole::FEATURES);
        check_interval_problem(&mut p, policy, &thetas, &same, &same, None, mode)
    }

    pub(super) fn mlp_softmax_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
        let thetas = mlp_theta(policy.net());
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        check_interval_problem(&mut p, policy, &thetas, &same, &same, None, mode)
    }

    pub(super) fn linear_gaussian_interval_problem(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
        let (lq, li) = (
            lift_vec::<BigRational, Vec<f64>>,
            lift_vec::<Interval, Vec<f64>>,
        );
        let pq = gaussian();
        let exact = exact_terms::<ObstacleTask, _, _, _>(&pq, &lq, &lq);
        let thetas = obstacle_theta(obstacle::FEATURES);
        check_interval_problem(&mut p, gaussian(), &thetas, &li, &li, Some(&exact), mode)
    }

    pub(super) fn linear_gaussian_inline_interval_problem(
        horizon: Option<AfterEnd>,
        mode: Mode,
    ) -> Tally {
        let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
        let (lq, li) = (lift_pair::<BigRational>, lift_pair::<Interval>);
        let pq = gaussian_pair();
        let exact = exact_terms::<ObstacleTask<[f64; 2]>, _, _, _>(&pq, &lq, &lq);
        let thetas = obstacle_theta(obstacle::FEATURES);
        check_interval_problem(
            &mut p,
            gaussian_pair(),
            &thetas,
            &li,
            &li,
            Some(&exact),
            mode,
        )
    }

    pub(super) fn speed_limited_interval_problem(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
        let li = lift_pair::<Interval>;
        let thetas = obstacle_theta(obstacle::FEATURES);
        check_interval_problem(&mut p, speed_limited(), &thetas, &li, &li, None, mode)
    }

    /// The MLP-Gaussian policy with `routes`' weights (the linear pull through the tanh layer),
    /// on fixed streams of [`LONG_STEPS`] decisions.
    pub(super) fn mlp_gaussian_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let (mut p, thetas) = mlp_gaussian_problem(horizon);
        let pi = MlpGaussian::new(obstacle::FEATURES, 4, 2, exact::<Interval>(SIGMA)).unwrap();
        let li = lift_vec::<Interval, Vec<f64>>;
        check_interval_problem(&mut p, pi, &thetas, &li, &li, None, mode)
    }
}

#[cfg(feature = "mpfr")]
use mpfr_instances::*;

/// The f32 and `Dual<f64>` instances of every policy of `routes`. Their references: exact
/// (rationals, duals over rationals) for the linear-Gaussian policies, and enclosures (intervals,
/// duals over intervals) for the speed-limited one; with the `mpfr` feature, enclosures also for
/// the quantities that need an `exp` and for the policies whose terms do (without it, those
/// policies run every route with the bit-for-bit checks only).
mod lifted_instances {
    use super::*;

    type DI = Dual<Interval>;
    type References<'a, T> = Vec<Box<dyn Reference<T> + 'a>>;

    /// The intervals' `exp`, where they have one (the `mpfr` feature).
    fn interval_exp() -> Option<fn(&Interval) -> Interval> {
        #[cfg(feature = "mpfr")]
        return Some(<Interval as Real>::exp);
        #[cfg(not(feature = "mpfr"))]
        None
    }

    fn dual_interval_exp() -> Option<fn(&DI) -> DI> {
        #[cfg(feature = "mpfr")]
        return Some(<DI as Real>::exp);
        #[cfg(not(feature = "mpfr"))]
        None
    }

    /// The interval reference of the f32 instance (values).
    fn enclosed_values<'a, T, PI, L, A>(
        pi: PI,
        label: fn(&T::Label) -> L,
        action: fn(&T::Action) -> A,
    ) -> Box<dyn Reference<T> + 'a>
    where
        T: Task<f64> + 'a,
        PI: LikelihoodRatio<Interval, Action = A> + 'a,
        L: Borrow<PI::Label> + 'a,
        A: 'a,
    {
        reference_in(
            pi,
            label,
            action,
            lift_theta::<Interval>,
            interval_exp(),
            interval_bounds,
        )
    }

    /// The interval reference of the dual instance (tangents).
    fn enclosed_tangents<'a, T, PI, L, A>(
        pi: PI,
        label: fn(&T::Label) -> L,
        action: fn(&T::Action) -> A,
    ) -> Box<dyn Reference<T> + 'a>
    where
        T: Task<f64> + 'a,
        PI: LikelihoodRatio<DI, Action = A> + 'a,
        L: Borrow<PI::Label> + 'a,
        A: 'a,
    {
        reference_in(
            pi,
            label,
            action,
            dual_theta::<Interval>,
            dual_interval_exp(),
            |x| interval_bounds(&tangent(x)),
        )
    }

    /// The speed-limited policy with the f32 instance's limit (0.1 rounded to f32), so that
    /// the f32 policy and its references limit at the same real number.
    fn speed_limited_at_f32<S: ilopt::scalar::Sqrt>() -> SpeedLimitedGaussian<S, [S; 2]> {
        SpeedLimitedGaussian::new(gaussian_pair(), exact(to_f32(0.1))).unwrap()
    }

    fn mlp_gaussian<S: Scalar>() -> MlpGaussian<S> {
        MlpGaussian::new(obstacle::FEATURES, 4, 2, exact::<S>(SIGMA)).unwrap()
    }

    type Obstacle = ObstacleTask;
    type ObstaclePair = ObstacleTask<[f64; 2]>;
    type CartPole = CartPoleTask<f64>;

    pub(super) fn linear_gaussian_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
        let thetas = obstacle_theta(obstacle::FEATURES);
        let li = lift_vec::<Interval, Vec<f64>>;
        let refs: References<Obstacle> = vec![enclosed_values(gaussian(), li, li)];
        let l32 = lift_vec::<f32, Vec<f64>>;
        let round = round_vec;
        check_f32(
            &mut p,
            gaussian(),
            &thetas,
            &round,
            &round,
            &l32,
            &l32,
            &refs,
            mode,
        )
    }

    pub(super) fn linear_gaussian_inline_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
        let thetas = obstacle_theta(obstacle::FEATURES);
        let li = lift_pair::<Interval>;
        let refs: References<ObstaclePair> = vec![enclosed_values(gaussian_pair(), li, li)];
        let (l32, round) = (lift_pair::<f32>, round_pair);
        let policy = gaussian_pair();
        check_f32(
            &mut p, policy, &thetas, &round, &round, &l32, &l32, &refs, mode,
        )
    }

    pub(super) fn speed_limited_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
        let thetas = obstacle_theta(obstacle::FEATURES);
        let li = lift_pair::<Interval>;
        let refs: References<ObstaclePair> = vec![enclosed_values(speed_limited_at_f32(), li, li)];
        let (l32, round) = (lift_pair::<f32>, round_pair);
        let policy = speed_limited_at_f32();
        check_f32(
            &mut p, policy, &thetas, &round, &round, &l32, &l32, &refs, mode,
        )
    }

    pub(super) fn logistic_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = Logistic::new(cartpole::FEATURES).unwrap();
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        let thetas = cartpole_theta(cartpole::FEATURES);
        #[cfg(feature = "mpfr")]
        let refs: References<CartPole> = vec![enclosed_values(policy, same, same)];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<CartPole> = vec![];
        check_f32(
            &mut p, policy, &thetas, &same, &same, &same, &same, &refs, mode,
        )
    }

    pub(super) fn softmax_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = Softmax::new(2, cartpole::FEATURES).unwrap();
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        let thetas = cartpole_theta(2 * cartpole::FEATURES);
        #[cfg(feature = "mpfr")]
        let refs: References<CartPole> = vec![enclosed_values(policy, same, same)];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<CartPole> = vec![];
        check_f32(
            &mut p, policy, &thetas, &same, &same, &same, &same, &refs, mode,
        )
    }

    pub(super) fn mlp_softmax_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
        let thetas = mlp_theta(policy.net());
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        #[cfg(feature = "mpfr")]
        let refs: References<CartPole> = vec![enclosed_values(policy, same, same)];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<CartPole> = vec![];
        check_f32(
            &mut p, policy, &thetas, &same, &same, &same, &same, &refs, mode,
        )
    }

    pub(super) fn mlp_gaussian_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let (mut p, thetas) = mlp_gaussian_problem(horizon);
        #[cfg(feature = "mpfr")]
        let refs: References<Obstacle> = vec![enclosed_values(
            mlp_gaussian::<Interval>(),
            lift_vec::<Interval, Vec<f64>>,
            lift_vec::<Interval, Vec<f64>>,
        )];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<Obstacle> = vec![];
        let (l32, round) = (lift_vec::<f32, Vec<f64>>, round_vec);
        let policy = mlp_gaussian::<f32>();
        check_f32(
            &mut p, policy, &thetas, &round, &round, &l32, &l32, &refs, mode,
        )
    }

    pub(super) fn linear_gaussian_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
        let thetas = obstacle_theta(obstacle::FEATURES);
        let li = lift_vec::<DI, Vec<f64>>;
        let refs: References<Obstacle> = vec![enclosed_tangents(gaussian(), li, li)];
        let ld = lift_vec::<Dual<f64>, Vec<f64>>;
        check_dual(&mut p, gaussian(), &thetas, &ld, &ld, &refs, mode)
    }

    pub(super) fn linear_gaussian_inline_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
        let thetas = obstacle_theta(obstacle::FEATURES);
        let li = lift_pair::<DI>;
        let refs: References<ObstaclePair> = vec![enclosed_tangents(gaussian_pair(), li, li)];
        let ld = lift_pair::<Dual<f64>>;
        check_dual(&mut p, gaussian_pair(), &thetas, &ld, &ld, &refs, mode)
    }

    pub(super) fn speed_limited_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
        let thetas = obstacle_theta(obstacle::FEATURES);
        let li = lift_pair::<DI>;
        let refs: References<ObstaclePair> = vec![enclosed_tangents(speed_limited(), li, li)];
        let ld = lift_pair::<Dual<f64>>;
        check_dual(&mut p, speed_limited(), &thetas, &ld, &ld, &refs, mode)
    }

    pub(super) fn logistic_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = Logistic::new(cartpole::FEATURES).unwrap();
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        let thetas = cartpole_theta(cartpole::FEATURES);
        #[cfg(feature = "mpfr")]
        let refs: References<CartPole> = vec![enclosed_tangents(policy, same, same)];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<CartPole> = vec![];
        check_dual(&mut p, policy, &thetas, &same, &same, &refs, mode)
    }

    pub(super) fn softmax_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = Softmax::new(2, cartpole::FEATURES).unwrap();
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        let thetas = cartpole_theta(2 * cartpole::FEATURES);
        #[cfg(feature = "mpfr")]
        let refs: References<CartPole> = vec![enclosed_tangents(policy, same, same)];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<CartPole> = vec![];
        check_dual(&mut p, policy, &thetas, &same, &same, &refs, mode)
    }

    pub(super) fn mlp_softmax_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
        let thetas = mlp_theta(policy.net());
        let mut p = with_horizon(cartpole_task(), policy, horizon);
        #[cfg(feature = "mpfr")]
        let refs: References<CartPole> = vec![enclosed_tangents(policy, same, same)];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<CartPole> = vec![];
        check_dual(&mut p, policy, &thetas, &same, &same, &refs, mode)
    }

    pub(super) fn mlp_gaussian_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
        let (mut p, thetas) = mlp_gaussian_problem(horizon);
        #[cfg(feature = "mpfr")]
        let refs: References<Obstacle> = vec![enclosed_tangents(
            mlp_gaussian::<DI>(),
            lift_vec::<DI, Vec<f64>>,
            lift_vec::<DI, Vec<f64>>,
        )];
        #[cfg(not(feature = "mpfr"))]
        let refs: References<Obstacle> = vec![];
        let ld = lift_vec::<Dual<f64>, Vec<f64>>;
        check_dual(&mut p, mlp_gaussian(), &thetas, &ld, &ld, &refs, mode)
    }
}

use lifted_instances::*;

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
