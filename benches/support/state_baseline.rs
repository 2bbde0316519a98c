//! The state-dependent baseline as the CartPole benchmarks time it, its weights fitted before
//! any timing.

use ilopt::baseline::{Baseline, Baselined, PerDecisionTerms};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use nalgebra::DVector;
use rand::SeedableRng;

/// `Baselined` over `problem` (m = 1) with the state-dependent baseline (the problem's features,
/// the decision index and 1; `fit_every` as given, `None` the default), its weights fitted on
/// `singles` (one-trajectory batches): each estimated at θ, then committed by a roll-out seeded
/// from `seed`, so that exactly the share `fit_every` takes enters the weights.
pub fn fitted_state<P>(
    problem: &P,
    theta: &DVector<f64>,
    singles: &[Vec<P::Trajectory>],
    fit_every: Option<u64>,
    seed: u64,
) -> Baselined<P, f64>
where
    P: PerDecisionTerms<f64> + Clone,
{
    let mut o = Baselined::new(
        problem.clone(),
        1,
        &Baseline::StateDependent {
            features: None,
            time: true,
            decay: None,
            ridge: None,
            fit_every,
        },
    )
    .expect("a state-dependent baseline");
    let mut rng = KitRng::seed_from_u64(seed);
    let mut warm = Cost::default();
    for one in singles {
        o.estimate(theta, one, EstimatorForm::Causal, &mut warm)
            .expect("estimate");
        o.rollout(&Behaviour::Learner(theta), &mut rng, &mut warm)
            .expect("roll-out");
    }
    o
}
