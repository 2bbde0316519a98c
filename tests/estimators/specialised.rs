//! The hand-specialised `f64` CartPole + logistic oracle of `benches/support/specialised.rs` (the
//! yardstick of the generic code's speed) computes exactly what the generic
//! `TaskProblem<CartPoleTask<f64>, Logistic>` computes: the same trajectories from the same seeds
//! and bit-identical causal gradients.

#[path = "../../benches/support/specialised.rs"]
mod yardstick;

use ilopt::expert::lqr::LqrExpert;
use ilopt::policy::Logistic;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::{self, CartPoleTask};
use nalgebra::DVector;
use rand::SeedableRng;
use yardstick::{D, Specialised, Trajectory};

#[test]
fn specialised_and_generic_agree_bit_for_bit() {
    let mut generic = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let gain = *LqrExpert::cartpole().unwrap().gain();
    let fast = Specialised {
        k: std::array::from_fn(|i| gain[i]),
        max_steps: 500,
    };
    let thetas: [[f64; D]; 3] = [
        [0.3, 1.0, 8.0, 2.0, 0.1],
        [0.0, 0.2, 1.0, 0.1, 0.0],
        [-0.5, 0.7, 12.0, 3.0, -0.2],
    ];
    let mut t = Trajectory::default();
    let mut cost = Cost::default();
    let mut lengths = vec![];
    for theta in &thetas {
        let th = DVector::from_column_slice(theta);
        for seed in 0..30 {
            let mut rng = KitRng::seed_from_u64(seed);
            let gt = generic
                .rollout(&Behaviour::Learner(&th), &mut rng, &mut cost)
                .unwrap();
            let mut rng = KitRng::seed_from_u64(seed);
            fast.rollout(theta, &mut rng, &mut t);
            assert_eq!(gt.len(), t.actions.len(), "seed {seed}");
            lengths.push(gt.len());
            for (i, row) in gt.feature_rows().enumerate() {
                assert_eq!(row, &t.features[i][..], "seed {seed}, step {i}");
                assert_eq!(gt.actions[i], usize::from(t.actions[i]));
                assert_eq!(gt.labels[i], usize::from(t.labels[i]));
            }
            let g = generic
                .estimate(&th, &gt, EstimatorForm::Causal, &mut cost)
                .unwrap();
            let h = Specialised::estimate(theta, &t);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(g.as_slice()), bits(&h), "seed {seed}");
        }
    }
    assert!(lengths.iter().any(|&n| n < 100) && lengths.contains(&500));
}
