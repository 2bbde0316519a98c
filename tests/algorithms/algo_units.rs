//! Unit tests of the algorithms against hand-computed steps, and construction-time validation.
//!
//! The scripted problem below makes every oracle value explicit: trajectory i of the script has
//! `g(θ, τ_i) = a_i θ + b_i` (entrywise), the whole-trajectory importance weight is
//! `(2 + θ_old)/(2 + θ_new)` and the per-decision one `(3 + θ_old)/(3 + θ_new)` (first entry).
//! The expected numbers in the tests were worked out by hand from the update formulas.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use ilopt::algo::adam::{Adam, AdamConfig, AdamOptimizerConfig};
use ilopt::algo::as_printed::{PrintedAlgorithm4Config, printed_algorithm_4};
use ilopt::algo::dagger::{BetaSchedule, Dagger, DaggerConfig};
use ilopt::algo::dataset::{InnerConfig, Retrain, RuleConfig};
use ilopt::algo::o2nc::O2ncConfig;
use ilopt::algo::rmsprop::{RmsProp, RmsPropConfig, RmsPropOptimizerConfig};
use ilopt::algo::sgd::{Sgd, SgdConfig, SgdStep};
use ilopt::algo::storm::{Correction, Storm, StormConfig, StormSchedule};
use ilopt::algo::storm_plus::{StormPlus, StormPlusConfig};
use ilopt::algo::{
    AlgoError, Algorithm, AlgorithmConfig, ConfigNumber, Divergence, RunConfig, Runner,
    StepContext, StoppingRule, Termination,
};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::scalar::{BigRational, Interval, Roots, Scalar};
use nalgebra::DVector;
use rand::SeedableRng;
use std::cell::Cell;

/// A problem whose roll-outs follow a fixed script (the RNG is not used).
#[derive(Debug)]
struct Scripted {
    script: Vec<(i64, i64)>,
    next: Cell<usize>,
}

impl Scripted {
    fn new(script: Vec<(i64, i64)>) -> Self {
        Scripted {
            script,
            next: Cell::new(0),
        }
    }
}

impl<S: Scalar> IlProblem<S> for Scripted {
    type Trajectory = usize;
    type Labelled = usize;
    fn dim(&self) -> usize {
        1
    }
    fn rollout(
        &mut self,
        _: &Behaviour<'_, S>,
        _: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<usize, OracleError> {
        let i = self.next.get();
        self.next.set(i + 1);
        cost.trajectories += 1;
        Ok(i % self.script.len())
    }
    fn estimate(
        &mut self,
        theta: &DVector<S>,
        tau: &usize,
        _: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let (a, b) = self.script[*tau];
        cost.gradient_evaluations += 1;
        Ok(theta.map(|t| S::from_i64(a) * t + S::from_i64(b)))
    }
    fn weighted_estimate(
        &mut self,
        old: &DVector<S>,
        new: &DVector<S>,
        tau: &usize,
        w: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let c = S::from_i64(match w {
            Weighting::Trajectory => 2,
            Weighting::PerDecision => 3,
        });
        let weight = (c.clone() + &old[0]) / (c + &new[0]);
        let g = self.estimate(old, tau, EstimatorForm::Causal, cost)?;
        Ok(g.map(|x| x * &weight))
    }
    fn trajectory_loss(&self, _: &DVector<S>, _: &usize) -> Result<S, OracleError> {
        Ok(S::zero())
    }
    fn labelled_states(&self, tau: &usize) -> Vec<usize> {
        vec![*tau]
    }
    fn supervised(
        &self,
        theta: &DVector<S>,
        ex: &usize,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError> {
        // l(θ) = (θ − b)²/2 with b the script's second entry: ∇l = θ − b.
        let b = S::from_i64(self.script[*ex].1);
        let r = theta[0].clone() - b;
        cost.gradient_evaluations += 1;
        grad[0] = r.clone();
        Ok(r.square() / S::from_i64(2))
    }
}

fn q(n: i64, d: i64) -> BigRational {
    BigRational::new(n.into(), d.into())
}

fn v<S: Scalar>(x: S) -> DVector<S> {
    DVector::from_element(1, x)
}

/// Drive an algorithm by hand: init then `steps` steps; returns the iterates θ₁, θ₂, ….
fn drive<S: Scalar, A: Algorithm<S, Scripted>>(
    alg: &mut A,
    p: &mut Scripted,
    theta0: S,
    steps: usize,
) -> Vec<S> {
    let mut rng = KitRng::seed_from_u64(0);
    let mut cost = Cost::default();
    let mut ctx = StepContext {
        rng: &mut rng,
        cost: &mut cost,
    };
    alg.init(p, v(theta0), &mut ctx).unwrap();
    let mut out = vec![alg.theta()[0].clone()];
    for _ in 0..steps {
        alg.step(p, &mut ctx).unwrap();
        out.push(alg.theta()[0].clone());
    }
    out
}

fn storm_cfg(correction: Correction) -> StormConfig {
    StormConfig {
        schedule: StormSchedule::constant(ConfigNumber::ratio(1, 4), ConfigNumber::ratio(1, 2)),
        correction,
        form: EstimatorForm::Causal,
    }
}

// Script: τ₁ = (a, b) = (2, −1), τ₂ = (3, 1). θ₁ = 1, η = 1/4, a = 1/2.
// d₁ = 2·1 − 1 = 1; θ₂ = 1 − 1/4 = 3/4; g(θ₂, τ₂) = 3·3/4 + 1 = 13/4; g(θ₁, τ₂) = 4.
fn script() -> Scripted {
    Scripted::new(vec![(2, -1), (3, 1)])
}

#[test]
fn one_storm_step_in_rationals() {
    let mut p = script();
    let mut s = Storm::<BigRational>::new(&storm_cfg(Correction::Unweighted)).unwrap();
    let th = drive(&mut s, &mut p, q(1, 1), 1);
    assert_eq!(th[1], q(3, 4));
    // d₂ = 13/4 + (1/2)(1 − 4) = 7/4.
    assert_eq!(s.direction().unwrap()[0], q(7, 4));
    assert_eq!(s.last_schedule().unwrap(), &(q(1, 4), q(1, 2)));
    // Next step: θ₃ = 3/4 − (1/4)(7/4) = 5/16.
    let mut rng = KitRng::seed_from_u64(0);
    let mut cost = Cost::default();
    s.step(
        &mut p,
        &mut StepContext {
            rng: &mut rng,
            cost: &mut cost,
        },
    )
    .unwrap();
    assert_eq!(Algorithm::<BigRational, Scripted>::theta(&s)[0], q(5, 16));
}

#[test]
fn one_is_storm_step_in_rationals() {
    // Whole-trajectory weight (2 + 1)/(2 + 3/4) = 12/11: g̃ = 48/11,
    // d₂ = 13/4 + (1/2)(1 − 48/11) = 69/44.
    let mut p = script();
    let mut s = Storm::<BigRational>::new(&storm_cfg(Correction::Trajectory)).unwrap();
    drive(&mut s, &mut p, q(1, 1), 1);
    assert_eq!(s.direction().unwrap()[0], q(69, 44));
    // Per-decision weight (3 + 1)/(3 + 3/4) = 16/15: g̃ = 64/15,
    // d₂ = 13/4 + (1/2)(1 − 64/15) = 13/4 − 49/30 = 97/60.
    let mut p = script();
    let mut s = Storm::<BigRational>::new(&storm_cfg(Correction::PerDecision)).unwrap();
    drive(&mut s, &mut p, q(1, 1), 1);
    assert_eq!(s.direction().unwrap()[0], q(97, 60));
    assert_eq!(Algorithm::<BigRational, Scripted>::name(&s), "is-storm");
}

#[test]
fn printed_algorithm_4_uses_the_e9_update() {
    // d₂ = 13/4 + (1/2)·4 = 21/4: no d₁, and the correction enters with a plus sign.
    let mut p = script();
    let cfg = PrintedAlgorithm4Config {
        schedule: StormSchedule::constant(ConfigNumber::ratio(1, 4), ConfigNumber::ratio(1, 2)),
        form: EstimatorForm::Causal,
    };
    let mut s = printed_algorithm_4::<BigRational>(&cfg).unwrap();
    drive(&mut s, &mut p, q(1, 1), 1);
    assert_eq!(s.direction().unwrap()[0], q(21, 4));
    assert_eq!(
        Algorithm::<BigRational, Scripted>::name(&s),
        "printed-algorithm-4"
    );
}

#[test]
fn explicit_storm_schedule_is_followed_and_repeats_its_last_entry() {
    // η = (1/2, 1/4), a = (1): with a = 1 the direction is the fresh estimate.
    // θ₁ = 1, d₁ = 1 → θ₂ = 1/2; d₂ = g(1/2, τ₂) = 5/2 → θ₃ = 1/2 − (1/4)(5/2) = −1/8;
    // d₃ = g(−1/8, τ₁) = −5/4 → θ₄ = −1/8 + 5/16 = 3/16.
    let mut p = script();
    let cfg = StormConfig {
        schedule: StormSchedule::Explicit {
            eta: vec![ConfigNumber::ratio(1, 2), ConfigNumber::ratio(1, 4)],
            a: vec![ConfigNumber::ratio(1, 1)],
        },
        correction: Correction::Unweighted,
        form: EstimatorForm::Causal,
    };
    let mut s = Storm::<BigRational>::new(&cfg).unwrap();
    let th = drive(&mut s, &mut p, q(1, 1), 3);
    assert_eq!(th, vec![q(1, 1), q(1, 2), q(-1, 8), q(3, 16)]);
}

#[test]
fn thesis_schedule_matches_eq_3_43() {
    // L = 2: η₁ = (1/8)(7/8)^{1/3}, a₂ = (7/8)^{2/3}.
    let mut p = script();
    let cfg = StormConfig {
        schedule: StormSchedule::Thesis {
            l: ConfigNumber::ratio(2, 1),
        },
        correction: Correction::Unweighted,
        form: EstimatorForm::Causal,
    };
    let mut s = Storm::<f64>::new(&cfg).unwrap();
    drive(&mut s, &mut p, 1.0, 1);
    let (eta, a) = *s.last_schedule().unwrap();
    let r = (7.0f64 / 8.0).cbrt();
    assert_abs_diff_eq!(eta, r / 8.0, epsilon = 1e-16);
    assert_abs_diff_eq!(a, r * r, epsilon = 1e-15);
    // 16 L² η² = a.
    assert_abs_diff_eq!(16.0 * 4.0 * eta * eta, a, epsilon = 1e-15);
    // Rationals have no cube roots.
    assert!(matches!(
        Storm::<BigRational>::new(&cfg),
        Err(AlgoError::NeedsRoots { .. })
    ));
}

#[test]
fn adaptive_schedule_matches_algorithm_4() {
    // k' = 1, w = 7, c = 1/2. G₁² = 1 (d₁ = 1): η₁ = 1/(7 + 1)^{1/3} = 1/2, a₂ = (1/2)(1/4) = 1/8.
    let mut p = script();
    let cfg = StormConfig {
        schedule: StormSchedule::Adaptive {
            k: ConfigNumber::ratio(1, 1),
            w: ConfigNumber::ratio(7, 1),
            c: ConfigNumber::ratio(1, 2),
        },
        correction: Correction::Unweighted,
        form: EstimatorForm::Causal,
    };
    let mut s = Storm::<f64>::new(&cfg).unwrap();
    let th = drive(&mut s, &mut p, 1.0, 1);
    assert_eq!(*s.last_schedule().unwrap(), (0.5, 0.125));
    assert_eq!(th[1], 0.5);
    // g(1/2, τ₂) = 5/2, g(1, τ₂) = 4: d₂ = 5/2 + (7/8)(1 − 4) = −1/8. G₂² = 25/4:
    // η₂ = 1/(8 + 25/4)^{1/3} = (4/57)^{1/3}.
    assert_eq!(s.direction().unwrap()[0], -0.125);
    let mut rng = KitRng::seed_from_u64(0);
    let mut cost = Cost::default();
    s.step(
        &mut p,
        &mut StepContext {
            rng: &mut rng,
            cost: &mut cost,
        },
    )
    .unwrap();
    let eta2 = s.last_schedule().unwrap().0;
    assert_abs_diff_eq!(eta2, (4.0f64 / 57.0).cbrt(), epsilon = 1e-16);
}

#[test]
fn one_sgd_step_in_rationals_and_inverse_time_schedule() {
    // θ₂ = 1 − (1/3)·1 = 2/3; then η₂ = (1/3)·2/(2 + 1) = 2/9, g(2/3, τ₂) = 3 → θ₃ = 0.
    let mut p = script();
    let cfg = SgdConfig {
        step: SgdStep::InverseTime {
            eta0: ConfigNumber::ratio(1, 3),
            k0: ConfigNumber::ratio(2, 1),
        },
        form: EstimatorForm::Causal,
    };
    let mut s = Sgd::<BigRational>::new(&cfg).unwrap();
    let th = drive(&mut s, &mut p, q(1, 1), 2);
    assert_eq!(th, vec![q(1, 1), q(2, 3), q(0, 1)]);
}

#[test]
fn one_adam_step_in_f64_from_kingma_ba() {
    // Constant gradient g = 1/2 (a = 0, b = 1/2 is not an integer: use a = 0, b = 1 and read
    // α accordingly). First step: m = (1−β₁)g, v = (1−β₂)g², m̂ = g, v̂ = g²,
    // θ₁ = θ₀ − α g/(|g| + ε) with g = 1.
    let mut p = Scripted::new(vec![(0, 1), (0, -2)]);
    let cfg = AdamOptimizerConfig {
        adam: AdamConfig {
            alpha: ConfigNumber::ratio(1, 10),
            beta1: ConfigNumber::ratio(9, 10),
            beta2: ConfigNumber::ratio(999, 1000),
            epsilon: ConfigNumber::Float(1e-8),
        },
        form: EstimatorForm::Causal,
    };
    let mut s = Adam::<f64>::new(&cfg).unwrap();
    let th = drive(&mut s, &mut p, 1.0, 2);
    let expect1 = 1.0 - 0.1 * 1.0 / (1.0 + 1e-8);
    assert_abs_diff_eq!(th[1], expect1, epsilon = 1e-15);
    // Second step, g = −2: m = 0.9·0.1 + 0.1·(−2) = −0.11, v = 0.999·0.001 + 0.001·4 = 0.004999,
    // m̂ = −0.11/0.19, v̂ = 0.004999/(1 − 0.998001).
    let mhat = -0.11 / 0.19;
    let vhat: f64 = 0.004999 / (1.0 - 0.998001);
    let expect2 = expect1 - 0.1 * mhat / (vhat.sqrt() + 1e-8);
    assert_abs_diff_eq!(th[2], expect2, epsilon = 1e-12);
}

#[test]
fn rmsprop_follows_eqs_2_14_and_2_15() {
    // β = 3/4, η = 1/8, ε = 0 (eq. 2.15 as printed). g = 3: v = (1/4)·9, √v = 3/2,
    // θ₁ = 1 − (1/8)·3/(3/2) = 3/4 exactly. Then g = 1: v = (3/4)(9/4) + 1/4 = 31/16.
    let mut p = Scripted::new(vec![(0, 3), (0, 1)]);
    let cfg = RmsPropOptimizerConfig {
        rmsprop: RmsPropConfig {
            eta: ConfigNumber::ratio(1, 8),
            beta: ConfigNumber::ratio(3, 4),
            epsilon: ConfigNumber::ratio(0, 1),
        },
        form: EstimatorForm::Causal,
    };
    let mut s = RmsProp::<f64>::new(&cfg).unwrap();
    let th = drive(&mut s, &mut p, 1.0, 2);
    assert_eq!(th[1], 0.75);
    let expect = 0.75 - 0.125 / (31.0f64 / 16.0).sqrt();
    assert_abs_diff_eq!(th[2], expect, epsilon = 1e-15);
}

#[test]
fn rmsprop_without_epsilon_stops_on_a_zero_denominator() {
    let mut p = Scripted::new(vec![(0, 0)]);
    let cfg = RmsPropOptimizerConfig {
        rmsprop: RmsPropConfig {
            eta: ConfigNumber::ratio(1, 8),
            beta: ConfigNumber::ratio(3, 4),
            epsilon: ConfigNumber::ratio(0, 1),
        },
        form: EstimatorForm::Causal,
    };
    let mut s = RmsProp::<f64>::new(&cfg).unwrap();
    let rec = Runner::new(StoppingRule::iterations(3))
        .unwrap()
        .run(&mut s, &mut p, v(1.0), 1)
        .unwrap();
    assert!(matches!(
        rec.termination,
        Termination::Diverged(Divergence::StepFailed(AlgoError::NonFinite(_)))
    ));
}

#[test]
fn storm_plus_first_step_matches_the_paper_form() {
    // a₀ = 1, b₀ = 0, c = 1: g₁ = d₁ = 1; a₂ = (1 + 1)^{−2/3}; η₁ = (1/a₂)^{−1/3} = 2^{−2/9}.
    let mut p = script();
    let cfg = StormPlusConfig::paper(Correction::Unweighted, EstimatorForm::Causal);
    let mut s = StormPlus::<f64>::new(&cfg).unwrap();
    let th = drive(&mut s, &mut p, 1.0, 1);
    let expect = 1.0 - 2f64.powf(-2.0 / 9.0);
    assert_abs_diff_eq!(th[1], expect, epsilon = 1e-15);
}

#[test]
fn o2nc_parameters_are_exact() {
    // x = GNδ/Δ₀ = 2·100·(1/10)/1 = 20, x² = 400, 7³ = 343 < 400 ≤ 512 = 8³ → T = 8;
    // K = ⌊100/8⌋ = 12, M = 96, D = δ/T = 1/80.
    let cfg = O2ncConfig {
        budget: 100,
        delta: ConfigNumber::ratio(1, 10),
        g: ConfigNumber::ratio(2, 1),
        delta0: ConfigNumber::ratio(1, 1),
        form: EstimatorForm::Causal,
    };
    let prm = cfg.parameters().unwrap();
    assert_eq!((prm.t, prm.k, prm.m), (8, 12, 96));
    assert_eq!(prm.d, q(1, 80));
    // Huge x: T is capped at ⌊N/2⌋.
    let cfg = O2ncConfig {
        g: ConfigNumber::ratio(1000, 1),
        ..cfg
    };
    let prm = cfg.parameters().unwrap();
    assert_eq!((prm.t, prm.k), (50, 2));
    // Exactly a cube: x² = 8³ ⇔ x = 16√8 is irrational, so use x = 8 (x² = 64 = 4³) → T = 4.
    let cfg = O2ncConfig {
        budget: 40,
        delta: ConfigNumber::ratio(1, 5),
        g: ConfigNumber::ratio(1, 1),
        delta0: ConfigNumber::ratio(1, 1),
        form: EstimatorForm::Causal,
    };
    assert_eq!(cfg.parameters().unwrap().t, 4);
}

#[test]
fn interval_cube_root_encloses() {
    for x in [0.0, 1e-300, 0.3, 2.0, 27.0, 1e10, 7.0 / 9.0] {
        let i = Interval::try_from((x, x)).unwrap();
        let c = i.try_cbrt().unwrap();
        assert!(c.contains(x.cbrt()), "cbrt({x})");
        // c³ encloses x.
        assert!((c * c * c).contains(x));
        assert!(c.wid() <= 4.0 * f64::EPSILON * x.cbrt().max(f64::MIN_POSITIVE));
    }
}

fn expect_invalid<T: std::fmt::Debug>(r: Result<T, AlgoError>, name: &str) {
    match r {
        Err(AlgoError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
        other => panic!("expected an invalid `{name}`, got {other:?}"),
    }
}

#[test]
fn invalid_hyper_parameters_are_rejected_by_name() {
    let sgd = |eta: ConfigNumber| {
        Sgd::<f64>::new(&SgdConfig {
            step: SgdStep::Constant { eta },
            form: EstimatorForm::Causal,
        })
    };
    expect_invalid(sgd(ConfigNumber::Float(-0.1)), "eta");
    expect_invalid(sgd(ConfigNumber::Float(f64::NAN)), "eta");
    expect_invalid(sgd(ConfigNumber::Float(f64::INFINITY)), "eta");
    expect_invalid(sgd(ConfigNumber::ratio(0, 1)), "eta");
    let storm = |eta: ConfigNumber, a: ConfigNumber| {
        Storm::<f64>::new(&StormConfig {
            schedule: StormSchedule::Constant { eta, a },
            correction: Correction::Trajectory,
            form: EstimatorForm::Causal,
        })
    };
    expect_invalid(
        storm(ConfigNumber::ratio(1, 10), ConfigNumber::ratio(3, 2)),
        "a",
    );
    expect_invalid(
        storm(ConfigNumber::ratio(1, 10), ConfigNumber::Float(f64::NAN)),
        "a",
    );
    expect_invalid(
        storm(ConfigNumber::Float(-1.0), ConfigNumber::ratio(1, 2)),
        "eta",
    );
    expect_invalid(
        Storm::<f64>::new(&StormConfig {
            schedule: StormSchedule::Thesis {
                l: ConfigNumber::ratio(-1, 1),
            },
            correction: Correction::Unweighted,
            form: EstimatorForm::Causal,
        }),
        "l",
    );
    expect_invalid(
        Storm::<f64>::new(&StormConfig {
            schedule: StormSchedule::Explicit {
                eta: vec![],
                a: vec![ConfigNumber::ratio(1, 2)],
            },
            correction: Correction::Unweighted,
            form: EstimatorForm::Causal,
        }),
        "eta",
    );
    let mut adam = AdamConfig::with_alpha(0.01);
    adam.beta1 = ConfigNumber::ratio(1, 1);
    expect_invalid(
        Adam::<f64>::new(&AdamOptimizerConfig {
            adam,
            form: EstimatorForm::Causal,
        }),
        "beta1",
    );
    expect_invalid(
        RmsProp::<f64>::new(&RmsPropOptimizerConfig {
            rmsprop: RmsPropConfig::with_eta(f64::NAN),
            form: EstimatorForm::Causal,
        }),
        "eta",
    );
    let mut sp = StormPlusConfig::paper(Correction::Unweighted, EstimatorForm::Causal);
    sp.a0 = ConfigNumber::ratio(0, 1);
    expect_invalid(StormPlus::<f64>::new(&sp), "a0");
    let dagger = |beta: ConfigNumber, n: u64| {
        Dagger::<f64, Scripted>::new(&DaggerConfig {
            trajectories_per_iteration: n,
            beta: BetaSchedule::Constant { beta },
            aggregate: true,
            retrain: Retrain::WarmStart,
            inner: InnerConfig::gradient_descent(0.5, 1),
        })
    };
    expect_invalid(dagger(ConfigNumber::ratio(3, 2), 1), "beta");
    expect_invalid(dagger(ConfigNumber::Float(-0.25), 1), "beta");
    expect_invalid(
        dagger(ConfigNumber::ratio(1, 2), 0),
        "trajectories_per_iteration",
    );
    expect_invalid(
        Dagger::<f64, Scripted>::new(&DaggerConfig {
            trajectories_per_iteration: 1,
            beta: BetaSchedule::Exponential {
                p: ConfigNumber::ratio(2, 1),
            },
            aggregate: true,
            retrain: Retrain::WarmStart,
            inner: InnerConfig::gradient_descent(0.5, 1),
        }),
        "beta.p",
    );
    expect_invalid(
        Dagger::<f64, Scripted>::new(&DaggerConfig {
            trajectories_per_iteration: 1,
            beta: BetaSchedule::Constant {
                beta: ConfigNumber::ratio(0, 1),
            },
            aggregate: true,
            retrain: Retrain::WarmStart,
            inner: InnerConfig {
                rule: RuleConfig::Sgd {
                    step: SgdStep::constant(0.5),
                },
                iterations: 0,
                batch_size: None,
            },
        }),
        "inner.iterations",
    );
    let o2nc = |budget: u64, delta: ConfigNumber| {
        O2ncConfig {
            budget,
            delta,
            g: ConfigNumber::ratio(1, 1),
            delta0: ConfigNumber::ratio(1, 1),
            form: EstimatorForm::Causal,
        }
        .parameters()
    };
    expect_invalid(o2nc(0, ConfigNumber::ratio(1, 10)), "budget");
    expect_invalid(o2nc(100, ConfigNumber::ratio(-1, 10)), "delta");
    expect_invalid(
        Runner::<f64>::new(StoppingRule::gradient_budget(0)),
        "stop.max_gradient_evaluations",
    );
    expect_invalid(
        Runner::<f64>::new(StoppingRule::iterations(0)),
        "stop.max_iterations",
    );
    expect_invalid(Runner::<f64>::new(StoppingRule::default()), "stop");
}

#[test]
fn field_builds_refuse_what_needs_roots() {
    let adam = AlgorithmConfig::Adam(AdamOptimizerConfig {
        adam: AdamConfig::with_alpha(0.1),
        form: EstimatorForm::Causal,
    });
    assert!(matches!(
        adam.build::<BigRational, Scripted>(),
        Err(AlgoError::NeedsRoots { .. })
    ));
    let sgd = AlgorithmConfig::Sgd(SgdConfig {
        step: SgdStep::InverseSqrt {
            eta0: ConfigNumber::ratio(1, 2),
        },
        form: EstimatorForm::Causal,
    });
    assert!(matches!(
        sgd.build::<BigRational, Scripted>(),
        Err(AlgoError::NeedsRoots { .. })
    ));
    assert!(sgd.build::<f64, Scripted>().is_ok());
}

#[test]
fn a_non_finite_iterate_stops_the_run() {
    // g ≈ 9.2·10¹⁸ and η = 10³⁰⁰: the first step overflows to −∞.
    let mut p = Scripted::new(vec![(0, i64::MAX)]);
    let mut s = Sgd::<f64>::new(&SgdConfig {
        step: SgdStep::constant(1e300),
        form: EstimatorForm::Causal,
    })
    .unwrap();
    let rec = Runner::new(StoppingRule::iterations(5))
        .unwrap()
        .run(&mut s, &mut p, v(0.0), 3)
        .unwrap();
    assert_eq!(
        rec.termination,
        Termination::Diverged(Divergence::StepFailed(AlgoError::NonFinite("θ")))
    );
    assert!(rec.history.iter().all(|m| m.theta[0].is_finite()));
}

#[test]
fn num_round_trips_exactly_through_json() {
    for n in [
        ConfigNumber::Float(0.1),
        ConfigNumber::ratio(1, 3),
        ConfigNumber::Float(-2.5e-300),
        ConfigNumber::ratio(-7, 1),
    ] {
        let text = serde_json::to_string(&n).unwrap();
        let back: ConfigNumber = serde_json::from_str(&text).unwrap();
        assert_eq!(back, n, "{text}");
        assert_eq!(
            back.to::<f64>("x").unwrap().to_bits(),
            n.to::<f64>("x").unwrap().to_bits()
        );
    }
    let dec: ConfigNumber = serde_json::from_str("\"0.05\"").unwrap();
    assert_eq!(dec, ConfigNumber::ratio(1, 20));
    let nan = ConfigNumber::Float(f64::NAN);
    let back: ConfigNumber = serde_json::from_str(&serde_json::to_string(&nan).unwrap()).unwrap();
    assert!(back.exact("x").is_err());
}

#[test]
fn run_config_round_trips_through_json() {
    let cfg = RunConfig {
        algorithm: AlgorithmConfig::Storm(storm_cfg(Correction::PerDecision)),
        theta0: vec![ConfigNumber::Float(0.3)],
        seed: 7,
        stop: StoppingRule {
            max_iterations: Some(5),
            target_loss: Some(ConfigNumber::ratio(1, 8)),
            ..Default::default()
        },
    };
    let back = RunConfig::from_json(&cfg.to_json().unwrap()).unwrap();
    assert_eq!(back, cfg);
}

/// Records the θ of every learner roll-out (to check where an algorithm samples).
#[derive(Debug)]
struct Recording {
    inner: Scripted,
    sampled_at: std::cell::RefCell<Vec<f64>>,
}

impl IlProblem<f64> for Recording {
    type Trajectory = usize;
    type Labelled = usize;
    fn dim(&self) -> usize {
        1
    }
    fn rollout(
        &mut self,
        b: &Behaviour<'_, f64>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<usize, OracleError> {
        if let Behaviour::Learner(th) = b {
            self.sampled_at.borrow_mut().push(th[0]);
        }
        self.inner.rollout(b, rng, cost)
    }
    fn estimate(
        &mut self,
        th: &DVector<f64>,
        t: &usize,
        f: EstimatorForm,
        c: &mut Cost,
    ) -> Result<DVector<f64>, OracleError> {
        self.inner.estimate(th, t, f, c)
    }
    fn weighted_estimate(
        &mut self,
        o: &DVector<f64>,
        n: &DVector<f64>,
        t: &usize,
        w: Weighting,
        c: &mut Cost,
    ) -> Result<DVector<f64>, OracleError> {
        self.inner.weighted_estimate(o, n, t, w, c)
    }
    fn trajectory_loss(&self, th: &DVector<f64>, t: &usize) -> Result<f64, OracleError> {
        self.inner.trajectory_loss(th, t)
    }
    fn labelled_states(&self, t: &usize) -> Vec<usize> {
        IlProblem::<f64>::labelled_states(&self.inner, t)
    }
    fn supervised(
        &self,
        th: &DVector<f64>,
        e: &usize,
        g: &mut [f64],
        c: &mut Cost,
    ) -> Result<f64, OracleError> {
        self.inner.supervised(th, e, g, c)
    }
}

#[test]
fn o2nc_samples_at_w_n_and_the_printed_algorithm_5_at_theta_n() {
    use ilopt::algo::as_printed::printed_algorithm_5;
    use ilopt::algo::o2nc::O2nc;
    let cfg = O2ncConfig {
        budget: 40,
        delta: ConfigNumber::ratio(1, 2),
        g: ConfigNumber::ratio(1, 1),
        delta0: ConfigNumber::ratio(1, 1),
        form: EstimatorForm::Causal,
    };
    for printed in [false, true] {
        let mut p = Recording {
            inner: Scripted::new(vec![(1, -1), (2, 1), (-1, 3)]),
            sampled_at: Default::default(),
        };
        let mut alg = if printed {
            printed_algorithm_5::<f64>(&cfg).unwrap()
        } else {
            O2nc::<f64>::new(&cfg).unwrap()
        };
        let mut rng = KitRng::seed_from_u64(1);
        let mut cost = Cost::default();
        let mut ctx = StepContext {
            rng: &mut rng,
            cost: &mut cost,
        };
        alg.init(&mut p, v(0.0), &mut ctx).unwrap();
        let m = alg.parameters().m;
        let mut moved = 0;
        for _ in 0..m {
            let before = alg.theta()[0];
            alg.step(&mut p, &mut ctx).unwrap();
            let at = *p.sampled_at.borrow().last().unwrap();
            let (w, th) = (alg.last_w().unwrap()[0], alg.theta()[0]);
            // w_n = θ_{n−1} + s_n Δ_n lies between θ_{n−1} and θ_n.
            assert!((before.min(th)..=before.max(th)).contains(&w));
            assert_eq!(at, if printed { th } else { w });
            moved += usize::from(w != th);
        }
        // Δ_n ≠ 0 within blocks, so the two sampling points differ on most steps.
        assert!(moved > (m as usize) / 2, "{moved} of {m}");
        let name = Algorithm::<f64, Recording>::name(&alg);
        assert_eq!(
            name,
            if printed {
                "printed-algorithm-5"
            } else {
                "o2nc"
            }
        );
    }
}

#[test]
fn the_fixture_oracle_is_unbiased_for_its_closed_form_gradient() {
    // M1 in the fixture's parameter p = π(1): F'(p) = 4p − 3 (math.md §6), F'(3/10) = −9/5. The
    // plain estimate at p and the IS-weighted old-point estimates (τ drawn at p' = 3/5) must all
    // have mean F'(p); tolerance 6 standard errors (see tests/algorithms/algo_m1.rs for the policy).
    // (At p = 1/2 the old-point estimate happens to be unbiased even without weights, since
    // l(A) = l(B) there, so p = 3/10 is used.)
    use crate::fixture::AliasedTwoState;
    let mut fx = AliasedTwoState::m1();
    assert_eq!(fx.derivative(&q(3, 10)), q(-9, 5));
    let target = -1.8;
    let p = v(0.3);
    let p_new = v(0.6);
    let mut rng = KitRng::seed_from_u64(123);
    let mut cost = Cost::default();
    let n = 40_000;
    let mut samples = [Vec::new(), Vec::new(), Vec::new()];
    let mut unweighted = Vec::new();
    for _ in 0..n {
        let tau = fx
            .rollout(&Behaviour::Learner(&p), &mut rng, &mut cost)
            .unwrap();
        samples[0].push(
            IlProblem::<f64>::estimate(&mut fx, &p, &tau, EstimatorForm::Causal, &mut cost)
                .unwrap()[0],
        );
        let tau = fx
            .rollout(&Behaviour::Learner(&p_new), &mut rng, &mut cost)
            .unwrap();
        for (i, w) in [Weighting::Trajectory, Weighting::PerDecision]
            .into_iter()
            .enumerate()
        {
            samples[i + 1].push(
                fx.weighted_estimate(&p, &p_new, &tau, w, &mut cost)
                    .unwrap()[0],
            );
        }
        unweighted.push(
            IlProblem::<f64>::estimate(&mut fx, &p, &tau, EstimatorForm::Causal, &mut cost)
                .unwrap()[0],
        );
    }
    // Negative control (E10): without the weight the old-point estimate is biased, and the test
    // is sharp enough to see it.
    let m = unweighted.iter().sum::<f64>() / n as f64;
    let se =
        (unweighted.iter().map(|x| (x - m).powi(2)).sum::<f64>() / ((n - 1) * n) as f64).sqrt();
    assert!(
        (m - target).abs() > 6.0 * se,
        "unweighted mean {m}, SE {se}"
    );
    for xs in &samples {
        let m = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        let se = (var / n as f64).sqrt();
        assert!(
            abs_diff_eq!(m, target, epsilon = 6.0 * se),
            "mean {m}, SE {se}"
        );
        assert!(se < 0.03);
    }
    assert_eq!(cost.trajectories, 2 * n as u64);
}

#[test]
fn cutkosky_orabona_constants_satisfy_their_definitions() {
    // Theorem 1 of Cutkosky & Orabona (math.md §3.3): c = 28L² + G²/(7Lk'³) and
    // w = max((4Lk')³, 2G², (ck'/(4L))³), with k' = bG^{2/3}/L.
    for (b, g, l) in [(1.0, 2.0, 3.0), (0.1, 5.0, 0.5), (2.5, 0.3, 7.0)] {
        let StormSchedule::Adaptive { k, w, c } = StormSchedule::cutkosky_orabona(b, g, l).unwrap()
        else {
            panic!("not adaptive");
        };
        let (k, w, c) = (
            k.to::<f64>("k").unwrap(),
            w.to::<f64>("w").unwrap(),
            c.to::<f64>("c").unwrap(),
        );
        let rel = |x: f64, y: f64| abs_diff_eq!(x, y, epsilon = 1e-12 * y.abs());
        assert!(rel(k.powi(3), b.powi(3) * g * g / l.powi(3)));
        assert!(rel(c, 28.0 * l * l + g * g / (7.0 * l * k.powi(3))));
        let w_def = (4.0 * l * k)
            .powi(3)
            .max(2.0 * g * g)
            .max((c * k / (4.0 * l)).powi(3));
        assert!(rel(w, w_def), "{w} vs {w_def}");
    }
    expect_invalid(StormSchedule::cutkosky_orabona(0.0, 1.0, 1.0), "b");
    expect_invalid(StormSchedule::cutkosky_orabona(1.0, f64::NAN, 1.0), "g");
}
