//! The policies, problems and θ of the instances, and the kernel-route instances in exact
//! rationals and intervals.

use super::*;

/// Two θ of `d` entries: `base` plus independent uniform noise of half-width `spread` (as
/// `routes`).
pub(super) fn two_thetas(d: usize, base: impl Fn(usize) -> f64, spread: f64) -> [DVector<f64>; 2] {
    let mut rng = KitRng::seed_from_u64(d as u64);
    let mut one = || {
        DVector::from_fn(d, |i, _| {
            base(i) + spread * (2.0 * rng.random::<f64>() - 1.0)
        })
    };
    [one(), one()]
}

/// A pull towards the goal (rows of `n` features), with noise.
pub(super) fn obstacle_theta(n: usize) -> [DVector<f64>; 2] {
    two_thetas(
        2 * n,
        |i| if i == 0 || i == n + 1 { 0.05 } else { 0.0 },
        0.01,
    )
}

pub(super) fn with_horizon<T, P>(
    task: T,
    policy: P,
    horizon: Option<AfterEnd>,
) -> TaskProblem<T, P> {
    match horizon {
        Some(after_end) => TaskProblem::fixed(task, policy, STEPS, after_end).unwrap(),
        None => TaskProblem::episodic(task, policy),
    }
}

/// The linear-Gaussian policy (P3) of the obstacle task in `S`, σ = [`SIGMA`].
pub(super) fn gaussian<S: Scalar>() -> LinearGaussian<S> {
    LinearGaussian::new(2, obstacle::FEATURES, exact(SIGMA)).unwrap()
}

/// The same with actions stored inline.
pub(super) fn gaussian_pair<S: Scalar>() -> LinearGaussian<S, [S; 2]> {
    gaussian().with_actions::<[S; 2]>().unwrap()
}

/// The obstacle task with the actions of `A`.
pub(super) fn obstacle_task<A: ActionVector<f64>>() -> ObstacleTask<A> {
    ObstacleTask::thesis().unwrap().with_actions::<A>()
}

pub(super) fn linear_gaussian_rational(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let lift = lift_vec::<BigRational, Vec<f64>>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_rational(&mut p, &gaussian(), &thetas, &lift, &lift, mode)
}

pub(super) fn linear_gaussian_inline_rational(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let lift = lift_pair::<BigRational>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_rational(&mut p, &gaussian_pair(), &thetas, &lift, &lift, mode)
}

pub(super) fn linear_gaussian_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let (lq, li) = (
        lift_vec::<BigRational, Vec<f64>>,
        lift_vec::<Interval, Vec<f64>>,
    );
    let pq = gaussian();
    let exact = exact_terms::<ObstacleTask, _, _, _>(&pq, &lq, &lq);
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_kernel(&mut p, &gaussian(), &thetas, &li, &li, Some(&exact), mode)
}

pub(super) fn linear_gaussian_inline_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let (lq, li) = (lift_pair::<BigRational>, lift_pair::<Interval>);
    let pq = gaussian_pair();
    let exact = exact_terms::<ObstacleTask<[f64; 2]>, _, _, _>(&pq, &lq, &lq);
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_kernel(
        &mut p,
        &gaussian_pair(),
        &thetas,
        &li,
        &li,
        Some(&exact),
        mode,
    )
}

/// The speed-limited linear-Gaussian policy, with a limit below the pull's speed at the start
/// so that both branches of the loss occur (as `routes`); its loss needs a square root, so it
/// has no rational reference.
pub(super) fn speed_limited<S: ilopt::scalar::Sqrt>() -> SpeedLimitedGaussian<S, [S; 2]> {
    SpeedLimitedGaussian::new(gaussian_pair(), exact(0.1)).unwrap()
}

pub(super) fn speed_limited_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
    let li = lift_pair::<Interval>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_kernel(&mut p, &speed_limited(), &thetas, &li, &li, None, mode)
}

/// The instances with the `mpfr` feature: every policy of `routes` over intervals.
pub(super) fn cartpole_task() -> CartPoleTask<f64> {
    CartPoleTask::with_lqr().unwrap()
}

pub(super) fn cartpole_theta(d: usize) -> [DVector<f64>; 2] {
    two_thetas(d, |_| 0.0, 2.0)
}

/// The network's initial weights, and the same scaled by 1.001 (as `routes`).
pub(super) fn mlp_theta(net: &Mlp) -> [DVector<f64>; 2] {
    let theta = DVector::from_vec(net.init::<f64>(&mut KitRng::seed_from_u64(5)));
    let near = theta.map(|x| 1.001 * x);
    [theta, near]
}

pub(super) fn same(x: &usize) -> usize {
    *x
}

/// The MLP-Gaussian policy's θ, as `routes`': the linear pull through the tanh layer.
pub(super) fn mlp_gaussian_theta(net: &Mlp, n: usize, h: usize) -> [DVector<f64>; 2] {
    mlp_theta(net).map(|theta| {
        let mut theta = theta.map(|x| 0.01 * x);
        theta[0] = 0.1;
        theta[n + 1] = 0.1;
        theta[h * n + h] = 0.5;
        theta[h * n + h + h + 1] = 0.5;
        theta
    })
}

/// The MLP-Gaussian problem, on fixed streams of [`LONG_STEPS`] decisions.
pub(super) fn mlp_gaussian_problem(
    horizon: Option<AfterEnd>,
) -> (
    TaskProblem<ObstacleTask, MlpGaussian<f64>>,
    [DVector<f64>; 2],
) {
    let (n, h) = (obstacle::FEATURES, 4);
    let policy = MlpGaussian::new(n, h, 2, SIGMA).unwrap();
    let thetas = mlp_gaussian_theta(policy.net(), n, h);
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), policy, horizon);
    if let Some(after_end) = horizon {
        p.horizon = Horizon::fixed(LONG_STEPS, after_end);
    }
    (p, thetas)
}
