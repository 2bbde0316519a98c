//! The thesis's fixed-horizon objective on the real tasks: streams of exactly T decisions with
//! resets, absorbing ends with their stated loss, and the eq. 3.15 estimators on such streams
//! checked against a direct evaluation of their defining sums.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use ilopt::policy::{LikelihoodRatio, LinearGaussian, Policy, Softmax};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, Task, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;

type CartPole = TaskProblem<CartPoleTask<f64>, Softmax>;

fn cartpole(steps: usize, after_end: AfterEnd) -> CartPole {
    TaskProblem::fixed(
        CartPoleTask::with_lqr().unwrap(),
        Softmax::new(2, cartpole::FEATURES).unwrap(),
        steps,
        after_end,
    )
    .unwrap()
}

fn learner_rollout<P: IlProblem<f64>>(p: &mut P, theta: &DVector<f64>, seed: u64) -> P::Trajectory {
    let mut rng = KitRng::seed_from_u64(seed);
    p.rollout(&Behaviour::Learner(theta), &mut rng, &mut Cost::default())
        .unwrap()
}

/// Per decision `(l_t, ∇l_t, ψ_t)` by the policy's own per-decision call.
fn terms(
    p: &CartPole,
    theta: &DVector<f64>,
    t: &TaskTrajectory<f64, usize, usize>,
) -> Vec<(f64, Vec<f64>, Vec<f64>)> {
    let d = p.dim();
    t.feature_rows()
        .zip(&t.actions)
        .zip(&t.labels)
        .map(|((phi, a), y)| {
            let (mut grad, mut score) = (vec![0.0; d], vec![0.0; d]);
            let l = p
                .policy
                .loss_score_into(theta.as_slice(), phi, y, a, &mut grad, &mut score)
                .unwrap();
            (l, grad, score)
        })
        .collect()
}

/// `Σ_t w_{1:t−1} ∇l_t + Σ_{i} ψ_i Σ_{t>i} w_{1:t−1} l_t`, the absorbing losses
/// (`w_{1:n} L_abs`) included, from the definition (quadratic in n: every loss-to-go summed
/// afresh). `w` holds the prefix weights `w_{1:0} = 1, w_{1:1}, …, w_{1:n}`.
fn causal_by_definition(
    terms: &[(f64, Vec<f64>, Vec<f64>)],
    absorbed: Option<f64>,
    w: &[f64],
) -> Vec<f64> {
    let n = terms.len();
    let d = terms[0].1.len();
    let mut g = vec![0.0; d];
    for (t, (_, grad, _)) in terms.iter().enumerate() {
        for j in 0..d {
            g[j] += w[t] * grad[j];
        }
    }
    for (i, (_, _, psi)) in terms.iter().enumerate() {
        let mut to_go: f64 = (i + 1..n).map(|t| w[t] * terms[t].0).sum();
        if let Some(tail) = absorbed {
            to_go += w[n] * tail;
        } else if i + 1 == n {
            continue;
        }
        for j in 0..d {
            g[j] += psi[j] * to_go;
        }
    }
    g
}

fn assert_close(a: &[f64], b: &[f64]) {
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (x, y) in a.iter().zip(b) {
        assert!(abs_diff_eq!(x, y, epsilon = 1e-11 * scale), "{a:?}\n{b:?}");
    }
}

#[test]
fn a_reset_stream_has_exactly_the_horizon_across_resets() {
    let mut p = cartpole(500, AfterEnd::Reset);
    // θ = 0 pushes at random: the pole falls within a few dozen steps, so the stream resets.
    let theta = DVector::zeros(p.dim());
    let t = learner_rollout(&mut p, &theta, 7);
    assert_eq!(t.len(), 500);
    assert!(t.resets >= 3, "resets {}", t.resets);
    assert_eq!(t.absorbed, None);
    assert_eq!(t, learner_rollout(&mut p, &theta, 7));
    // The estimator runs over the whole stream: one gradient evaluation per decision, and the
    // score sum crosses the resets (the definition with every i < T).
    let mut cost = Cost::default();
    let g = p
        .estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
        .unwrap();
    assert_eq!(cost.gradient_evaluations, 500);
    let ones = vec![1.0; 501];
    assert_close(
        g.as_slice(),
        &causal_by_definition(&terms(&p, &theta, &t), None, &ones),
    );
}

#[test]
fn an_absorbing_stream_charges_the_remaining_steps_and_no_gradient_evaluations() {
    let mut p = cartpole(500, AfterEnd::Absorb);
    let theta = DVector::from_fn(p.dim(), |i, _| 0.3 * (i as f64 - 2.0));
    let t = learner_rollout(&mut p, &theta, 3);
    let n = t.len();
    assert!(n < 500, "the learner balanced for {n} steps");
    assert_eq!(t.absorbed, Some(2.0 * (500 - n) as f64));
    assert_eq!(t.resets, 0);
    let tm = terms(&p, &theta, &t);
    let loss: f64 = tm.iter().map(|x| x.0).sum();
    let total = p.trajectory_loss(&theta, &t).unwrap();
    assert_abs_diff_eq!(
        total,
        loss + 2.0 * (500 - n) as f64,
        epsilon = 1e-12 * total
    );
    let mut cost = Cost::default();
    let g = p
        .estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
        .unwrap();
    assert_eq!(cost.gradient_evaluations as usize, n);
    let tail = t.absorbed;
    assert_close(
        g.as_slice(),
        &causal_by_definition(&tm, tail, &vec![1.0; n + 1]),
    );
    // The full form: Σ∇l + (Σl + L_abs) Σ_{i≤n} ψ_i.
    let full = p
        .estimate(&theta, &t, EstimatorForm::Full, &mut Cost::default())
        .unwrap();
    let total = loss + tail.unwrap();
    let by_def: Vec<f64> = (0..p.dim())
        .map(|j| tm.iter().map(|x| x.1[j] + total * x.2[j]).sum())
        .collect();
    assert_close(full.as_slice(), &by_def);
}

#[test]
fn weighted_estimates_of_an_absorbed_stream_weigh_the_tail_by_every_decision() {
    let mut p = cartpole(500, AfterEnd::Absorb);
    let old = DVector::from_fn(p.dim(), |i, _| 0.3 * (i as f64 - 2.0));
    let new = DVector::from_fn(p.dim(), |i, _| 0.25 * (i as f64 - 1.5));
    let t = learner_rollout(&mut p, &new, 11);
    let n = t.len();
    assert!(n < 500);
    // Prefix weights w_{1:k} = Π_{i≤k} π_old(a_i|s_i)/π_new(a_i|s_i), k = 0..n.
    let mut w = vec![1.0];
    for (phi, a) in t.feature_rows().zip(&t.actions) {
        let r = p
            .policy
            .log_likelihood_ratio(old.as_slice(), new.as_slice(), phi, a)
            .unwrap();
        w.push(w.last().unwrap() * r.exp());
    }
    let per_decision = p
        .weighted_estimate(&old, &new, &t, Weighting::PerDecision, &mut Cost::default())
        .unwrap();
    let tm = terms(&p, &old, &t);
    assert_close(
        per_decision.as_slice(),
        &causal_by_definition(&tm, t.absorbed, &w),
    );
    let whole = p
        .weighted_estimate(&old, &new, &t, Weighting::Trajectory, &mut Cost::default())
        .unwrap();
    let plain = causal_by_definition(&tm, t.absorbed, &vec![1.0; n + 1]);
    let scaled: Vec<f64> = plain.iter().map(|x| x * w[n]).collect();
    assert_close(whole.as_slice(), &scaled);
    // At θ_new = θ_old both are the plain estimate.
    let same = p
        .weighted_estimate(&old, &old, &t, Weighting::PerDecision, &mut Cost::default())
        .unwrap();
    assert_close(same.as_slice(), &plain);
}

#[test]
fn the_obstacle_task_absorbs_at_zero_loss_after_success_and_at_the_supremum_after_a_crash() {
    let task = ObstacleTask::thesis().unwrap();
    let mut p = TaskProblem::fixed(
        task,
        LinearGaussian::new(2, obstacle::FEATURES, 0.02).unwrap(),
        200,
        AfterEnd::Absorb,
    )
    .unwrap();
    // The expert reaches the goal before the horizon: the remaining steps cost nothing.
    let mut rng = KitRng::seed_from_u64(1);
    let e = p
        .rollout(&Behaviour::Expert, &mut rng, &mut Cost::default())
        .unwrap();
    assert!(e.len() < 200);
    assert_eq!(e.absorbed, Some(0.0));
    // Heading straight for the goal (a proportional pull on φ's goal offset) ignores the
    // obstacle: over a few seeds some episodes crash, each charged (2·0.1)² per remaining step.
    let theta = DVector::from_fn(p.dim(), |i, _| if i == 0 || i == 10 { 0.05 } else { 0.0 });
    let mut crashed = 0;
    for seed in 0..40 {
        let t = learner_rollout(&mut p, &theta, seed);
        match t.absorbed {
            Some(0.0) => {}
            Some(x) => {
                crashed += 1;
                let expected = 0.04 * (200 - t.len()) as f64;
                assert_abs_diff_eq!(x, expected, epsilon = 1e-12);
            }
            None => assert_eq!(t.len(), 200),
        }
    }
    assert!(crashed > 0, "no crash in 40 episodes");
}

#[test]
fn a_task_without_an_absorbing_loss_cannot_absorb_and_a_horizon_needs_a_decision() {
    #[derive(Debug, Clone)]
    struct EndsAtOnce;
    impl Task<f64> for EndsAtOnce {
        type Episode = ();
        type Label = usize;
        type Action = usize;
        fn start(&self, _: &mut KitRng) -> Result<(), OracleError> {
            Ok(())
        }
        fn features(&self, _: &()) -> Vec<f64> {
            vec![1.0]
        }
        fn expert(&self, _: &()) -> Result<(usize, usize), OracleError> {
            Ok((0, 0))
        }
        fn advance(&self, _: &mut (), _: &usize) -> Result<bool, OracleError> {
            Ok(true)
        }
    }
    let policy = Softmax::new(2, 1).unwrap();
    let mut p = TaskProblem::fixed(EndsAtOnce, policy, 5, AfterEnd::Absorb).unwrap();
    let err = p
        .rollout(
            &Behaviour::Expert,
            &mut KitRng::seed_from_u64(0),
            &mut Cost::default(),
        )
        .unwrap_err();
    assert!(
        err.to_string().contains("defines no absorbing loss"),
        "{err}"
    );
    // With resets the same task gives 5 one-step episodes.
    let mut p = TaskProblem::fixed(EndsAtOnce, policy, 5, AfterEnd::Reset).unwrap();
    let t = p
        .rollout(
            &Behaviour::Expert,
            &mut KitRng::seed_from_u64(0),
            &mut Cost::default(),
        )
        .unwrap();
    assert_eq!((t.len(), t.resets), (5, 4));
    let err = TaskProblem::fixed(EndsAtOnce, policy, 0, AfterEnd::Reset).unwrap_err();
    assert!(err.to_string().contains("at least 1 decision"), "{err}");
    assert_eq!(p.horizon, Horizon::fixed(5, AfterEnd::Reset));
}
