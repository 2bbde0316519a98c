//! Minibatches: m roll-outs per oracle call, the mean of their estimates, every cost counted.

use approx::assert_abs_diff_eq;
use ilopt::batched::Batched;
use ilopt::policy::Softmax;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::{AfterEnd, TaskProblem};
use nalgebra::DVector;
use rand::SeedableRng;

fn cartpole() -> TaskProblem<CartPoleTask<f64>, Softmax> {
    TaskProblem::fixed(
        CartPoleTask::with_lqr().unwrap(),
        Softmax::new(2, cartpole::FEATURES).unwrap(),
        100,
        AfterEnd::Reset,
    )
    .unwrap()
}

#[test]
fn a_batch_is_m_independent_rollouts_and_the_mean_of_their_estimates() {
    let mut p = cartpole();
    let mut b = Batched::new(p.clone(), 3).unwrap();
    assert_eq!((b.size(), IlProblem::<f64>::dim(&b)), (3, p.dim()));
    let theta = DVector::from_fn(p.dim(), |i, _| 0.1 * i as f64 - 0.2);
    let new = DVector::from_fn(p.dim(), |i, _| 0.1 * i as f64 - 0.25);
    let behaviour = Behaviour::Learner(&theta);
    let mut cost = Cost::default();
    let batch = b
        .rollout(&behaviour, &mut KitRng::seed_from_u64(5), &mut cost)
        .unwrap();
    // The same RNG stream, one roll-out after another.
    let mut rng = KitRng::seed_from_u64(5);
    let mut one = Cost::default();
    let singles: Vec<_> = (0..3)
        .map(|_| p.rollout(&behaviour, &mut rng, &mut one).unwrap())
        .collect();
    assert_eq!(batch, singles);
    assert_eq!(cost, one);
    assert_eq!(cost.trajectories, 3);
    assert_ne!(singles[0], singles[1]);

    let mut c = Cost::default();
    let g = b
        .estimate(&theta, &batch, EstimatorForm::Causal, &mut c)
        .unwrap();
    assert_eq!(c.gradient_evaluations, 300);
    let parts: Vec<DVector<f64>> = singles
        .iter()
        .map(|t| {
            p.estimate(&theta, t, EstimatorForm::Causal, &mut Cost::default())
                .unwrap()
        })
        .collect();
    let mean = (&parts[0] + &parts[1] + &parts[2]) / 3.0;
    assert!((g - &mean).norm() <= 1e-12 * mean.norm());
    assert!((&parts[0] - &parts[1]).norm() > 1e-6);

    let w = b
        .weighted_estimate(&theta, &new, &batch, Weighting::PerDecision, &mut c)
        .unwrap();
    let d = p.dim();
    let wm: DVector<f64> = singles
        .iter()
        .map(|t| {
            p.weighted_estimate(
                &theta,
                &new,
                t,
                Weighting::PerDecision,
                &mut Cost::default(),
            )
            .unwrap()
        })
        .fold(DVector::zeros(d), |a, x| a + x)
        / 3.0;
    assert!((w - &wm).norm() <= 1e-12 * wm.norm());

    let loss = b.trajectory_loss(&theta, &batch).unwrap();
    let lm: f64 = singles
        .iter()
        .map(|t| p.trajectory_loss(&theta, t).unwrap())
        .sum::<f64>()
        / 3.0;
    assert_abs_diff_eq!(loss, lm, epsilon = 1e-12 * lm);
    assert_eq!(b.labelled_states(&batch).len(), 300);
}

#[test]
fn an_empty_batch_is_an_error() {
    let err = Batched::new(cartpole(), 0).unwrap_err();
    assert!(err.to_string().contains("at least 1 trajectory"), "{err}");
    let mut b = Batched::new(cartpole(), 2).unwrap();
    let theta = DVector::zeros(5);
    let err = b
        .estimate(
            &theta,
            &Vec::new(),
            EstimatorForm::Causal,
            &mut Cost::default(),
        )
        .unwrap_err();
    assert!(err.to_string().contains("empty minibatch"), "{err}");
}

/// Every kind of baseline refuses an empty minibatch by name, in the plain estimate and in the
/// importance-weighted one.
#[test]
fn every_baseline_refuses_an_empty_batch() {
    use ilopt::algo::ConfigNumber;
    use ilopt::baseline::{Baseline, Baselined};
    let kinds = [
        Baseline::Constant {
            value: ConfigNumber::Float(0.5),
        },
        Baseline::LeaveOneOut,
        Baseline::Estimated {
            time_indexed: true,
            decay: None,
        },
        Baseline::StateDependent {
            features: None,
            time: true,
            decay: None,
            ridge: None,
            fit_every: None,
        },
    ];
    let theta = DVector::zeros(5);
    let mut cost = Cost::default();
    for kind in &kinds {
        let mut b = Baselined::<_, f64>::new(cartpole(), 2, kind).unwrap();
        let err = b
            .estimate(&theta, &Vec::new(), EstimatorForm::Causal, &mut cost)
            .unwrap_err();
        assert!(
            err.to_string().contains("empty minibatch"),
            "{kind:?}: {err}"
        );
        let err = b
            .weighted_estimate(
                &theta,
                &theta,
                &Vec::new(),
                Weighting::PerDecision,
                &mut cost,
            )
            .unwrap_err();
        assert!(
            err.to_string().contains("empty minibatch"),
            "{kind:?}: {err}"
        );
    }
}
