//! The softmax policy notes the probabilities it samples from, and the causal estimate at the
//! same θ reads them (`EstimatorKernel::sample_noting`, `causal_sum_noted`): bit for bit the
//! estimate recomputed from the features, on episodes and on fixed-horizon streams with resets
//! and with an absorbing end; at another θ the notes are not used.

use ilopt::policy::Softmax;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::{AfterEnd, Horizon, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};

/// The trajectory without the roll-out's notes: rebuilt from its parts.
fn without_notes<S, L, A>(t: &TaskTrajectory<S, L, A>) -> TaskTrajectory<S, L, A>
where
    S: Clone + PartialEq + std::fmt::Debug,
    L: Clone + PartialEq + std::fmt::Debug,
    A: Clone + PartialEq + std::fmt::Debug,
{
    let mut u = TaskTrajectory::from_parts(t.features(), t.actions.clone(), t.labels.clone())
        .expect("equal feature lengths");
    u.absorbed = t.absorbed.clone();
    u.resets = t.resets;
    assert_eq!(&u, t);
    u
}

fn bits(g: &DVector<f64>) -> Vec<u64> {
    g.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn the_estimate_from_the_noted_probabilities_is_the_recomputed_one() {
    let mut rng = KitRng::seed_from_u64(5);
    let mut cost = Cost::default();
    let (mut compared, mut differ) = (0, 0);
    for horizon in [
        Horizon::Episodic,
        Horizon::fixed(500, AfterEnd::Reset),
        Horizon::fixed(200, AfterEnd::Absorb),
    ] {
        let p = TaskProblem {
            task: CartPoleTask::<f64>::with_lqr().unwrap(),
            policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
            horizon,
        };
        for scale in [0.0, 0.3, 3.0, 30.0] {
            let theta = DVector::from_fn(2 * cartpole::FEATURES, |_, _| {
                scale * (2.0 * rng.random::<f64>() - 1.0)
            });
            // Another θ: the first action's row moved (moving both rows alike would leave the
            // probabilities unchanged, up to rounding).
            let mut other = theta.clone();
            other.rows_mut(0, cartpole::FEATURES).add_scalar_mut(0.25);
            let t = p
                .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
                .unwrap();
            let u = without_notes(&t);
            for at in [&theta, &other] {
                let (g_t, l_t) = p
                    .estimate_with_loss(at, &t, EstimatorForm::Causal, &mut cost)
                    .unwrap();
                let (g_u, l_u) = p
                    .estimate_with_loss(at, &u, EstimatorForm::Causal, &mut cost)
                    .unwrap();
                assert_eq!(bits(&g_t), bits(&g_u), "{horizon:?}, scale {scale}");
                assert_eq!(l_t.to_bits(), l_u.to_bits());
                compared += 1;
            }
            // θ's notes read at the other θ would give exactly θ's estimate (a decision's terms
            // depend on θ only through its probabilities), so every case where the two
            // estimates differ would catch notes used at the wrong θ.
            let g = p
                .estimate(&theta, &u, EstimatorForm::Causal, &mut cost)
                .unwrap();
            let h = p
                .estimate(&other, &u, EstimatorForm::Causal, &mut cost)
                .unwrap();
            differ += usize::from(bits(&g) != bits(&h));
        }
    }
    assert_eq!(compared, 24);
    assert_eq!(differ, 12, "every case can catch notes used at the wrong θ");
}
