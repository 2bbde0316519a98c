//! The trajectory loss computes each decision's loss alone (`EstimatorKernel::loss_trusted`): bit for bit
//! the sum of `Policy::loss_into`'s values, inside and beyond the speed limit, with and without an
//! absorbing end.

use ilopt::policy::{LinearGaussian, Policy, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, IlProblem, KitRng};
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
        let p = TaskProblem {
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
