//! The feature policies of `ilopt::policy`: every analytic gradient against
//! forward-mode dual derivatives of the *value* code (an independent route):
//!
//! * linear-Gaussian (P3): loss and score exactly, with `Dual<BigRational>` (the score is the
//!   derivative of the exact log-density ratio);
//! * softmax, logistic, MLP heads: with `Dual<f64>` under the documented tolerance
//!   [`ilopt::tolerance::derivative_f64_agrees`];
//! * with the `mpfr` feature: `Dual<Interval>` against the interval analytic gradient, the two
//!   enclosures must intersect (tolerance-free);
//!
//! plus sampling (one seed, one path in every scalar; empirical frequencies), numerical safety at
//! extreme logits, and constructor/argument validation.

use crate::common;
use approx::{abs_diff_eq, assert_abs_diff_eq};

use ilopt::policy::{
    LikelihoodRatio, LinearGaussian, Logistic, Mlp, MlpGaussian, MlpSoftmax, Policy, PolicyError,
    PolicyExt, Softmax, from_f64_exact, logistic_sigmoid, softmax_probs, softplus, tanh,
};
use ilopt::problem::KitRng;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::tolerance::{derivative_f64_agrees, derivative_f64_error};
use proptest::prelude::*;
use rand::SeedableRng;

type Q = BigRational;

/// A proptest configuration with a fixed seed, so every run explores the same cases (a failure is
/// reproducible from the source alone; the seed can be varied by editing it).
fn seeded(cases: u32, seed: u64) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: proptest::test_runner::RngSeed::Fixed(seed),
        ..ProptestConfig::default()
    }
}

fn rational() -> impl Strategy<Value = Q> {
    (-12i64..=12, 1i64..=5).prop_map(|(n, d)| Q::new(n.into(), d.into()))
}

/// Quarter-integers in [−3, 3]: exact in f64.
fn quarter() -> impl Strategy<Value = f64> {
    (-12i32..=12).prop_map(|k| f64::from(k) / 4.0)
}

fn consts<S: Scalar>(xs: &[S]) -> Vec<Dual<S>> {
    xs.iter().cloned().map(Dual::constant).collect()
}

// ---------------------------------------------------------------------------------------------
// Linear-Gaussian: exact.

/// (m, n, W, φ, π*, a, σ).
type GaussianCase = (usize, usize, Vec<Q>, Vec<Q>, Vec<Q>, Vec<Q>, Q);

fn gaussian_case() -> impl Strategy<Value = GaussianCase> {
    (1usize..=3, 1usize..=3).prop_flat_map(|(m, n)| {
        (
            Just(m),
            Just(n),
            prop::collection::vec(rational(), m * n),
            prop::collection::vec(rational(), n),
            prop::collection::vec(rational(), m),
            prop::collection::vec(rational(), m),
            (1i64..=6, 1i64..=6).prop_map(|(a, b)| Q::new(a.into(), b.into())),
        )
    })
}

proptest! {
    #![proptest_config(seeded(128, 0x9e37_0001))]

    /// ∇_W l = 2(Wφ − π*)φᵀ and ∇_W log π = (a − Wφ)φᵀ/σ² (math.md §1.3, P3) equal the exact dual
    /// derivatives of l and of the log-density ratio log π_W − log π_{W'} (W' fixed).
    #[test]
    fn linear_gaussian_gradients_are_exact((m, n, w, phi, target, action, sigma) in gaussian_case()) {
        let d = m * n;
        let pol = LinearGaussian::new(m, n, sigma.clone()).unwrap();
        let (l, dl) = pol.loss(&w, &phi, &target).unwrap();
        let psi = pol.score(&w, &phi, &action).unwrap();

        let pol_d = LinearGaussian::new(m, n, Dual::constant(sigma)).unwrap();
        let wd = Dual::variables(&w);
        let (ld, _) = pol_d.loss(&wd, &consts(&phi), &consts(&target)).unwrap();
        prop_assert_eq!(ld.value(), &l);
        prop_assert_eq!(ld.gradient_padded(d), dl);

        let other = consts(&vec![Q::from_ratio(1, 3); d]);
        let ratio = pol_d.log_ratio(&wd, &other, &consts(&phi), &consts(&action)).unwrap();
        prop_assert_eq!(ratio.gradient_padded(d), psi);
    }
}

/// A hand-computed instance: m = 1, n = 2, W = (1, −2), φ = (3, 1/2), π* = 1/2, a = 2, σ = 1/2.
/// Wφ = 2, l = (3/2)² = 9/4, ∇l = 2·(3/2)·φ = (9, 3/2), ψ = (2 − 2)φ/σ² = 0; with a = 3: ψ = 4φ.
#[test]
fn linear_gaussian_hand_values() {
    let qs = common::qs;
    let pol = LinearGaussian::new(1, 2, common::q("1/2")).unwrap();
    let (w, phi) = (qs(&["1", "-2"]), qs(&["3", "1/2"]));
    let (l, dl) = pol.loss(&w, &phi, &qs(&["1/2"])).unwrap();
    assert_eq!(l, common::q("9/4"));
    assert_eq!(dl, qs(&["9", "3/2"]));
    assert_eq!(pol.score(&w, &phi, &qs(&["2"])).unwrap(), qs(&["0", "0"]));
    assert_eq!(pol.score(&w, &phi, &qs(&["3"])).unwrap(), qs(&["12", "2"]));
    // log π_W(a) − log π_W'(a) with W' = 0: (‖a‖² − ‖a − 2‖²)/(2σ²) = (9 − 1)·2 = 16 at a = 3.
    let r = pol
        .log_ratio(&w, &qs(&["0", "0"]), &phi, &qs(&["3"]))
        .unwrap();
    assert_eq!(r, common::q("16"));
}

/// The unnormalised log-density differentiates to the score, and differences of it are the exact
/// log-ratio (f64, within the derivative tolerance).
#[test]
fn linear_gaussian_log_density_is_consistent() {
    let pol = LinearGaussian::new(2, 2, 0.75).unwrap();
    let (w, phi, a) = (vec![0.5, -1.0, 0.25, 2.0], vec![1.5, -0.5], vec![0.1, -0.3]);
    let pol_d = LinearGaussian::new(2, 2, Dual::constant(0.75)).unwrap();
    let lp = pol_d
        .log_prob_unnormalised(&Dual::variables(&w), &consts(&phi), &consts(&a))
        .unwrap();
    let psi = pol.score(&w, &phi, &a).unwrap();
    assert!(derivative_f64_agrees(&lp.gradient_padded(4), &psi));
    let w2 = vec![0.0, 1.0, -0.5, 0.5];
    let diff = pol.log_prob_unnormalised(&w, &phi, &a).unwrap()
        - pol.log_prob_unnormalised(&w2, &phi, &a).unwrap();
    let ratio = pol.log_ratio(&w, &w2, &phi, &a).unwrap();
    assert!(derivative_f64_agrees(&[diff], &[ratio]));
    let wr = pol.density_ratio(&w, &w2, &phi, &a).unwrap();
    assert_abs_diff_eq!(wr.ln(), ratio, epsilon = 1e-12 * (1.0 + ratio.abs()));
}

// ---------------------------------------------------------------------------------------------
// Softmax, logistic, MLP: Dual<f64> under the documented tolerance.

/// Check `policy`'s analytic ∇l and score against `Dual<f64>` derivatives of the loss value and of
/// log π (given by `log_prob`), returning the largest scaled error.
fn check_discrete<P, L>(
    policy: &P,
    theta: &[f64],
    phi: &[f64],
    label: usize,
    log_prob: L,
) -> Result<f64, String>
where
    P: Policy<f64, Action = usize, Label = usize>
        + Policy<Dual<f64>, Action = usize, Label = usize>,
    L: Fn(&[Dual<f64>], &[Dual<f64>], usize) -> Dual<f64>,
{
    let d = theta.len();
    let (_, dl) = PolicyExt::<f64>::loss(policy, theta, phi, &label).map_err(|e| e.to_string())?;
    let td = Dual::variables(theta);
    let (ld, _) = PolicyExt::<Dual<f64>>::loss(policy, &td, &consts(phi), &label)
        .map_err(|e| e.to_string())?;
    let mut worst = derivative_f64_error(&ld.gradient_padded(d), &dl);
    if !derivative_f64_agrees(&ld.gradient_padded(d), &dl) {
        return Err(format!("∇l: dual {:?} vs analytic {dl:?}", ld.gradient()));
    }
    for a in [0, 1] {
        let psi = PolicyExt::<f64>::score(policy, theta, phi, &a).map_err(|e| e.to_string())?;
        let lp = log_prob(&td, &consts(phi), a);
        let dual = lp.gradient_padded(d);
        worst = worst.max(derivative_f64_error(&dual, &psi));
        if !derivative_f64_agrees(&dual, &psi) {
            return Err(format!("score a={a}: dual {dual:?} vs analytic {psi:?}"));
        }
    }
    Ok(worst)
}

/// (A, n, Θ, φ, expert action).
type SoftmaxCase = (usize, usize, Vec<f64>, Vec<f64>, usize);

fn softmax_case() -> impl Strategy<Value = SoftmaxCase> {
    (2usize..=4, 1usize..=4).prop_flat_map(|(a, n)| {
        (
            Just(a),
            Just(n),
            prop::collection::vec(quarter(), a * n),
            prop::collection::vec(quarter(), n),
            0..a,
        )
    })
}

/// (n, h, k, θ, φ, expert action).
type MlpCase = (usize, usize, usize, Vec<f64>, Vec<f64>, usize);

fn mlp_case() -> impl Strategy<Value = MlpCase> {
    (1usize..=3, 1usize..=4, 2usize..=3).prop_flat_map(|(n, h, k)| {
        let d = Mlp::new(n, h, k).unwrap().param_dim();
        (
            Just(n),
            Just(h),
            Just(k),
            prop::collection::vec(quarter(), d),
            prop::collection::vec(quarter(), n),
            0..k,
        )
    })
}

proptest! {
    #![proptest_config(seeded(128, 0x9e37_0002))]

    /// Softmax: ∇l = (∂l/∂z)φᵀ (Brier, math.md §1.2) and score (e_a − π)φᵀ vs Dual<f64>.
    #[test]
    fn softmax_gradients_match_duals((a, n, theta, phi, label) in softmax_case()) {
        let pol = Softmax::new(a, n).unwrap();
        let r = check_discrete(&pol, &theta, &phi, label, |t, p, act| pol.log_prob(t, p, act).unwrap());
        prop_assert!(r.is_ok(), "{:?}", r);
    }

    /// Logistic: ∇l = 4(p − y)p(1 − p)φ and score (a − p)φ vs Dual<f64>; and it is the two-action
    /// softmax with logits (0, θ·φ).
    #[test]
    fn logistic_gradients_match_duals(
        (theta, phi, label) in (1usize..=4).prop_flat_map(|n| (
            prop::collection::vec(quarter(), n), prop::collection::vec(quarter(), n), 0usize..2))
    ) {
        let n = theta.len();
        let pol = Logistic::new(n).unwrap();
        let r = check_discrete(&pol, &theta, &phi, label, |t, p, act| pol.log_prob(t, p, act).unwrap());
        prop_assert!(r.is_ok(), "{:?}", r);
        let sm = Softmax::new(2, n).unwrap();
        let mut big = vec![0.0; n];
        big.extend_from_slice(&theta);
        let (l1, _) = PolicyExt::<f64>::loss(&pol, &theta, &phi, &label).unwrap();
        let (l2, _) = PolicyExt::<f64>::loss(&sm, &big, &phi, &label).unwrap();
        prop_assert!(derivative_f64_agrees(&[l1], &[l2]));
    }

    /// MLP softmax head: back-propagated ∇l and score vs Dual<f64> through the forward pass.
    #[test]
    fn mlp_softmax_gradients_match_duals((n, h, k, theta, phi, label) in mlp_case()) {
        let pol = MlpSoftmax::new(n, h, k).unwrap();
        let r = check_discrete(&pol, &theta, &phi, label, |t, p, act| pol.log_prob(t, p, act).unwrap());
        prop_assert!(r.is_ok(), "{:?}", r);
    }

    /// MLP Gaussian head: ∇l (from 2(o − π*)) and score (from (a − o)/σ²) vs Dual<f64> derivatives
    /// of the loss value and of the unnormalised log-density.
    #[test]
    fn mlp_gaussian_gradients_match_duals(
        (n, h, k, theta, phi, _l) in mlp_case(),
        target in prop::collection::vec(quarter(), 3),
        action in prop::collection::vec(quarter(), 3),
    ) {
        let (target, action) = (&target[..k], &action[..k]);
        let d = theta.len();
        let pol = MlpGaussian::new(n, h, k, 0.5).unwrap();
        let pol_d = MlpGaussian::new(n, h, k, Dual::constant(0.5)).unwrap();
        let td = Dual::variables(&theta);
        let (_, dl) = pol.loss(&theta, &phi, target).unwrap();
        let (ld, _) = pol_d.loss(&td, &consts(&phi), &consts(target)).unwrap();
        prop_assert!(derivative_f64_agrees(&ld.gradient_padded(d), &dl), "{:?} vs {:?}", ld.gradient(), dl);
        let psi = pol.score(&theta, &phi, &action.to_vec()).unwrap();
        let lp = pol_d.log_prob_unnormalised(&td, &consts(&phi), &consts(action)).unwrap();
        prop_assert!(derivative_f64_agrees(&lp.gradient_padded(d), &psi));
    }
}

/// Measure the largest scaled disagreement over many seeded random points, so the report can
/// state how much of the tolerance is used (printed with `--nocapture`).
#[test]
fn derivative_tolerance_is_not_tight() {
    use rand::Rng;
    let mut rng = KitRng::seed_from_u64(5);
    let mut worst: f64 = 0.0;
    for _ in 0..300 {
        let (n, h, k) = (
            rng.random_range(1..=4),
            rng.random_range(1..=6),
            rng.random_range(2..=4),
        );
        let pol = MlpSoftmax::new(n, h, k).unwrap();
        let theta: Vec<f64> = (0..pol.net().param_dim())
            .map(|_| rng.random_range(-3.0..3.0))
            .collect();
        let phi: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
        let label = rng.random_range(0..k);
        let e = check_discrete(&pol, &theta, &phi, label, |t, p, a| {
            pol.log_prob(t, p, a).unwrap()
        })
        .unwrap();
        worst = worst.max(e);
        let sm = Softmax::new(k, n).unwrap();
        let th: Vec<f64> = (0..k * n).map(|_| rng.random_range(-4.0..4.0)).collect();
        let e = check_discrete(&sm, &th, &phi, label, |t, p, a| {
            sm.log_prob(t, p, a).unwrap()
        })
        .unwrap();
        worst = worst.max(e);
    }
    eprintln!(
        "largest scaled Dual<f64> vs analytic discrepancy: {worst:e} (= 2^{:.1})",
        worst.log2()
    );
    // The tolerance leaves at least a factor 2⁸ of room over what is observed.
    assert!(
        worst * 256.0 <= ilopt::tolerance::DERIVATIVE_F64_REL,
        "{worst:e}"
    );
}

/// The analytic gradients are not trivially equal to the duals because both are zero: a wrong
/// formula (the score without the `−π` term) is caught by the same tolerance.
#[test]
fn the_derivative_check_catches_a_wrong_formula() {
    let pol = Softmax::new(3, 2).unwrap();
    let (theta, phi) = (vec![0.5, -1.0, 0.25, 1.0, -0.75, 0.0], vec![1.0, 2.0]);
    let td = Dual::variables(&theta);
    let lp = pol.log_prob(&td, &consts(&phi), 1).unwrap();
    let mut wrong = vec![0.0; 6];
    wrong[2] = phi[0];
    wrong[3] = phi[1];
    assert!(!derivative_f64_agrees(&lp.gradient_padded(6), &wrong));
    let right = pol.score(&theta, &phi, &1).unwrap();
    assert!(derivative_f64_agrees(&lp.gradient_padded(6), &right));
}

/// The likelihood ratios of importance weighting (math.md §4) reweight π_θ' into π_θ:
/// `Σ_a π_θ'(a|s) exp(log π_θ(a|s) − log π_θ'(a|s)) = Σ_a π_θ(a|s)`, action by action.
#[test]
fn likelihood_ratios_reweight_one_policy_into_another() {
    let phi = vec![0.5, -1.25];
    let sm = Softmax::new(3, 2).unwrap();
    let (t, t2) = (
        vec![0.5, -1.0, 0.25, 1.0, -0.75, 0.0],
        vec![0.0, 1.0, -0.5, 0.5, 2.0, -1.0],
    );
    let (p, p2) = (sm.probs(&t, &phi).unwrap(), sm.probs(&t2, &phi).unwrap());
    for a in 0..3 {
        let r: f64 = sm.log_likelihood_ratio(&t, &t2, &phi, &a).unwrap();
        assert!(
            derivative_f64_agrees(&[p2[a] * r.exp()], &[p[a]]),
            "softmax a={a}"
        );
    }
    let lg = Logistic::new(2).unwrap();
    let (u, u2) = (vec![0.75, -0.5], vec![-1.0, 0.25]);
    let (q1, q2) = (
        lg.prob_one(&u, &phi).unwrap(),
        lg.prob_one(&u2, &phi).unwrap(),
    );
    let r1: f64 = lg.log_likelihood_ratio(&u, &u2, &phi, &1).unwrap();
    let r0: f64 = lg.log_likelihood_ratio(&u, &u2, &phi, &0).unwrap();
    assert!(derivative_f64_agrees(
        &[q2 * r1.exp(), (1.0 - q2) * r0.exp()],
        &[q1, 1.0 - q1]
    ));
    let ms = MlpSoftmax::new(2, 3, 2).unwrap();
    let v: Vec<f64> = ms.net().init(&mut KitRng::seed_from_u64(4));
    let v2: Vec<f64> = ms.net().init(&mut KitRng::seed_from_u64(5));
    let (m1, m2) = (ms.probs(&v, &phi).unwrap(), ms.probs(&v2, &phi).unwrap());
    for a in 0..2 {
        let r: f64 = ms.log_likelihood_ratio(&v, &v2, &phi, &a).unwrap();
        assert!(
            derivative_f64_agrees(&[m2[a] * r.exp()], &[m1[a]]),
            "mlp a={a}"
        );
    }
    // P3: exact in rationals.
    let g = LinearGaussian::new(1, 2, common::q("1/2")).unwrap();
    let (w, w2, x, a) = (
        common::qs(&["1", "2"]),
        common::qs(&["0", "-1"]),
        common::qs(&["1/2", "1"]),
        vec![common::q("3")],
    );
    // ‖a − W'φ‖² = (3 + 1)² = 16, ‖a − Wφ‖² = (3 − 5/2)² = 1/4, /(2σ²) = ·2.
    assert_eq!(
        g.log_likelihood_ratio(&w, &w2, &x, &a).unwrap(),
        common::q("63/2")
    );
}

// ---------------------------------------------------------------------------------------------
// Numerical safety, sampling, validation.

#[test]
fn extreme_logits_stay_finite() {
    let p = softmax_probs(&[1000.0, 0.0, -1000.0]).unwrap();
    assert_eq!(p, vec![1.0, 0.0, 0.0]);
    let p = softmax_probs(&[-800.0, -800.0]).unwrap();
    assert_eq!(p, vec![0.5, 0.5]);
    assert_eq!(tanh(&800.0).unwrap(), 1.0);
    assert_eq!(tanh(&-800.0).unwrap(), -1.0);
    assert_eq!(logistic_sigmoid(&-800.0).unwrap(), 0.0);
    assert_eq!(logistic_sigmoid(&800.0).unwrap(), 1.0);
    assert_eq!(softplus(&800.0).unwrap(), 800.0);
    assert!(softplus(&-800.0).unwrap() >= 0.0);
    let pol = Logistic::new(1).unwrap();
    let lp = pol.log_prob(&[1.0], &[-700.0], 1).unwrap();
    assert_eq!(lp, -700.0, "log σ(−700) = −700 − ln(1 + e⁻⁷⁰⁰)");
    // tanh agrees with std's in the moderate range.
    for x in [-3.0, -0.5, 0.0, 1e-3, 0.7, 5.0] {
        assert_abs_diff_eq!(
            tanh(&x).unwrap(),
            f64::tanh(x),
            epsilon = 4.0 * f64::EPSILON
        );
    }
    assert!(matches!(
        softmax_probs(&[f64::NAN, 0.0]),
        Err(PolicyError::NonFinite { .. })
    ));
    assert!(matches!(
        tanh(&f64::INFINITY),
        Err(PolicyError::NonFinite { .. })
    ));
}

#[test]
fn f64_draws_convert_exactly() {
    let x = 0.1f64;
    let q: Q = from_f64_exact(x, "x").unwrap();
    assert_eq!(q, BigRational::from_float(0.1).unwrap());
    assert_ne!(q, common::q("1/10"), "0.1 as a double is not 1/10");
    let i: Interval = from_f64_exact(x, "x").unwrap();
    assert!(i.is_singleton() && i.inf() == x);
    assert_eq!(from_f64_exact::<f64>(x, "x").unwrap(), x);
    assert!(matches!(
        from_f64_exact::<Q>(f64::NAN, "draw"),
        Err(PolicyError::NonFinite { param: "draw" })
    ));
}

/// One seed, one path: the linear-Gaussian policy sampled in f64, in intervals and in rationals
/// from one seed gives one action (the f64 action lies in the enclosure and is the rounding of the
/// exact one).
#[test]
fn gaussian_sampling_follows_one_path_in_every_scalar() {
    let (w, phi) = (vec![0.5, -0.25, 1.0, 2.0], vec![0.75, -1.5]);
    let pf = LinearGaussian::new(2, 2, 0.5).unwrap();
    let pq = LinearGaussian::new(2, 2, common::q("1/2")).unwrap();
    let pi = LinearGaussian::new(2, 2, Interval::from_ratio(1, 2)).unwrap();
    let (mut rf, mut rq, mut ri) = (
        KitRng::seed_from_u64(3),
        KitRng::seed_from_u64(3),
        KitRng::seed_from_u64(3),
    );
    let cq = |x: &f64| BigRational::from_float(*x).unwrap();
    let wq: Vec<Q> = w.iter().map(cq).collect();
    let phiq: Vec<Q> = phi.iter().map(cq).collect();
    let wi: Vec<Interval> = wq.iter().map(Interval::from_rational).collect();
    let phii: Vec<Interval> = phiq.iter().map(Interval::from_rational).collect();
    for _ in 0..20 {
        let af = pf.sample(&w, &phi, &mut rf).unwrap();
        let aq = pq.sample(&wq, &phiq, &mut rq).unwrap();
        let ai = pi.sample(&wi, &phii, &mut ri).unwrap();
        for j in 0..2 {
            assert!(ai[j].contains(af[j]));
            assert!(ilopt::scalar::interval_contains_rational(ai[j], &aq[j]));
            assert_abs_diff_eq!(
                aq[j].to_f64(),
                af[j],
                epsilon = 4.0 * f64::EPSILON * (1.0 + af[j].abs())
            );
        }
    }
}

/// Softmax sampling frequencies match π (each count within 5 binomial standard deviations; a false
/// alarm has probability < 3·10⁻⁶ per category by the normal approximation to the binomial).
#[test]
fn softmax_sampling_frequencies_match_probabilities() {
    let pol = Softmax::new(3, 2).unwrap();
    let (theta, phi) = (vec![0.5, -1.0, 0.25, 1.0, -0.75, 0.0], vec![1.0, 0.5]);
    let p = pol.probs(&theta, &phi).unwrap();
    let mut rng = KitRng::seed_from_u64(11);
    let n = 20_000;
    let mut counts = [0usize; 3];
    for _ in 0..n {
        counts[pol.sample(&theta, &phi, &mut rng).unwrap()] += 1;
    }
    for a in 0..3 {
        let mean = n as f64 * p[a];
        let sd = (n as f64 * p[a] * (1.0 - p[a])).sqrt();
        assert!(
            abs_diff_eq!(counts[a] as f64, mean, epsilon = 5.0 * sd),
            "{counts:?} vs {p:?}"
        );
    }
}

#[test]
fn mlp_initialisation_is_seeded_and_scalar_independent() {
    let net = Mlp::new(4, 8, 2).unwrap();
    let a: Vec<f64> = net.init(&mut KitRng::seed_from_u64(1));
    let b: Vec<f64> = net.init(&mut KitRng::seed_from_u64(1));
    let c: Vec<f64> = net.init(&mut KitRng::seed_from_u64(2));
    let q: Vec<Q> = net.init(&mut KitRng::seed_from_u64(1));
    assert_eq!(a.len(), net.param_dim());
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert!(
        a.iter()
            .zip(&q)
            .all(|(x, y)| BigRational::from_float(*x).as_ref() == Some(y))
    );
    let r1 = (6.0f64 / 12.0).sqrt();
    assert!(a[..32].iter().all(|x| x.abs() <= r1) && a[..32].iter().any(|x| *x != 0.0));
    assert!(
        a[32..40].iter().all(|x| *x == 0.0),
        "hidden biases start at 0"
    );
}

#[test]
fn invalid_arguments_are_rejected_with_the_parameter_named() {
    assert_eq!(
        LinearGaussian::new(1, 1, 0.0).unwrap_err(),
        PolicyError::NotPositive {
            param: "sigma",
            value: 0.0
        }
    );
    assert_eq!(
        LinearGaussian::new(1, 1, f64::NAN).unwrap_err(),
        PolicyError::NonFinite { param: "sigma" }
    );
    assert!(matches!(
        LinearGaussian::new(1, 1, Interval::try_from((-1.0, 1.0)).unwrap()),
        Err(PolicyError::NotPositive { param: "sigma", .. })
    ));
    assert_eq!(
        LinearGaussian::new(0, 1, 1.0).unwrap_err(),
        PolicyError::TooSmall {
            param: "actions",
            min: 1,
            got: 0
        }
    );
    assert_eq!(
        Softmax::new(1, 3).unwrap_err(),
        PolicyError::TooSmall {
            param: "actions",
            min: 2,
            got: 1
        }
    );
    assert!(matches!(
        Mlp::new(2, 0, 2),
        Err(PolicyError::TooSmall {
            param: "hidden",
            ..
        })
    ));
    assert!(matches!(
        MlpGaussian::new(2, 2, 1, -1.0),
        Err(PolicyError::NotPositive { param: "sigma", .. })
    ));
    let pol = LinearGaussian::new(2, 3, 1.0).unwrap();
    let err = pol.loss(&[0.0; 5], &[0.0; 3], &[0.0; 2]).unwrap_err();
    assert_eq!(
        err,
        PolicyError::Shape {
            param: "theta",
            expected: 6,
            got: 5
        }
    );
    assert!(err.to_string().contains("`theta`"));
    assert_eq!(
        pol.loss(&[0.0; 6], &[0.0, f64::NAN, 0.0], &[0.0; 2])
            .unwrap_err(),
        PolicyError::NonFinite { param: "phi" }
    );
    assert_eq!(
        pol.score(&[0.0; 6], &[0.0; 3], &vec![0.0; 3]).unwrap_err(),
        PolicyError::Shape {
            param: "action",
            expected: 2,
            got: 3
        }
    );
    let sm = Softmax::new(2, 1).unwrap();
    assert_eq!(
        PolicyExt::<f64>::score(&sm, &[0.0, 0.0], &[1.0], &2).unwrap_err(),
        PolicyError::Action {
            action: 2,
            actions: 2
        }
    );
    assert!(matches!(
        PolicyExt::<f64>::loss(&sm, &[f64::INFINITY, 0.0], &[1.0], &0),
        Err(PolicyError::NonFinite { param: "theta" })
    ));
    // Overflowing logits from finite inputs are reported, not turned into NaN.
    assert!(matches!(
        PolicyExt::<f64>::loss(&sm, &[1e300, 0.0], &[1e300], &0),
        Err(PolicyError::NonFinite { .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Intervals (feature `mpfr`): Dual<Interval> vs the interval analytic gradient, tolerance-free.

#[cfg(feature = "mpfr")]
mod intervals {
    use super::*;

    fn iv(xs: &[f64]) -> Vec<Interval> {
        xs.iter()
            .map(|x| from_f64_exact(*x, "x").unwrap())
            .collect()
    }

    /// Both enclosures intersect (they contain the same real number), and both are narrow, so
    /// that the intersection test has teeth: width ≤ 2⁻²⁰·(1 + |midpoint|).
    fn intersect(a: &[Interval], b: &[Interval]) -> bool {
        let narrow = |x: &Interval| x.wid() <= (1.0 + x.mid().abs()) / f64::from(1u32 << 20);
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| !x.disjoint(*y) && narrow(x) && narrow(y))
    }

    fn check<P>(
        policy: &P,
        theta: &[f64],
        phi: &[f64],
        label: usize,
        lp: impl Fn(&[Dual<Interval>], &[Dual<Interval>], usize) -> Dual<Interval>,
    ) -> Result<(), String>
    where
        P: Policy<Interval, Action = usize, Label = usize>
            + Policy<Dual<Interval>, Action = usize, Label = usize>,
    {
        let d = theta.len();
        let (t, p) = (iv(theta), iv(phi));
        let (_, dl) =
            PolicyExt::<Interval>::loss(policy, &t, &p, &label).map_err(|e| e.to_string())?;
        let td = Dual::variables(&t);
        let (ld, _) = PolicyExt::<Dual<Interval>>::loss(policy, &td, &consts(&p), &label)
            .map_err(|e| e.to_string())?;
        if !intersect(&ld.gradient_padded(d), &dl) {
            return Err(format!("∇l: {:?} vs {dl:?}", ld.gradient()));
        }
        for a in [0, 1] {
            let psi =
                PolicyExt::<Interval>::score(policy, &t, &p, &a).map_err(|e| e.to_string())?;
            if !intersect(&lp(&td, &consts(&p), a).gradient_padded(d), &psi) {
                return Err(format!("score a={a}"));
            }
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(seeded(64, 0x9e37_0003))]

        #[test]
        fn softmax_interval_enclosures_intersect((a, n, theta, phi, label) in softmax_case()) {
            let pol = Softmax::new(a, n).unwrap();
            let r = check(&pol, &theta, &phi, label, |t, p, act| pol.log_prob(t, p, act).unwrap());
            prop_assert!(r.is_ok(), "{:?}", r);
        }

        #[test]
        fn logistic_interval_enclosures_intersect(
            (theta, phi, label) in (1usize..=4).prop_flat_map(|n| (
                prop::collection::vec(quarter(), n), prop::collection::vec(quarter(), n), 0usize..2))
        ) {
            let pol = Logistic::new(theta.len()).unwrap();
            let r = check(&pol, &theta, &phi, label, |t, p, act| pol.log_prob(t, p, act).unwrap());
            prop_assert!(r.is_ok(), "{:?}", r);
        }

        #[test]
        fn mlp_interval_enclosures_intersect((n, h, k, theta, phi, label) in mlp_case()) {
            let pol = MlpSoftmax::new(n, h, k).unwrap();
            let r = check(&pol, &theta, &phi, label, |t, p, act| pol.log_prob(t, p, act).unwrap());
            prop_assert!(r.is_ok(), "{:?}", r);
        }

        #[test]
        fn mlp_gaussian_interval_enclosures_intersect(
            (n, h, k, theta, phi, _l) in mlp_case(),
            target in prop::collection::vec(quarter(), 3),
        ) {
            let d = theta.len();
            let (t, p, y) = (iv(&theta), iv(&phi), iv(&target[..k]));
            let pol = MlpGaussian::new(n, h, k, Interval::from_ratio(1, 2)).unwrap();
            let pol_d = MlpGaussian::new(n, h, k, Dual::constant(Interval::from_ratio(1, 2))).unwrap();
            let (_, dl) = pol.loss(&t, &p, &y).unwrap();
            let (ld, _) = pol_d.loss(&Dual::variables(&t), &consts(&p), &consts(&y)).unwrap();
            prop_assert!(intersect(&ld.gradient_padded(d), &dl));
            // The f64 analytic gradient also lies near the enclosure (a smoke check of the f64 path).
            let pf = MlpGaussian::new(n, h, k, 0.5).unwrap();
            let (_, df) = pf.loss(&theta, &phi, &target[..k]).unwrap();
            prop_assert!(df.iter().zip(&dl).all(|(x, i)| i.inf() - 1e-9 <= *x && *x <= i.sup() + 1e-9));
        }
    }

    /// The intersection test rejects a wrong formula (the score without its `−π` term).
    #[test]
    fn a_wrong_formula_is_disjoint() {
        let pol = Softmax::new(3, 2).unwrap();
        let (t, p) = (iv(&[0.5, -1.0, 0.25, 1.0, -0.75, 0.0]), iv(&[1.0, 2.0]));
        let lp = pol.log_prob(&Dual::variables(&t), &consts(&p), 1).unwrap();
        let mut wrong = vec![Interval::zero(); 6];
        wrong[2] = p[0];
        wrong[3] = p[1];
        assert!(!intersect(&lp.gradient_padded(6), &wrong));
        let right = PolicyExt::<Interval>::score(&pol, &t, &p, &1).unwrap();
        assert!(intersect(&lp.gradient_padded(6), &right));
    }

    /// One seed, one path with intervals: softmax sampling in f64 and in intervals picks the same
    /// actions (the interval comparisons stay decidable at these parameters).
    #[test]
    fn softmax_sampling_follows_one_path() {
        let pol = Softmax::new(3, 2).unwrap();
        let (theta, phi) = (vec![0.5, -1.0, 0.25, 1.0, -0.75, 0.0], vec![1.0, 0.5]);
        let (ti, pi) = (iv(&theta), iv(&phi));
        let (mut rf, mut ri) = (KitRng::seed_from_u64(9), KitRng::seed_from_u64(9));
        for _ in 0..200 {
            let af = Policy::<f64>::sample(&pol, &theta, &phi, &mut rf).unwrap();
            let ai = Policy::<Interval>::sample(&pol, &ti, &pi, &mut ri).unwrap();
            assert_eq!(af, ai);
        }
    }
}
