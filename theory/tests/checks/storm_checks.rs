//! Check 2 by Monte Carlo and the constants it needs over all of ℝ (ℝ² for L̃):
//! * the tail chart reproduces the engine's policy table exactly;
//! * the chart constants dominate exact values at rational points in both charts, and an
//!   understated L̃ is refuted by an exact quotient; tampered certificates are rejected;
//! * IS-STORM with schedule (3.43) against (3.60*), and the adaptive (Cutkosky–Orabona) schedule
//!   against its Theorem 1 (secondary): uninformative where the bound exceeds the statistic's
//!   maximum (K = 1000), holding at the full profile's K = 3·10⁴; each with a deliberately
//!   understated bound that must be flagged.

use crate::common::q;
use crate::common::quick_global_constants;
use ilopt::exact::enumerate::{for_each_prefix, moments, prefixes};
use ilopt::exact::forward::forward;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Scalar};
use ilopt::toy::ToyProblem;
use ilopt::toy::estimator::{causal, per_decision};
use ilopt_theory::certify::charts::{tail_jet, tied_table, verify_charts};
use ilopt_theory::certify::global::{GlobalConstants, GlobalSizes, recheck_l_tilde};
use ilopt_theory::check::{Role, Verdict};
use ilopt_theory::checks::montecarlo::McSettings;
use ilopt_theory::checks::storm;
use ilopt_theory::protocol::m1_tied;

type Q = BigRational;

fn exact(x: f64) -> Q {
    Q::from_float(x).unwrap()
}

/// V(θ, θ′) = Σ_τ̄ p(τ̄; θ′) (g(θ′, τ̄) − g̃(θ → θ′, τ̄))², exactly, with the trajectory weight
/// (from the prefix probabilities) or the engine's per-decision estimator.
fn v_is(w: Weighting, p: &ToyProblem<Q>, theta: &Q, prime: &Q) -> Q {
    match w {
        Weighting::Trajectory => crate::common::v_is_trajectory(p, theta, prime),
        Weighting::PerDecision => {
            let t_old = p.table(std::slice::from_ref(theta)).unwrap();
            let t_new = p.table(std::slice::from_ref(prime)).unwrap();
            let mut total = Q::zero();
            for_each_prefix(p, &t_new, |states, actions, prob| {
                let ratios: Vec<Q> = states
                    .iter()
                    .zip(actions)
                    .map(|(&s, &a)| t_old.prob(s, a).clone() / t_new.prob(s, a))
                    .collect();
                let d = causal(&t_new, states, actions)[0].clone()
                    - &per_decision(&t_old, states, actions, &ratios)[0];
                total += prob.clone() * &d * &d;
            })
            .unwrap();
            total
        }
    }
}

/// Points in the core and far in both tails.
const POINTS: [&str; 14] = [
    "0",
    "1/2",
    "-1/3",
    "1",
    "2",
    "-2",
    "7/2",
    "-4",
    "9/2",
    "-6",
    "17",
    "-100",
    "1000",
    "-250001/7",
];

/// At θ = 1/u (u rational ≠ 0) the tail-chart table equals the engine's table, exactly.
#[test]
fn tail_chart_table_is_the_engines_table() {
    let m1 = m1_tied();
    let p = ToyProblem::<Q>::new(&m1);
    for u in ["1/4", "-1/4", "1/7", "-3/16", "1/1000"] {
        let u = q(u);
        let theta = Q::one() / &u;
        let engine = p.table(std::slice::from_ref(&theta)).unwrap();
        let (pp, dp) = tail_jet(&u, p.c());
        let mine = tied_table(&m1, pp, dp).unwrap();
        assert_eq!(engine.probs, mine.probs);
        assert_eq!(engine.jacobian, mine.jacobian);
        assert_eq!(engine.score, mine.score);
        assert_eq!(engine.loss, mine.loss);
        assert_eq!(engine.loss_grad, mine.loss_grad);
    }
}

/// Every global constant dominates its exact value at rational points of both charts; L̃² dominates
/// the exact quotient V_IS/(θ′ − θ)² for pairs near, far, and across the tails.
#[test]
fn global_constants_dominate_exact_values() {
    let k = quick_global_constants();
    assert!(k.verified());
    // The quick budget converges: L̃ within 0.1 of the value the branch-and-bound attains.
    let attained = k
        .l_tilde
        .charts
        .iter()
        .map(|r| r.bound.lower)
        .fold(0.0, f64::max);
    assert!(k.l_tilde.value < 6.0 && k.l_tilde.value - (attained / 2.0).sqrt() < 0.1);
    assert_eq!(k.l_tilde.attained, Some((attained / 2.0).sqrt()));
    for c in [
        &k.l_f,
        &k.sigma2,
        &k.g_f,
        &k.g_inf,
        &k.l_tilde,
        &k.l_tilde_pd,
    ] {
        let a = c
            .attained
            .expect("rigorous constants report what they attained");
        assert!(
            0.0 < a && a <= c.value,
            "{}: attained {a}, bound {}",
            c.name,
            c.value
        );
    }
    let m1 = m1_tied();
    let p = ToyProblem::<Q>::new(&m1);
    let pd = ToyProblem::<Dual<Dual<Q>>>::new(&m1);
    for t in POINTS {
        let th = q(t);
        let m = moments(&p, std::slice::from_ref(&th)).unwrap();
        assert!(m.variance <= exact(k.sigma2.value), "Var at {t}");
        let f1 = m.expected_estimate[0].clone();
        assert!(f1.clone() * &f1 <= exact(k.g_f.value).square(), "F′ at {t}");
        for x in prefixes(&p, std::slice::from_ref(&th)).unwrap() {
            let g = x.estimate[0].clone();
            assert!(g.clone() * &g <= exact(k.g_inf.value).square(), "g at {t}");
        }
        let v = Dual::variable(Dual::variable(th.clone(), 0, 1), 0, 1);
        let f = forward(&pd, &[v]).unwrap().objective;
        let f2 = f.gradient_padded(1)[0].gradient_padded(1)[0].clone();
        assert!(f2.clone() * &f2 <= exact(k.l_f.value).square(), "F″ at {t}");
    }
    for (w, c) in [
        (Weighting::Trajectory, &k.l_tilde),
        (Weighting::PerDecision, &k.l_tilde_pd),
    ] {
        let l2 = exact(c.value).square();
        let mut worst = Q::zero();
        for a in POINTS {
            for b in POINTS {
                let (th, pr) = (q(a), q(b));
                if th == pr {
                    continue;
                }
                let d = pr.clone() - &th;
                let r = v_is(w, &p, &th, &pr) / (d.clone() * &d);
                assert!(r <= l2, "V/Δ² at ({a}, {b}) exceeds {}²", c.name);
                worst = worst.max(r);
            }
        }
        assert!(worst > Q::from_i64(1));
    }
}

/// An understated L̃ is refuted exactly: on the grid of eighths in [−2, 2]² some quotient
/// V_IS/Δ² exceeds 16 in rationals, so "(A4) holds with L̃ = 4" is false; the certified L̃ lies
/// above every such quotient.
#[test]
fn an_understated_l_tilde_is_refuted() {
    let k = quick_global_constants();
    let p = ToyProblem::<Q>::new(&m1_tied());
    let mut best = (Q::zero(), String::new());
    for i in -16i64..=16 {
        for j in -16i64..=16 {
            if i == j {
                continue;
            }
            let (th, pr) = (Q::new(i.into(), 8.into()), Q::new(j.into(), 8.into()));
            let d = pr.clone() - &th;
            let r = v_is(Weighting::Trajectory, &p, &th, &pr) / (d.clone() * &d);
            if r > best.0 {
                best = (r, format!("({th}, {pr})"));
            }
        }
    }
    assert!(
        best.0 > Q::from_i64(16),
        "max quotient {} at {}",
        best.0.to_f64(),
        best.1
    );
    assert!(best.0 <= exact(k.l_tilde.value).square());
}

/// Tampered certificates are rejected: a box removed, a region dropped, a region's domain shrunk,
/// a box's recorded enclosure lowered (found by re-evaluating every box), L̃ understated.
#[test]
fn tampered_chart_certificates_are_rejected() {
    let k = quick_global_constants();
    let m1 = m1_tied();
    let good = &k.l_tilde.charts;
    assert!(verify_charts(good, 2).is_some());
    let sup = recheck_l_tilde(&m1, Weighting::Trajectory, &k.l_tilde).unwrap();
    assert!(sup <= verify_charts(good, 2).unwrap());
    let mut low = k.l_tilde.clone();
    let top = &mut low.charts[0].bound.certificate[0];
    top.enclosure[1] /= 2.0;
    assert!(recheck_l_tilde(&m1, Weighting::Trajectory, &low).is_err());
    let mut under = k.l_tilde.clone();
    under.value = 5.0;
    assert!(recheck_l_tilde(&m1, Weighting::Trajectory, &under).is_err());
    let mut a = good.clone();
    a[0].bound.certificate.pop();
    assert!(verify_charts(&a, 2).is_none());
    let mut b = good.clone();
    b.pop();
    assert!(verify_charts(&b, 2).is_none());
    let mut c = k.l_f.charts.clone();
    c[1].domain[0] = [-0.125, 0.125];
    assert!(verify_charts(&c, 1).is_none());
}

#[test]
fn check2c_at_k_1000_is_uninformative_and_an_understated_bound_is_flagged() {
    let k = quick_global_constants();
    let m1 = m1_tied();
    let mc = McSettings {
        runs: 200,
        alpha: 0.002,
    };
    // At K = 1000 (3.60*) exceeds sup ‖∇F‖² = G_F², so no run could refute it: uninformative.
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        let row = storm::fixed_schedule(&m1, k, w, 0.0, 1000, mc, 1.0);
        assert_eq!(row.verdict, Verdict::Uninformative, "{}", row.details);
        assert!(row.tightness.unwrap() < 0.1, "{}", row.details);
    }
    // The bound divided by 100 is below what IS-STORM attains: flagged.
    let mc = McSettings {
        runs: 800,
        alpha: 0.002,
    };
    let wrong = storm::fixed_schedule(&m1, k, Weighting::Trajectory, 0.0, 300, mc, 0.01);
    assert_eq!(wrong.role, Role::NegativeControl);
    assert_eq!(wrong.verdict, Verdict::Fails, "{}", wrong.details);
}

#[test]
fn check2d_is_uninformative_and_an_understated_bound_is_flagged() {
    let k = quick_global_constants();
    let m1 = m1_tied();
    let mc = McSettings {
        runs: 200,
        alpha: 0.002,
    };
    // Its bound exceeds sup ‖∇F‖ = G_F at this K: uninformative.
    let row = storm::adaptive_schedule(&m1, k, 0.0, 1.0, 1000, mc, 1.0);
    assert_eq!(row.verdict, Verdict::Uninformative, "{}", row.details);
    let mc = McSettings {
        runs: 800,
        alpha: 0.002,
    };
    let wrong = storm::adaptive_schedule(&m1, k, 0.0, 1.0, 300, mc, 1e-4);
    assert_eq!(wrong.verdict, Verdict::Fails, "{}", wrong.details);
}

/// The full-profile sizes: tighter L̃, K = 3·10⁴ (where (3.60*) is below G_F²), R = 500.
#[test]
#[ignore = "the full profile's size, about 5 minutes in release (both L̃ at tolerance 0.1 with a re-check, then 500 runs of 30 000 iterations for 2c and 2c.pd, 500 of 10 000 for 2d); CI skips it, run it by hand: cargo test --release -p ilopt-theory --test checks storm_checks:: -- --ignored"]
fn check2_at_full_size() {
    let k = GlobalConstants::compute(
        &m1_tied(),
        &[q("0")],
        Some(&q("7/8")),
        GlobalSizes {
            tol: 1e-4,
            max_boxes: 200_000,
            l_tilde_tol: 0.1,
            l_tilde_boxes: 200_000,
        },
    )
    .unwrap();
    assert!(k.verified());
    assert!(k.l_tilde.value < 5.95, "{}", k.l_tilde.value);
    assert!(recheck_l_tilde(&m1_tied(), Weighting::PerDecision, &k.l_tilde_pd).is_ok());
    let m1 = m1_tied();
    let mc = McSettings {
        runs: 500,
        alpha: 0.002,
    };
    for c in k.all() {
        eprintln!("{} ≤ {} ({})", c.name, c.value, c.how);
    }
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        let row = storm::fixed_schedule(&m1, &k, w, 0.0, 30_000, mc, 1.0);
        eprintln!("{}: {} (X̄/B = {:?})", row.id, row.details, row.tightness);
        assert_eq!(row.verdict, Verdict::Holds, "{}", row.details);
    }
    let row = storm::adaptive_schedule(&m1, &k, 0.0, 1.0, 10_000, mc, 1.0);
    eprintln!("2d: {} (X̄/B = {:?})", row.details, row.tightness);
    assert_eq!(row.verdict, Verdict::Uninformative, "{}", row.details);
}

/// (h, ∂h/∂θ, ∂h/∂θ′) for h = ∂²V/∂θ′² at rational (θ, θ′), exactly: third-order nested duals
/// over ℚ (outer level in (θ, θ′), inner two in θ′) on the engine's own tables, with the engine's
/// causal and per-decision estimator code.
fn v_is_second_exact(weighting: Weighting, theta: &Q, prime: &Q) -> [Q; 3] {
    type D2q = Dual<Dual<Q>>;
    type D3q = Dual<D2q>;
    let m1 = m1_tied();
    let p3 = ToyProblem::<D3q>::new(&m1);
    let c2 = |x: &Q| D2q::constant(Dual::constant(x.clone()));
    let v2 = |x: &Q| D2q::variable(Dual::variable(x.clone(), 0, 1), 0, 1);
    let t_old = p3.table(&[Dual::variable(c2(theta), 0, 2)]).unwrap();
    let t_new = p3.table(&[Dual::variable(v2(prime), 1, 2)]).unwrap();
    let mut total = D3q::zero();
    for_each_prefix(&p3, &t_new, |states, actions, prob| {
        let ratios: Vec<D3q> = states
            .iter()
            .zip(actions)
            .map(|(&s, &a)| t_old.prob(s, a).clone() / t_new.prob(s, a))
            .collect();
        let old = match weighting {
            Weighting::Trajectory => {
                ratios.iter().fold(D3q::one(), |w, r| w * r) * &causal(&t_old, states, actions)[0]
            }
            Weighting::PerDecision => per_decision(&t_old, states, actions, &ratios)[0].clone(),
        };
        let e = causal(&t_new, states, actions)[0].clone() - old;
        total += prob.clone() * &e * &e;
    })
    .unwrap();
    let second = |d: &D2q| d.gradient_padded(1)[0].gradient_padded(1)[0].clone();
    let g = total.gradient_padded(2);
    [second(total.value()), second(&g[0]), second(&g[1])]
}

/// The chart enclosures of h = ∂²V_IS/∂θ′² and of its chart-coordinate derivatives contain the
/// exact values at dyadic points of every region (degenerate boxes, so the enclosures are tight):
/// this checks the tail chain rules h = u⁴V_uu + 2u³V_u, ∂_u h = u⁴V_uuu + 6u³V_uu + 6u²V_u
/// (∂_u = −θ²∂_θ) used by the mean-value form. On small boxes around the points, the natural and
/// mean-value enclosures contain the exact value too.
#[test]
fn chart_enclosures_contain_exact_values() {
    use ilopt::scalar::Interval;
    use ilopt_theory::certify::v_is::{v_is_second, v_is_second_jet, v_is_second_mean_value};
    use ilopt_theory::record::certificate::Chart;
    let m1 = m1_tied();
    let pd = ToyProblem::<Dual<Dual<Interval>>>::new(&m1);
    let p3 = ToyProblem::<Dual<Dual<Dual<Interval>>>>::new(&m1);
    // (chart, chart coordinate: dyadic, so exact in f64)
    let cases: [(Chart, &str); 6] = [
        (Chart::Core, "9/32"),
        (Chart::Core, "-95/64"),
        (Chart::Core, "97/32"),
        (Chart::Tail, "9/64"),
        (Chart::Tail, "-31/128"),
        (Chart::Tail, "-1/32"),
    ];
    let theta_of = |c: Chart, x: &Q| match c {
        Chart::Core => x.clone(),
        Chart::Tail => Q::one() / x,
    };
    // dθ/dx: 1 in the core, −1/u² = −θ² in the tail.
    let jac = |c: Chart, th: &Q| match c {
        Chart::Core => Q::one(),
        Chart::Tail => -(th.clone() * th),
    };
    let close = |e: Interval, x: f64, what: &str| {
        let slack = 1e-9 * (1.0 + x.abs());
        assert!(
            e.inf() - slack <= x && x <= e.sup() + slack,
            "{what}: {e:?} misses {x}"
        );
    };
    for ((c1, x1), (c2, x2), w) in cases
        .iter()
        .flat_map(|a| cases.iter().map(move |b| (*a, *b)))
        .flat_map(|(a, b)| [Weighting::Trajectory, Weighting::PerDecision].map(|w| (a, b, w)))
    {
        {
            let (x1q, x2q) = (q(x1), q(x2));
            let (th, pr) = (theta_of(c1, &x1q), theta_of(c2, &x2q));
            let [h, h_t, h_p] = v_is_second_exact(w, &th, &pr);
            let h1 = (h_t * jac(c1, &th)).to_f64();
            let h2 = (h_p * jac(c2, &pr)).to_f64();
            let h = h.to_f64();
            let pt = |x: &Q| {
                let f = x.to_f64();
                Interval::try_from((f, f)).unwrap()
            };
            let at = format!("({c1:?} {x1}, {c2:?} {x2}, {w:?})");
            let [e, d1, d2] =
                v_is_second_jet(&m1, &p3, w, &[c1, c2], &[pt(&x1q), pt(&x2q)]).unwrap();
            close(e, h, &format!("h at {at}"));
            close(d1, h1, &format!("∂₁h at {at}"));
            close(d2, h2, &format!("∂₂h at {at}"));
            let b = [x1q.to_f64(), x2q.to_f64()]
                .map(|f| Interval::try_from((f - 1.0 / 256.0, f + 1.0 / 256.0)).unwrap());
            let nat = v_is_second(&m1, &pd, w, &[c1, c2], &b).unwrap();
            let mv = v_is_second_mean_value(&m1, &pd, &p3, w, &[c1, c2], &b).unwrap();
            close(nat, h, &format!("natural on a box at {at}"));
            close(mv, h, &format!("mean-value on a box at {at}"));
        }
    }
}
