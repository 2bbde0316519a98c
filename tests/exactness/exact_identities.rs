//! The exact identities of math.md §1.4, in rational arithmetic with no tolerance:
//! (I1) F_X1 = F_X2 = F_X3, (I2) ∇F_X2 = ∇F_X3 = ∇F_enum = E[g] = E[g_full] (the thesis's
//! unbiasedness claim, eqs. 3.16/3.18), (I3) the importance-sampling identity, (I4) the bias.

use crate::common::{example, mdp_and_two_thetas, q, qs, terminating_mdp_and_two_thetas};
use ilopt::exact::backward::backward;
use ilopt::exact::enumerate::{gradient_by_duals, moments, prefixes};
use ilopt::exact::forward::forward;
use ilopt::exact::importance::{bias, unweighted_expectation, weighted_expectation};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp, ToyProblem};
use proptest::prelude::*;

type Q = BigRational;

/// Check I1–I3 at (θ, θ′); returns a description of the first identity that fails.
fn identities(mdp: &ToyMdp, theta: &[Q], theta_prime: &[Q]) -> Result<(), String> {
    let p = ToyProblem::<Q>::new(mdp);
    let x1 = moments(&p, theta).map_err(|e| e.to_string())?;
    let x2 = forward(&p, theta).map_err(|e| e.to_string())?;
    let x3 = backward(&p, theta).map_err(|e| e.to_string())?;
    let en = gradient_by_duals(&p, theta).map_err(|e| e.to_string())?;
    let f = &x2.objective;
    if &x1.objective != f || &x3.0 != f || &en.0 != f {
        return Err(format!(
            "I1: F_X1 = {}, F_X2 = {f}, F_X3 = {}, F_enum = {}",
            x1.objective, x3.0, en.0
        ));
    }
    let g = &x2.gradient;
    for (name, other) in [
        ("∇F_X3", &x3.1),
        ("∇F_enum", &en.1),
        ("E[g]", &x1.expected_estimate),
        ("E[g_full]", &x1.expected_full),
    ] {
        if other != g {
            return Err(format!("I2: {name} = {other:?} ≠ ∇F_X2 = {g:?}"));
        }
    }
    if x1.variance < Q::zero() {
        return Err(format!("negative variance {}", x1.variance));
    }
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        let is = weighted_expectation(&p, theta, theta_prime, w).map_err(|e| e.to_string())?;
        if &is != g {
            return Err(format!("I3 ({w:?}): {is:?} ≠ ∇F = {g:?}"));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("regressions"),
        )),
        ..ProptestConfig::default()
    })]

    /// I1–I3 hold exactly on random MDPs (all three policy kinds, aliasing, zero transitions).
    #[test]
    fn identities_hold_exactly_on_random_mdps((mdp, theta, theta_prime) in mdp_and_two_thetas()) {
        prop_assert_eq!(identities(&mdp, &theta, &theta_prime), Ok(()));
    }
}

/// Hand-picked regressions: the edge cases the generator reaches only rarely.
#[test]
fn identities_hold_on_edge_cases() {
    // T = 2 (no score terms at all), a single state, zero-probability transitions.
    let single = ToyMdp::from_json_str(
        r#"{"states":1,"actions":3,"horizon":2,"initial":["1"],
            "transition":[[["1"],["1"],["1"]]],"expert":[2],
            "policy":{"kind":"rational-softmax","c":"1/3"}}"#,
    )
    .unwrap();
    identities(&single, &qs(&["1", "-2", "1/2"]), &qs(&["0", "0", "0"])).unwrap();
    let three = example("three-state.json");
    let theta = qs(&["1/2", "-1", "0", "3", "2/3", "-5/4"]);
    let theta2 = qs(&["0", "1", "1", "0", "-1/3", "2"]);
    identities(&three, &theta, &theta2).unwrap();
    // θ = 0 is a stationary point of P2 (math.md §1.3 caveat): ∇F = 0 exactly there.
    let g = forward(&ToyProblem::<Q>::new(&three), &vec![Q::zero(); 6])
        .unwrap()
        .gradient;
    assert!(g.iter().all(|x| *x == Q::zero()));
}

/// math.md §1.4 reference table (M1, T = 3, P2', Brier): F, F′, E g², Var at θ ∈ {0, 1/2, 1}.
#[test]
fn m1_reference_values() {
    let p = ToyProblem::<Q>::new(&example("m1-tied.json"));
    for (theta, f, df, m2, var) in [
        ("0", "11/8", "-1/2", "185/192", "137/192"),
        ("1/2", "1", "-2/3", "28/9", "8/3"),
        ("1", "7/8", "0", "49/192", "49/192"),
    ] {
        let t = vec![q(theta)];
        let x1 = moments(&p, &t).unwrap();
        assert_eq!(x1.objective, q(f), "F({theta})");
        assert_eq!(x1.expected_estimate, vec![q(df)], "E g({theta})");
        assert_eq!(
            forward(&p, &t).unwrap().gradient,
            vec![q(df)],
            "F′({theta})"
        );
        assert_eq!(x1.second_moment, q(m2), "E g²({theta})");
        assert_eq!(x1.variance, q(var), "Var({theta})");
    }
}

/// The closed forms of math.md §1.3/§6 at many rational θ: p(θ) = (θ² + 1/2)/(2θ² − 2θ + 2),
/// F = 2 − 3p + 2p², F′ = (4p − 3) p′ with p′ = (−2θ² + 2θ + 1)/(2θ² − 2θ + 2)².
#[test]
fn m1_closed_form_objective_and_gradient() {
    let p = ToyProblem::<Q>::new(&example("m1-tied.json"));
    for n in -12i64..=12 {
        for d in [1i64, 3, 7] {
            let th = Q::new(n.into(), d.into());
            let den = q("2") * &th * &th - q("2") * &th + q("2");
            let pr = (th.clone() * &th + q("1/2")) / &den;
            let dp = (q("-2") * &th * &th + q("2") * &th + q("1")) / (den.clone() * &den);
            let f = q("2") - q("3") * &pr + q("2") * &pr * &pr;
            let df = (q("4") * &pr - q("3")) * dp;
            let x2 = forward(&p, std::slice::from_ref(&th)).unwrap();
            assert_eq!(x2.objective, f, "F at θ = {th}");
            assert_eq!(x2.gradient, vec![df], "F′ at θ = {th}");
        }
    }
}

/// The prefix table at θ = 0 (math.md §1.4), keys (s_1, a_1, s_2).
#[test]
fn m1_prefix_table() {
    let p = ToyProblem::<Q>::new(&example("m1-tied.json"));
    let got: Vec<(Vec<usize>, Vec<usize>, Q, Q)> = prefixes(&p, &[Q::zero()])
        .unwrap()
        .into_iter()
        .map(|x| (x.states, x.actions, x.prob, x.estimate[0].clone()))
        .collect();
    let want = [
        ([0, 0], 0, "3/16", "-15/8"),
        ([0, 1], 0, "3/16", "-13/24"),
        ([0, 0], 1, "1/8", "-3/8"),
        ([1, 0], 0, "3/16", "-7/8"),
        ([1, 1], 0, "3/16", "11/24"),
        ([1, 0], 1, "1/8", "5/8"),
    ];
    assert_eq!(got.len(), want.len());
    for (s, a, pr, g) in want {
        let key = (s.to_vec(), vec![a], q(pr), q(g));
        assert!(got.contains(&key), "missing prefix {key:?}");
    }
}

/// (I3) and (I4) on M1: Σ p(·;1) w g(0,·) = −1/2 = F′(0); without w it is −1/12, bias 5/12.
#[test]
fn m1_importance_identity_and_bias() {
    let p = ToyProblem::<Q>::new(&example("m1-tied.json"));
    let (zero, one) = (vec![q("0")], vec![q("1")]);
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        assert_eq!(
            weighted_expectation(&p, &zero, &one, w).unwrap(),
            vec![q("-1/2")]
        );
    }
    assert_eq!(
        unweighted_expectation(&p, &zero, &one).unwrap(),
        vec![q("-1/12")]
    );
    assert_eq!(bias(&p, &zero, &one).unwrap(), vec![q("5/12")]);
    // The bias vanishes when the sampling point is the evaluation point.
    assert_eq!(bias(&p, &zero, &zero).unwrap(), vec![q("0")]);
}

/// M-family with general T (math.md §6): F(p) = 2p² − Tp + (T − 1), so F(θ = 0) = 17/8 (T = 4),
/// 23/8 (T = 5); and the direct-parameterisation closed form F(p) = A₂p² + A₁p + A₀.
#[test]
fn m_family_objectives() {
    for (t, want) in [(4, "17/8"), (5, "23/8")] {
        let m = ToyMdp::m_family(
            q("1/2"),
            q("1/2"),
            q("1"),
            t,
            PolicyKind::TiedSoftmax,
            Some(q("1/2")),
        )
        .unwrap();
        let f = forward(&ToyProblem::<Q>::new(&m), &[q("0")])
            .unwrap()
            .objective;
        assert_eq!(f, q(want), "T = {t}");
    }
    // M(1/2, 1/4, 1/2, T) for T = 4, 5 with P1: θ = π(0|·), p = 1 − θ.
    for (t, a2, a1, a0) in [(4usize, "4", "-3", "2"), (5, "5", "-7/2", "5/2")] {
        let m =
            ToyMdp::m_family(q("1/2"), q("1/4"), q("1/2"), t, PolicyKind::Direct, None).unwrap();
        let prob = ToyProblem::<Q>::new(&m);
        for pn in 1..10 {
            let pp = Q::new(pn.into(), 10.into());
            let f = forward(&prob, &[Q::one() - &pp]).unwrap().objective;
            assert_eq!(
                f,
                q(a2) * &pp * &pp + q(a1) * &pp + q(a0),
                "T = {t}, p = {pp}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("regressions"),
        )),
        ..ProptestConfig::default()
    })]

    /// I1–I3 hold exactly on random MDPs with terminal states (math.md §8), reset and absorbing:
    /// the fixed-horizon estimators are unbiased and every route agrees on the augmented chain.
    #[test]
    fn identities_hold_exactly_on_random_terminating_mdps(
        (mdp, theta, theta_prime) in terminating_mdp_and_two_thetas()
    ) {
        prop_assert_eq!(identities(&mdp, &theta, &theta_prime), Ok(()));
    }
}
