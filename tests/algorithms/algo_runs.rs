//! Whole runs on the toy MDP M1 (math.md §6, `examples/toy/m1-direct.json`, θ = π(0|·)) and on its
//! P2 variant: every algorithm runs in f64; field-only algorithms run in exact rationals; interval
//! runs with the same seed follow the same trajectories and enclose the f64 (and rational)
//! iterates; seeded runs are bit-for-bit reproducible and replay from their JSON record; costs are
//! accounted in the same units.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use ilopt::algo::adam::{AdamConfig, AdamOptimizerConfig};
use ilopt::algo::as_printed::PrintedAlgorithm4Config;
use ilopt::algo::bc::BcConfig;
use ilopt::algo::dagger::{BetaSchedule, DaggerConfig};
use ilopt::algo::dataset::{InnerConfig, Retrain};
use ilopt::algo::forward_training::ForwardTrainingConfig;
use ilopt::algo::o2nc::{O2nc, O2ncConfig};
use ilopt::algo::rmsprop::{RmsPropConfig, RmsPropOptimizerConfig};
use ilopt::algo::rrm::RrmConfig;
use ilopt::algo::sgd::{SgdConfig, SgdStep};
use ilopt::algo::smile::SmileConfig;
use ilopt::algo::storm::{Correction, StormConfig, StormSchedule};
use ilopt::algo::storm_plus::StormPlusConfig;
use ilopt::algo::{
    Algorithm, AlgorithmConfig, ConfigNumber, IterationMetrics, RunConfig, RunRecord, Runner,
    StepContext, StoppingRule, Termination, replay,
};
use ilopt::problem::{Cost, EstimatorForm, KitRng};
use ilopt::scalar::{BigRational, Interval, Scalar, interval_contains_rational};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;
use rand::SeedableRng;
use std::path::Path;

fn mdp(name: &str) -> ToyMdp {
    ToyMdp::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/toy")
            .join(name),
    )
    .unwrap()
}

fn causal() -> EstimatorForm {
    EstimatorForm::Causal
}

fn storm(schedule: StormSchedule, correction: Correction) -> AlgorithmConfig {
    AlgorithmConfig::Storm(StormConfig {
        schedule,
        correction,
        form: causal(),
    })
}

/// Exact argmin of the M1 dataset loss in one full-batch step (the Brier loss has curvature 4).
fn argmin_inner() -> InnerConfig {
    InnerConfig::gradient_descent(ConfigNumber::ratio(1, 4), 1)
}

fn o2nc_config() -> O2ncConfig {
    O2ncConfig {
        budget: 60,
        delta: ConfigNumber::ratio(1, 10),
        g: ConfigNumber::ratio(4, 1),
        delta0: ConfigNumber::ratio(2, 1),
        form: causal(),
    }
}

/// Field-only configurations (they run in exact rationals).
fn field_configs() -> Vec<AlgorithmConfig> {
    let constant = StormSchedule::constant(ConfigNumber::ratio(1, 128), ConfigNumber::ratio(1, 2));
    vec![
        AlgorithmConfig::Sgd(SgdConfig {
            step: SgdStep::constant(ConfigNumber::ratio(1, 128)),
            form: causal(),
        }),
        AlgorithmConfig::Sgd(SgdConfig {
            step: SgdStep::InverseTime {
                eta0: ConfigNumber::ratio(1, 64),
                k0: ConfigNumber::ratio(4, 1),
            },
            form: EstimatorForm::Full,
        }),
        storm(constant.clone(), Correction::Unweighted),
        storm(constant.clone(), Correction::Trajectory),
        storm(constant.clone(), Correction::PerDecision),
        AlgorithmConfig::PrintedAlgorithm4(PrintedAlgorithm4Config {
            schedule: constant,
            form: causal(),
        }),
        AlgorithmConfig::Bc(BcConfig {
            trajectories_per_iteration: 10,
            inner: argmin_inner(),
            retrain: Retrain::WarmStart,
        }),
        AlgorithmConfig::Dagger(DaggerConfig {
            trajectories_per_iteration: 10,
            beta: BetaSchedule::Exponential {
                p: ConfigNumber::ratio(1, 2),
            },
            aggregate: true,
            retrain: Retrain::FromScratch,
            inner: argmin_inner(),
        }),
        AlgorithmConfig::Dagger(DaggerConfig {
            trajectories_per_iteration: 10,
            beta: BetaSchedule::Linear { iterations: 3 },
            aggregate: true,
            retrain: Retrain::WarmStart,
            inner: InnerConfig {
                batch_size: Some(5),
                ..InnerConfig::gradient_descent(ConfigNumber::ratio(1, 8), 3)
            },
        }),
        AlgorithmConfig::Rrm(RrmConfig {
            trajectories_per_iteration: 10,
            retrain: Retrain::WarmStart,
            inner: argmin_inner(),
        }),
        AlgorithmConfig::Smile(SmileConfig {
            alpha: ConfigNumber::ratio(1, 2),
            trajectories_per_iteration: 10,
            retrain: Retrain::FromScratch,
            inner: argmin_inner(),
        }),
        AlgorithmConfig::ForwardTraining(ForwardTrainingConfig {
            trajectories_per_iteration: 10,
            inner: argmin_inner(),
        }),
    ]
}

/// Everything else (needs square or cube roots).
fn root_configs() -> Vec<AlgorithmConfig> {
    vec![
        AlgorithmConfig::Sgd(SgdConfig {
            step: SgdStep::InverseSqrt {
                eta0: ConfigNumber::ratio(1, 64),
            },
            form: causal(),
        }),
        storm(
            StormSchedule::Thesis {
                l: ConfigNumber::ratio(32, 1),
            },
            Correction::Unweighted,
        ),
        storm(
            StormSchedule::Thesis {
                l: ConfigNumber::ratio(32, 1),
            },
            Correction::Trajectory,
        ),
        storm(
            StormSchedule::Adaptive {
                k: ConfigNumber::Float(0.02),
                w: ConfigNumber::ratio(10, 1),
                c: ConfigNumber::ratio(10, 1),
            },
            Correction::PerDecision,
        ),
        AlgorithmConfig::StormPlus(StormPlusConfig {
            eta_scale: ConfigNumber::ratio(1, 40),
            b0: ConfigNumber::ratio(1, 1),
            ..StormPlusConfig::paper(Correction::PerDecision, causal())
        }),
        AlgorithmConfig::Adam(AdamOptimizerConfig {
            adam: AdamConfig::with_alpha(ConfigNumber::ratio(1, 50)),
            form: causal(),
        }),
        AlgorithmConfig::RmsProp(RmsPropOptimizerConfig {
            rmsprop: RmsPropConfig::with_eta(ConfigNumber::ratio(1, 50)),
            form: causal(),
        }),
        AlgorithmConfig::O2nc(o2nc_config()),
        AlgorithmConfig::PrintedAlgorithm5(o2nc_config()),
        AlgorithmConfig::Dagger(DaggerConfig {
            trajectories_per_iteration: 10,
            beta: BetaSchedule::Constant {
                beta: ConfigNumber::ratio(1, 2),
            },
            aggregate: true,
            retrain: Retrain::WarmStart,
            inner: InnerConfig {
                rule: ilopt::algo::dataset::RuleConfig::Adam(AdamConfig::with_alpha(
                    ConfigNumber::ratio(1, 20),
                )),
                iterations: 5,
                batch_size: None,
            },
        }),
    ]
}

fn run_config(algorithm: AlgorithmConfig, seed: u64, iterations: u64) -> RunConfig {
    RunConfig {
        algorithm,
        theta0: vec![ConfigNumber::ratio(1, 2)],
        seed,
        stop: StoppingRule::iterations(iterations),
    }
}

fn ok_end(t: &Termination) -> bool {
    matches!(t, Termination::MaxIterations | Termination::Finished)
}

#[test]
fn every_algorithm_runs_on_m1_in_f64() {
    for file in ["m1-direct.json", "m1-softmax.json"] {
        let mut problem = ToyProblem::<f64>::new(&mdp(file));
        let dim = ilopt::problem::IlProblem::<f64>::dim(&problem);
        let theta0 = if file == "m1-direct.json" {
            ConfigNumber::ratio(1, 2)
        } else {
            ConfigNumber::ratio(0, 1)
        };
        for algorithm in field_configs().into_iter().chain(root_configs()) {
            let cfg = RunConfig {
                theta0: vec![theta0.clone(); dim],
                ..run_config(algorithm, 11, 40)
            };
            let rec: RunRecord<f64> = replay(&cfg, &mut problem).unwrap();
            assert!(
                ok_end(&rec.termination),
                "{file} {}: {}",
                rec.algorithm,
                rec.termination
            );
            assert!(rec.theta.iter().all(|x| x.is_finite()));
            assert!(
                rec.cost.trajectories > 0 && rec.cost.gradient_evaluations > 0,
                "{}",
                rec.algorithm
            );
            // Cumulative costs never decrease.
            assert!(rec.history.windows(2).all(|w| {
                let (a, b) = (w[0].cost, w[1].cost);
                a.trajectories <= b.trajectories
                    && a.gradient_evaluations <= b.gradient_evaluations
                    && a.env_steps <= b.env_steps
                    && a.expert_queries <= b.expert_queries
            }));
        }
    }
}

#[test]
fn seeded_runs_are_bit_for_bit_reproducible() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    for algorithm in field_configs().into_iter().chain(root_configs()) {
        let cfg = run_config(algorithm, 2024, 30);
        let a: RunRecord<f64> = replay(&cfg, &mut problem).unwrap();
        let b: RunRecord<f64> = replay(&cfg, &mut problem).unwrap();
        assert!(a.same_run(&b), "{}", a.algorithm);
        let bits = |r: &RunRecord<f64>| {
            r.history
                .iter()
                .flat_map(|m| m.theta.iter().map(|x| x.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&a), bits(&b), "{}", a.algorithm);
        // A different seed gives a different run (all these algorithms sample).
        let c: RunRecord<f64> = replay(&RunConfig { seed: 2025, ..cfg }, &mut problem).unwrap();
        assert_ne!(bits(&a), bits(&c), "{}", a.algorithm);
    }
}

#[test]
fn a_recorded_config_replays_to_the_same_result() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    for algorithm in field_configs().into_iter().chain(root_configs()) {
        let cfg = run_config(algorithm, 99, 25);
        let mut seen = 0u64;
        let original = Runner::new(cfg.stop.clone())
            .unwrap()
            .with_observer(|_: &IterationMetrics<f64>| seen += 1)
            .run_config(&cfg, &mut problem)
            .unwrap();
        assert_eq!(seen, original.iterations + 1);
        let h = original.history_json();
        assert_eq!(h.as_array().unwrap().len() as u64, original.iterations + 1);
        assert_eq!(h[1]["iteration"], 1);
        assert_eq!(
            h[1]["cost"]["trajectories"].as_u64().unwrap(),
            original.history[1].cost.trajectories
        );
        let text = serde_json::to_string(&original.summary_json()["config"]).unwrap();
        let recorded = RunConfig::from_json(&text).unwrap();
        assert_eq!(recorded, cfg);
        let again: RunRecord<f64> = replay(&recorded, &mut problem).unwrap();
        assert!(again.same_run(&original), "{}", original.algorithm);
    }
}

fn encloses(i: &IterationMetrics<Interval>, f: &IterationMetrics<f64>) -> bool {
    i.cost == f.cost
        && i.theta
            .iter()
            .zip(f.theta.iter())
            .all(|(x, y)| x.contains(*y))
}

#[test]
fn interval_runs_follow_and_enclose_the_f64_runs() {
    let mut pf = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    let mut pi = ToyProblem::<Interval>::new(&mdp("m1-direct.json"));
    // The last root config (DAgger with an Adam inner optimiser, 5 inner steps per iteration) is
    // left out: as the inner gradients vanish, Adam's m̂/√v̂ in interval arithmetic widens by a
    // factor ≈ 100 per outer iteration (the wrapping effect), and after 6 iterations the enclosure
    // of θ no longer lies certainly inside the simplex. Adam as an outer optimiser is included.
    let mut configs = field_configs();
    configs.extend(root_configs());
    configs.pop();
    for algorithm in configs {
        let cfg = run_config(algorithm, 5, 12);
        let f: RunRecord<f64> = replay(&cfg, &mut pf).unwrap();
        let i: RunRecord<Interval> = replay(&cfg, &mut pi).unwrap();
        assert!(ok_end(&i.termination), "{}: {}", i.algorithm, i.termination);
        assert_eq!(f.history.len(), i.history.len(), "{}", f.algorithm);
        for (a, b) in i.history.iter().zip(&f.history) {
            assert!(
                encloses(a, b),
                "{} at iteration {}: {:?} vs {:?}",
                f.algorithm,
                b.iteration,
                a.theta,
                b.theta
            );
        }
        for (a, b) in i.outputs.iter().zip(&f.outputs) {
            assert!(
                a.iter().zip(b.iter()).all(|(x, y)| x.contains(*y)),
                "{} outputs",
                f.algorithm
            );
        }
    }
}

#[test]
fn rational_runs_are_exact_and_enclosed_by_interval_runs() {
    let mut pq = ToyProblem::<BigRational>::new(&mdp("m1-direct.json"));
    let mut pi = ToyProblem::<Interval>::new(&mdp("m1-direct.json"));
    let mut pf = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    for algorithm in field_configs() {
        let cfg = run_config(algorithm, 3, 4);
        let q: RunRecord<BigRational> = replay(&cfg, &mut pq).unwrap();
        let i: RunRecord<Interval> = replay(&cfg, &mut pi).unwrap();
        let f: RunRecord<f64> = replay(&cfg, &mut pf).unwrap();
        assert!(ok_end(&q.termination), "{}: {}", q.algorithm, q.termination);
        assert_eq!(q.history.len(), i.history.len());
        for ((mq, mi), mf) in q.history.iter().zip(&i.history).zip(&f.history) {
            assert_eq!(mq.cost, mi.cost, "{}", q.algorithm);
            assert_eq!(mq.cost, mf.cost, "{}", q.algorithm);
            for (x, y) in mq.theta.iter().zip(mi.theta.iter()) {
                assert!(
                    interval_contains_rational(*y, x),
                    "{}: {x} ∉ {y:?}",
                    q.algorithm
                );
            }
        }
    }
}

#[test]
fn field_builds_work_through_the_same_config_and_refuse_roots() {
    let mut pq = ToyProblem::<BigRational>::new(&mdp("m1-direct.json"));
    for algorithm in root_configs() {
        let cfg = run_config(algorithm, 3, 2);
        assert!(replay::<BigRational, _>(&cfg, &mut pq).is_err());
    }
}

#[test]
fn costs_are_accounted_in_the_same_units() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    // One SGD step = one trajectory and one eq. 3.15 estimate; one STORM step = one trajectory
    // and two estimates (new point and old point), so twice the gradient evaluations.
    let sgd: RunRecord<f64> =
        replay(&run_config(field_configs()[0].clone(), 1, 10), &mut problem).unwrap();
    let st: RunRecord<f64> =
        replay(&run_config(field_configs()[2].clone(), 1, 10), &mut problem).unwrap();
    let per_sgd = sgd.cost.gradient_evaluations / 10;
    assert!(per_sgd > 0);
    assert_eq!(sgd.cost.gradient_evaluations, 10 * per_sgd);
    assert_eq!(sgd.cost.trajectories, 10);
    // STORM's init draws d₁ (one estimate), then two per step.
    assert_eq!(st.cost.gradient_evaluations, per_sgd + 20 * per_sgd);
    assert_eq!(st.cost.trajectories, 11);
    // DAgger with n trajectories per iteration and one full-batch inner update: iteration i
    // trains on all 2·n·i labelled states (T − 1 = 2 per trajectory), one ∇l each.
    let n = 10u64;
    let dg: RunRecord<f64> =
        replay(&run_config(field_configs()[7].clone(), 1, 5), &mut problem).unwrap();
    assert_eq!(dg.cost.trajectories, 5 * n);
    assert_eq!(dg.cost.expert_queries, 5 * n * 2);
    assert_eq!(
        dg.cost.gradient_evaluations,
        (1..=5).map(|i| 2 * n * i).sum::<u64>()
    );
}

#[test]
fn the_gradient_budget_and_target_loss_stop_the_run() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    let mut cfg = run_config(field_configs()[2].clone(), 8, 1);
    cfg.stop = StoppingRule::gradient_budget(100);
    let rec: RunRecord<f64> = replay(&cfg, &mut problem).unwrap();
    assert_eq!(rec.termination, Termination::GradientBudget);
    let last = rec.history[rec.history.len() - 2].cost.gradient_evaluations;
    assert!(rec.cost.gradient_evaluations >= 100 && last < 100);
    // Target: F(θ) ≤ 0.9 with the exact objective of the engine (min F = 7/8 at θ = 1/4).
    let mut cfg = run_config(field_configs()[0].clone(), 8, 5000);
    cfg.stop.target_loss = Some(ConfigNumber::ratio(9, 10));
    let rec = Runner::new(cfg.stop.clone())
        .unwrap()
        .with_objective(|th: &DVector<f64>| {
            ilopt::exact::forward::forward(&problem, th.as_slice())
                .ok()
                .map(|f| f.objective)
        })
        .run_config(&cfg, &mut problem.clone())
        .unwrap();
    assert_eq!(rec.termination, Termination::TargetLoss);
    let f = rec.history.last().unwrap().objective.unwrap();
    assert!(
        f <= 0.9
            && rec.history[..rec.history.len() - 1]
                .iter()
                .all(|m| m.objective.unwrap() > 0.9)
    );
}

#[test]
fn o2nc_blocks_stay_within_delta_and_output_block_means() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    let cfg = o2nc_config();
    let mut alg = O2nc::<f64>::new(&cfg).unwrap();
    let prm = alg.parameters().clone();
    let delta = 0.1;
    let mut rng = KitRng::seed_from_u64(4);
    let mut cost = Cost::default();
    let mut ctx = StepContext {
        rng: &mut rng,
        cost: &mut cost,
    };
    alg.init(&mut problem, DVector::from_element(1, 0.5), &mut ctx)
        .unwrap();
    let mut ws = Vec::new();
    let mut finished = false;
    for _ in 0..prm.m {
        let r = alg.step(&mut problem, &mut ctx).unwrap();
        ws.push(alg.last_w().unwrap()[0]);
        finished = r.finished;
    }
    assert!(finished);
    let outs = Algorithm::<f64, ToyProblem<f64>>::outputs(&alg);
    assert_eq!(outs.len() as u64, prm.k);
    for (k, block) in ws.chunks(prm.t as usize).enumerate() {
        let mean = block.iter().sum::<f64>() / prm.t as f64;
        assert_abs_diff_eq!(outs[k][0], mean, epsilon = 1e-12);
        assert!(
            block
                .iter()
                .all(|w| abs_diff_eq!(*w, mean, epsilon = delta)),
            "block {k}"
        );
    }
}

#[test]
fn scalar_choice_does_not_change_the_interval_of_a_rational_hyper_parameter() {
    // 1/10 as a rational hyper-parameter is correctly rounded in f64 and enclosed in intervals.
    let x = ConfigNumber::ratio(1, 10);
    assert_eq!(x.to::<f64>("x").unwrap(), 0.1);
    assert!(interval_contains_rational(
        x.to::<Interval>("x").unwrap(),
        &x.exact("x").unwrap()
    ));
    assert!(!x.to::<Interval>("x").unwrap().is_singleton());
    let f = ConfigNumber::Float(0.1);
    assert!(f.to::<Interval>("x").unwrap().is_singleton());
    assert_eq!(
        f.to::<BigRational>("x").unwrap(),
        BigRational::from_float(0.1).unwrap()
    );
    assert_eq!(<f64 as Scalar>::from_rational(&f.exact("x").unwrap()), 0.1);
}

#[test]
fn forward_training_finishes_after_one_policy_per_step_and_smile_mixes_exactly() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    let ft = field_configs().pop().unwrap();
    let rec: RunRecord<f64> = replay(&run_config(ft, 1, 100), &mut problem).unwrap();
    // M1 has T = 3: losses at t = 1, 2, so two policies.
    assert_eq!(rec.termination, Termination::Finished);
    assert_eq!(rec.iterations, 2);
    assert_eq!(rec.outputs.len(), 2);
    // π₁ is trained on s₁ ∼ μ = (1/2, 1/2) only: θ₁ = fraction of B among 10 initial states.
    let x = rec.outputs[0][0] * 10.0;
    assert_abs_diff_eq!(x, x.round(), epsilon = 1e-12);

    let cfg = SmileConfig {
        alpha: ConfigNumber::ratio(1, 3),
        trajectories_per_iteration: 10,
        retrain: Retrain::FromScratch,
        inner: argmin_inner(),
    };
    let mut smile = ilopt::algo::smile::Smile::<f64, ToyProblem<f64>>::new(&cfg).unwrap();
    let mut rng = KitRng::seed_from_u64(2);
    let mut cost = Cost::default();
    let mut ctx = StepContext {
        rng: &mut rng,
        cost: &mut cost,
    };
    smile
        .init(&mut problem, DVector::from_element(1, 0.5), &mut ctx)
        .unwrap();
    for _ in 0..4 {
        smile.step(&mut problem, &mut ctx).unwrap();
    }
    let w = smile.mixture_weights();
    let q = |n: i64, d: i64| BigRational::new(n.into(), d.into());
    // α(1−α)^{j−1}/(1 − (1−α)⁴) with α = 1/3: (1/3, 2/9, 4/27, 8/81)/(65/81).
    assert_eq!(w, vec![q(27, 65), q(18, 65), q(12, 65), q(8, 65)]);
    assert_eq!(smile.outputs().len(), 4);
}

#[test]
fn a_time_limit_ends_the_run() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    // A step (10⁻⁹) so small that θ stays near 1/2, inside the open simplex, however many
    // iterations fit in the time limit: the limit is then the only way the run can end (with
    // a larger step the walk may leave the simplex first, on a fast machine).
    let sgd = AlgorithmConfig::Sgd(SgdConfig {
        step: SgdStep::constant(ConfigNumber::ratio(1, 1_000_000_000)),
        form: causal(),
    });
    let mut cfg = run_config(sgd, 1, 1);
    cfg.stop = StoppingRule {
        time_limit_ms: Some(5),
        ..Default::default()
    };
    let mut seen_progress = false;
    let rec = Runner::new(cfg.stop.clone())
        .unwrap()
        .with_observer(ilopt::algo::Progress { every: u64::MAX })
        .with_observer(|m: &IterationMetrics<f64>| seen_progress |= m.wall_time > 0.0)
        .run_config(&cfg, &mut problem)
        .unwrap();
    assert_eq!(rec.termination, Termination::TimeOut);
    assert!(rec.wall_time >= 0.005 && rec.iterations > 0);
    assert!(seen_progress);
}

#[test]
fn dataset_learners_train_to_the_exact_argmin_in_rationals() {
    // With the one-step inner solver, θ = fraction of examples labelled 0 (state B) in the data:
    // the exact minimiser of the mean Brier loss 2θ²·#A + 2(1−θ)²·#B.
    use ilopt::algo::bc::Bc;
    use ilopt::algo::dagger::Dagger;
    let mut problem = ToyProblem::<BigRational>::new(&mdp("m1-direct.json"));
    let q = |n: usize, d: usize| BigRational::new((n as i64).into(), (d as i64).into());
    let frac_b = |data: &[ilopt::toy::ToyExample]| {
        q(data.iter().filter(|e| e.label == 0).count(), data.len())
    };
    let mut rng = KitRng::seed_from_u64(17);
    let mut cost = Cost::default();
    let mut ctx = StepContext {
        rng: &mut rng,
        cost: &mut cost,
    };
    let theta0 = DVector::from_element(1, q(1, 2));

    let mut bc = Bc::<BigRational, ToyProblem<BigRational>>::new(&BcConfig {
        trajectories_per_iteration: 25,
        inner: argmin_inner(),
        retrain: Retrain::FromScratch,
    })
    .unwrap();
    bc.init(&mut problem, theta0.clone(), &mut ctx).unwrap();
    for i in 1..=2 {
        bc.step(&mut problem, &mut ctx).unwrap();
        // 25 trajectories × (T − 1 = 2) labelled states per step, aggregated.
        assert_eq!(bc.dataset().len(), 50 * i);
        assert_eq!(
            Algorithm::<BigRational, ToyProblem<BigRational>>::theta(&bc)[0],
            frac_b(bc.dataset())
        );
    }

    let mut dagger = Dagger::<BigRational, ToyProblem<BigRational>>::new(&DaggerConfig {
        trajectories_per_iteration: 25,
        beta: BetaSchedule::Linear { iterations: 2 },
        aggregate: true,
        retrain: Retrain::FromScratch,
        inner: argmin_inner(),
    })
    .unwrap();
    dagger.init(&mut problem, theta0, &mut ctx).unwrap();
    // β₁ = 1 (expert only), β₂ = 1/2, β₃ = 0 = β₄.
    let mut betas = Vec::new();
    for i in 1..=4 {
        betas.push(dagger.next_beta());
        dagger.step(&mut problem, &mut ctx).unwrap();
        assert_eq!(dagger.dataset().len(), 50 * i);
        assert_eq!(
            Algorithm::<BigRational, ToyProblem<BigRational>>::theta(&dagger)[0],
            frac_b(dagger.dataset())
        );
    }
    assert_eq!(betas, vec![q(1, 1), q(1, 2), q(0, 1), q(0, 1)]);
}

#[test]
fn the_runner_records_where_o2nc_evaluated_its_gradients() {
    let mut problem = ToyProblem::<f64>::new(&mdp("m1-direct.json"));
    let cfg = run_config(AlgorithmConfig::O2nc(o2nc_config()), 21, 1000);
    let rec: RunRecord<f64> = replay(&cfg, &mut problem).unwrap();
    let prm = o2nc_config().parameters().unwrap();
    assert_eq!(rec.termination, Termination::Finished);
    assert_eq!(rec.iterations, prm.m);
    assert!(rec.history[0].evaluated_at.is_none());
    let ws: Vec<f64> = rec.history[1..]
        .iter()
        .map(|m| m.evaluated_at.as_ref().unwrap()[0])
        .collect();
    for (k, block) in ws.chunks(prm.t as usize).enumerate() {
        let mean = block.iter().sum::<f64>() / prm.t as f64;
        assert_abs_diff_eq!(rec.outputs[k][0], mean, epsilon = 1e-12);
        assert!(block.iter().all(|w| abs_diff_eq!(*w, mean, epsilon = 0.1)));
    }
    // The SGD-type algorithms evaluate at θ and leave it empty.
    let sgd: RunRecord<f64> =
        replay(&run_config(field_configs()[0].clone(), 1, 3), &mut problem).unwrap();
    assert!(sgd.history.iter().all(|m| m.evaluated_at.is_none()));
}

/// A baseline is an option of the oracle: every algorithm runs on `Baselined` (m = 2) with each
/// kind, and with no baseline the run is the plain minibatch run bit for bit.
#[test]
fn every_algorithm_runs_with_every_baseline() {
    use ilopt::baseline::{Baseline, Baselined};
    let problem = ToyProblem::<f64>::new(&mdp("m1-softmax.json"));
    let dim = ilopt::problem::IlProblem::<f64>::dim(&problem);
    let kinds = [
        Baseline::None,
        Baseline::Constant {
            value: ConfigNumber::ratio(1, 2),
        },
        Baseline::TimeIndexed {
            values: vec![ConfigNumber::ratio(1, 3)],
        },
        Baseline::Estimated {
            time_indexed: true,
            decay: Some(ConfigNumber::ratio(9, 10)),
        },
        Baseline::LeaveOneOut,
    ];
    let mut baselined = 0;
    for algorithm in field_configs().into_iter().chain(root_configs()) {
        let cfg = RunConfig {
            theta0: vec![ConfigNumber::ratio(0, 1); dim],
            ..run_config(algorithm, 5, 20)
        };
        let mut batched = ilopt::batched::Batched::new(problem.clone(), 2).unwrap();
        let plain: RunRecord<f64> = replay(&cfg, &mut batched).unwrap();
        for kind in &kinds {
            let mut oracle = Baselined::<_, f64>::new(problem.clone(), 2, kind).unwrap();
            let rec: RunRecord<f64> = replay(&cfg, &mut oracle).unwrap();
            if *kind != Baseline::None
                && rec
                    .termination
                    .to_string()
                    .contains("apply to the causal form")
            {
                // A configuration with the full form: baselines are refused, by design.
                continue;
            }
            baselined += 1;
            assert!(
                ok_end(&rec.termination),
                "{} with {kind:?}: {}",
                rec.algorithm,
                rec.termination
            );
            assert!(rec.theta.iter().all(|x| x.is_finite()));
            if *kind == Baseline::None {
                assert!(
                    rec.same_run(&plain),
                    "{}: no baseline is the plain run",
                    rec.algorithm
                );
            }
        }
    }
    assert!(baselined > 40, "runs with a baseline: {baselined}");
}
