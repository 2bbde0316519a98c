//! The oracle's sample mean approaches ∇F at the 1/√N rate (the thesis's Fig. 4.2 claim, §4.1.3),
//! checked against the exact ∇F, the exact per-coordinate variance and the exact range of the
//! estimator (all from the exact engine, in rationals).
//!
//! 1. **Rigorous envelope.** Bernstein's inequality for i.i.d. X_i with |X_i − μ| ≤ b and variance
//!    σ²: P(|X̄_N − μ| ≥ ε) ≤ 2 exp(−Nε² / (2σ² + 2bε/3)). Solving for ε at α = 10⁻⁶ per
//!    coordinate and N gives ε_N ≈ σ √(2 ln(2/α) / N): the error must lie inside it.
//! 2. **The rate itself.** Over R = 200 independent seeded repetitions, N‖X̄_N − μ‖² has mean
//!    exactly Var_total = E‖g‖² − ‖∇F‖², so the ratio MSE_N / (Var_total/N) must be ≈ 1 for every
//!    N ∈ {10², 10³, 10⁴}. Its standard deviation is ≈ √(2/R) = 0.1 (normal approximation), so the
//!    window [0.6, 1.5] is 4 to 5 standard deviations wide: an approximate false-alarm probability
//!    below 10⁻⁴ per N. An estimator with a wrong mean fails (1) at large N; one with the right
//!    mean but the wrong variance scaling fails (2).

use crate::common::{example, q};
use ilopt::exact::enumerate::prefixes;
use ilopt::exact::forward::forward;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;
use rand::SeedableRng;

struct Exact {
    mean: Vec<f64>,
    var: Vec<f64>,
    range: Vec<f64>,
    var_total: f64,
}

fn exact(mdp: &ToyMdp, theta: &[BigRational]) -> Exact {
    let p = ToyProblem::<BigRational>::new(mdp);
    let grad = forward(&p, theta).unwrap().gradient;
    let pre = prefixes(&p, theta).unwrap();
    let d = grad.len();
    let mut var = vec![BigRational::zero(); d];
    let mut range = vec![BigRational::zero(); d];
    for x in &pre {
        for j in 0..d {
            let dev = x.estimate[j].clone() - &grad[j];
            var[j] += x.prob.clone() * &dev * &dev;
            let a = if dev < BigRational::zero() { -dev } else { dev };
            if a > range[j] {
                range[j] = a;
            }
        }
    }
    let var_total = var.iter().fold(BigRational::zero(), |a, b| a + b);
    Exact {
        mean: grad.iter().map(Scalar::to_f64).collect(),
        var: var.iter().map(Scalar::to_f64).collect(),
        range: range.iter().map(Scalar::to_f64).collect(),
        var_total: var_total.to_f64(),
    }
}

/// Mean of N oracle estimates at θ (f64, fresh trajectories from `rng`).
fn sample_mean(
    p: &mut ToyProblem<f64>,
    theta: &DVector<f64>,
    n: usize,
    rng: &mut KitRng,
) -> Vec<f64> {
    let mut cost = Cost::default();
    let mut acc = vec![0.0; theta.len()];
    for _ in 0..n {
        let tau = p
            .rollout(&Behaviour::Learner(theta), rng, &mut cost)
            .unwrap();
        let g = p
            .estimate(theta, &tau, EstimatorForm::Causal, &mut cost)
            .unwrap();
        for (a, x) in acc.iter_mut().zip(g.iter()) {
            *a += x;
        }
    }
    assert_eq!(cost.trajectories, n as u64);
    acc.iter().map(|a| a / n as f64).collect()
}

/// Bernstein radius ε with 2 exp(−Nε²/(2σ² + 2bε/3)) = α.
fn bernstein(n: f64, var: f64, b: f64, alpha: f64) -> f64 {
    let l = (2.0 / alpha).ln();
    let lin = 2.0 * b * l / 3.0;
    (lin + (lin * lin + 8.0 * n * l * var).sqrt()) / (2.0 * n)
}

fn check(name: &str, theta: &[&str], seed: u64) {
    let mdp = example(name);
    let th: Vec<BigRational> = theta.iter().map(|x| q(x)).collect();
    let ex = exact(&mdp, &th);
    let mut p = ToyProblem::<f64>::new(&mdp);
    let theta = DVector::from_iterator(th.len(), th.iter().map(Scalar::to_f64));
    let mut rng = KitRng::seed_from_u64(seed);
    for n in [100usize, 1_000, 10_000] {
        // (1) one run, rigorous envelope per coordinate.
        let m = sample_mean(&mut p, &theta, n, &mut rng);
        for (j, mj) in m.iter().enumerate() {
            let eps = bernstein(n as f64, ex.var[j], ex.range[j], 1e-6);
            let err = (mj - ex.mean[j]).abs();
            assert!(
                err <= eps,
                "{name} N={n} coord {j}: |error| {err} > Bernstein radius {eps}"
            );
        }
        // (2) the 1/N law of the mean squared error.
        let reps = 200;
        let mut mse = 0.0;
        for _ in 0..reps {
            let m = sample_mean(&mut p, &theta, n, &mut rng);
            mse += m
                .iter()
                .zip(&ex.mean)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>();
        }
        let ratio = (mse / reps as f64) / (ex.var_total / n as f64);
        eprintln!("{name} N={n}: MSE/(Var/N) = {ratio:.3}");
        assert!(
            (0.6..=1.5).contains(&ratio),
            "{name} N={n}: MSE/(Var/N) = {ratio}, expected ≈ 1"
        );
    }
}

#[test]
fn m1_sample_mean_converges_at_root_n() {
    check("m1-tied.json", &["0"], 1);
}

#[test]
fn three_state_sample_mean_converges_at_root_n_per_coordinate() {
    check(
        "three-state.json",
        &["1/2", "-1", "0.1", "3", "2/3", "-5/4"],
        2,
    );
}
