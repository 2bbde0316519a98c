//! The allocation-free oracle of `TaskProblem` against the straightforward computation it
//! replaced: per-decision `Policy::loss`/`Policy::score` vectors first, then the sums of eq. 3.15
//! (kept here verbatim as the reference). Every output must agree **bit for bit** in `f64`, on
//! CartPole with the logistic and softmax policies and on the obstacle task with the
//! linear-Gaussian policy; and golden hashes computed by the pre-issue-8 code pin roll-outs and
//! estimates across versions.

use ilopt::oracle::EstimatorKernel;
use ilopt::policy::{LikelihoodRatio, LinearGaussian, Logistic, Policy, PolicyExt, Softmax};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::scalar::{Real, Scalar};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{Task, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;
use std::borrow::Borrow;

/// Per-decision losses, gradients and scores, as the oracle computed them before its allocation-free rewrite.
#[allow(clippy::type_complexity)]
fn terms<S: Scalar, P: Policy<S>, L: Borrow<P::Label>>(
    policy: &P,
    theta: &[S],
    t: &TaskTrajectory<S, L, P::Action>,
) -> (Vec<S>, Vec<Vec<S>>, Vec<Vec<S>>) {
    let (mut losses, mut grads, mut scores) = (vec![], vec![], vec![]);
    for ((phi, a), y) in t.features().iter().zip(&t.actions).zip(&t.labels) {
        let (l, g) = policy.loss(theta, phi, y.borrow()).unwrap();
        losses.push(l);
        grads.push(g);
        scores.push(policy.score(theta, phi, a).unwrap());
    }
    (losses, grads, scores)
}

fn causal_weighted<S: Scalar>(
    d: usize,
    losses: &[S],
    grads: &[Vec<S>],
    scores: &[Vec<S>],
    prefix_weights: Option<&[S]>,
) -> Vec<S> {
    let mut g = vec![S::zero(); d];
    let mut score_sum = vec![S::zero(); d];
    for t in 0..losses.len() {
        let w = prefix_weights.map_or_else(S::one, |w| w[t].clone());
        let wl = w.clone() * &losses[t];
        for j in 0..d {
            g[j] += w.clone() * &grads[t][j] + wl.clone() * &score_sum[j];
        }
        for j in 0..d {
            score_sum[j] += &scores[t][j];
        }
    }
    g
}

/// `[causal, full, per-decision weighted, trajectory weighted]` and the trajectory loss.
#[allow(clippy::needless_range_loop)]
fn reference<S: Real, P: LikelihoodRatio<S>, L: Borrow<P::Label>>(
    policy: &P,
    theta: &[S],
    theta_new: &[S],
    t: &TaskTrajectory<S, L, P::Action>,
) -> ([Vec<S>; 4], S) {
    let d = policy.param_dim();
    let (losses, grads, scores) = terms(policy, theta, t);
    let causal = causal_weighted(d, &losses, &grads, &scores, None);
    let total = losses.iter().fold(S::zero(), |a, l| a + l);
    let n = losses.len();
    let mut full = vec![S::zero(); d];
    for t in 0..n {
        for j in 0..d {
            full[j] += &grads[t][j];
            if t + 1 < n {
                full[j] += total.clone() * &scores[t][j];
            }
        }
    }
    let features = t.features();
    let mut prefix = Vec::with_capacity(n);
    let mut log_w = S::zero();
    for i in 0..n {
        prefix.push(log_w.exp());
        if i + 1 < n {
            log_w += policy
                .log_likelihood_ratio(theta, theta_new, &features[i], &t.actions[i])
                .unwrap();
        }
    }
    let per_decision = causal_weighted(d, &losses, &grads, &scores, Some(&prefix));
    let w = log_w.exp();
    let trajectory = causal.iter().map(|x| x.clone() * &w).collect();
    let mut loss = S::zero();
    for l in &losses {
        loss += l;
    }
    ([causal, full, per_decision, trajectory], loss)
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn check_problem<T, P>(p: &TaskProblem<T, P>, th: &DVector<f64>, th2: &DVector<f64>, seeds: u64)
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let mut c = Cost::default();
    for seed in 0..seeds {
        let mut rng = KitRng::seed_from_u64(seed);
        let t = p
            .rollout(&Behaviour::Learner(th2), &mut rng, &mut c)
            .unwrap();
        let (want, loss) = reference(&p.policy, th.as_slice(), th2.as_slice(), &t);
        let got = [
            p.estimate(th, &t, EstimatorForm::Causal, &mut c).unwrap(),
            p.estimate(th, &t, EstimatorForm::Full, &mut c).unwrap(),
            p.weighted_estimate(th, th2, &t, Weighting::PerDecision, &mut c)
                .unwrap(),
            p.weighted_estimate(th, th2, &t, Weighting::Trajectory, &mut c)
                .unwrap(),
        ];
        for (k, (w, g)) in want.iter().zip(&got).enumerate() {
            assert_eq!(bits(w), bits(g.as_slice()), "seed {seed}, form {k}");
        }
        assert_eq!(
            loss.to_bits(),
            p.trajectory_loss(th, &t).unwrap().to_bits(),
            "seed {seed}"
        );
        // The flat features are the task's features, step by step.
        assert_eq!(t.features().len(), t.len());
        assert_eq!(t.feature_data().len(), t.len() * t.feature_dim());
    }
}

fn logistic() -> TaskProblem<CartPoleTask<f64>, Logistic> {
    TaskProblem {
        task: CartPoleTask::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

fn softmax() -> TaskProblem<CartPoleTask<f64>, Softmax> {
    TaskProblem {
        task: CartPoleTask::with_lqr().unwrap(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

fn obstacle_problem() -> TaskProblem<ObstacleTask, LinearGaussian<f64>> {
    TaskProblem {
        task: ObstacleTask::thesis().unwrap(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.05).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

fn thetas() -> [DVector<f64>; 6] {
    [
        DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1]),
        DVector::from_vec(vec![0.5, 1.5, 9.0, 2.5, -0.1]),
        DVector::from_fn(10, |i, _| 0.4 * (i as f64 - 4.5)),
        DVector::from_fn(10, |i, _| 0.3 * (i as f64 - 4.0)),
        DVector::from_fn(18, |i, _| {
            if i % 10 == 0 {
                0.05
            } else {
                0.01 * (i as f64 - 9.0)
            }
        }),
        DVector::from_fn(18, |i, _| {
            if i % 10 == 0 {
                0.04
            } else {
                0.012 * (i as f64 - 8.0)
            }
        }),
    ]
}

#[test]
fn cartpole_logistic_matches_the_reference_bit_for_bit() {
    let [a, b, ..] = thetas();
    check_problem(&logistic(), &a, &b, 40);
}

#[test]
fn cartpole_softmax_matches_the_reference_bit_for_bit() {
    let [_, _, a, b, ..] = thetas();
    check_problem(&softmax(), &a, &b, 20);
}

#[test]
fn obstacle_linear_gaussian_matches_the_reference_bit_for_bit() {
    let [.., a, b] = thetas();
    check_problem(&obstacle_problem(), &a, &b, 20);
    check_problem(&obstacle_inline(), &a, &b, 20);
}

/// Inline actions (`[f64; 2]`) instead of `Vec<f64>`: the same trajectories and numbers.
fn obstacle_inline() -> TaskProblem<ObstacleTask<[f64; 2]>, LinearGaussian<f64, [f64; 2]>> {
    let p = obstacle_problem();
    TaskProblem {
        task: p.task.with_actions(),
        policy: p.policy.with_actions().unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

fn fnv(h: &mut u64, x: f64) {
    for b in x.to_bits().to_le_bytes() {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

fn hash_problem<P: IlProblem<f64>>(p: &P, th: &DVector<f64>, th2: &DVector<f64>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut c = Cost::default();
    for seed in 0..40u64 {
        let mut rng = KitRng::seed_from_u64(seed);
        let t = p
            .rollout(&Behaviour::Learner(th2), &mut rng, &mut c)
            .unwrap();
        for g in [
            p.estimate(th, &t, EstimatorForm::Causal, &mut c).unwrap(),
            p.estimate(th, &t, EstimatorForm::Full, &mut c).unwrap(),
            p.weighted_estimate(th, th2, &t, Weighting::PerDecision, &mut c)
                .unwrap(),
            p.weighted_estimate(th, th2, &t, Weighting::Trajectory, &mut c)
                .unwrap(),
        ] {
            for x in g.iter() {
                fnv(&mut h, *x);
            }
        }
        fnv(&mut h, p.trajectory_loss(th, &t).unwrap());
    }
    fnv(&mut h, c.env_steps as f64);
    h
}

/// Hashes of the same computations by the code before the allocation-free rewrite (commit c7339ac): roll-outs,
/// estimates of every form and trajectory losses on 40 seeds per problem.
#[test]
fn outputs_match_the_pre_issue_8_code() {
    let [l1, l2, s1, s2, o1, o2] = thetas();
    let got = [
        hash_problem(&logistic(), &l1, &l2),
        hash_problem(&softmax(), &s1, &s2),
        hash_problem(&obstacle_problem(), &o1, &o2),
    ];
    assert_eq!(got, GOLDEN);
    assert_eq!(hash_problem(&obstacle_inline(), &o1, &o2), GOLDEN[2]);
}

const GOLDEN: [u64; 3] = [
    4_897_245_781_274_432_189,
    13_798_414_826_660_304_781,
    12_331_457_234_670_763_619,
];
