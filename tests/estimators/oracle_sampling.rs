//! The oracle's roll-outs: seeded and reproducible, identical across scalar types, honest cost
//! accounting, and clear errors for invalid behaviours, trajectories and parameters.

use crate::common::{example, q};
use approx::assert_abs_diff_eq;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::sampling::sample_categorical;
use ilopt::scalar::{BigRational, Interval, Scalar, Undecidable, interval_contains_rational};
use ilopt::toy::{ToyMdp, ToyProblem, ToyTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;

fn theta<S: Scalar>(xs: &[&str]) -> DVector<S> {
    DVector::from_iterator(xs.len(), xs.iter().map(|x| S::from_rational(&q(x))))
}

fn trajectories<S: Scalar>(mdp: &ToyMdp, th: &[&str], seed: u64, n: usize) -> Vec<ToyTrajectory> {
    let mut p = ToyProblem::<S>::new(mdp);
    let t = theta::<S>(th);
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    (0..n)
        .map(|_| {
            p.rollout(&Behaviour::Learner(&t), &mut rng, &mut cost)
                .unwrap()
        })
        .collect()
}

const TH3: [&str; 6] = ["1/2", "-1", "0.1", "3", "2/3", "-5/4"];

#[test]
fn same_seed_same_trajectories_in_every_scalar() {
    let mdp = example("three-state.json");
    let f = trajectories::<f64>(&mdp, &TH3, 7, 500);
    assert_eq!(
        f,
        trajectories::<f64>(&mdp, &TH3, 7, 500),
        "not reproducible"
    );
    assert_ne!(f, trajectories::<f64>(&mdp, &TH3, 8, 500), "seed ignored");
    assert_eq!(f, trajectories::<BigRational>(&mdp, &TH3, 7, 500));
    assert_eq!(f, trajectories::<Interval>(&mdp, &TH3, 7, 500));
}

#[test]
fn interval_estimates_enclose_exact_and_f64_estimates_on_the_same_trajectory() {
    let mdp = example("three-state.json");
    let (mut pf, mut pq, mut pi) = (
        ToyProblem::<f64>::new(&mdp),
        ToyProblem::<BigRational>::new(&mdp),
        ToyProblem::<Interval>::new(&mdp),
    );
    let th2 = ["0", "1", "1", "0", "-1/3", "2"];
    let mut c = Cost::default();
    for tau in trajectories::<f64>(&mdp, &TH3, 3, 50) {
        for form in [EstimatorForm::Causal, EstimatorForm::Full] {
            let gf = pf.estimate(&theta(&TH3), &tau, form, &mut c).unwrap();
            let gq = pq.estimate(&theta(&TH3), &tau, form, &mut c).unwrap();
            let gi = pi.estimate(&theta(&TH3), &tau, form, &mut c).unwrap();
            for j in 0..6 {
                assert!(interval_contains_rational(gi[j], &gq[j]));
                assert!(gi[j].contains(gf[j]));
            }
        }
        for w in [Weighting::Trajectory, Weighting::PerDecision] {
            let gq = pq
                .weighted_estimate(&theta(&TH3), &theta(&th2), &tau, w, &mut c)
                .unwrap();
            let gi = pi
                .weighted_estimate(&theta(&TH3), &theta(&th2), &tau, w, &mut c)
                .unwrap();
            assert!((0..6).all(|j| interval_contains_rational(gi[j], &gq[j])));
        }
    }
}

#[test]
fn cost_accounting() {
    let mdp = example("three-state.json"); // T = 4
    let mut p = ToyProblem::<f64>::new(&mdp);
    let t = theta::<f64>(&TH3);
    let mut rng = KitRng::seed_from_u64(1);
    let mut cost = Cost::default();
    let tau = p
        .rollout(&Behaviour::Learner(&t), &mut rng, &mut cost)
        .unwrap();
    assert_eq!(
        cost,
        Cost {
            trajectories: 1,
            env_steps: 3,
            gradient_evaluations: 0,
            expert_queries: 3
        }
    );
    p.estimate(&t, &tau, EstimatorForm::Causal, &mut cost)
        .unwrap();
    assert_eq!(
        cost.gradient_evaluations, 3,
        "one per state with a loss, t = 1..T−1"
    );
    p.weighted_estimate(&t, &t, &tau, Weighting::PerDecision, &mut cost)
        .unwrap();
    assert_eq!(cost.gradient_evaluations, 6);
    for ex in p.labelled_states(&tau).iter().take(3) {
        let mut g = vec![0.0; t.len()];
        p.supervised(&t, ex, &mut g, &mut cost).unwrap();
    }
    assert_eq!(cost.gradient_evaluations, 9);
    assert_eq!(cost.trajectories, 1);
}

#[test]
fn labels_are_the_experts_and_expert_rollouts_follow_it() {
    let mdp = example("three-state.json");
    let mut p = ToyProblem::<f64>::new(&mdp);
    let mut rng = KitRng::seed_from_u64(5);
    let mut cost = Cost::default();
    for _ in 0..200 {
        let tau = p.rollout(&Behaviour::Expert, &mut rng, &mut cost).unwrap();
        for (t, &s) in tau.states[..3].iter().enumerate() {
            assert_eq!(tau.labels[t], mdp.expert[s]);
            assert_eq!(tau.actions[t], mdp.expert[s]);
        }
    }
}

#[test]
fn mixture_frequencies_match_their_weights() {
    // M1: the learner with θ = 1 (p = 3/4 for action 1); the expert plays 1 in A, 0 in B.
    // With β = 1/2 the probability of action 1 at s_1 is ½·[μ_A·1 + μ_B·0] + ½·¾ = 5/8.
    let mdp = example("m1-tied.json");
    let mut p = ToyProblem::<f64>::new(&mdp);
    let t = theta::<f64>(&["1"]);
    let mut rng = KitRng::seed_from_u64(11);
    let mut cost = Cost::default();
    let n = 40_000;
    let b = Behaviour::Mixture {
        expert_weight: 0.5,
        learners: vec![(0.5, &t)],
    };
    let ones = (0..n)
        .filter(|_| p.rollout(&b, &mut rng, &mut cost).unwrap().actions[0] == 1)
        .count();
    let freq = ones as f64 / n as f64;
    // Binomial sd = √(5/8·3/8/40000) ≈ 0.0024; 6 sd.
    assert_abs_diff_eq!(freq, 0.625, epsilon = 0.015);
}

#[test]
fn invalid_inputs_are_errors() {
    let mdp = example("three-state.json");
    let mut p = ToyProblem::<f64>::new(&mdp);
    let mut rng = KitRng::seed_from_u64(1);
    let mut c = Cost::default();
    let short = DVector::from_vec(vec![0.0; 5]);
    assert_eq!(
        p.rollout(&Behaviour::Learner(&short), &mut rng, &mut c)
            .unwrap_err(),
        OracleError::Dimension {
            expected: 6,
            got: 5
        }
    );
    let nan = DVector::from_vec(vec![f64::NAN; 6]);
    assert!(matches!(
        p.rollout(&Behaviour::Learner(&nan), &mut rng, &mut c),
        Err(OracleError::NonFinite(_))
    ));
    let t = theta::<f64>(&TH3);
    for (ew, lw) in [(0.5, 0.6), (-0.1, 1.1), (f64::NAN, 1.0)] {
        let b = Behaviour::Mixture {
            expert_weight: ew,
            learners: vec![(lw, &t)],
        };
        assert!(matches!(
            p.rollout(&b, &mut rng, &mut c),
            Err(OracleError::Behaviour(_))
        ));
    }
    let good = p
        .rollout(&Behaviour::Learner(&t), &mut rng, &mut c)
        .unwrap();
    let mut bad = good.clone();
    bad.states[1] = 3;
    assert!(matches!(
        p.estimate(&t, &bad, EstimatorForm::Causal, &mut c),
        Err(OracleError::Trajectory(_))
    ));
    let mut bad = good.clone();
    bad.actions.pop();
    assert!(matches!(
        p.trajectory_loss(&t, &bad),
        Err(OracleError::Trajectory(_))
    ));
    // Off the open simplex in the direct parameterisation.
    let mut d = ToyProblem::<f64>::new(&example("m1-direct.json"));
    let out = DVector::from_vec(vec![1.0]);
    assert!(matches!(
        d.rollout(&Behaviour::Learner(&out), &mut rng, &mut c),
        Err(OracleError::Domain(_))
    ));
}

#[test]
fn undecidable_interval_sampling_is_an_error() {
    // u = 1/2 lies inside the enclosure [0.4, 0.6] of the first cumulative probability.
    let p0 = Interval::try_from((0.4, 0.6)).unwrap();
    let probs = [p0, Interval::one() - p0];
    let u = Interval::from_ratio(1, 2);
    assert_eq!(
        sample_categorical(&probs, &u),
        Err(Undecidable {
            what: "categorical sampling"
        })
    );
    assert_eq!(
        sample_categorical(&probs, &Interval::from_ratio(1, 4)),
        Ok(0)
    );
    assert_eq!(
        sample_categorical(&probs, &Interval::from_ratio(3, 4)),
        Ok(1)
    );
    // Zero-probability categories are never sampled, even at the end of a row.
    let exact = [q("1/2"), q("1/2"), q("0")];
    assert_eq!(sample_categorical(&exact, &q("0.999")), Ok(1));
    assert_eq!(sample_categorical(&[0.5, 0.5, 0.0], &0.9999999999), Ok(1));
}
