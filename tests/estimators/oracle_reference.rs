//! Golden hashes computed by the pre-issue-8 code pin the roll-outs and estimates of
//! `TaskProblem` across versions (CartPole with the logistic and softmax policies, the obstacle
//! task with the linear-Gaussian policy, `Vec` and inline actions). Every route's agreement with
//! the reference sums of eq. 3.15 on the same trajectories is the contract of `routes.rs`.

use ilopt::policy::{LinearGaussian, Logistic, Softmax};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use nalgebra::DVector;
use rand::SeedableRng;

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

fn hash_problem<P: IlProblem<f64>>(p: &mut P, th: &DVector<f64>, th2: &DVector<f64>) -> u64 {
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
        hash_problem(&mut logistic(), &l1, &l2),
        hash_problem(&mut softmax(), &s1, &s2),
        hash_problem(&mut obstacle_problem(), &o1, &o2),
    ];
    assert_eq!(got, GOLDEN);
    assert_eq!(hash_problem(&mut obstacle_inline(), &o1, &o2), GOLDEN[2]);
}

const GOLDEN: [u64; 3] = [
    4_897_245_781_274_432_189,
    13_798_414_826_660_304_781,
    12_331_457_234_670_763_619,
];
