//! Throughput of the kit's hot kernels: CartPole steps, the velocity-obstacle expert,
//! the toy oracle (roll-out + eq. 3.15 estimate), the exact engine (prefixes per second, rational
//! and `f64`), the CartPole oracle with the softmax policy, and the interval product (inari's
//! operator against `Scalar::product`, which gives the same intervals).
//! Run with `cargo bench --bench kernels`. The oracle hot paths (CartPole + logistic,
//! generic against hand-specialised; the obstacle task) are in `benches/oracle.rs`, whole runs
//! through the runner in `benches/end_to_end.rs`; `benches/README.md` records the figures.

use criterion::{BenchmarkId, Criterion, Throughput, black_box, criterion_group, criterion_main};
use ilopt::exact::enumerate::moments;
use ilopt::expert::vo::vo_expert;
use ilopt::policy::Softmax;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::scalar::{BigRational, Interval, Scalar, parse_exact};
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;
use rand::SeedableRng;

fn example(name: &str) -> ToyMdp {
    ToyMdp::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/toy")
            .join(name),
    )
    .unwrap()
}

fn cartpole_env(c: &mut Criterion) {
    let mut g = c.benchmark_group("cartpole");
    g.throughput(Throughput::Elements(1));
    g.bench_function("step (f64)", |b| {
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
    g.finish();
}

fn vo(c: &mut Criterion) {
    let mut g = c.benchmark_group("vo_expert");
    g.throughput(Throughput::Elements(1));
    g.bench_function("solve", |b| {
        let mut k = 0.0f64;
        b.iter(|| {
            k += 1e-3;
            vo_expert(
                black_box([1.0, 0.1 + k.sin() * 0.3]),
                [-0.01, 0.005],
                [0.08, 0.0],
                [0.1, 0.0],
                0.5,
                0.46,
            )
        })
    });
    g.finish();
}

fn toy_oracle(c: &mut Criterion) {
    let mdp = example("three-state.json");
    let mut p = ToyProblem::<f64>::new(&mdp);
    let theta = DVector::from_vec(vec![0.5, -1.0, 0.1, 3.0, 0.6, -1.2]);
    let mut g = c.benchmark_group("toy oracle");
    g.throughput(Throughput::Elements((mdp.horizon - 1) as u64));
    g.bench_function("roll-out + causal estimate (f64, T = 4)", |b| {
        let mut rng = KitRng::seed_from_u64(1);
        let mut cost = Cost::default();
        b.iter(|| {
            let t = p
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
                .unwrap();
            p.estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap()
        })
    });
    g.finish();
}

fn exact_engine(c: &mut Criterion) {
    let mdp = example("three-state.json");
    let mut g = c.benchmark_group("exact engine X1 (three-state, T = 4)");
    let th: Vec<BigRational> = ["1/2", "-1", "0.1", "3", "2/3", "-5/4"]
        .iter()
        .map(|x| parse_exact(x).unwrap())
        .collect();
    let pq = ToyProblem::<BigRational>::new(&mdp);
    let n = moments(&pq, &th).unwrap().prefixes;
    g.throughput(Throughput::Elements(n));
    g.bench_function(BenchmarkId::new("moments", "rational"), |b| {
        b.iter(|| moments(&pq, black_box(&th)).unwrap())
    });
    let pf = ToyProblem::<f64>::new(&mdp);
    let thf: Vec<f64> = th.iter().map(ilopt::scalar::Scalar::to_f64).collect();
    g.bench_function(BenchmarkId::new("moments", "f64"), |b| {
        b.iter(|| moments(&pf, black_box(&thf)).unwrap())
    });
    g.finish();
}

fn cartpole_oracle(c: &mut Criterion) {
    let mut p = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().unwrap(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let theta = DVector::from_vec(vec![0.0, 0.0, -2.0, -0.5, 0.0, 0.0, 0.0, 2.0, 0.5, 0.0]);
    // Measure the mean episode length once, to report trajectory-steps per second.
    let mut rng = KitRng::seed_from_u64(3);
    let mut cost = Cost::default();
    for _ in 0..200 {
        p.rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
            .unwrap();
    }
    let mut g = c.benchmark_group("cartpole oracle");
    g.throughput(Throughput::Elements(cost.env_steps / 200));
    g.bench_function("roll-out + LQR labels + softmax + causal estimate", |b| {
        let mut rng = KitRng::seed_from_u64(1);
        let mut cost = Cost::default();
        b.iter(|| {
            let t = p
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
                .unwrap();
            p.estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap()
        })
    });
    g.finish();
}

/// 4096 products of intervals from a fixed list (narrow boxes of mixed signs, as the
/// branch-and-bound gives, and positive ones), by inari's `*` and by [`Scalar::product`].
fn interval_product(c: &mut Criterion) {
    use rand::Rng;
    let mut rng = KitRng::seed_from_u64(1);
    let mut boxes = |lo: f64, hi: f64| -> Vec<Interval> {
        (0..4096)
            .map(|_| {
                let m: f64 = rng.random_range(lo..hi);
                let w = 2f64.powi(rng.random_range(-40..-1));
                Interval::try_from((m, m + w)).unwrap()
            })
            .collect()
    };
    let sets = [
        ("mixed signs", boxes(-3.0, 3.0)),
        ("positive", boxes(1.0, 3.0)),
    ];
    let mut g = c.benchmark_group("interval product");
    g.throughput(Throughput::Elements(4096));
    for (name, xs) in &sets {
        let pairs: Vec<(Interval, Interval)> = xs
            .iter()
            .zip(xs.iter().rev().cycle().skip(7))
            .map(|(x, y)| (*x, *y))
            .collect();
        g.bench_with_input(BenchmarkId::new("inari", name), &pairs, |b, pairs| {
            b.iter(|| {
                let mut s = 0.0;
                for (x, y) in pairs {
                    s += (black_box(*x) * black_box(*y)).sup();
                }
                s
            });
        });
        g.bench_with_input(
            BenchmarkId::new("Scalar::product", name),
            &pairs,
            |b, pairs| {
                b.iter(|| {
                    let mut s = 0.0;
                    for (x, y) in pairs {
                        s += black_box(*x).product(&black_box(*y)).sup();
                    }
                    s
                });
            },
        );
    }
    g.finish();
}

criterion_group!(
    benches,
    cartpole_env,
    vo,
    toy_oracle,
    exact_engine,
    cartpole_oracle,
    interval_product
);
criterion_main!(benches);
