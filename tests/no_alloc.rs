//! No heap allocation per step in the hot loops of a roll-out and of the oracle.
//!
//! A counting global allocator counts, per thread, every `alloc`/`alloc_zeroed`/`realloc`. The
//! definition checked here: **the number of allocations of a roll-out or an estimate does not
//! depend on the number of steps** — a call allocates its result storage once (reserved from the
//! task's time limit for a roll-out; the returned vector and one scratch buffer for an estimate)
//! and the per-step loop allocates nothing, so an episode of 500 steps costs as many allocations
//! as one of 10. The per-step primitives (features, expert, sampling, environment step, loss and
//! score) are also checked directly: zero allocations over many steps. CartPole is checked with
//! both the logistic and the softmax policy.

use ilopt::oracle::EstimatorKernel;
use ilopt::policy::{
    LikelihoodRatio, LinearGaussian, Logistic, Policy, PolicyExt, Softmax, SpeedLimitedGaussian,
};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleFeatures, ObstacleTask};
use ilopt::task::{Task, TaskProblem};
use nalgebra::DVector;
use rand::SeedableRng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

/// A roll-out's buffers, each allocated once per call: features, actions, labels, and for a
/// policy that notes per decision ([`EstimatorKernel::sample_noting`]) the notes and their θ.
const ROLLOUT_BUFFERS: u64 = 5;

fn bump() {
    // `try_with`: the allocator may run while the thread-local is being torn down.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread, and its result.
fn count<R>(f: impl FnOnce() -> R) -> (u64, R) {
    let before = ALLOCATIONS.with(Cell::get);
    let r = f();
    (ALLOCATIONS.with(Cell::get) - before, r)
}

#[test]
fn the_counter_counts() {
    let (n, v) = count(|| vec![1u8; 10]);
    assert_eq!(n, 1, "one Vec, one allocation");
    let (n, _) = count(|| {
        let mut w = Vec::new();
        for i in 0..100u32 {
            w.push(i);
        }
        w
    });
    assert!(n >= 5, "a growing Vec reallocates: {n}");
    let (n, _) = count(|| v.len());
    assert_eq!(n, 0);
}

fn cartpole() -> TaskProblem<CartPoleTask<f64>, Logistic> {
    TaskProblem {
        task: CartPoleTask::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

/// θ for which the logistic policy balances the pole for a while (about the LQR gain).
fn balancing() -> DVector<f64> {
    DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1])
}

/// The CartPole task with the two-action softmax policy.
fn cartpole_softmax() -> TaskProblem<CartPoleTask<f64>, Softmax> {
    TaskProblem {
        task: CartPoleTask::with_lqr().unwrap(),
        policy: Softmax::new(2, cartpole::FEATURES).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

/// The softmax policy with rows `(−θ/2, θ/2)`: `π(1|s) = σ(θ·φ)`, the logistic policy θ.
fn as_softmax(theta: &DVector<f64>) -> DVector<f64> {
    let half: Vec<f64> = theta.iter().map(|x| x / 2.0).collect();
    DVector::from_vec(
        half.iter()
            .map(|x| -x)
            .chain(half.iter().copied())
            .collect(),
    )
}

/// 10 000 CartPole steps of the per-step primitives (features, expert, sampling, loss and score,
/// likelihood ratio, environment step) with policy `P`: zero allocations.
fn cartpole_step_primitives<P>(p: &TaskProblem<CartPoleTask<f64>, P>, theta: &DVector<f64>)
where
    P: LikelihoodRatio<f64, Action = usize, Label = usize> + EstimatorKernel<f64>,
{
    let th = theta.as_slice();
    let other: Vec<f64> = th.iter().map(|x| 0.5 * x).collect();
    let d = p.policy.param_dim();
    let mut rng = KitRng::seed_from_u64(7);
    let mut features = Vec::with_capacity(5 * 10_000);
    let mut grad = vec![0.0; d];
    let mut score = vec![0.0; d];
    let mut ep = p.task.start(&mut rng).unwrap();
    let mut steps = 0;
    let (n, ()) = count(|| {
        while steps < 10_000 {
            let start = features.len();
            p.task.push_features(&ep, &mut features);
            let phi = &features[start..];
            let (label, _) = p.task.expert(&ep).unwrap();
            let a = p.policy.sample(th, phi, &mut rng).unwrap();
            p.policy
                .loss_score_into(th, phi, &label, &a, &mut grad, &mut score)
                .unwrap();
            p.policy.loss_into(th, phi, &label, &mut grad).unwrap();
            p.policy.score_into(th, phi, &a, &mut score).unwrap();
            p.policy.log_likelihood_ratio(th, &other, phi, &a).unwrap();
            steps += 1;
            if p.task.advance(&mut ep, &a).unwrap() {
                ep = p.task.start(&mut rng).unwrap();
            }
        }
    });
    assert_eq!(n, 0, "allocations over {steps} CartPole steps");
}

#[test]
fn cartpole_step_primitives_allocate_nothing() {
    cartpole_step_primitives(&cartpole(), &balancing());
    cartpole_step_primitives(&cartpole_softmax(), &as_softmax(&balancing()));
}

/// The allocating `PolicyExt::loss` and `PolicyExt::score` of the softmax policy (each allocates
/// its result) are seen by the counter (so the softmax cases above and below could fail).
#[test]
fn softmax_loss_and_score_allocate() {
    let p = cartpole_softmax();
    let theta = as_softmax(&balancing());
    let phi = [0.01, -0.02, 0.03, 0.0, 1.0];
    let (n, _) = count(|| p.policy.loss(theta.as_slice(), &phi, &1).unwrap());
    assert!(n >= 1, "{n}");
    let (n, _) = count(|| p.policy.score(theta.as_slice(), &phi, &1).unwrap());
    assert!(n >= 1, "{n}");
}

/// Roll-outs and estimates of many lengths with policy `P`: the allocation count of each call is
/// one constant.
fn cartpole_per_call<P>(p: &mut TaskProblem<CartPoleTask<f64>, P>, thetas: &[DVector<f64>; 3])
where
    P: LikelihoodRatio<f64, Action = usize, Label = usize> + EstimatorKernel<f64>,
{
    let mut rng = KitRng::seed_from_u64(11);
    let mut cost = Cost::default();
    let mut lengths = std::collections::BTreeSet::new();
    let (mut rollout_counts, mut estimate_counts, mut weighted_counts, mut full_counts) =
        (vec![], vec![], vec![], vec![]);
    for _ in 0..30 {
        for theta in thetas {
            let (n, t) = count(|| {
                p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                    .unwrap()
            });
            rollout_counts.push(n);
            lengths.insert(t.len());
            let (n, _) = count(|| {
                p.estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                    .unwrap()
            });
            estimate_counts.push(n);
            let (n, _) = count(|| {
                p.estimate(theta, &t, EstimatorForm::Full, &mut cost)
                    .unwrap()
            });
            full_counts.push(n);
            let (n, _) = count(|| {
                p.weighted_estimate(&thetas[1], theta, &t, Weighting::PerDecision, &mut cost)
                    .unwrap()
            });
            weighted_counts.push(n);
        }
    }
    assert!(
        lengths.len() >= 10 && lengths.first() < Some(&50) && lengths.last() == Some(&500),
        "episode lengths should vary widely: {lengths:?}"
    );
    for (what, counts, max) in [
        // Features, actions and labels; with a policy that notes per decision (the softmax),
        // its notes and their θ.
        ("roll-out", &rollout_counts, ROLLOUT_BUFFERS),
        ("causal estimate", &estimate_counts, 2),
        ("full estimate", &full_counts, 2),
        ("per-decision weighted estimate", &weighted_counts, 2),
    ] {
        assert!(
            counts.iter().all(|&n| n == counts[0] && n <= max),
            "{what}: allocations per call {counts:?} (must be one constant ≤ {max})"
        );
    }
}

/// Roll-outs and estimates of many lengths: the allocation count of each call is one constant.
#[test]
fn cartpole_rollout_and_oracle_allocate_per_call_not_per_step() {
    let thetas = [
        balancing(),
        DVector::from_vec(vec![0.0, 0.2, 1.0, 0.1, 0.0]),
        DVector::from_vec(vec![0.0, 0.0, 0.0, 0.0, 0.0]),
    ];
    cartpole_per_call(&mut cartpole(), &thetas);
    cartpole_per_call(&mut cartpole_softmax(), &thetas.map(|t| as_softmax(&t)));
}

/// The obstacle task with inline actions and labels (`[f64; 2]`; the default `Vec<f64>` allocates
/// one vector per stored action and label).
fn obstacle_inline() -> TaskProblem<ObstacleTask<[f64; 2]>, LinearGaussian<f64, [f64; 2]>> {
    TaskProblem {
        task: ObstacleTask::thesis().unwrap().with_actions(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.02)
            .unwrap()
            .with_actions()
            .unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

/// W with a proportional pull towards the goal.
fn pull() -> DVector<f64> {
    pull_n(obstacle::FEATURES)
}

#[test]
fn obstacle_step_primitives_allocate_nothing() {
    let p = obstacle_inline();
    let theta = pull();
    let th = theta.as_slice();
    let mut rng = KitRng::seed_from_u64(7);
    let mut features = Vec::with_capacity(obstacle::FEATURES * 5_000);
    let mut grad = vec![0.0; 2 * obstacle::FEATURES];
    let mut score = vec![0.0; 2 * obstacle::FEATURES];
    let mut ep = p.task.start(&mut rng).unwrap();
    let mut steps = 0;
    let mut episodes = 0;
    let (n, ()) = count(|| {
        while steps < 5_000 {
            let start = features.len();
            p.task.push_features(&ep, &mut features);
            let phi = &features[start..];
            let (label, _) = p.task.expert(&ep).unwrap();
            let a = p.policy.sample(th, phi, &mut rng).unwrap();
            p.policy
                .loss_score_into(th, phi, &label, &a, &mut grad, &mut score)
                .unwrap();
            steps += 1;
            if p.task.advance(&mut ep, &a).unwrap() {
                episodes += 1;
                // `start` clones the environment (no heap data).
                ep = p.task.start(&mut rng).unwrap();
            }
        }
    });
    assert!(episodes > 10, "{episodes} episodes");
    assert_eq!(n, 0, "allocations over {steps} obstacle steps");
}

/// The appendix's obstacle learner: RBF features and the loss of the executed velocity.
fn obstacle_rbf() -> TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>> {
    let task = ObstacleTask::thesis()
        .unwrap()
        .with_features(ObstacleFeatures::rbf_default())
        .unwrap()
        .with_actions();
    let inner = LinearGaussian::new(2, task.feature_dim(), 0.02)
        .unwrap()
        .with_actions()
        .unwrap();
    TaskProblem {
        task,
        policy: SpeedLimitedGaussian::new(inner, 0.1).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    }
}

/// W (`n` features per row) with a proportional pull towards the goal.
fn pull_n(n: usize) -> DVector<f64> {
    let mut w = DVector::zeros(2 * n);
    w[0] = 0.05;
    w[n + 1] = 0.05;
    w
}

/// Roll-outs, causal and per-decision-weighted estimates: allocation counts equal for every
/// episode length and at most 3 (roll-out) / 2 (estimate).
fn obstacle_per_call<P>(p: &mut TaskProblem<ObstacleTask<[f64; 2]>, P>, n: usize)
where
    P: LikelihoodRatio<f64, Action = [f64; 2], Label = [f64]> + EstimatorKernel<f64>,
{
    let mut rng = KitRng::seed_from_u64(5);
    let mut cost = Cost::default();
    let thetas = [pull_n(n), DVector::zeros(2 * n)];
    let mut lengths = std::collections::BTreeSet::new();
    let (mut rollouts, mut estimates) = (vec![], vec![]);
    for _ in 0..20 {
        for theta in &thetas {
            let (n, t) = count(|| {
                p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                    .unwrap()
            });
            rollouts.push(n);
            lengths.insert(t.len());
            let (n, _) = count(|| {
                p.estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                    .unwrap()
            });
            estimates.push(n);
            let (n, _) = count(|| {
                p.weighted_estimate(&thetas[1], theta, &t, Weighting::PerDecision, &mut cost)
                    .unwrap()
            });
            estimates.push(n);
        }
    }
    assert!(lengths.len() >= 5, "episode lengths {lengths:?}");
    assert!(
        rollouts
            .iter()
            .all(|&n| n == rollouts[0] && n <= ROLLOUT_BUFFERS),
        "{rollouts:?}"
    );
    assert!(
        estimates.iter().all(|&n| n == estimates[0] && n <= 2),
        "{estimates:?}"
    );
}

#[test]
fn obstacle_rollout_and_oracle_allocate_per_call_not_per_step() {
    obstacle_per_call(&mut obstacle_inline(), obstacle::FEATURES);
}

#[test]
fn rbf_speed_limited_obstacle_allocates_per_call_not_per_step() {
    let mut p = obstacle_rbf();
    let n = p.task.feature_dim();
    obstacle_per_call(&mut p, n);
}

/// The default `Vec<f64>` actions do allocate per step: the counter sees it (so the tests above
/// could fail).
#[test]
fn vec_actions_allocate_per_step() {
    let mut p = TaskProblem {
        task: ObstacleTask::thesis().unwrap(),
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.02).unwrap(),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let mut rng = KitRng::seed_from_u64(5);
    let (n, t) = count(|| {
        p.rollout(&Behaviour::Learner(&pull()), &mut rng, &mut Cost::default())
            .unwrap()
    });
    assert!(
        n as usize >= 2 * t.len(),
        "{n} allocations for {} steps",
        t.len()
    );
}

/// The baselined oracle (`ilopt::baseline`): once its reused buffers have seen the longest
/// trajectory, every estimate allocates one constant number of times whatever the episodes'
/// lengths (its per-decision terms, or for leave-one-out the recorded losses-to-go and scores,
/// are written into those buffers, never per step).
#[test]
fn baselined_estimates_allocate_per_call_not_per_step() {
    use ilopt::algo::ConfigNumber;
    use ilopt::baseline::{Baseline, Baselined};
    let thetas = [
        balancing(),
        DVector::from_vec(vec![0.0, 0.2, 1.0, 0.1, 0.0]),
        DVector::from_vec(vec![0.0, 0.0, 0.0, 0.0, 0.0]),
    ];
    for (m, kind) in [
        (
            1,
            Baseline::Constant {
                value: ConfigNumber::ratio(1, 2),
            },
        ),
        (
            2,
            Baseline::Estimated {
                time_indexed: true,
                decay: None,
            },
        ),
        (2, Baseline::LeaveOneOut),
        (3, Baseline::LeaveOneOut),
        (
            2,
            Baseline::StateDependent {
                features: None,
                time: true,
                decay: Some(ConfigNumber::ratio(99, 100)),
                ridge: None,
                fit_every: Some(1),
            },
        ),
        (
            2,
            Baseline::StateDependent {
                features: None,
                time: true,
                decay: Some(ConfigNumber::ratio(99, 100)),
                ridge: None,
                fit_every: None,
            },
        ),
    ] {
        let mut p = Baselined::<_, f64>::new(cartpole(), m, &kind).unwrap();
        let mut rng = KitRng::seed_from_u64(5);
        let mut cost = Cost::default();
        let mut batches = vec![];
        let mut rollout_counts = vec![];
        for _ in 0..20 {
            for theta in &thetas {
                let (n, b) = count(|| {
                    p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                        .unwrap()
                });
                rollout_counts.push(n);
                batches.push((theta.clone(), b));
            }
        }
        let lengths: std::collections::BTreeSet<usize> = batches
            .iter()
            .flat_map(|(_, b)| b.iter().map(|t| t.len()))
            .collect();
        assert!(
            lengths.len() >= 10 && lengths.last() == Some(&500),
            "{kind:?}: episode lengths should vary widely: {lengths:?}"
        );
        // Warm-up: the longest trajectory in every place of a batch sizes the reused buffers.
        let (theta, longest) = batches
            .iter()
            .flat_map(|(theta, b)| b.iter().map(move |t| (theta, t)))
            .max_by_key(|(_, t)| t.len())
            .unwrap();
        let warm = vec![longest.clone(); m];
        p.estimate(theta, &warm, EstimatorForm::Causal, &mut cost)
            .unwrap();
        p.weighted_estimate(&thetas[1], theta, &warm, Weighting::PerDecision, &mut cost)
            .unwrap();
        let (mut estimate_counts, mut weighted_counts) = (vec![], vec![]);
        for (theta, b) in &batches {
            let (n, _) = count(|| {
                p.estimate(theta, b, EstimatorForm::Causal, &mut cost)
                    .unwrap()
            });
            estimate_counts.push(n);
            let (n, _) = count(|| {
                p.weighted_estimate(&thetas[1], theta, b, Weighting::PerDecision, &mut cost)
                    .unwrap()
            });
            weighted_counts.push(n);
        }
        // Per call, never per step: every baseline records the decisions into kept buffers, so
        // each call allocates only its result.
        let fast = 1;
        // The weighted estimate: every kind's terms go into kept buffers, then per trajectory
        // its estimate, then the mean.
        let weighted = m as u64 + 2;
        for (what, counts, max) in [
            ("baselined estimate", &estimate_counts, fast),
            ("baselined weighted estimate", &weighted_counts, weighted),
        ] {
            assert!(
                counts.iter().all(|&n| n == counts[0] && n <= max),
                "{kind:?}, {what}: allocations per call {counts:?} (must be one constant ≤ {max})"
            );
        }
        if m == 1 {
            assert!(
                rollout_counts.iter().all(|&n| n == rollout_counts[0]),
                "{kind:?}: roll-out allocations {rollout_counts:?}"
            );
        }
        if let Baseline::Estimated { .. } = kind {
            // Each roll-out commits the statistics of the estimate before it: once the sums have
            // seen the longest trajectory, a commit allocates nothing, whatever the lengths — the
            // roll-out allocates what the same roll-out without a baseline does.
            let mut plain = Baselined::<_, f64>::new(cartpole(), m, &Baseline::None).unwrap();
            p.estimate(theta, &warm, EstimatorForm::Causal, &mut cost)
                .unwrap();
            p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .unwrap();
            let mut commit_counts = vec![];
            for (theta, b) in &batches {
                p.estimate(theta, b, EstimatorForm::Causal, &mut cost)
                    .unwrap();
                let mut same = rng.clone();
                let (with_commit, _) = count(|| {
                    p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                        .unwrap()
                });
                let (without, _) = count(|| {
                    plain
                        .rollout(&Behaviour::Learner(theta), &mut same, &mut cost)
                        .unwrap()
                });
                commit_counts.push((with_commit, without));
            }
            assert!(
                commit_counts.iter().all(|&(a, b)| a == b),
                "{kind:?}: roll-out allocations with the estimated baselines, without: \
                 {commit_counts:?}"
            );
        }
    }
}

/// The fixed-horizon objective (streams of T decisions): roll-outs with resets after a crash, and
/// with an absorbing end, allocate a constant per call whatever the number of resets or the
/// decision at which the stream absorbed; so do the causal, full and weighted estimates on them.
fn fixed_per_call<T, P>(
    p: &mut TaskProblem<T, P>,
    thetas: &[DVector<f64>],
    seed: u64,
) -> (usize, usize)
where
    T: ilopt::task::Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: std::borrow::Borrow<P::Label>,
{
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    let (mut shapes, mut rollouts, mut estimates) =
        (std::collections::BTreeSet::new(), Vec::new(), Vec::new());
    for _ in 0..20 {
        for theta in thetas {
            let (n, t) = count(|| {
                p.rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                    .unwrap()
            });
            rollouts.push(n);
            shapes.insert((t.len(), t.resets, t.absorbed.is_some()));
            // Grouped by estimator and by whether the stream absorbed (an absorbed trajectory
            // takes the estimator's general pass, with its scratch buffer).
            let absorbed = t.absorbed.is_some();
            for (k, form) in [EstimatorForm::Causal, EstimatorForm::Full]
                .into_iter()
                .enumerate()
            {
                let (n, _) = count(|| p.estimate(theta, &t, form, &mut cost).unwrap());
                estimates.push(((k, absorbed), n));
            }
            let (n, _) = count(|| {
                p.weighted_estimate(&thetas[0], theta, &t, Weighting::PerDecision, &mut cost)
                    .unwrap()
            });
            estimates.push(((2, absorbed), n));
        }
    }
    assert!(
        rollouts
            .iter()
            .all(|&n| n == rollouts[0] && n <= ROLLOUT_BUFFERS),
        "roll-outs: {rollouts:?}"
    );
    for &(group, n) in &estimates {
        assert!(
            n <= 2 && estimates.iter().all(|&(g, m)| g != group || m == n),
            "estimates (estimator, absorbed) → allocations: {estimates:?}"
        );
    }
    let lengths = shapes
        .iter()
        .map(|s| s.0)
        .collect::<std::collections::BTreeSet<_>>();
    let resets = shapes
        .iter()
        .map(|s| s.1)
        .collect::<std::collections::BTreeSet<_>>();
    (lengths.len(), resets.len())
}

#[test]
fn fixed_horizon_reset_allocates_per_call_not_per_step() {
    use ilopt::task::AfterEnd;
    let thetas = [
        DVector::from_vec(vec![0.0, 0.2, 1.0, 0.1, 0.0]),
        balancing(),
        DVector::zeros(5),
    ];
    let mut p =
        TaskProblem::fixed(cartpole().task, cartpole().policy, 500, AfterEnd::Reset).unwrap();
    let (lengths, resets) = fixed_per_call(&mut p, &thetas, 11);
    assert_eq!(lengths, 1, "every stream has 500 decisions");
    assert!(resets >= 5, "{resets} different reset counts");
    let s = cartpole_softmax();
    let mut p = TaskProblem::fixed(s.task, s.policy, 500, AfterEnd::Reset).unwrap();
    let (_, resets) = fixed_per_call(&mut p, &thetas.clone().map(|t| as_softmax(&t)), 12);
    assert!(resets >= 5, "{resets} different reset counts");
    // The experiments' CartPole: the PPO expert labels every state (its network evaluated
    // without storing the hidden layer).
    let ppo = CartPoleTask::<f64>::with_ppo(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json"),
    )
    .unwrap();
    let mut p = TaskProblem::fixed(ppo, Softmax::new(2, 5).unwrap(), 500, AfterEnd::Reset).unwrap();
    let (_, resets) = fixed_per_call(&mut p, &thetas.map(|t| as_softmax(&t)), 15);
    assert!(resets >= 5, "{resets} different reset counts");
}

#[test]
fn fixed_horizon_absorb_allocates_per_call_not_per_step() {
    use ilopt::task::AfterEnd;
    let c = cartpole();
    let mut p = TaskProblem::fixed(c.task, c.policy, 500, AfterEnd::Absorb).unwrap();
    let thetas = [
        DVector::from_vec(vec![0.0, 0.2, 1.0, 0.1, 0.0]),
        balancing(),
        DVector::zeros(5),
    ];
    let (lengths, _) = fixed_per_call(&mut p, &thetas, 13);
    assert!(lengths >= 10, "{lengths} different decision counts");
    let o = obstacle_rbf();
    let n = o.task.feature_dim();
    let mut p = TaskProblem::fixed(o.task, o.policy, 200, AfterEnd::Absorb).unwrap();
    let (lengths, _) = fixed_per_call(&mut p, &[DVector::zeros(2 * n), pull_n(n)], 14);
    assert!(lengths >= 5, "{lengths} different decision counts");
}
