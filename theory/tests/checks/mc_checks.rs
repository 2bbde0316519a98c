//! Checks 1 and 3 at a test size, each with a deliberately wrong (understated) bound that the
//! check must flag, and check 8's certificates. Constants are rigorous but computed with a coarse
//! branch-and-bound tolerance to keep the test quick (they are still upper bounds).

use ilopt::scalar::parse_exact;
use ilopt_theory::certify::box_constants::{ToyConstants, compute};
use ilopt_theory::certify::recheck::Coverage;
use ilopt_theory::check::{Role, Verdict};
use ilopt_theory::checks::constants::toy_row;
use ilopt_theory::checks::montecarlo::{self, McSettings};
use ilopt_theory::protocol::m1_tied;
use std::sync::OnceLock;

const DOMAIN: [[f64; 2]; 1] = [[-200.0, 200.0]];

fn constants() -> &'static ToyConstants {
    static K: OnceLock<ToyConstants> = OnceLock::new();
    K.get_or_init(|| {
        compute(
            &m1_tied(),
            &[parse_exact("0").unwrap()],
            Some(&parse_exact("7/8").unwrap()),
            &DOMAIN,
            5e-2,
            100_000,
        )
        .unwrap()
    })
}

#[test]
fn check8_constants_are_rigorous_and_certified() {
    let k = constants();
    let row = toy_row(k, "M1", &DOMAIN, Coverage::All, "8");
    assert_eq!(row.verdict, Verdict::Holds, "{}", row.details);
    // Upper bounds above math.md's orientation values (§2: L ≈ 2.02, sup Var ≈ 2.82,
    // sup E g² ≈ 3.47, sup |g| ≈ 3.64, sup |F′| ≈ 0.857) and within the tolerance of the attained
    // lower bounds; B_F = 1/2 exactly.
    assert_eq!(k.b_f.value, 0.5);
    for (c, approx) in [
        (&k.l_f, 2.02),
        (&k.sigma2, 2.82),
        (&k.g2, 3.47),
        (&k.g_inf, 3.64),
        (&k.g_f, 0.857),
    ] {
        let cert = c.certificate.as_ref().unwrap();
        assert!(
            c.value >= approx - 0.01 && c.value <= approx * 1.1,
            "{}: {}",
            c.name,
            c.value
        );
        assert!(cert.lower <= cert.upper);
        // The attained value is reported in the constant's own units (G_F and G_∞ are square
        // roots of the searched quantity): a lower bound below the upper bound, near the
        // orientation value.
        let a = c
            .attained
            .expect("rigorous constants report what they attained");
        assert!(a <= c.value, "{}: attained {a} > bound {}", c.name, c.value);
        assert!(
            (a - approx).abs() <= 0.02 * approx,
            "{}: attained {a}",
            c.name
        );
    }
    // An understated constant is refuted by the certified attained value: claiming L_F = 2 is
    // wrong because F″ attains more than 2 somewhere (lower bound of the B&B).
    assert!(k.l_f.certificate.as_ref().unwrap().lower > 2.0);
}

#[test]
fn check1_sgd_bound_holds_and_an_understated_bound_is_flagged() {
    let k = constants();
    let m1 = m1_tied();
    let mc = McSettings {
        runs: 60,
        alpha: 0.005,
    };
    let row = montecarlo::sgd(&m1, k, 0.0, (1, 20), 500, mc, 1.0);
    assert_eq!(row.verdict, Verdict::Holds, "{}", row.details);
    assert!(
        row.tightness.unwrap() < 0.2,
        "the bound is loose on M1: {}",
        row.details
    );
    // A bound 50× too small must be flagged (more, shorter runs: the a-priori range of the
    // per-run statistic is sup ‖∇F‖² ≈ 0.73, so the LCB needs R ≈ 10³).
    let wrong = montecarlo::sgd(
        &m1,
        k,
        0.0,
        (1, 20),
        200,
        McSettings {
            runs: 800,
            alpha: 0.005,
        },
        0.02,
    );
    assert_eq!(wrong.role, Role::NegativeControl);
    assert_eq!(wrong.verdict, Verdict::Fails, "{}", wrong.details);
    // The side condition is enforced: η = 1 > 1/L.
    let big = montecarlo::sgd(&m1, k, 0.0, (1, 1), 10, mc, 1.0);
    assert_eq!(big.verdict, Verdict::Inconclusive);
}

#[test]
fn check3_o2nc_bounds_hold_and_an_understated_bound_is_flagged() {
    let k = constants();
    let m1 = m1_tied();
    let mc = McSettings {
        runs: 60,
        alpha: 0.005,
    };
    let rows = montecarlo::o2nc(&m1, k, 0.0, 1000, (1, 10), mc, 1.0);
    assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
    assert_eq!(rows[1].verdict, Verdict::Holds, "{}", rows[1].details);
    let wrong = montecarlo::o2nc(&m1, k, 0.0, 1000, (1, 10), mc, 0.2);
    assert_eq!(wrong[1].verdict, Verdict::Fails, "{}", wrong[1].details);
}
