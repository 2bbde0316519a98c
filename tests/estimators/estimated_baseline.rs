//! The estimated variance-minimising baseline's fast route (`Baselined::estimate`: every
//! trajectory's decisions recorded, its plain estimate summed once, then one read of its scores for
//! both the statistics and the correction `g − Σ_i b_i ψ_i`) against the reference route assembled
//! from `DecisionTerms` (`Baselined::estimate_by_terms`), call after call with the statistics
//! committed between them: equal in exact arithmetic on toy MDPs (with and without terminal
//! states), close in `f64` on the real tasks (the logistic policy's own records, the softmax and
//! linear-Gaussian policies' default rows; episodic, reset and absorbing horizons). After each
//! call, the importance-weighted old-point estimate with the committed baselines (both
//! weightings) against the same terms assembled in the test.

use crate::common::example;
use approx::abs_diff_eq;
use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined, PerDecisionTerms};
use ilopt::oracle::DecisionTerms;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::scalar::{BigRational, Scalar, parse_exact_list};
use ilopt::toy::ToyProblem;
use nalgebra::DVector;
use rand::SeedableRng;

/// Two oracles stepped in lockstep from one seed, one through each route, for both estimated
/// kinds and m = 1, 3: per call the same roll-out, estimates that are `same`, equal costs.
fn lockstep<S, P>(p: &P, theta: &DVector<S>, same: impl Fn(&[S], &[S]) -> bool, what: &str)
where
    S: Scalar,
    P: PerDecisionTerms<S> + Clone,
{
    for time_indexed in [true, false] {
        for m in [1, 3] {
            let kind = Baseline::Estimated {
                time_indexed,
                decay: Some(ConfigNumber::ratio(9, 10)),
            };
            let mut fast = Baselined::<_, S>::new(p.clone(), m, &kind).unwrap();
            let mut reference = Baselined::<_, S>::new(p.clone(), m, &kind).unwrap();
            let (mut r1, mut r2) = (KitRng::seed_from_u64(5), KitRng::seed_from_u64(5));
            for call in 0..6 {
                let (mut c1, mut c2) = (Cost::default(), Cost::default());
                let b1 = fast
                    .rollout(&Behaviour::Learner(theta), &mut r1, &mut c1)
                    .unwrap();
                let b2 = reference
                    .rollout(&Behaviour::Learner(theta), &mut r2, &mut c2)
                    .unwrap();
                let g1 = fast
                    .estimate(theta, &b1, EstimatorForm::Causal, &mut c1)
                    .unwrap();
                let g2 = reference.estimate_by_terms(theta, &b2, &mut c2).unwrap();
                assert!(
                    same(g1.as_slice(), g2.as_slice()),
                    "{what}, time-indexed {time_indexed}, m = {m}, call {call}: {g1:?} vs {g2:?}"
                );
                assert_eq!(c1, c2, "{what}, call {call}: the cost");
                // The importance-weighted old-point estimate with the committed baselines (the
                // route a problem's weighted pass takes) against the same terms assembled here.
                let committed = reference.running().unwrap();
                let baseline = |i: usize| {
                    if time_indexed {
                        committed.time_indexed(i)
                    } else {
                        committed.constant()
                    }
                };
                let old = theta.map(|x| x + S::from_ratio(1, 50));
                for w in [Weighting::PerDecision, Weighting::Trajectory] {
                    let g1 = fast
                        .weighted_estimate(&old, theta, &b1, w, &mut c1)
                        .unwrap();
                    let mut g2 = vec![S::zero(); theta.len()];
                    for t in &b2 {
                        let mut terms = DecisionTerms::new();
                        p.decision_terms(&old, t, Some((theta, w)), &mut terms, &mut c2)
                            .unwrap();
                        terms.finish();
                        let mut one = vec![S::zero(); theta.len()];
                        terms.estimate_into(baseline, &mut one);
                        for (x, y) in g2.iter_mut().zip(one) {
                            *x += y;
                        }
                    }
                    let count = S::from_i64(m as i64);
                    let g2: Vec<S> = g2.into_iter().map(|x| x / &count).collect();
                    assert!(
                        same(g1.as_slice(), &g2),
                        "{what}, weighted {w:?}, time-indexed {time_indexed}, m = {m}, call {call}: {g1:?} vs {g2:?}"
                    );
                }
            }
        }
    }
}

/// Within 1e-12 of the reference's largest entry, relatively: the routes sum the same terms in
/// different orders, so they differ by rounding — at most n·ε ≈ 500 · 1.1e-16 ≈ 6e-14 of the
/// terms' magnitudes for n ≤ 500 decisions, carried from call to call through the baselines —
/// and a wrong term (a sign, a missing decision) moves the estimate by its own size.
fn close(a: &[f64], b: &[f64]) -> bool {
    let scale = b.iter().fold(1.0_f64, |s, x| s.max(x.abs()));
    abs_diff_eq!(a, b, epsilon = 1e-12 * scale)
}

#[test]
fn toy_estimated_baseline_fast_route_equals_terms_exactly() {
    for (file, theta) in [
        ("three-state.json", "-1/2,3,1/4,-7/2,1/3,1"),
        ("terminal-absorb.json", "1/3"),
        ("terminal-reset.json", "1/3"),
    ] {
        let mdp = example(file);
        let theta = DVector::from_vec(parse_exact_list(theta).unwrap());
        let p = ToyProblem::<BigRational>::new(&mdp);
        lockstep(&p, &theta, |a, b| a == b, file);
    }
}

#[test]
fn task_estimated_baseline_fast_route_agrees_with_terms() {
    use ilopt::policy::{Logistic, Softmax};
    use ilopt::task::cartpole::{self, CartPoleTask};
    use ilopt::task::{AfterEnd, Horizon, TaskProblem};
    let lqr = || CartPoleTask::<f64>::with_lqr().unwrap();
    let logistic = || Logistic::new(cartpole::FEATURES).unwrap();
    let balancing = DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1]);
    lockstep(
        &TaskProblem::episodic(lqr(), logistic()),
        &balancing,
        close,
        "logistic, episodic",
    );
    for (after_end, what) in [
        (AfterEnd::Reset, "logistic, reset"),
        (AfterEnd::Absorb, "logistic, absorb"),
    ] {
        let p = TaskProblem::fixed(lqr(), logistic(), 150, after_end).unwrap();
        let theta = DVector::from_vec(vec![0.0, 0.2, 1.0, 0.1, 0.0]);
        lockstep(&p, &theta, close, what);
    }
    let softmax = TaskProblem {
        task: lqr(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: Horizon::Episodic,
    };
    let theta = DVector::from_vec(vec![0.1, -0.2, 0.3, 0.5, 0.0, 0.2, 0.1, -0.4, 0.3, 0.1]);
    lockstep(&softmax, &theta, close, "softmax, episodic");
    let (obstacle, w) = crate::common::absorbing_obstacle_problem();
    lockstep(&obstacle, &w, close, "linear-Gaussian, obstacle, absorb");
}
