//! Fig. 4.2's routes and statistics against independent computations.

use super::*;
use crate::stats::derive_seed;
use ilopt::exact::backward::backward;
use ilopt::exact::enumerate::gradient_by_duals;
use ilopt::exact::enumerate::moments;
use ilopt::exact::evaluation::{EvaluationOptions, evaluate};
use ilopt::problem::KitRng;
use ilopt::scalar::BigRational;
use ilopt::toy::ToyProblem;
use nalgebra::DVector;
use rand::SeedableRng;

fn toy_section(ns: Vec<u64>, repetitions: u32) -> GradientError {
    GradientError {
        repetitions,
        bootstrap: 400,
        toy: ToyRoute {
            mdp: "examples/toy/three-state.json".into(),
            theta: ["1/2", "-1", "1", "1/3", "-1/2", "2"]
                .map(String::from)
                .to_vec(),
            ns,
        },
        obstacle: ObstacleRoute {
            sigma: 0.1,
            theta: vec![0.0; 18],
            horizon: 200,
            reference_trajectories: 100_000,
            ns: vec![1, 10, 100, 1000],
        },
    }
}

/// The toy route's reference (forward DP, X2) equals ∇F by dual numbers over the enumeration
/// (no score formula) and by the backward DP, exactly; its σ² equals the enumeration's
/// Var = E‖g‖² − ‖E g‖² (E g = ∇F: the oracle is unbiased).
#[test]
fn toy_reference_is_the_exact_gradient_by_independent_routes() {
    let g = toy_section(vec![1, 2, 4], 2);
    assert_eq!(g.validate(), Ok(()));
    let (mdp, grad, m2, sigma2) = toy_exact(&g.toy).unwrap();
    let p = ToyProblem::<BigRational>::new(&mdp);
    let theta = parse_exact_list(&g.toy.theta.join(",")).unwrap();
    let (_, by_duals) = gradient_by_duals(&p, &theta).unwrap();
    let (_, by_backward) = backward(&p, &theta).unwrap();
    assert_eq!(grad, by_duals);
    assert_eq!(grad, by_backward);
    let mom = moments(&p, &theta).unwrap();
    assert_eq!(mom.expected_estimate, grad);
    assert_eq!(mom.second_moment, m2);
    assert_eq!(mom.variance, sigma2);
    assert!(sigma2 > <BigRational as Scalar>::zero());
    assert!(grad.iter().any(|x| *x != <BigRational as Scalar>::zero()));
    // The library route of `ilopt toy eval` gives the same gradient.
    let evaluation = evaluate::<BigRational>(&mdp, &theta, &EvaluationOptions::default()).unwrap();
    assert_eq!(evaluation.gradient, grad);
}

fn toy_sampler(g: &GradientError) -> (ToyProblem<f64>, DVector<f64>, Vec<f64>, f64) {
    let (mdp, grad, _, sigma2) = toy_exact(&g.toy).unwrap();
    let theta = parse_exact_list(&g.toy.theta.join(",")).unwrap();
    (
        ToyProblem::<f64>::new(&mdp),
        DVector::from_vec(theta.iter().map(<f64 as Scalar>::from_rational).collect()),
        grad.iter().map(Scalar::to_f64).collect(),
        sigma2.to_f64(),
    )
}

/// At N = 1 the MSE is E‖g − ∇F‖² = σ²: the RMSE's interval holds σ; and the slope's interval
/// contains −1/2 and excludes 0.
#[test]
fn unbiased_oracle_rmse_starts_at_sigma_and_decays_at_the_inverse_square_root() {
    let g = toy_section(vec![1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024], 200);
    let r = toy_route(&g).unwrap();
    let s = r.sigma2.sqrt();
    let p = r.rmse[0];
    assert!(p.raw_lo <= s && s <= p.raw_hi, "{p:?} vs σ = {s}");
    assert!((p.line - s).abs() < 1e-12);
    assert!(r.slope.hi < 0.0, "{:?}", r.slope);
    assert!(r.slope.consistent_with_inverse_sqrt(), "{:?}", r.slope);
    assert_eq!(r.slope.n, 200);
}

/// A biased oracle (a constant added to every estimate) flattens the RMSE at ‖b‖: the slope
/// test rejects it — the claim can fail.
#[test]
fn biased_oracle_is_caught_by_the_slope_test() {
    let g = toy_section(vec![1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024], 200);
    let (p, theta, reference, sigma2) = toy_sampler(&g);
    let d = reference.len();
    // ‖b‖ = σ/10: the error flattens from N ≈ 100 on.
    let b = DVector::from_element(d, (sigma2 / 100.0 / d as f64).sqrt());
    let key = "biased";
    let blocks = [(0, d)];
    let sq = repetition_errors(&g.toy.ns, 200, key, &blocks, &reference, || {
        let (mut p, theta, b) = (p.clone(), &theta, &b);
        move |rng: &mut KitRng| toy_draw(&mut p, theta, rng).map(|x| x + b)
    })
    .unwrap();
    let (pts, slope) = summarise(&g.toy.ns, &sq, sigma2, 0.0, 400, key);
    assert!(!slope.consistent_with_inverse_sqrt(), "{slope:?}");
    assert!(slope.lo > -0.5, "{slope:?}");
    let last = pts.last().unwrap();
    assert!(last.raw_lo > 2.0 * last.line, "{last:?}");
    // The same streams without the bias pass.
    let sq = repetition_errors(&g.toy.ns, 200, key, &blocks, &reference, || {
        let (mut p, theta) = (p.clone(), &theta);
        move |rng: &mut KitRng| toy_draw(&mut p, theta, rng)
    })
    .unwrap();
    let (_, slope) = summarise(&g.toy.ns, &sq, sigma2, 0.0, 400, key);
    assert!(slope.consistent_with_inverse_sqrt(), "{slope:?}");
}

/// Repetitions and reference chunks do not depend on the thread count; the chunked moments
/// equal the direct two-pass ones.
#[test]
fn streams_and_reference_are_thread_count_independent() {
    let g = toy_section(vec![1, 3, 9], 6);
    let (mut p, theta, reference, _) = toy_sampler(&g);
    let d = reference.len();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let sq =
                repetition_errors(&g.toy.ns, 6, "t", &[(0, 2), (2, d - 2)], &reference, || {
                    let (mut p, theta) = (p.clone(), &theta);
                    move |rng: &mut KitRng| toy_draw(&mut p, theta, rng)
                })
                .unwrap();
            let m = reference_moments(1000, d, 64, "r", || {
                let (mut p, theta) = (p.clone(), &theta);
                move |rng: &mut KitRng| toy_draw(&mut p, theta, rng)
            })
            .unwrap();
            (sq, m.mean, m.m2)
        })
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a, b);
    // Direct moments of the same 1000 draws (chunk c draws from seed derive_seed("r", c)).
    let mut draws = Vec::new();
    for c in 0..1000u64.div_ceil(64) {
        let mut rng = KitRng::seed_from_u64(derive_seed("r", c));
        for _ in 0..64.min(1000 - 64 * c) {
            draws.push(toy_draw(&mut p, &theta, &mut rng).unwrap());
        }
    }
    let mean = draws.iter().fold(DVector::zeros(d), |s, x| s + x) / 1000.0;
    let m2 = draws.iter().fold(DVector::zeros(d), |s, x| {
        let e: DVector<f64> = x - &mean;
        s + e.component_mul(&e)
    });
    assert!((&a.1 - &mean).norm() < 1e-12 * (1.0 + a.1.norm()));
    assert!((&a.2 - &m2).norm() < 1e-9 * (1.0 + m2.norm()));
}

/// The exact spread of one squared error equals its f64 value by enumerating the prefixes
/// directly.
#[test]
fn exact_spread_of_one_squared_error() {
    let g = toy_section(vec![1, 2, 4], 2);
    let (mdp, grad, _, sigma2) = toy_exact(&g.toy).unwrap();
    let sd = squared_error_sd(&mdp, &g.toy, &grad, &sigma2).unwrap();
    let (p, theta, reference, s2) = toy_sampler(&g);
    let (mut m2, mut m4) = (0.0, 0.0);
    for q in ilopt::exact::enumerate::prefixes(&p, theta.as_slice()).unwrap() {
        let e: f64 = q
            .estimate
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).powi(2))
            .sum();
        m2 += q.prob * e;
        m4 += q.prob * e * e;
    }
    assert!((m2 - s2).abs() < 1e-9 * s2);
    assert!((sd - (m4 - m2 * m2).sqrt()).abs() < 1e-9 * sd);
}

#[test]
fn the_slope_rule_on_synthetic_intervals() {
    let s = |lo, hi| SlopeCi {
        estimate: (lo + hi) / 2.0,
        lo,
        hi,
        n: 100,
    };
    assert!(s(-0.55, -0.45).consistent_with_inverse_sqrt());
    assert!(!s(-0.45, -0.35).consistent_with_inverse_sqrt());
    assert!(!s(-0.6, 0.1).consistent_with_inverse_sqrt());
    assert!(!s(-0.7, -0.55).consistent_with_inverse_sqrt());
}

#[test]
fn slope_of_a_power_law() {
    let x = [1.0, 10.0, 100.0];
    let y = x.map(|v: f64| 3.0 * v.powf(-0.5));
    assert!((loglog_slope(&x, &y) + 0.5).abs() < 1e-12);
}
