//! Rows 2.b and 2.b.ctl (IS-STORM with a constant baseline against (3.60*)) and their constants:
//! * the control is flagged at the quick size, the row holds, and its bound is below row 2c's;
//! * σ²_b at b = 0 is the plain global σ² by both routes;
//! * the certified σ²_b and L̃_b dominate Var g_b and the (A4) quotient of g_b computed exactly in ℚ;
//! * the second route's baselined (A4) curvature equals the first route's, and b = 0 gives the
//!   plain one; a certificate re-checked for another b, or lowered, fails;
//! * the importance-weighted baselined old-point estimate is exactly unbiased in ℚ with a constant
//!   baseline, and biased with one that looks at the scored action.

use crate::common::{q, quick_global_constants, table_alpha, v_b};
use ilopt::exact::baseline::baselined_moments;
use ilopt::exact::enumerate::for_each_prefix;
use ilopt::exact::forward::forward;
use ilopt::oracle::DecisionTerms;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::toy::ToyProblem;
use ilopt::toy::estimator::decision_terms;
use ilopt_theory::certify::global_baselined::{
    BaselinedConstants, l_tilde_baselined, sigma2_baselined,
};
use ilopt_theory::certify::recheck::{Coverage, Quantity, coverage_for, pieces, recheck};
use ilopt_theory::certify::v_is::v_is_second_mean_value_baselined;
use ilopt_theory::check::{Role, Verdict};
use ilopt_theory::checks::baselined_storm::{self, Choice, choose};
use ilopt_theory::checks::montecarlo::McSettings;
use ilopt_theory::protocol::m1_tied;
use ilopt_theory::record::certificate::Chart;
use ilopt_theory::suite::{Profile, global_sizes};
use std::sync::OnceLock;

type Q = BigRational;

fn exact(x: f64) -> Q {
    Q::from_float(x).unwrap()
}

/// The rule's choice at the quick size (shared by the tests).
fn quick_choice() -> &'static Choice {
    static C: OnceLock<Choice> = OnceLock::new();
    C.get_or_init(|| choose(&m1_tied(), global_sizes(Profile::Quick.sizes())).unwrap())
}

/// Var_θ g_b exactly, from the engine's baselined moments.
fn var_b(p: &ToyProblem<Q>, b: &Q, theta: &Q) -> Q {
    let m = baselined_moments(p, std::slice::from_ref(theta), std::slice::from_ref(b)).unwrap();
    m.second_moment - m.expected_estimate[0].clone() * &m.expected_estimate[0]
}

/// The rows at the quick size: 2.b holds, its control (the bound × 1/200, as 2c.ctl) is flagged,
/// both decided by row 2c's code at its K, R and α; the bound is at most row 2c's when σ²_b and
/// L̃_b are.
#[test]
fn the_control_is_detected_at_the_quick_size() {
    let m1 = m1_tied();
    let s = Profile::Quick.sizes();
    let g = quick_global_constants();
    let rows = baselined_storm::rows(
        &m1,
        g,
        global_sizes(s),
        s.storm_k,
        McSettings {
            runs: s.storm_runs,
            alpha: table_alpha(),
        },
        coverage_for(false),
    );
    let ids: Vec<&str> = rows.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(ids, ["2.b", "2.b.ctl"]);
    assert_eq!(rows[0].role, Role::Corrected);
    assert_eq!(rows[1].role, Role::NegativeControl);
    assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
    assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
    assert!(rows[0].details.contains("passed"), "{}", rows[0].details);
    assert!(!rows[0].details.contains("FAILED"), "{}", rows[0].details);
    let c = &quick_choice().constants;
    if c.sigma2.value <= g.sigma2.value && c.l_tilde.value <= g.l_tilde.value {
        let plain = ilopt_theory::bounds::storm_fixed(
            g.l(ilopt::problem::Weighting::Trajectory),
            g.sigma2.value,
            g.b_f.value,
            s.storm_k,
        );
        assert!(rows[0].bound.unwrap() <= plain);
    }
}

/// b = 0 is the plain estimator: its global σ²_b and the plain σ² certify the same supremum (each
/// one's attained value is below the other's bound), each certificate re-checks by the second
/// route as the other quantity, and the second route's two quantities agree exactly in ℚ.
#[test]
fn sigma2_b_at_zero_is_the_plain_sigma2_by_both_routes() {
    let m1 = m1_tied();
    let s = Profile::Quick.sizes();
    let plain = &quick_global_constants().sigma2;
    let zero = sigma2_baselined(&m1, &q("0"), s.bnb_tol, 200_000).unwrap();
    for (a, b) in [(&zero, plain), (plain, &zero)] {
        let attained = a.attained.expect("an attained value");
        assert!(attained <= b.value, "{} vs {}", a.value, b.value);
    }
    assert!((zero.value - plain.value).abs() <= 2.0 * s.bnb_tol * plain.value.max(1.0));
    let zero_q = Quantity::BaselinedVariance {
        numerator: 0,
        denominator: 1,
    };
    for (c, quantity) in [(&zero, Quantity::Variance), (plain, zero_q)] {
        for r in &c.charts {
            let out = recheck(
                &m1,
                quantity,
                &r.charts,
                &r.domain,
                &r.bound,
                r.bound.upper,
                Coverage::All,
            );
            assert!(out.passed(), "{quantity:?} on {:?}: {out:?}", r.charts);
        }
    }
    for (chart, x) in [
        (Chart::Core, "0"),
        (Chart::Core, "-3/2"),
        (Chart::Core, "7/3"),
        (Chart::Tail, "1/9"),
        (Chart::Tail, "-1/5"),
        (Chart::Tail, "0"),
    ] {
        let x = [q(x)];
        assert_eq!(
            pieces(&m1, zero_q, &[chart], &x).unwrap(),
            pieces(&m1, Quantity::Variance, &[chart], &x).unwrap()
        );
    }
}

/// The chosen b's certified σ²_b ≥ Var g_b(θ) and L̃_b²(θ′ − θ)² ≥ V_b(θ, θ′), both exact in ℚ,
/// at rational points near and far; every grid value's σ²_b ≥ its exact variance at θ = 0 and 3.
#[test]
fn the_certified_constants_dominate_exact_values() {
    let m1 = m1_tied();
    let p = ToyProblem::<Q>::new(&m1);
    let choice = quick_choice();
    let c = &choice.constants;
    let points = ["0", "1/2", "-1/3", "2", "-5", "40", "-1000"];
    for t in points {
        assert!(
            exact(c.sigma2.value) >= var_b(&p, &c.b, &q(t)),
            "σ²_b at θ = {t}"
        );
    }
    for (b, s2) in &choice.grid {
        for t in ["0", "3"] {
            assert!(exact(*s2) >= var_b(&p, b, &q(t)), "b = {b}, θ = {t}");
        }
    }
    let l2 = exact(c.l_tilde.value) * exact(c.l_tilde.value);
    for t in points {
        for u in points {
            let (th, pr) = (q(t), q(u));
            let d = pr.clone() - &th;
            assert!(
                l2.clone() * &d * &d >= v_b(&p, &c.b, &th, &pr),
                "(A4) at ({t}, {u})"
            );
        }
    }
    // V_b vanishes on the diagonal (w = 1) and depends on b off it.
    assert_eq!(v_b(&p, &c.b, &q("1/2"), &q("1/2")), Q::zero());
    assert_ne!(
        v_b(&p, &q("1/2"), &q("1/3"), &q("-2")),
        v_b(&p, &q("0"), &q("1/3"), &q("-2"))
    );
}

/// The second route's ∂²V_b/∂θ′² in ℚ lies in the first route's enclosure at points of every
/// chart pair, for b = 0 equals the plain trajectory quantity, and differs from it for b ≠ 0;
/// a certificate of L̃_b re-checked as another b's, or lowered below an attained value, fails.
#[test]
fn the_baselined_curvature_agrees_across_routes_and_tampering_fails() {
    let m1 = m1_tied();
    let pd = ToyProblem::<Dual<Dual<Interval>>>::new(&m1);
    let p3 = ToyProblem::<Dual<Dual<Dual<Interval>>>>::new(&m1);
    let b = q("1/2");
    let vb = |n, d| Quantity::VisTrajectoryBaselined {
        numerator: n,
        denominator: d,
    };
    let cases = [
        (Chart::Core, "9/32"),
        (Chart::Core, "-95/64"),
        (Chart::Tail, "9/64"),
        (Chart::Tail, "-1/32"),
    ];
    for (c1, x1) in cases {
        for (c2, x2) in cases {
            let x = [q(x1), q(x2)];
            let second = pieces(&m1, vb(1, 2), &[c1, c2], &x).unwrap()[0].to_f64();
            let pt = |v: &Q| {
                let f = v.to_f64();
                Interval::try_from((f, f)).unwrap()
            };
            let e = v_is_second_mean_value_baselined(
                &m1,
                &pd,
                &p3,
                &b,
                &[c1, c2],
                &[pt(&x[0]), pt(&x[1])],
            )
            .unwrap();
            let slack = 1e-9 * (1.0 + second.abs());
            assert!(
                e.inf() - slack <= second && second <= e.sup() + slack,
                "({c1:?} {x1}, {c2:?} {x2}): {e:?} misses {second}"
            );
            assert_eq!(
                pieces(&m1, vb(0, 1), &[c1, c2], &x).unwrap(),
                pieces(&m1, Quantity::VisTrajectory, &[c1, c2], &x).unwrap()
            );
        }
    }
    assert_ne!(
        pieces(
            &m1,
            vb(1, 2),
            &[Chart::Core, Chart::Core],
            &[q("0"), q("1")]
        )
        .unwrap(),
        pieces(
            &m1,
            Quantity::VisTrajectory,
            &[Chart::Core, Chart::Core],
            &[q("0"), q("1")]
        )
        .unwrap()
    );
    // A coarse certificate (cheap), re-checked in full: it passes for its own b only.
    let c = BaselinedConstants {
        b: b.clone(),
        sigma2: sigma2_baselined(&m1, &b, 0.05, 20_000).unwrap(),
        l_tilde: l_tilde_baselined(&m1, &b, 4.0, 4_000).unwrap(),
        mdp: m1.clone(),
    };
    assert!(
        c.recheck(Coverage::All).iter().all(|(_, r)| r.passed()),
        "{:?}",
        c.recheck(Coverage::All)
    );
    let other = BaselinedConstants {
        b: q("2"),
        ..c.clone()
    };
    assert!(!other.recheck(Coverage::All)[0].1.passed());
    let mut low = c.clone();
    let cap = low.l_tilde.attained.unwrap() * 0.99;
    low.l_tilde.value = cap;
    assert!(!low.recheck(Coverage::Sample(50))[1].1.passed());
}

/// `E_{τ∼θ′}[w g_b(θ, τ)] = ∇F(θ)` exactly (trajectory weight on the baselined estimate, the
/// engine's decision terms), for a constant b; with `b = 1[a₁ = 0]`, which looks at the action it
/// multiplies, the weighted mean is off by `−E_θ[b ψ₁] = p′(θ)` on M1 (T = 3).
#[test]
fn the_weighted_baselined_old_point_estimate_is_unbiased_and_a_peeking_baseline_is_not() {
    let m1 = m1_tied();
    let p = ToyProblem::<Q>::new(&m1);
    let weighted_mean = |theta: &Q, prime: &Q, peek: bool, b: &Q| -> Q {
        let t_old = p.table(std::slice::from_ref(theta)).unwrap();
        let t_new = p.table(std::slice::from_ref(prime)).unwrap();
        let mut terms = DecisionTerms::new();
        let mut g = vec![Q::zero(); 1];
        let mut acc = Q::zero();
        for_each_prefix(&p, &t_new, |states, actions, prob| {
            let scored = p.scored_actions(states, actions);
            let ratios: Vec<Q> = states
                .iter()
                .zip(scored)
                .map(|(&s, &a)| t_old.prob(s, a).clone() / t_new.prob(s, a))
                .collect();
            decision_terms(&t_old, states, scored, Some(&ratios), false, &mut terms);
            terms.estimate_into(
                |i| {
                    Some(if peek {
                        if scored[i] == 0 { Q::one() } else { Q::zero() }
                    } else {
                        b.clone()
                    })
                },
                &mut g,
            );
            acc += prob.clone() * &g[0];
        })
        .unwrap();
        acc
    };
    let pairs = [("0", "1"), ("1/3", "-2"), ("5/2", "1/2"), ("-4", "7")];
    for (t, u) in pairs {
        let (th, pr) = (q(t), q(u));
        let grad = forward(&p, std::slice::from_ref(&th)).unwrap().gradient[0].clone();
        for b in ["0", "1/8", "5/8", "2"] {
            assert_eq!(
                weighted_mean(&th, &pr, false, &q(b)),
                grad,
                "b = {b} at ({t}, {u})"
            );
        }
        // E_θ[1[a₁ = 0] ψ₁] = ∂π(0|s₁)/∂θ = −p′(θ), so the mean is ∇F + p′(θ) ≠ ∇F.
        let biased = weighted_mean(&th, &pr, true, &Q::zero());
        let dp = {
            let table = p.table(std::slice::from_ref(&th)).unwrap();
            table.prob_grad(0, 1)[0].clone()
        };
        assert_ne!(dp, Q::zero());
        assert_eq!(biased - &grad, dp, "peeking baseline at ({t}, {u})");
    }
}
