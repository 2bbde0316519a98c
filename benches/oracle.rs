//! Benchmarks of the oracle hot paths, in trajectory-steps per second:
//!
//! 1. CartPole: the environment step; roll-out (LQR labels, logistic policy) + causal estimate of
//!    eq. 3.15, generic `TaskProblem<CartPoleTask<f64>, Logistic>` next to the hand-specialised
//!    `f64` version of `support/specialised.rs` (same trajectories, bit-identical gradients);
//! 2. the obstacle task: roll-out (linear-Gaussian policy, VO expert labels) + causal estimate,
//!    with the default `Vec<f64>` actions and with inline `[f64; 2]` actions (no allocation);
//! 3. the VO expert alone (solves per second);
//! 4. the baselined causal estimate (`ilopt::baseline`) on the CartPole trajectories of (1): one
//!    constant baseline (m = 1) and leave-one-out over pairs (m = 2), beside the plain estimate of
//!    the same trajectories, and the variance-minimising per-decision constants estimated from
//!    earlier trajectories (m = 1, decay 0.99, statistics of every trajectory committed first);
//!    and roll-out + estimate with the constant baseline, with the estimated baselines (their
//!    statistics committed at each roll-out, as in training), and with leave-one-out over pairs
//!    beside the plain mean of pairs.
//! 5. the fixed-horizon objective (streams of T decisions, reset or absorbing) through the same
//!    roll-out and estimator: CartPole (LQR labels) with resets and absorbing ends, CartPole with
//!    the experiments' PPO labels and softmax learner, the obstacle task with absorbing ends.
//!
//! Each iteration rolls out the same fixed set of seeds (re-seeded), so the throughput in steps
//! is exact. Run with `cargo bench --bench oracle`.

#[path = "support/specialised.rs"]
mod specialised;
#[path = "support/state_baseline.rs"]
mod state_baseline;

use criterion::{Criterion, Throughput, black_box, criterion_group, criterion_main};
use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined};
use ilopt::env::obstacle::ObstacleEnv;
use ilopt::expert::lqr::LqrExpert;
use ilopt::expert::vo_policy::VoExpertPolicy;
use ilopt::policy::{LinearGaussian, Logistic, Softmax};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, TaskProblem};
use nalgebra::DVector;
use rand::SeedableRng;
use specialised::{D, Specialised, Trajectory};
use state_baseline::fitted_state;

/// Seeds rolled out per benchmark iteration.
const SEEDS: u64 = 16;

/// The logistic θ of the CartPole benchmarks: it balances for a while (episodes of every length
/// up to the 500-step limit).
const CARTPOLE_THETA: [f64; D] = [0.3, 1.0, 8.0, 2.0, 0.1];

fn steps_of<P: IlProblem<f64>>(p: &mut P, theta: &DVector<f64>) -> u64 {
    let mut cost = Cost::default();
    for seed in 0..SEEDS {
        let mut rng = KitRng::seed_from_u64(seed);
        p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
            .unwrap();
    }
    cost.env_steps
}

/// Roll out and estimate (causal) on every seed; returns a sum so nothing is optimised away (each
/// gradient goes through `black_box` whole, so that no entry's arithmetic can be dropped).
fn oracle_pass<P: IlProblem<f64>>(p: &mut P, theta: &DVector<f64>) -> f64 {
    let mut cost = Cost::default();
    let mut acc = 0.0;
    for seed in 0..SEEDS {
        let mut rng = KitRng::seed_from_u64(seed);
        let t = p
            .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
            .unwrap();
        acc += black_box(
            p.estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap(),
        )[0];
    }
    acc
}

fn cartpole(c: &mut Criterion) {
    let mut g = c.benchmark_group("cartpole");
    g.throughput(Throughput::Elements(1));
    g.bench_function("env step (f64)", |b| {
        let dynamics = ilopt::env::cartpole::CartPoleDynamics::<f64>::new();
        let mut s = [0.01, -0.02, 0.03, 0.04];
        let mut a = 0usize;
        b.iter(|| {
            let (next, term) = dynamics.step(black_box(&s), a).unwrap();
            s = if term {
                [0.01, -0.02, 0.03, 0.04]
            } else {
                next
            };
            a ^= 1;
        })
    });

    let mut generic = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let theta = DVector::from_column_slice(&CARTPOLE_THETA);
    g.throughput(Throughput::Elements(steps_of(&mut generic, &theta)));
    g.bench_function("roll-out + causal estimate, generic (f64)", |b| {
        b.iter(|| oracle_pass(&mut generic, black_box(&theta)))
    });
    g.bench_function("roll-out only, generic (f64)", |b| {
        b.iter(|| {
            let mut cost = Cost::default();
            for seed in 0..SEEDS {
                let mut rng = KitRng::seed_from_u64(seed);
                black_box(
                    generic
                        .rollout(&Behaviour::Learner(black_box(&theta)), &mut rng, &mut cost)
                        .unwrap(),
                );
            }
        })
    });
    let trajectories: Vec<_> = (0..SEEDS)
        .map(|seed| {
            let mut rng = KitRng::seed_from_u64(seed);
            generic
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut Cost::default())
                .unwrap()
        })
        .collect();
    g.bench_function("causal estimate only, generic (f64)", |b| {
        b.iter(|| {
            let mut cost = Cost::default();
            for t in &trajectories {
                black_box(
                    generic
                        .estimate(black_box(&theta), t, EstimatorForm::Causal, &mut cost)
                        .unwrap(),
                );
            }
        })
    });

    let singles: Vec<Vec<_>> = trajectories.iter().map(|t| vec![t.clone()]).collect();
    let pairs: Vec<Vec<_>> = trajectories.chunks(2).map(<[_]>::to_vec).collect();
    let mut constant = Baselined::new(
        generic.clone(),
        1,
        &Baseline::Constant {
            value: ConfigNumber::ratio(50, 1),
        },
    )
    .unwrap();
    // The variance-minimising per-decision constants estimated from earlier trajectories (decay
    // 0.99), with statistics from every trajectory of the set committed first, so that the
    // estimate subtracts real baselines.
    let mut estimated = Baselined::new(
        generic.clone(),
        1,
        &Baseline::Estimated {
            time_indexed: true,
            decay: Some(ConfigNumber::ratio(99, 100)),
        },
    )
    .unwrap();
    let mut warm = Cost::default();
    for one in &singles {
        estimated
            .estimate(&theta, one, EstimatorForm::Causal, &mut warm)
            .unwrap();
    }
    estimated
        .rollout(
            &Behaviour::Learner(&theta),
            &mut KitRng::seed_from_u64(SEEDS),
            &mut warm,
        )
        .unwrap();
    // The state-dependent baseline with the default share of trajectories' statistics, and with
    // every trajectory's.
    let mut state = fitted_state(&generic, &theta, &singles, None, SEEDS);
    let mut state_all = fitted_state(&generic, &theta, &singles, Some(1), SEEDS);
    let mut loo = Baselined::new(generic.clone(), 2, &Baseline::LeaveOneOut).unwrap();
    let mut plain_pairs = Baselined::new(generic.clone(), 2, &Baseline::None).unwrap();
    let estimate_all = |p: &mut Baselined<_, f64>, batches: &[Vec<_>]| {
        let mut cost = Cost::default();
        for t in batches {
            black_box(
                p.estimate(black_box(&theta), t, EstimatorForm::Causal, &mut cost)
                    .unwrap(),
            );
        }
    };
    g.bench_function(
        "causal estimate only, constant baseline, generic (f64)",
        |b| b.iter(|| estimate_all(&mut constant, &singles)),
    );
    g.bench_function(
        "causal estimate only, estimated per-decision baselines, generic (f64)",
        |b| b.iter(|| estimate_all(&mut estimated, &singles)),
    );
    g.bench_function(
        "causal estimate only, pairs, no baseline, generic (f64)",
        |b| b.iter(|| estimate_all(&mut plain_pairs, &pairs)),
    );
    g.bench_function(
        "causal estimate only, pairs, leave-one-out baseline, generic (f64)",
        |b| b.iter(|| estimate_all(&mut loo, &pairs)),
    );
    g.bench_function(
        "roll-out + causal estimate, constant baseline, generic (f64)",
        |b| b.iter(|| oracle_pass(&mut constant, black_box(&theta))),
    );
    g.bench_function(
        "roll-out + causal estimate, estimated per-decision baselines, generic (f64)",
        |b| b.iter(|| oracle_pass(&mut estimated, black_box(&theta))),
    );
    g.bench_function(
        "roll-out + causal estimate, state-dependent baseline (statistics from every 8th trajectory), generic (f64)",
        |b| b.iter(|| oracle_pass(&mut state, black_box(&theta))),
    );
    g.bench_function(
        "roll-out + causal estimate, state-dependent baseline (statistics from every trajectory), generic (f64)",
        |b| b.iter(|| oracle_pass(&mut state_all, black_box(&theta))),
    );
    // Pairs rolled out per seed: the whole oracle call with leave-one-out against the plain mean.
    g.throughput(Throughput::Elements(steps_of(&mut loo, &theta)));
    g.bench_function(
        "roll-out + causal estimate, pairs, no baseline, generic (f64)",
        |b| b.iter(|| oracle_pass(&mut plain_pairs, black_box(&theta))),
    );
    g.bench_function(
        "roll-out + causal estimate, pairs, leave-one-out baseline, generic (f64)",
        |b| b.iter(|| oracle_pass(&mut loo, black_box(&theta))),
    );
    g.throughput(Throughput::Elements(steps_of(&mut generic, &theta)));

    let gain = *LqrExpert::cartpole().unwrap().gain();
    let fast = Specialised {
        k: std::array::from_fn(|i| gain[i]),
        max_steps: ilopt::env::cartpole::MAX_EPISODE_STEPS,
    };
    // The yardstick: the specialised roll-out and estimate, functions of their own as the generic
    // ones are (`support/specialised.rs`).
    g.bench_function("roll-out + causal estimate, hand-specialised (f64)", |b| {
        let mut t = Trajectory::default();
        b.iter(|| {
            let mut acc = 0.0;
            for seed in 0..SEEDS {
                let mut rng = KitRng::seed_from_u64(seed);
                fast.rollout(black_box(&CARTPOLE_THETA), &mut rng, &mut t);
                // The whole gradient through `black_box`: with only `g[0]` used, the compiler
                // could drop the other entries' arithmetic (it did while the estimate was inlined
                // here: a yardstick ≈ 4 % too fast).
                acc += black_box(Specialised::estimate(black_box(&CARTPOLE_THETA), &t))[0];
            }
            acc
        })
    });

    // The thesis's fixed-horizon objective through the same roll-out and estimator: streams of
    // exactly 500 decisions, reset after a crash or absorbing (the same policy, so the episodic
    // rows above are the yardstick per step).
    for (name, after_end) in [("reset", AfterEnd::Reset), ("absorb", AfterEnd::Absorb)] {
        let mut fixed = TaskProblem {
            horizon: Horizon::fixed(ilopt::env::cartpole::MAX_EPISODE_STEPS, after_end),
            ..generic.clone()
        };
        g.throughput(Throughput::Elements(steps_of(&mut fixed, &theta)));
        g.bench_function(
            format!("roll-out + causal estimate, generic, fixed 500 {name} (f64)"),
            |b| b.iter(|| oracle_pass(&mut fixed, black_box(&theta))),
        );
    }
    // What the chapter-4 experiments run: the PPO expert's labels, the softmax learner, 500
    // decisions with resets (θ = 0: the learner crashes often, so resets are frequent).
    let mut ppo = TaskProblem {
        task: CartPoleTask::<f64>::with_ppo(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json"),
        )
        .unwrap(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: Horizon::fixed(ilopt::env::cartpole::MAX_EPISODE_STEPS, AfterEnd::Reset),
    };
    let zero = DVector::zeros(2 * cartpole::FEATURES);
    g.throughput(Throughput::Elements(steps_of(&mut ppo, &zero)));
    g.bench_function(
        "roll-out + causal estimate, PPO labels + softmax, fixed 500 reset (f64)",
        |b| b.iter(|| oracle_pass(&mut ppo, black_box(&zero))),
    );
    g.finish();
}

/// W with a proportional pull towards the goal (paper-checks' quick profile).
fn obstacle_theta() -> DVector<f64> {
    let mut w = vec![0.0; 2 * obstacle::FEATURES];
    w[0] = 0.05;
    w[obstacle::FEATURES + 1] = 0.05;
    DVector::from_vec(w)
}

fn obstacle_task(c: &mut Criterion) {
    let mut g = c.benchmark_group("obstacle");
    let theta = obstacle_theta();
    let mut p = TaskProblem {
        task: ObstacleTask::thesis().unwrap(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.02).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    g.throughput(Throughput::Elements(steps_of(&mut p, &theta)));
    g.bench_function(
        "roll-out + VO labels + linear-Gaussian + causal estimate (f64, Vec actions)",
        |b| b.iter(|| oracle_pass(&mut p, black_box(&theta))),
    );
    let mut inline = TaskProblem {
        task: p.task.clone().with_actions::<[f64; 2]>(),
        policy: p.policy.clone().with_actions::<[f64; 2]>().unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    g.bench_function(
        "roll-out + VO labels + linear-Gaussian + causal estimate (f64, inline actions)",
        |b| b.iter(|| oracle_pass(&mut inline, black_box(&theta))),
    );
    // The fixed-horizon objective of the experiments: 200 decisions, absorbing ends.
    let mut absorb = TaskProblem {
        horizon: Horizon::fixed(200, AfterEnd::Absorb),
        ..inline.clone()
    };
    g.throughput(Throughput::Elements(steps_of(&mut absorb, &theta)));
    g.bench_function(
        "roll-out + VO labels + linear-Gaussian + causal estimate (f64, inline actions, fixed 200 absorb)",
        |b| b.iter(|| oracle_pass(&mut absorb, black_box(&theta))),
    );
    g.finish();
}

fn vo_expert(c: &mut Criterion) {
    let mut g = c.benchmark_group("vo expert");
    // The states of real episodes (the expert driving), cycled.
    let config = ilopt::env::obstacle::ObstacleConfig::default();
    let expert = VoExpertPolicy::new(&config, Default::default()).unwrap();
    let mut env = ObstacleEnv::new(config).unwrap();
    let mut states = vec![];
    for seed in 0..SEEDS {
        let mut rng = KitRng::seed_from_u64(seed);
        let mut obs = env.reset(&mut rng);
        loop {
            states.push(obs);
            let s = env.step(expert.act(&obs).unwrap()).unwrap();
            obs = s.observation;
            if s.terminated || s.truncated {
                break;
            }
        }
    }
    g.throughput(Throughput::Elements(states.len() as u64));
    g.bench_function("solve (policy act on visited states)", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for s in &states {
                acc += black_box(expert.act(black_box(s)).unwrap())[0];
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, cartpole, obstacle_task, vo_expert);
criterion_main!(benches);
