//! The real environments as IL problems: seeded, reproducible roll-outs with expert labels, the
//! oracle's forms and cost accounting, and errors for bad input.

use approx::assert_abs_diff_eq;
use ilopt::policy::LinearGaussian;
use ilopt::policy::Softmax;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use nalgebra::DVector;
use rand::SeedableRng;

fn cartpole_problem() -> TaskProblem<CartPoleTask<f64>, Softmax> {
    TaskProblem {
        task: CartPoleTask::with_lqr().unwrap(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

fn obstacle_problem() -> TaskProblem<ObstacleTask, LinearGaussian<f64>> {
    TaskProblem {
        task: ObstacleTask::thesis().unwrap(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.02).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

#[test]
fn cartpole_rollouts_are_seeded_and_labelled() {
    let mut p = cartpole_problem();
    let theta = DVector::from_fn(p.dim(), |i, _| 0.1 * (i as f64 - 4.0));
    let mut run = |seed| {
        let mut rng = KitRng::seed_from_u64(seed);
        let mut c = Cost::default();
        (
            p.rollout(&Behaviour::Learner(&theta), &mut rng, &mut c)
                .unwrap(),
            c,
        )
    };
    let (a, ca) = run(1);
    assert_eq!(a, run(1).0);
    assert_ne!(a, run(2).0);
    assert_eq!(ca.trajectories, 1);
    assert_eq!(ca.env_steps as usize, a.len());
    assert_eq!(ca.expert_queries as usize, a.len());
    // The LQR expert balances for the full 500 steps.
    let mut rng = KitRng::seed_from_u64(3);
    let e = p
        .rollout(&Behaviour::Expert, &mut rng, &mut Cost::default())
        .unwrap();
    assert_eq!(e.len(), 500);
    assert_eq!(e.actions, e.labels);
}

#[test]
fn cartpole_with_the_ppo_expert_balances() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json");
    let mut p = TaskProblem {
        task: CartPoleTask::<f64>::with_ppo(&path).unwrap(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let mut rng = KitRng::seed_from_u64(5);
    let e = p
        .rollout(&Behaviour::Expert, &mut rng, &mut Cost::default())
        .unwrap();
    assert_eq!(e.len(), 500);
    assert!(CartPoleTask::<f64>::with_ppo(std::path::Path::new("/nonexistent.json")).is_err());
}

#[test]
fn weighted_estimate_at_the_same_point_is_the_plain_estimate() {
    let mut p = cartpole_problem();
    let theta = DVector::from_fn(p.dim(), |i, _| 0.05 * i as f64);
    let mut rng = KitRng::seed_from_u64(9);
    let mut c = Cost::default();
    let t = p
        .rollout(&Behaviour::Learner(&theta), &mut rng, &mut c)
        .unwrap();
    let g = p
        .estimate(&theta, &t, EstimatorForm::Causal, &mut c)
        .unwrap();
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        let gw = p.weighted_estimate(&theta, &theta, &t, w, &mut c).unwrap();
        assert_eq!(g, gw, "{w:?}");
    }
    assert_eq!(c.gradient_evaluations as usize, 3 * t.len());
    // The full form differs per trajectory (it adds mean-zero terms).
    let f = p.estimate(&theta, &t, EstimatorForm::Full, &mut c).unwrap();
    assert_eq!(f.len(), g.len());
    // The trajectory loss is the sum of the supervised losses.
    let total: f64 = p
        .labelled_states(&t)
        .iter()
        .map(|ex| {
            let mut g = vec![0.0; theta.len()];
            p.supervised(&theta, ex, &mut g, &mut Cost::default())
                .unwrap()
        })
        .sum();
    assert_abs_diff_eq!(
        p.trajectory_loss(&theta, &t).unwrap(),
        total,
        epsilon = 1e-12
    );
}

#[test]
fn obstacle_expert_episodes_succeed_and_learner_rollouts_work() {
    let mut p = obstacle_problem();
    let mut rng = KitRng::seed_from_u64(4);
    let mut c = Cost::default();
    let e = p.rollout(&Behaviour::Expert, &mut rng, &mut c).unwrap();
    assert!(e.len() > 10 && e.len() < 200, "{}", e.len());
    // The oracle on a learner roll-out: right shape, finite.
    let theta = DVector::from_element(p.dim(), 0.01);
    let t = p
        .rollout(&Behaviour::Learner(&theta), &mut rng, &mut c)
        .unwrap();
    let g = p
        .estimate(&theta, &t, EstimatorForm::Causal, &mut c)
        .unwrap();
    assert_eq!(g.len(), 2 * obstacle::FEATURES);
    assert!(g.iter().all(|x| x.is_finite()));
    let b = Behaviour::Mixture {
        expert_weight: 0.5,
        learners: vec![(0.5, &theta)],
    };
    assert!(p.rollout(&b, &mut rng, &mut c).is_ok());
}

#[test]
fn bad_input_is_an_error() {
    let mut p = cartpole_problem();
    let mut rng = KitRng::seed_from_u64(1);
    let mut c = Cost::default();
    let short = DVector::from_element(3, 0.0);
    assert_eq!(
        p.rollout(&Behaviour::Learner(&short), &mut rng, &mut c)
            .unwrap_err(),
        OracleError::Dimension {
            expected: 10,
            got: 3
        }
    );
    let nan = DVector::from_element(10, f64::NAN);
    assert!(matches!(
        p.rollout(&Behaviour::Learner(&nan), &mut rng, &mut c),
        Err(OracleError::NonFinite(_))
    ));
    let theta = DVector::from_element(10, 0.0);
    let b = Behaviour::Mixture {
        expert_weight: 0.7,
        learners: vec![(0.7, &theta)],
    };
    assert!(matches!(
        p.rollout(&b, &mut rng, &mut c),
        Err(OracleError::Behaviour(_))
    ));
}

/// A learner's roll-out knows its features are finite (each φ went through the policy's checked
/// sampling) and the estimators skip their pass over them; the same data rebuilt from its parts
/// (features not known finite) gives bit-for-bit the same estimates and compares equal, and a
/// non-finite feature in rebuilt data is reported as φ's error.
#[test]
fn learner_rollouts_skip_the_feature_check_with_the_same_results() {
    use ilopt::policy::Logistic;
    use ilopt::task::TaskTrajectory;
    let mut p = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let theta = DVector::from_column_slice(&[0.3, 1.0, 8.0, 2.0, 0.1]);
    let mut c = Cost::default();
    for seed in 0..8 {
        let t = p
            .rollout(
                &Behaviour::Learner(&theta),
                &mut KitRng::seed_from_u64(seed),
                &mut c,
            )
            .unwrap();
        let rebuilt =
            TaskTrajectory::from_parts(t.features(), t.actions.clone(), t.labels.clone()).unwrap();
        assert_eq!(rebuilt, t);
        for form in [EstimatorForm::Causal, EstimatorForm::Full] {
            let mut bits = |t: &TaskTrajectory<f64, usize, usize>| {
                p.estimate(&theta, t, form, &mut Cost::default())
                    .map(|g| g.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
            };
            assert_eq!(bits(&t), bits(&rebuilt));
        }
        let mut features = t.features();
        features[t.len() / 2][1] = f64::NAN;
        let bad =
            TaskTrajectory::from_parts(features, t.actions.clone(), t.labels.clone()).unwrap();
        let err = p
            .estimate(&theta, &bad, EstimatorForm::Causal, &mut Cost::default())
            .unwrap_err();
        assert!(err.to_string().contains("phi"), "{err}");
    }
}

/// A task whose features grow by one entry at the third decision, where its expert fails too:
/// the roll-out stops with the features' error, naming both lengths (it is checked first, as
/// before φ was handed on by value), whoever acts (the expert, or a learner whose policy would
/// otherwise reject φ's length itself).
#[test]
fn features_that_change_length_are_an_error() {
    use ilopt::policy::Logistic;
    use ilopt::task::Task;
    #[derive(Debug, Clone)]
    struct Growing;
    impl Task<f64> for Growing {
        type Episode = usize;
        type Label = usize;
        type Action = usize;
        fn start(&self, _: &mut KitRng) -> Result<usize, OracleError> {
            Ok(0)
        }
        fn features(&self, step: &usize) -> Vec<f64> {
            vec![0.5; if *step < 2 { 1 } else { 2 }]
        }
        fn expert(&self, step: &usize) -> Result<(usize, usize), OracleError> {
            if *step < 2 {
                Ok((1, 1))
            } else {
                Err(OracleError::Environment("no label after two steps".into()))
            }
        }
        fn advance(&self, step: &mut usize, _: &usize) -> Result<bool, OracleError> {
            *step += 1;
            Ok(*step == 5)
        }
    }
    let mut p = TaskProblem {
        task: Growing,
        policy: Logistic::new(1).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let theta = DVector::from_element(1, 0.25);
    for behaviour in [Behaviour::Expert, Behaviour::Learner(&theta)] {
        let err = p
            .rollout(
                &behaviour,
                &mut KitRng::seed_from_u64(1),
                &mut Cost::default(),
            )
            .unwrap_err();
        assert!(
            matches!(&err, OracleError::Environment(m) if m.contains("from 1 to 2")),
            "{err}"
        );
    }
}

/// CartPole builds φ once, in a local array: what it appends, what it hands on, and
/// [`Task::features`] are the same values, `(x, ẋ, θ, θ̇, 1)` of the episode's state.
#[test]
fn cartpole_features_are_the_state_and_one_wherever_they_go() {
    use ilopt::task::Task;
    let task = CartPoleTask::<f64>::with_lqr().unwrap();
    let mut rng = KitRng::seed_from_u64(9);
    let mut ep = task.start(&mut rng).unwrap();
    let mut stored = vec![-7.0];
    for _ in 0..20 {
        let expected = [ep.state[0], ep.state[1], ep.state[2], ep.state[3], 1.0];
        let before = stored.len();
        let handed = task.push_features_then(&ep, &mut stored, <[f64]>::to_vec);
        assert_eq!(handed, expected);
        assert_eq!(stored[before..], expected);
        assert_eq!(task.features(&ep), expected);
        let mut pushed = Vec::new();
        task.push_features(&ep, &mut pushed);
        assert_eq!(pushed, expected);
        if task.advance(&mut ep, &1).unwrap() {
            break;
        }
    }
    assert_eq!(stored[0], -7.0);
}
