//! PPO expert training on CartPole-v1 (`ilopt::expert::ppo`), single-threaded:
//!
//! * one training iteration (a rollout of 8 × 32 steps, GAE, then 20 epochs of one 256-sample
//!   mini-batch update of both networks) from the state after 50 iterations of seed 1;
//! * the whole default run of seed 1 (391 iterations, 100 096 environment steps), the run that
//!   writes `experts/cartpole-ppo.json`, checked to reach the target mean return.
//!
//! Run with `cargo bench --bench ppo`; `benches/README.md` ("PPO expert training") has the
//! figures and where the time goes.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use ilopt::expert::ppo::{PpoConfig, PpoTrainer, TARGET_MEAN_RETURN, train};
use std::hint::black_box;
use std::time::Duration;

fn ppo(c: &mut Criterion) {
    let config = PpoConfig::default();
    let mut g = c.benchmark_group("ppo");
    g.sample_size(10);
    let mut trainer = PpoTrainer::new(&config, 1).unwrap();
    for _ in 0..50 {
        trainer.iteration().unwrap();
    }
    g.bench_function("one iteration (256 steps, 20 epochs of 256)", |b| {
        b.iter_batched(
            || trainer.clone(),
            |mut t| black_box(t.iteration().unwrap()),
            BatchSize::SmallInput,
        )
    });
    let (expert, _) = train(&config, 1, |_| {}).unwrap();
    assert!(expert.evaluate().unwrap().mean_return >= TARGET_MEAN_RETURN);
    g.measurement_time(Duration::from_secs(30));
    g.bench_function("training, seed 1, 100 096 steps", |b| {
        b.iter(|| black_box(train(&config, 1, |_| {}).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, ppo);
criterion_main!(benches);
