//! End-to-end runs through the library's runner, one seed each, sizes of
//! paper-checks' quick profile:
//!
//! * a Table 4.1-like run: STORM (η = 10⁻⁸, a = 1/2, causal, unweighted) with the linear-Gaussian
//!   policy (σ_π = 0.02) on the obstacle task, θ₀ = 0, 40 iterations — with the default `Vec<f64>`
//!   actions and with inline `[f64; 2]` actions (the same run). (The quick profile's η = 10⁻⁶ (and 10⁻⁷)
//!   with one trajectory per step diverges at iteration 8 with seed 1:
//!   a non-finite estimate.)
//! * a Table 4.3-like run: STORM (η = 0.01, a = 1/2) with the logistic policy on CartPole-v1 (LQR
//!   expert), θ₀ = 0, 200 iterations.
//!
//! Run with `cargo bench --bench end_to_end`; the time per run is the figure to compare with the
//! thesis's Tables 4.2 and 4.4 (per seed).

use criterion::{Criterion, criterion_group, criterion_main};
use ilopt::algo::config::RunConfig;
use ilopt::algo::{RunRecord, Runner, Termination};
use ilopt::policy::{LinearGaussian, Logistic};
use ilopt::problem::IlProblem;
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};

fn storm(eta: &str, dim: usize, iterations: u64) -> RunConfig {
    let zeros = vec!["0"; dim];
    RunConfig::from_json(
        &serde_json::json!({
            "algorithm": {
                "algorithm": "storm",
                "form": "causal",
                "correction": "unweighted",
                "schedule": { "kind": "constant", "eta": eta, "a": "1/2" }
            },
            "theta0": zeros,
            "seed": 1,
            "stop": { "max_iterations": iterations }
        })
        .to_string(),
    )
    .unwrap()
}

fn record<P: IlProblem<f64>>(config: &RunConfig, problem: &mut P) -> RunRecord<f64> {
    let mut runner = Runner::<f64>::new(config.stop.clone())
        .unwrap()
        .keep_history(false);
    runner.run_config(config, problem).unwrap()
}

fn run<P: IlProblem<f64>>(config: &RunConfig, problem: &mut P) -> u64 {
    record(config, problem).cost.env_steps
}

fn end_to_end(c: &mut Criterion) {
    let mut g = c.benchmark_group("end to end");
    g.sample_size(10);
    let mut obstacle_vec = TaskProblem {
        task: ObstacleTask::thesis().unwrap(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.02).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let mut obstacle_inline = TaskProblem {
        task: ObstacleTask::thesis().unwrap().with_actions::<[f64; 2]>(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.02)
            .unwrap()
            .with_actions::<[f64; 2]>()
            .unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let cfg = storm("1e-8", obstacle_vec.dim(), 40);
    let rec = record(&cfg, &mut obstacle_vec);
    let steps = rec.cost.env_steps;
    assert!(rec.same_run(&record(&cfg, &mut obstacle_inline)));
    assert_eq!(rec.termination, Termination::MaxIterations);
    eprintln!(
        "Table 4.1-like STORM run: {} iterations ({:?}), {steps} environment steps",
        rec.iterations, rec.termination
    );
    g.bench_function(
        "Table 4.1-like: STORM, linear-Gaussian, obstacle, 40 it. (Vec actions)",
        |b| b.iter(|| run(&cfg, &mut obstacle_vec)),
    );
    g.bench_function(
        "Table 4.1-like: STORM, linear-Gaussian, obstacle, 40 it. (inline actions)",
        |b| b.iter(|| run(&cfg, &mut obstacle_inline)),
    );

    let mut cartpole = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let cfg = storm("0.01", cartpole.dim(), 200);
    let rec = record(&cfg, &mut cartpole);
    assert_eq!(rec.termination, Termination::MaxIterations);
    eprintln!(
        "Table 4.3-like STORM run: {} iterations ({:?}), {} environment steps",
        rec.iterations, rec.termination, rec.cost.env_steps
    );
    g.bench_function("Table 4.3-like: STORM, logistic, CartPole, 200 it.", |b| {
        b.iter(|| run(&cfg, &mut cartpole))
    });
    g.finish();
}

criterion_group!(benches, end_to_end);
criterion_main!(benches);
