//! The leave-one-out baseline's fast route (`Baselined::estimate`: every trajectory's decisions
//! recorded, then each estimate summed once with the baseline folded into its per-step losses)
//! against the reference
//! route assembled from `DecisionTerms` (`Baselined::estimate_by_terms`): equal in exact
//! arithmetic on toy MDPs (with and without terminal states), close in `f64` there and on the
//! real tasks (the logistic policy's fixed-dimension pass, the softmax and linear-Gaussian
//! policies' default pass, episodic, reset and absorbing horizons), with the same cost and the
//! same errors.

use crate::common::example;
use approx::abs_diff_eq;
use ilopt::baseline::{Baseline, Baselined, PerDecisionTerms};
use ilopt::oracle::RecordedPass;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError};
use ilopt::scalar::{BigRational, Scalar, parse_exact_list};
use ilopt::toy::{ToyProblem, ToyTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;

/// Toy MDPs with a θ each: no termination, and terminal states that absorb or reset.
const TOY_CASES: [(&str, &str); 5] = [
    ("three-state.json", "-1/2,3,1/4,-7/2,1/3,1"),
    ("m1-tied.json", "1/2"),
    ("m2-tied-two-groups.json", "1/3,-2"),
    ("terminal-absorb.json", "1/3"),
    ("terminal-reset.json", "1/3"),
];

/// Equal entry by entry (exact scalars).
fn equal(a: &[BigRational], b: &[BigRational]) -> bool {
    a == b
}

/// Within a relative 1e-12 of the reference's largest entry (floating point: the two routes sum
/// in different orders).
fn close(a: &[f64], b: &[f64]) -> bool {
    let scale = b.iter().fold(1.0_f64, |s, x| s.max(x.abs()));
    abs_diff_eq!(a, b, epsilon = 1e-12 * scale)
}

/// Both routes on `batch` split into minibatches of m = 2, 3, 4: `same` results, equal costs.
fn compare_routes<S, P>(
    p: &P,
    theta: &DVector<S>,
    batch: &[P::Trajectory],
    same: impl Fn(&[S], &[S]) -> bool,
    what: &str,
) where
    S: Scalar,
    P: PerDecisionTerms<S> + Clone,
{
    for m in [2, 3, 4] {
        let mut o = Baselined::<_, S>::new(p.clone(), m, &Baseline::LeaveOneOut).unwrap();
        for chunk in batch.chunks_exact(m) {
            let (mut c1, mut c2) = (Cost::default(), Cost::default());
            let fast = o
                .estimate(theta, &chunk.to_vec(), EstimatorForm::Causal, &mut c1)
                .unwrap();
            let reference = o.estimate_by_terms(theta, chunk, &mut c2).unwrap();
            assert!(
                same(fast.as_slice(), reference.as_slice()),
                "{what}, m = {m}: {fast:?} vs {reference:?}"
            );
            assert_eq!(c1, c2, "{what}, m = {m}: the cost");
        }
        // One trajectory has no other to take its baseline from: an error on both routes.
        for r in [
            o.estimate(
                theta,
                &batch[..1].to_vec(),
                EstimatorForm::Causal,
                &mut Cost::default(),
            ),
            o.estimate_by_terms(theta, &batch[..1], &mut Cost::default()),
        ] {
            assert!(
                matches!(r, Err(OracleError::Baseline(ref e)) if e.contains("at least 2")),
                "{what}: {r:?}"
            );
        }
    }
}

/// Leave-one-out on toy MDPs in the scalar `$s`: trajectories rolled out in `f64`, estimated in
/// `$s` by both routes and compared with `$same`.
macro_rules! toy_leave_one_out_matches_terms {
    ($name:ident, $s:ty, $same:expr) => {
        #[test]
        fn $name() {
            for (file, theta) in TOY_CASES {
                let mdp = example(file);
                let exact = parse_exact_list(theta).unwrap();
                if exact.len() != mdp.policy.dim() {
                    panic!("{file}: θ of {} entries", exact.len());
                }
                let theta_f = DVector::from_iterator(exact.len(), exact.iter().map(Scalar::to_f64));
                let theta_s: DVector<$s> = DVector::from_iterator(
                    exact.len(),
                    exact.iter().map(<$s as Scalar>::from_rational),
                );
                let mut pf = ToyProblem::<f64>::new(&mdp);
                let mut rng = KitRng::seed_from_u64(21);
                let batch: Vec<ToyTrajectory> = (0..24)
                    .map(|_| {
                        pf.rollout(
                            &Behaviour::Learner(&theta_f),
                            &mut rng,
                            &mut Cost::default(),
                        )
                        .unwrap()
                    })
                    .collect();
                let p = ToyProblem::<$s>::new(&mdp);
                compare_routes(&p, &theta_s, &batch, $same, file);
            }
        }
    };
}

toy_leave_one_out_matches_terms!(
    toy_leave_one_out_fast_route_equals_terms_exactly,
    BigRational,
    equal
);
toy_leave_one_out_matches_terms!(
    toy_leave_one_out_fast_route_agrees_with_terms_in_f64,
    f64,
    close
);

/// `n` roll-outs of `p` at θ.
fn rollouts<P: IlProblem<f64>>(
    p: &mut P,
    theta: &DVector<f64>,
    n: usize,
    seed: u64,
) -> Vec<P::Trajectory> {
    let mut rng = KitRng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            p.rollout(&Behaviour::Learner(theta), &mut rng, &mut Cost::default())
                .unwrap()
        })
        .collect()
}

/// The real tasks: the logistic policy's own recording pass (one score coefficient per decision)
/// and the default one (rows of ψ_t: softmax, linear-Gaussian), episodic, with resets and with
/// absorbing tails. The recorded decisions summed with their own losses are the plain estimate,
/// bit for bit (every policy's recorded sum runs its plain pass's order).
#[test]
fn task_leave_one_out_fast_route_agrees_with_terms() {
    use ilopt::policy::{Logistic, Softmax};
    use ilopt::task::cartpole::{self, CartPoleTask};
    use ilopt::task::{AfterEnd, Horizon, TaskProblem};

    fn check<T, P>(p: &mut TaskProblem<T, P>, theta: &DVector<f64>, what: &str)
    where
        TaskProblem<T, P>: PerDecisionTerms<
                f64,
                Trajectory = ilopt::task::TaskTrajectory<f64, T::Label, T::Action>,
            > + Clone,
        T: ilopt::task::Task<f64>,
    {
        let batch = rollouts(p, theta, 12, 8);
        compare_routes(p, theta, &batch, close, what);
        let mut recorded = RecordedPass::new();
        for t in &batch {
            p.record_decisions(theta, t, &mut recorded, &mut Cost::default())
                .unwrap();
            let mut g = vec![0.0; p.dim()];
            let losses = recorded.losses().to_vec();
            p.estimate_recorded(t, &mut recorded, Some(&losses), &mut g);
            let plain = p
                .estimate(theta, t, EstimatorForm::Causal, &mut Cost::default())
                .unwrap();
            assert_eq!(
                g.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                plain.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "{what}: the recorded decisions summed with their own losses"
            );
        }
    }
    let lqr = || CartPoleTask::<f64>::with_lqr().unwrap();
    let logistic = || Logistic::new(cartpole::FEATURES).unwrap();
    let balancing = DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1]);
    check(
        &mut TaskProblem::episodic(lqr(), logistic()),
        &balancing,
        "logistic, episodic",
    );
    for (after_end, what) in [
        (AfterEnd::Reset, "logistic, reset"),
        (AfterEnd::Absorb, "logistic, absorb"),
    ] {
        let mut p = TaskProblem::fixed(lqr(), logistic(), 150, after_end).unwrap();
        check(
            &mut p,
            &DVector::from_vec(vec![0.0, 0.2, 1.0, 0.1, 0.0]),
            what,
        );
    }
    let mut softmax = TaskProblem {
        task: lqr(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: Horizon::Episodic,
    };
    check(
        &mut softmax,
        &DVector::from_vec(vec![0.1, -0.2, 0.3, 0.5, 0.0, 0.2, 0.1, -0.4, 0.3, 0.1]),
        "softmax, episodic",
    );
    let (mut obstacle, w) = crate::common::absorbing_obstacle_problem();
    assert!(
        rollouts(&mut obstacle, &w, 12, 8)
            .iter()
            .any(|t| t.absorbed.is_some()),
        "an absorbing tail among the obstacle trajectories"
    );
    check(&mut obstacle, &w, "linear-Gaussian, obstacle, absorb");
}

/// Invalid θ: the fast route reports the reference route's error.
#[test]
fn task_leave_one_out_errors_as_the_terms_route() {
    use ilopt::policy::Logistic;
    use ilopt::task::TaskProblem;
    use ilopt::task::cartpole::{self, CartPoleTask};
    let mut p = TaskProblem::episodic(
        CartPoleTask::<f64>::with_lqr().unwrap(),
        Logistic::new(cartpole::FEATURES).unwrap(),
    );
    let theta = DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1]);
    let batch = rollouts(&mut p, &theta, 2, 3);
    let mut o = Baselined::<_, f64>::new(p, 2, &Baseline::LeaveOneOut).unwrap();
    for bad in [
        DVector::from_vec(vec![0.3, 1.0]),
        DVector::from_vec(vec![0.3, f64::NAN, 8.0, 2.0, 0.1]),
    ] {
        let fast = o.estimate(&bad, &batch, EstimatorForm::Causal, &mut Cost::default());
        let reference = o.estimate_by_terms(&bad, &batch, &mut Cost::default());
        assert!(fast.is_err(), "{fast:?}");
        assert_eq!(fast, reference);
    }
}
