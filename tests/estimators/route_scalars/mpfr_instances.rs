//! The interval instances of every policy at problem level (the `mpfr` feature).

use super::*;

pub(super) fn logistic_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = Logistic::new(cartpole::FEATURES).unwrap();
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    let thetas = cartpole_theta(cartpole::FEATURES);
    check_interval_problem(&mut p, policy, &thetas, &same, &same, None, mode)
}

pub(super) fn softmax_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = Softmax::new(2, cartpole::FEATURES).unwrap();
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    let thetas = cartpole_theta(2 * cartpole::FEATURES);
    check_interval_problem(&mut p, policy, &thetas, &same, &same, None, mode)
}

pub(super) fn mlp_softmax_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
    let thetas = mlp_theta(policy.net());
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    check_interval_problem(&mut p, policy, &thetas, &same, &same, None, mode)
}

pub(super) fn linear_gaussian_interval_problem(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let (lq, li) = (
        lift_vec::<BigRational, Vec<f64>>,
        lift_vec::<Interval, Vec<f64>>,
    );
    let pq = gaussian();
    let exact = exact_terms::<ObstacleTask, _, _, _>(&pq, &lq, &lq);
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_problem(&mut p, gaussian(), &thetas, &li, &li, Some(&exact), mode)
}

pub(super) fn linear_gaussian_inline_interval_problem(
    horizon: Option<AfterEnd>,
    mode: Mode,
) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let (lq, li) = (lift_pair::<BigRational>, lift_pair::<Interval>);
    let pq = gaussian_pair();
    let exact = exact_terms::<ObstacleTask<[f64; 2]>, _, _, _>(&pq, &lq, &lq);
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_problem(
        &mut p,
        gaussian_pair(),
        &thetas,
        &li,
        &li,
        Some(&exact),
        mode,
    )
}

pub(super) fn speed_limited_interval_problem(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
    let li = lift_pair::<Interval>;
    let thetas = obstacle_theta(obstacle::FEATURES);
    check_interval_problem(&mut p, speed_limited(), &thetas, &li, &li, None, mode)
}

/// The MLP-Gaussian policy with `routes`' weights (the linear pull through the tanh layer),
/// on fixed streams of [`LONG_STEPS`] decisions.
pub(super) fn mlp_gaussian_interval(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let (mut p, thetas) = mlp_gaussian_problem(horizon);
    let pi = MlpGaussian::new(obstacle::FEATURES, 4, 2, exact::<Interval>(SIGMA)).unwrap();
    let li = lift_vec::<Interval, Vec<f64>>;
    check_interval_problem(&mut p, pi, &thetas, &li, &li, None, mode)
}
