//! The trajectory loss computes each decision's loss alone (`EstimatorKernel::loss_validated`): bit for bit
//! the sum of `Policy::loss_into`'s values, inside and beyond the speed limit, with and without an
//! absorbing end; and the loss summed in the estimate's own pass is the same.

use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined};
use ilopt::batched::Batched;
use ilopt::policy::{LinearGaussian, Logistic, Policy, Softmax, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{ObstacleFeatures, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, TaskProblem};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};

#[test]
fn trajectory_loss_is_the_sum_of_the_per_decision_losses() {
    let task = ObstacleTask::thesis()
        .unwrap()
        .with_features(ObstacleFeatures::rbf_default())
        .unwrap()
        .with_actions::<[f64; 2]>();
    let n = task.feature_dim();
    let inner = LinearGaussian::new(2, n, 0.1)
        .unwrap()
        .with_actions::<[f64; 2]>()
        .unwrap();
    let policy = SpeedLimitedGaussian::new(inner, 0.1).unwrap();
    let mut rng = KitRng::seed_from_u64(3);
    let mut clipped = 0;
    for horizon in [Horizon::Episodic, Horizon::fixed(200, AfterEnd::Absorb)] {
        let mut p = TaskProblem {
            task: task.clone(),
            policy: policy.clone(),
            horizon,
        };
        for scale in [0.0, 0.05, 1.0, 20.0] {
            let theta = DVector::from_fn(2 * n, |_, _| scale * (2.0 * rng.random::<f64>() - 1.0));
            let t = p
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut Cost::default())
                .unwrap();
            let mut grad = vec![0.0; 2 * n];
            let mut want = t.absorbed.unwrap_or(0.0);
            for (phi, y) in t.feature_rows().zip(&t.labels) {
                want += p
                    .policy
                    .loss_into(theta.as_slice(), phi, y, &mut grad)
                    .unwrap();
                let raw: f64 = (0..2)
                    .map(|i| {
                        theta.as_slice()[i * n..(i + 1) * n]
                            .iter()
                            .zip(phi)
                            .map(|(a, b)| a * b)
                            .sum::<f64>()
                    })
                    .map(|x| x * x)
                    .sum();
                // Beyond the speed limit v = 0.1: the clipped branch.
                clipped += usize::from(raw > 0.01);
            }
            let got = p.trajectory_loss(&theta, &t).unwrap();
            assert_eq!(got.to_bits(), want.to_bits(), "scale {scale}, {horizon:?}");
        }
    }
    assert!(clipped > 100, "{clipped} clipped decisions");
}

/// `estimate_with_loss` returns the estimate and the trajectory loss of `estimate` then
/// `trajectory_loss`, bit for bit, on `p`'s learner roll-outs at each θ of `thetas`.
fn assert_estimate_with_loss<P: IlProblem<f64>>(p: &mut P, thetas: &[DVector<f64>], what: &str) {
    let mut rng = KitRng::seed_from_u64(11);
    for (k, theta) in thetas.iter().enumerate() {
        for _ in 0..3 {
            let mut c = Cost::default();
            let t = p
                .rollout(&Behaviour::Learner(theta), &mut rng, &mut c)
                .unwrap();
            let (mut c1, mut c2) = (c, c);
            let (g, loss) = p
                .estimate_with_loss(theta, &t, EstimatorForm::Causal, &mut c1)
                .unwrap();
            let want_g = p
                .estimate(theta, &t, EstimatorForm::Causal, &mut c2)
                .unwrap();
            let want_loss = p.trajectory_loss(theta, &t).unwrap();
            let bits = |v: &DVector<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&g), bits(&want_g), "{what}, θ #{k}: the estimate");
            assert_eq!(
                loss.to_bits(),
                want_loss.to_bits(),
                "{what}, θ #{k}: the loss {loss} vs {want_loss}"
            );
            assert_eq!(c1, c2, "{what}: the cost");
        }
    }
}

/// Baselines whose estimates record every trajectory's decisions, from which the loss is read:
/// a constant, per-decision constants, the estimated optimum (time-indexed and one constant) and
/// leave-one-out.
fn recorded_baselines() -> Vec<Baseline> {
    let estimated = |time_indexed| Baseline::Estimated {
        time_indexed,
        decay: Some(ConfigNumber::ratio(9, 10)),
    };
    vec![
        Baseline::Constant {
            value: ConfigNumber::ratio(1, 4),
        },
        Baseline::TimeIndexed {
            values: (0..600).map(|i| ConfigNumber::ratio(i % 7, 8)).collect(),
        },
        estimated(true),
        estimated(false),
        Baseline::LeaveOneOut,
    ]
}

/// The loss summed in the estimate's own pass (`IlProblem::estimate_with_loss`) is the trajectory
/// loss bit for bit: the obstacle task (inside and beyond the speed limit, episodic and with an
/// absorbing tail, which the loss must start from), CartPole with the softmax and the logistic
/// policies (episodic and reset streams; the logistic policy's fixed-dimension loop), one
/// trajectory and minibatches, with and without the baselines' wrapper (with the baselines whose
/// records the loss is read from).
#[test]
fn the_estimate_pass_gives_the_trajectory_loss_bit_for_bit() {
    let obstacle = ObstacleTask::thesis()
        .unwrap()
        .with_features(ObstacleFeatures::rbf_default())
        .unwrap()
        .with_actions::<[f64; 2]>();
    let n = obstacle.feature_dim();
    let inner = LinearGaussian::new(2, n, 0.1)
        .unwrap()
        .with_actions::<[f64; 2]>()
        .unwrap();
    let policy = SpeedLimitedGaussian::new(inner, 0.1).unwrap();
    let mut rng = KitRng::seed_from_u64(5);
    let thetas: Vec<DVector<f64>> = [0.0, 0.05, 20.0]
        .iter()
        .map(|s| DVector::from_fn(2 * n, |_, _| s * (2.0 * rng.random::<f64>() - 1.0)))
        .collect();
    let mut absorbed = 0;
    for horizon in [Horizon::Episodic, Horizon::fixed(200, AfterEnd::Absorb)] {
        let mut p = TaskProblem {
            task: obstacle.clone(),
            policy: policy.clone(),
            horizon,
        };
        for th in &thetas {
            let t = p
                .rollout(&Behaviour::Learner(th), &mut rng, &mut Cost::default())
                .unwrap();
            absorbed += usize::from(t.absorbed.is_some_and(|l| l > 0.0));
        }
        assert_estimate_with_loss(&mut p, &thetas, &format!("obstacle, {horizon:?}"));
        let mut batched = Batched::new(p.clone(), 3).unwrap();
        assert_estimate_with_loss(&mut batched, &thetas, "obstacle, m = 3");
        for b in recorded_baselines() {
            let mut wrapped = Baselined::new(p.clone(), 3, &b).unwrap();
            assert_estimate_with_loss(&mut wrapped, &thetas, &format!("obstacle, m = 3, {b:?}"));
        }
        let mut wrapped = Baselined::new(p, 3, &Baseline::None).unwrap();
        assert_estimate_with_loss(&mut wrapped, &thetas, "obstacle, m = 3, no baseline");
    }
    assert!(absorbed > 0, "no roll-out ended in a costly absorbing tail");

    let cartpole_thetas = |d: usize, rng: &mut KitRng| -> Vec<DVector<f64>> {
        [0.0, 0.5, 3.0]
            .iter()
            .map(|s| DVector::from_fn(d, |_, _| s * (2.0 * rng.random::<f64>() - 1.0)))
            .collect()
    };
    for horizon in [Horizon::Episodic, Horizon::fixed(500, AfterEnd::Reset)] {
        let mut softmax = TaskProblem {
            task: CartPoleTask::with_lqr().unwrap(),
            policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
            horizon,
        };
        let th = cartpole_thetas(2 * cartpole::FEATURES, &mut rng);
        assert_estimate_with_loss(&mut softmax, &th, &format!("CartPole softmax, {horizon:?}"));
        for b in recorded_baselines() {
            let mut wrapped = Baselined::new(softmax.clone(), 3, &b).unwrap();
            assert_estimate_with_loss(
                &mut wrapped,
                &th,
                &format!("CartPole softmax, m = 3, {b:?}"),
            );
        }
        let mut batched = Batched::new(softmax, 3).unwrap();
        assert_estimate_with_loss(&mut batched, &th, "CartPole softmax, m = 3");
        let mut logistic = TaskProblem {
            task: CartPoleTask::with_lqr().unwrap(),
            policy: Logistic::new(cartpole::FEATURES).unwrap(),
            horizon,
        };
        let th = cartpole_thetas(cartpole::FEATURES, &mut rng);
        assert_estimate_with_loss(
            &mut logistic,
            &th,
            &format!("CartPole logistic, {horizon:?}"),
        );
    }
}
