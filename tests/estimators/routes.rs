//! One contract for every route to the causal estimate of eq. 3.15: on the same trajectories and
//! θ, every remaining route — the problem's oracle passes, the policy's kernel passes, the
//! per-decision terms, the recorded passes and the baselined oracle with every kind of baseline —
//! against one reference built from [`Policy`]'s in-place methods alone (`loss_into`,
//! `score_into`, `log_likelihood_ratio`) and the sums of eq. 3.15 written out (math.md §1.1, §4).
//!
//! Bit for bit (`f64` bits) where the route forms the reference's products in the reference's
//! order: the plain estimate, the weighted estimates, the policy's causal sum, and the policy's
//! recorded passes (one summation order per policy: the recorded losses give the plain estimate,
//! shifted losses the plain order with `l'_t` for `l_t`). Within [`TOLERANCE`] (relative to the
//! reference's largest entry) where a route sums the same products in another order: the
//! per-decision terms (loss-to-go summed backwards) and the reference's baselined sum (each
//! `b_i ψ_i` subtracted as it is met) against the shifted losses.
//!
//! One macro instantiates the contract for every policy × horizon kind; inside, every baseline
//! kind runs on the same batches. The scalar is `f64` (the routes are generic; the exact
//! per-scalar identities of the policies are `tests/exactness/policy_*.rs`).

use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined, PerDecisionTerms, baselined_estimate};
use ilopt::oracle::{DecisionTerms, EstimatorKernel, Given, RecordedPass};
use ilopt::policy::{
    LikelihoodRatio, LinearGaussian, Logistic, Mlp, MlpGaussian, MlpSoftmax, Softmax,
    SpeedLimitedGaussian,
};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::scalar::Scalar;
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, Task, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use std::borrow::Borrow;

/// The largest difference allowed, relative to `1 +` the reference's largest entry, for a route
/// that sums the reference's products in another order: two summation orders of at most
/// [`LONG_STEPS`] terms, each within `LONG_STEPS · ε` of the exact sum relative to the terms'
/// magnitudes, which on these trajectories stay within that scale (the worst route observed sits
/// about 20× below this bound).
const TOLERANCE: f64 = 2.0 * LONG_STEPS as f64 * f64::EPSILON;

/// Decisions of a fixed-horizon stream (the absorbing tail follows an episode that ends sooner).
const STEPS: usize = 40;

/// Decisions of the MLP-Gaussian policy's fixed-horizon streams: its episodes outlast [`STEPS`].
const LONG_STEPS: usize = 600;

/// Trajectories per batch (leave-one-out needs two) and batches per baseline kind (the estimated
/// baselines use the statistics of earlier batches).
const M: usize = 2;
const BATCHES: usize = 3;

/// More decisions than any trajectory of these tasks takes (the time-indexed baselines' length).
pub(super) const LONGEST: usize = 5000;

/// The time-indexed baseline of decision i, `3/8 − i/1024` (dyadic: exact in every scalar, so
/// that `route_scalars`' lifted oracles estimate the f64 oracle's real number).
pub(super) fn time_indexed(i: usize) -> f64 {
    0.375 - i as f64 / 1024.0
}

/// One trajectory's per-decision terms from the policy's in-place methods in `S`: losses, loss
/// gradients, scores, and the log-ratios `log π_θ(a|s) − log π_θnew(a|s)`; with the absorbing
/// tail's losses and the number of scored decisions (n − 1, or n with an absorbing tail). Also
/// `route_scalars`' terms, in every scalar.
#[derive(Clone)]
pub(super) struct Terms<S> {
    pub(super) losses: Vec<S>,
    pub(super) grads: Vec<Vec<S>>,
    pub(super) scores: Vec<Vec<S>>,
    pub(super) log_ratios: Vec<S>,
    pub(super) tail: Option<S>,
    pub(super) scored: usize,
}

pub(super) fn terms<S, P, L>(
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

/// The reference: `Σ_t [w_{1:t−1} ∇l_t + w_{1:t−1} l_t Σ_{i<t} ψ_i] + w_{1:n} L_abs Σ_{i≤n} ψ_i
/// − Σ_{i<s} w_{1:i} b_i ψ_i` (s scored decisions: n − 1, or n with an absorbing tail), with the
/// per-decision prefix weights (`weighted`) or every weight 1, and the trajectory's log-weight
/// `Σ_{i<s} log-ratio_i`.
#[allow(clippy::needless_range_loop)] // the sums' indices, as written
fn reference(
    t: &Terms<f64>,
    tail: Option<f64>,
    weighted: bool,
    baselines: &dyn Fn(usize) -> f64,
) -> (Vec<f64>, f64) {
    let d = t.grads.first().map_or(0, Vec::len);
    let n = t.losses.len();
    let scored = if tail.is_some() { n } else { n - 1 };
    let (mut g, mut score_sum) = (vec![0.0; d], vec![0.0; d]);
    let mut log_w = 0.0;
    let mut w = 1.0f64;
    for step in 0..n {
        let wl = w * t.losses[step];
        for j in 0..d {
            g[j] += w * t.grads[step][j] + wl * score_sum[j];
        }
        for j in 0..d {
            score_sum[j] += t.scores[step][j];
        }
        if step < scored {
            log_w += t.log_ratios[step];
            if weighted {
                w = f64::exp(log_w);
            }
            let c = w * baselines(step);
            for j in 0..d {
                g[j] -= c * t.scores[step][j];
            }
        }
    }
    if let Some(tail) = tail {
        for j in 0..d {
            g[j] += w * tail * score_sum[j];
        }
    }
    (g, log_w)
}

/// The unweighted reference without a baseline, bit for bit the plain pass's order.
fn plain(t: &Terms<f64>, tail: Option<f64>) -> Vec<f64> {
    let mut losses = t.losses.clone();
    losses.extend(tail);
    plain_with(t, &losses)
}

/// The plain pass's order with the per-step losses `l'` in place of the policy's:
/// `Σ_t [∇l_t + l'_t Σ_{i<t} ψ_i]`, then `l'_n Σ_{i≤n} ψ_i` for an (n + 1)-th loss — how every
/// route that sums recorded decisions folds a baseline in (shifted losses).
#[allow(clippy::needless_range_loop)] // the sums' indices, as written
pub(super) fn plain_with<S: Scalar>(t: &Terms<S>, losses: &[S]) -> Vec<S> {
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

/// The full form (eq. 3.16) `Σ_t ∇l_t + (L_abs + Σ_t l_t) Σ_{i<s} ψ_i`, s scored decisions.
#[allow(clippy::needless_range_loop)] // the sums' indices, as written
fn full(t: &Terms<f64>, tail: Option<f64>) -> Vec<f64> {
    let d = t.grads.first().map_or(0, Vec::len);
    let n = t.losses.len();
    let scored = if tail.is_some() { n } else { n - 1 };
    let total = t.losses.iter().fold(tail.unwrap_or(0.0), |a, l| a + l);
    let mut g = vec![0.0; d];
    for step in 0..n {
        for j in 0..d {
            g[j] += t.grads[step][j];
            if step < scored {
                g[j] += total * t.scores[step][j];
            }
        }
    }
    g
}

/// The loss-to-go `L_i = Σ_{t>i} l_t` (the tail included) of each decision.
fn loss_to_go(t: &Terms<f64>, tail: Option<f64>) -> Vec<f64> {
    let mut after = tail.unwrap_or(0.0);
    let mut out = vec![0.0; t.losses.len()];
    for i in (0..t.losses.len()).rev() {
        out[i] = after;
        after += t.losses[i];
    }
    out
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[track_caller]
fn same(route: &str, got: &[f64], want: &[f64]) {
    assert_eq!(bits(got), bits(want), "{route}: {got:?} != {want:?}");
}

#[track_caller]
fn close(route: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{route}: length");
    let scale = 1.0 + want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (j, (a, b)) in got.iter().zip(want).enumerate() {
        assert!(
            (a - b).abs() <= TOLERANCE * scale,
            "{route}: entry {j}: {a} vs {b} (scale {scale})"
        );
    }
}

fn mean(gs: &[Vec<f64>]) -> Vec<f64> {
    let d = gs[0].len();
    (0..d)
        .map(|j| gs.iter().map(|g| g[j]).sum::<f64>() / gs.len() as f64)
        .collect()
}

/// Every route of one problem on its learner's trajectories at `thetas[0]` (the softmax policy's
/// noted probabilities usable), estimated at both θ, with both weightings towards the other θ.
fn check_routes<T, P>(p: &mut TaskProblem<T, P>, thetas: &[DVector<f64>; 2])
where
    T: Task<f64> + Clone,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64> + Clone,
    T::Label: Borrow<P::Label>,
{
    let mut cost = Cost::default();
    let mut tails = 0;
    for seed in 0..4 {
        let mut rng = KitRng::seed_from_u64(seed);
        let t = p
            .rollout(&Behaviour::Learner(&thetas[0]), &mut rng, &mut cost)
            .unwrap();
        tails += usize::from(t.absorbed.is_some());
        for (k, theta) in thetas.iter().enumerate() {
            let other = &thetas[1 - k];
            let th = theta.as_slice();
            let ref_terms = terms(&p.policy, th, other.as_slice(), &t);
            let tail = t.absorbed;
            let want = plain(&ref_terms, tail);
            let no_b = |_: usize| 0.0;
            close(
                "reference",
                &reference(&ref_terms, tail, false, &no_b).0,
                &want,
            );
            let route = |name: &str| format!("seed {seed}, θ{k}: {name}");

            // The problem's oracle: the causal pass (the policy's whole-trajectory kernel pass,
            // the noted one at the roll-out's θ) and its trajectory loss.
            let (g, loss) = p
                .estimate_with_loss(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap();
            same(&route("estimate_with_loss"), g.as_slice(), &want);
            let total = ref_terms
                .losses
                .iter()
                .fold(tail.unwrap_or(0.0), |a, l| a + l);
            assert_eq!(
                loss.to_bits(),
                total.to_bits(),
                "{}",
                route("trajectory loss")
            );
            let g = p
                .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap();
            same(&route("estimate"), g.as_slice(), &want);
            let g = p
                .estimate(theta, &t, EstimatorForm::Full, &mut cost)
                .unwrap();
            same(
                &route("estimate Full"),
                g.as_slice(),
                &full(&ref_terms, tail),
            );

            // The weighted passes towards the other θ: per-decision (the checked loop) and
            // whole-trajectory (the policy's causal sum, then the weight); towards θ itself every
            // weight is exactly 1 and the plain estimate comes back bit for bit.
            for weighting in [Weighting::PerDecision, Weighting::Trajectory] {
                let per_decision = weighting == Weighting::PerDecision;
                let (mut r, log_w) = reference(&ref_terms, tail, per_decision, &no_b);
                if !per_decision {
                    let w = f64::exp(log_w);
                    r.iter_mut().for_each(|x| *x *= w);
                }
                let g = p
                    .weighted_estimate(theta, other, &t, weighting, &mut cost)
                    .unwrap();
                same(
                    &route(&format!("weighted_estimate {weighting:?}")),
                    g.as_slice(),
                    &r,
                );
                let g = p
                    .weighted_estimate(theta, theta, &t, weighting, &mut cost)
                    .unwrap();
                same(
                    &route(&format!("weighted_estimate {weighting:?} at θ")),
                    g.as_slice(),
                    &want,
                );
                // The per-decision terms with the same weights.
                let mut dt = DecisionTerms::new();
                p.decision_terms(theta, &t, Some((other, weighting)), &mut dt, &mut cost)
                    .unwrap();
                dt.finish();
                let mut g = vec![0.0; th.len()];
                dt.estimate_into(|_| None, &mut g);
                close(&route(&format!("decision_terms {weighting:?}")), &g, &r);
            }

            // The policy's kernel on the trajectory's rows.
            let labels: Vec<&P::Label> = t.labels.iter().map(Borrow::borrow).collect();
            let (mut g, mut loss, mut scratch) = (vec![0.0; th.len()], tail.unwrap_or(0.0), vec![]);
            p.policy
                .causal_sum_validated(
                    th,
                    t.feature_data(),
                    None,
                    &labels,
                    &t.actions,
                    tail.as_ref(),
                    &mut g,
                    Some(&mut loss),
                    &mut scratch,
                )
                .unwrap();
            same(&route("causal_sum_validated"), &g, &want);
            assert_eq!(
                loss.to_bits(),
                total.to_bits(),
                "{}",
                route("causal_sum_validated loss")
            );
            // A baseline b_i on the scored decisions (b_t = 0 from the first unscored decision on).
            let scored = if tail.is_some() { t.len() } else { t.len() - 1 };
            let b = |i: usize| {
                if i < scored {
                    0.25 + 0.01 * i as f64
                } else {
                    0.0
                }
            };
            // The policy's records summed with the recorded losses, and with other losses.
            let (mut losses, mut records) = (vec![], vec![]);
            p.policy
                .record_validated(
                    th,
                    t.feature_data(),
                    None,
                    &labels,
                    &t.actions,
                    &mut losses,
                    &mut records,
                )
                .unwrap();
            assert_eq!(
                bits(&losses),
                bits(&ref_terms.losses),
                "{}",
                route("record_validated losses")
            );
            let mut g = vec![0.0; th.len()];
            let mut with_tail = losses.clone();
            with_tail.extend(tail);
            p.policy.accumulate_recorded(
                t.feature_data(),
                &records,
                &with_tail,
                &mut g,
                &mut scratch,
            );
            same(&route("record_validated + accumulate_recorded"), &g, &want);

            // The per-decision terms, unweighted.
            let mut dt = DecisionTerms::new();
            p.decision_terms(theta, &t, None, &mut dt, &mut cost)
                .unwrap();
            dt.finish();
            let mut g = vec![0.0; th.len()];
            dt.estimate_into(|i| Some(b(i)), &mut g);
            close(
                &route("decision_terms with b"),
                &g,
                &reference(&ref_terms, tail, false, &b).0,
            );
            // The problem's recorded pass, and the default form's (from the terms).
            let mut rec = RecordedPass::new();
            p.record_decisions(theta, &t, &mut rec, &mut cost).unwrap();
            let mut g = vec![0.0; th.len()];
            p.estimate_recorded(&t, &mut rec, None, &mut g);
            same(&route("record_decisions + estimate_recorded"), &g, &want);
            let mut rows = RecordedPass::new();
            p.decision_terms(theta, &t, None, rows.terms_mut(), &mut cost)
                .unwrap();
            rows.fill_from_terms();
            let mut g = vec![0.0; th.len()];
            p.estimate_recorded(&t, &mut rows, None, &mut g);
            close(&route("fill_from_terms + estimate_recorded"), &g, &want);
            // Other per-step losses: l'_t = l_t + b_t − b_{t−1} is the baselined estimate.
            let shifted: Vec<f64> = rec
                .losses()
                .iter()
                .enumerate()
                .map(|(i, l)| l + (b(i) - if i == 0 { 0.0 } else { b(i - 1) }))
                .collect();
            let want_b = reference(&ref_terms, tail, false, &b).0;
            // Baselines given before the pass take the same route: the records summed with the
            // losses shifted by b_t − b_{t−1}.
            let bs: Vec<f64> = (0..scored).map(b).collect();
            let g = baselined_estimate(p, theta, &t, Given::TimeIndexed(&bs), &mut cost).unwrap();
            let route_name = route("baselined_estimate, time-indexed");
            same(&route_name, g.as_slice(), &plain_with(&ref_terms, &shifted));
            close(&route_name, g.as_slice(), &want_b);
            // The policy's records sum the shifted losses in the plain pass's order; the rows of
            // the per-decision terms in theirs.
            let mut g = vec![0.0; th.len()];
            p.estimate_recorded(&t, &mut rec, Some(&shifted), &mut g);
            let route_name = route("estimate_recorded (recorded) with shifted losses");
            same(&route_name, &g, &plain_with(&ref_terms, &shifted));
            close(&route_name, &g, &want_b);
            let mut g = vec![0.0; th.len()];
            p.estimate_recorded(&t, &mut rows, Some(&shifted), &mut g);
            close(
                &route("estimate_recorded (rows) with shifted losses"),
                &g,
                &want_b,
            );
        }
    }
    if matches!(
        p.horizon,
        Horizon::Fixed {
            after_end: AfterEnd::Absorb,
            ..
        }
    ) {
        assert!(tails > 0, "no absorbing tail among the trajectories");
    }
    check_baselines(p, thetas);
}

/// The baselined oracle with every kind of baseline on the same batches: `estimate` against the
/// reference where the baselines are known from outside (none, constants, leave-one-out) and
/// against [`Baselined::estimate_by_terms`] for every kind; the weighted estimate at θ_new = θ
/// (every weight 1) against the unweighted reference.
fn check_baselines<T, P>(p: &TaskProblem<T, P>, thetas: &[DVector<f64>; 2])
where
    T: Task<f64> + Clone,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64> + Clone,
    T::Label: Borrow<P::Label>,
{
    let kinds = baseline_kinds();
    let theta = &thetas[0];
    let th = theta.as_slice();
    for kind in &kinds {
        let mut b = Baselined::new(p.clone(), M, kind).unwrap();
        let mut rng = KitRng::seed_from_u64(7);
        let mut cost = Cost::default();
        for batch in 0..BATCHES {
            let ts = b
                .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .unwrap();
            let route = |name: &str| format!("{kind:?}, batch {batch}: {name}");
            let g = b
                .estimate(theta, &ts, EstimatorForm::Causal, &mut cost)
                .unwrap();
            let by_terms = b.estimate_by_terms(theta, &ts, &mut cost).unwrap();
            close(
                &route("estimate vs estimate_by_terms"),
                g.as_slice(),
                by_terms.as_slice(),
            );
            let all: Vec<Terms<f64>> = ts.iter().map(|t| terms(&p.policy, th, th, t)).collect();
            let to_go: Vec<Vec<f64>> = all
                .iter()
                .zip(&ts)
                .map(|(x, t)| loss_to_go(x, t.absorbed))
                .collect();
            let known: Option<Vec<Vec<f64>>> = match kind {
                Baseline::None => Some(ts.iter().map(|_| vec![0.0; LONGEST]).collect()),
                Baseline::Constant { .. } => Some(ts.iter().map(|_| vec![0.5; LONGEST]).collect()),
                Baseline::TimeIndexed { .. } => Some(
                    ts.iter()
                        .map(|_| (0..LONGEST).map(time_indexed).collect())
                        .collect(),
                ),
                Baseline::LeaveOneOut => Some(
                    (0..M)
                        .map(|j| {
                            (0..LONGEST)
                                .map(|i| to_go[1 - j].get(i).copied().unwrap_or(0.0))
                                .collect()
                        })
                        .collect(),
                ),
                _ => None,
            };
            if let Some(bs) = known {
                let gs: Vec<Vec<f64>> = all
                    .iter()
                    .zip(&ts)
                    .zip(&bs)
                    .map(|((x, t), bj)| reference(x, t.absorbed, false, &|i| bj[i]).0)
                    .collect();
                close(&route("estimate vs reference"), g.as_slice(), &mean(&gs));
                if matches!(kind, Baseline::None) {
                    let plains: Vec<Vec<f64>> = all
                        .iter()
                        .zip(&ts)
                        .map(|(x, t)| plain(x, t.absorbed))
                        .collect();
                    close(&route("estimate vs plain"), g.as_slice(), &mean(&plains));
                }
                if !matches!(kind, Baseline::LeaveOneOut) {
                    for weighting in [Weighting::PerDecision, Weighting::Trajectory] {
                        let gw = b
                            .weighted_estimate(theta, theta, &ts, weighting, &mut cost)
                            .unwrap();
                        close(
                            &route(&format!("weighted {weighting:?} at θ")),
                            gw.as_slice(),
                            &mean(&gs),
                        );
                    }
                }
            }
        }
    }
}

/// Every kind of baseline the contracts run (its constants dyadic, so that the f64 and the
/// lifted oracles of `route_scalars` estimate the same real number).
pub(super) fn baseline_kinds() -> Vec<Baseline> {
    let number = |x: f64| ConfigNumber::from(x);
    vec![
        Baseline::None,
        Baseline::Constant { value: number(0.5) },
        Baseline::TimeIndexed {
            values: (0..LONGEST).map(|i| number(time_indexed(i))).collect(),
        },
        Baseline::LeaveOneOut,
        Baseline::Estimated {
            time_indexed: true,
            decay: Some(number(0.9)),
        },
        Baseline::Estimated {
            time_indexed: false,
            decay: None,
        },
        Baseline::StateDependent {
            features: None,
            time: true,
            decay: None,
            ridge: Some(number(1e-3)),
            fit_every: Some(1),
        },
        Baseline::StateDependent {
            features: None,
            time: false,
            decay: Some(number(0.9)),
            ridge: Some(number(1e-3)),
            fit_every: Some(2),
        },
        Baseline::StateDependent {
            features: Some(2),
            time: true,
            decay: None,
            ridge: Some(number(1e-2)),
            fit_every: Some(3),
        },
    ]
}

/// Two θ of `d` entries: `base` plus independent uniform noise of half-width `spread`.
fn two_thetas(d: usize, base: impl Fn(usize) -> f64, spread: f64) -> [DVector<f64>; 2] {
    let mut rng = KitRng::seed_from_u64(d as u64);
    let mut one = || {
        DVector::from_fn(d, |i, _| {
            base(i) + spread * (2.0 * rng.random::<f64>() - 1.0)
        })
    };
    [one(), one()]
}

fn cartpole_theta(d: usize) -> [DVector<f64>; 2] {
    two_thetas(d, |_| 0.0, 2.0)
}

/// A pull towards the goal (rows of `n` features), with noise.
fn obstacle_theta(n: usize) -> [DVector<f64>; 2] {
    two_thetas(
        2 * n,
        |i| if i == 0 || i == n + 1 { 0.05 } else { 0.0 },
        0.01,
    )
}

/// The network's initial weights, and the same scaled by 1.001 (a nearby θ, so that the
/// likelihood ratios of long episodes stay finite).
fn mlp_theta(net: &Mlp) -> [DVector<f64>; 2] {
    let theta = DVector::from_vec(net.init::<f64>(&mut KitRng::seed_from_u64(5)));
    let near = theta.map(|x| 1.001 * x);
    [theta, near]
}

fn with_horizon<T, P>(task: T, policy: P, horizon: Option<AfterEnd>) -> TaskProblem<T, P> {
    match horizon {
        Some(after_end) => TaskProblem::fixed(task, policy, STEPS, after_end).unwrap(),
        None => TaskProblem::episodic(task, policy),
    }
}

fn cartpole_task() -> CartPoleTask<f64> {
    CartPoleTask::with_lqr().unwrap()
}

fn logistic(horizon: Option<AfterEnd>) {
    let mut p = with_horizon(
        cartpole_task(),
        Logistic::new(cartpole::FEATURES).unwrap(),
        horizon,
    );
    check_routes(&mut p, &cartpole_theta(cartpole::FEATURES));
}

fn softmax(horizon: Option<AfterEnd>) {
    let mut p = with_horizon(
        cartpole_task(),
        Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon,
    );
    check_routes(&mut p, &cartpole_theta(2 * cartpole::FEATURES));
}

fn mlp_softmax(horizon: Option<AfterEnd>) {
    let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
    let thetas = mlp_theta(policy.net());
    check_routes(&mut with_horizon(cartpole_task(), policy, horizon), &thetas);
}

fn linear_gaussian(horizon: Option<AfterEnd>) {
    let policy = LinearGaussian::new(2, obstacle::FEATURES, 0.05).unwrap();
    let mut p = with_horizon(ObstacleTask::thesis().unwrap(), policy, horizon);
    check_routes(&mut p, &obstacle_theta(obstacle::FEATURES));
}

fn linear_gaussian_inline(horizon: Option<AfterEnd>) {
    let policy = LinearGaussian::new(2, obstacle::FEATURES, 0.05)
        .unwrap()
        .with_actions::<[f64; 2]>()
        .unwrap();
    let task = ObstacleTask::thesis().unwrap().with_actions::<[f64; 2]>();
    check_routes(
        &mut with_horizon(task, policy, horizon),
        &obstacle_theta(obstacle::FEATURES),
    );
}

fn speed_limited(horizon: Option<AfterEnd>) {
    let inner = LinearGaussian::new(2, obstacle::FEATURES, 0.05)
        .unwrap()
        .with_actions::<[f64; 2]>()
        .unwrap();
    // A limit below the pull's speed at the start, so that both branches of the loss occur.
    let policy = SpeedLimitedGaussian::new(inner, 0.1).unwrap();
    let task = ObstacleTask::thesis().unwrap().with_actions::<[f64; 2]>();
    check_routes(
        &mut with_horizon(task, policy, horizon),
        &obstacle_theta(obstacle::FEATURES),
    );
}

fn mlp_gaussian(horizon: Option<AfterEnd>) {
    let policy = MlpGaussian::new(obstacle::FEATURES, 4, 2, 0.05).unwrap();
    // The linear-Gaussian pull through the tanh layer (hidden units 0 and 1 read features 0 and
    // 1 at a tenth, the outputs read them back at five times), over the initial weights at a
    // hundredth: episodes end (and a fixed horizon absorbs) as with the pull.
    let (n, h) = (obstacle::FEATURES, 4);
    let thetas = mlp_theta(policy.net()).map(|theta| {
        let mut theta = theta.map(|x| 0.01 * x);
        theta[0] = 0.1;
        theta[n + 1] = 0.1;
        theta[h * n + h] = 0.5;
        theta[h * n + h + h + 1] = 0.5;
        theta
    });
    let mut p = with_horizon(ObstacleTask::thesis().unwrap(), policy, horizon);
    // Streams longer than the task's own episodes, so that the fixed horizon's early ends occur.
    if let Some(after_end) = horizon {
        p.horizon = Horizon::fixed(LONG_STEPS, after_end);
    }
    check_routes(&mut p, &thetas);
}

/// One test per policy × horizon kind: episodic; a fixed horizon whose early ends absorb; one
/// whose early ends reset.
macro_rules! route_contract {
    ($($policy:ident: $episodic:ident, $absorbing:ident, $reset:ident;)*) => {$(
        #[test]
        fn $episodic() {
            $policy(None);
        }

        #[test]
        fn $absorbing() {
            $policy(Some(AfterEnd::Absorb));
        }

        #[test]
        fn $reset() {
            $policy(Some(AfterEnd::Reset));
        }
    )*};
}

route_contract! {
    logistic: logistic_episodic, logistic_fixed_absorbing, logistic_fixed_reset;
    softmax: softmax_episodic, softmax_fixed_absorbing, softmax_fixed_reset;
    mlp_softmax: mlp_softmax_episodic, mlp_softmax_fixed_absorbing, mlp_softmax_fixed_reset;
    linear_gaussian: linear_gaussian_episodic, linear_gaussian_fixed_absorbing, linear_gaussian_fixed_reset;
    linear_gaussian_inline: linear_gaussian_inline_episodic, linear_gaussian_inline_fixed_absorbing, linear_gaussian_inline_fixed_reset;
    speed_limited: speed_limited_episodic, speed_limited_fixed_absorbing, speed_limited_fixed_reset;
    mlp_gaussian: mlp_gaussian_episodic, mlp_gaussian_fixed_absorbing, mlp_gaussian_fixed_reset;
}
