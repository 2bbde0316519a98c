//! The f32 and `Dual<f64>` instances of every policy of `routes`. Their references are
//! enclosures (intervals, duals over intervals): with the `mpfr` feature for every policy,
//! without it for the quantities and policies that need no `exp` (the others then run every
//! route with the bit-for-bit checks only).

use super::*;

type DI = Dual<Interval>;
type References<'a, T> = Vec<Box<dyn Reference<T> + 'a>>;

/// The intervals' `exp`, where they have one (the `mpfr` feature).
fn interval_exp() -> Option<fn(&Interval) -> Interval> {
    #[cfg(feature = "mpfr")]
    return Some(<Interval as Real>::exp);
    #[cfg(not(feature = "mpfr"))]
    None
}

fn dual_interval_exp() -> Option<fn(&DI) -> DI> {
    #[cfg(feature = "mpfr")]
    return Some(<DI as Real>::exp);
    #[cfg(not(feature = "mpfr"))]
    None
}

/// The interval reference of the f32 instance (values).
fn enclosed_values<'a, T, PI, L, A>(
    pi: PI,
    label: fn(&T::Label) -> L,
    action: fn(&T::Action) -> A,
) -> Box<dyn Reference<T> + 'a>
where
    T: Task<f64> + 'a,
    PI: LikelihoodRatio<Interval, Action = A> + 'a,
    L: Borrow<PI::Label> + 'a,
    A: 'a,
{
    reference_in(
        pi,
        label,
        action,
        lift_theta::<Interval>,
        interval_exp(),
        interval_bounds,
    )
}

/// The interval reference of the dual instance (tangents).
fn enclosed_tangents<'a, T, PI, L, A>(
    pi: PI,
    label: fn(&T::Label) -> L,
    action: fn(&T::Action) -> A,
) -> Box<dyn Reference<T> + 'a>
where
    T: Task<f64> + 'a,
    PI: LikelihoodRatio<DI, Action = A> + 'a,
    L: Borrow<PI::Label> + 'a,
    A: 'a,
{
    reference_in(
        pi,
        label,
        action,
        dual_theta::<Interval>,
        dual_interval_exp(),
        |x| interval_bounds(&tangent(x)),
    )
}

/// The speed-limited policy with the f32 instance's limit (0.1 rounded to f32), so that
/// the f32 policy and its references limit at the same real number.
fn speed_limited_at_f32<S: ilopt::scalar::Sqrt>() -> SpeedLimitedGaussian<S, [S; 2]> {
    SpeedLimitedGaussian::new(gaussian_pair(), exact(to_f32(0.1))).unwrap()
}

fn mlp_gaussian<S: Scalar>() -> MlpGaussian<S> {
    MlpGaussian::new(obstacle::FEATURES, 4, 2, exact::<S>(SIGMA)).unwrap()
}

type Obstacle = ObstacleTask;
type ObstaclePair = ObstacleTask<[f64; 2]>;
type CartPole = CartPoleTask<f64>;

pub(super) fn linear_gaussian_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let thetas = obstacle_theta(obstacle::FEATURES);
    let li = lift_vec::<Interval, Vec<f64>>;
    let refs: References<Obstacle> = vec![enclosed_values(gaussian(), li, li)];
    let l32 = lift_vec::<f32, Vec<f64>>;
    let round = round_vec;
    check_f32(
        &mut p,
        gaussian(),
        &thetas,
        &round,
        &round,
        &l32,
        &l32,
        &refs,
        mode,
    )
}

pub(super) fn linear_gaussian_inline_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let thetas = obstacle_theta(obstacle::FEATURES);
    let li = lift_pair::<Interval>;
    let refs: References<ObstaclePair> = vec![enclosed_values(gaussian_pair(), li, li)];
    let (l32, round) = (lift_pair::<f32>, round_pair);
    let policy = gaussian_pair();
    check_f32(
        &mut p, policy, &thetas, &round, &round, &l32, &l32, &refs, mode,
    )
}

pub(super) fn speed_limited_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
    let thetas = obstacle_theta(obstacle::FEATURES);
    let li = lift_pair::<Interval>;
    let refs: References<ObstaclePair> = vec![enclosed_values(speed_limited_at_f32(), li, li)];
    let (l32, round) = (lift_pair::<f32>, round_pair);
    let policy = speed_limited_at_f32();
    check_f32(
        &mut p, policy, &thetas, &round, &round, &l32, &l32, &refs, mode,
    )
}

pub(super) fn logistic_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = Logistic::new(cartpole::FEATURES).unwrap();
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    let thetas = cartpole_theta(cartpole::FEATURES);
    #[cfg(feature = "mpfr")]
    let refs: References<CartPole> = vec![enclosed_values(policy, same, same)];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<CartPole> = vec![];
    check_f32(
        &mut p, policy, &thetas, &same, &same, &same, &same, &refs, mode,
    )
}

pub(super) fn softmax_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = Softmax::new(2, cartpole::FEATURES).unwrap();
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    let thetas = cartpole_theta(2 * cartpole::FEATURES);
    #[cfg(feature = "mpfr")]
    let refs: References<CartPole> = vec![enclosed_values(policy, same, same)];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<CartPole> = vec![];
    check_f32(
        &mut p, policy, &thetas, &same, &same, &same, &same, &refs, mode,
    )
}

pub(super) fn mlp_softmax_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
    let thetas = mlp_theta(policy.net());
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    #[cfg(feature = "mpfr")]
    let refs: References<CartPole> = vec![enclosed_values(policy, same, same)];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<CartPole> = vec![];
    check_f32(
        &mut p, policy, &thetas, &same, &same, &same, &same, &refs, mode,
    )
}

pub(super) fn mlp_gaussian_f32(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let (mut p, thetas) = mlp_gaussian_problem(horizon);
    #[cfg(feature = "mpfr")]
    let refs: References<Obstacle> = vec![enclosed_values(
        mlp_gaussian::<Interval>(),
        lift_vec::<Interval, Vec<f64>>,
        lift_vec::<Interval, Vec<f64>>,
    )];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<Obstacle> = vec![];
    let (l32, round) = (lift_vec::<f32, Vec<f64>>, round_vec);
    let policy = mlp_gaussian::<f32>();
    check_f32(
        &mut p, policy, &thetas, &round, &round, &l32, &l32, &refs, mode,
    )
}

pub(super) fn linear_gaussian_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<Vec<f64>>(), gaussian(), horizon);
    let thetas = obstacle_theta(obstacle::FEATURES);
    let li = lift_vec::<DI, Vec<f64>>;
    let refs: References<Obstacle> = vec![enclosed_tangents(gaussian(), li, li)];
    let ld = lift_vec::<Dual<f64>, Vec<f64>>;
    check_dual(&mut p, gaussian(), &thetas, &ld, &ld, &refs, mode)
}

pub(super) fn linear_gaussian_inline_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), gaussian_pair(), horizon);
    let thetas = obstacle_theta(obstacle::FEATURES);
    let li = lift_pair::<DI>;
    let refs: References<ObstaclePair> = vec![enclosed_tangents(gaussian_pair(), li, li)];
    let ld = lift_pair::<Dual<f64>>;
    check_dual(&mut p, gaussian_pair(), &thetas, &ld, &ld, &refs, mode)
}

pub(super) fn speed_limited_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let mut p = with_horizon(obstacle_task::<[f64; 2]>(), speed_limited(), horizon);
    let thetas = obstacle_theta(obstacle::FEATURES);
    let li = lift_pair::<DI>;
    let refs: References<ObstaclePair> = vec![enclosed_tangents(speed_limited(), li, li)];
    let ld = lift_pair::<Dual<f64>>;
    check_dual(&mut p, speed_limited(), &thetas, &ld, &ld, &refs, mode)
}

pub(super) fn logistic_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = Logistic::new(cartpole::FEATURES).unwrap();
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    let thetas = cartpole_theta(cartpole::FEATURES);
    #[cfg(feature = "mpfr")]
    let refs: References<CartPole> = vec![enclosed_tangents(policy, same, same)];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<CartPole> = vec![];
    check_dual(&mut p, policy, &thetas, &same, &same, &refs, mode)
}

pub(super) fn softmax_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = Softmax::new(2, cartpole::FEATURES).unwrap();
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    let thetas = cartpole_theta(2 * cartpole::FEATURES);
    #[cfg(feature = "mpfr")]
    let refs: References<CartPole> = vec![enclosed_tangents(policy, same, same)];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<CartPole> = vec![];
    check_dual(&mut p, policy, &thetas, &same, &same, &refs, mode)
}

pub(super) fn mlp_softmax_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let policy = MlpSoftmax::new(cartpole::FEATURES, 4, 2).unwrap();
    let thetas = mlp_theta(policy.net());
    let mut p = with_horizon(cartpole_task(), policy, horizon);
    #[cfg(feature = "mpfr")]
    let refs: References<CartPole> = vec![enclosed_tangents(policy, same, same)];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<CartPole> = vec![];
    check_dual(&mut p, policy, &thetas, &same, &same, &refs, mode)
}

pub(super) fn mlp_gaussian_dual(horizon: Option<AfterEnd>, mode: Mode) -> Tally {
    let (mut p, thetas) = mlp_gaussian_problem(horizon);
    #[cfg(feature = "mpfr")]
    let refs: References<Obstacle> = vec![enclosed_tangents(
        mlp_gaussian::<DI>(),
        lift_vec::<DI, Vec<f64>>,
        lift_vec::<DI, Vec<f64>>,
    )];
    #[cfg(not(feature = "mpfr"))]
    let refs: References<Obstacle> = vec![];
    let ld = lift_vec::<Dual<f64>, Vec<f64>>;
    check_dual(&mut p, mlp_gaussian(), &thetas, &ld, &ld, &refs, mode)
}
