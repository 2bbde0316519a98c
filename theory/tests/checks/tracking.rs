//! The tracking rows' decision and ranges, and their power against a dropped importance weight.
//! (The rows at the table's own sizes are tested with the other statistical rows in `power.rs`.)

use crate::common::{quick_global_constants, table_alpha};
use ilopt_theory::check::Verdict;
use ilopt_theory::checks::tracking::{self, StormRange};
use ilopt_theory::protocol::m1_tied;
use ilopt_theory::stats::ZeroMeanTest;

/// The two-sided rule on a planted stream: mean 0 holds, a bias of a few times the minimum
/// detectable one is flagged either way, and values of zero width everywhere give a point interval.
#[test]
fn zero_mean_test_flags_a_planted_bias() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let xs: Vec<f64> = (0..20_000).map(|_| rng.random_range(-0.5..0.5)).collect();
    let t = ZeroMeanTest::new(&xs, &xs, 1.0, 1e-3);
    assert_eq!(t.verdict(), Verdict::Holds, "{t:?}");
    let b = 3.0 * t.min_detectable_bias();
    for sign in [1.0, -1.0] {
        let ys: Vec<f64> = xs.iter().map(|x| x + sign * b).collect();
        let s = ZeroMeanTest::new(&ys, &ys, 1.0, 1e-3);
        assert_eq!(s.verdict(), Verdict::Fails, "{s:?}");
    }
    // The interval is honest about the range: from two values it spans almost all of it.
    let few = ZeroMeanTest::new(&[0.1, -0.1], &[0.1, -0.1], 1.0, 1e-3);
    assert!(few.min_detectable_bias() > 0.9, "{few:?}");
    // An interval that spans the whole range is uninformative.
    let blind = ZeroMeanTest {
        lcb: -1.0,
        ucb: 1.0,
        ..few
    };
    assert_eq!(blind.verdict(), Verdict::Uninformative);
}

/// The STORM ranges are bounds of the update: on the deterministic worst case of the recursion
/// (every g at ±G_∞, every ∇F at ∓G_F) |u| reaches at most c_k.
#[test]
fn storm_range_bounds_the_worst_case_increment() {
    let (g_inf, g_f, w) = (2.0, 0.5, 7.0);
    for k in [1u64, 2, 10, 1000] {
        let oma = tracking::one_minus_a(k);
        // u = W + (1 − a)(∇F_k − g̃) with |W| ≤ G_∞ + G_F, |∇F_k − g̃| ≤ G_F + W.
        let worst = g_inf + g_f + oma * (g_f + w);
        assert!(StormRange::Recursion { w }.bound(k, g_inf, g_f) >= worst);
        let printed = g_inf + g_f + oma * (3.0 * g_inf + g_f);
        assert!(StormRange::Printed.bound(k, g_inf, g_f) >= printed);
    }
}

/// The row's power against a dropped importance weight where the weight matters: the table's
/// rows 2e.c and 2e.c.unweighted (a constant schedule of long steps, η = a = 1/4, from θ₁ = 0,
/// where the old-point bias is large: b(0, 1) = 5/12, math.md §4; near the minimiser it nearly
/// vanishes) flag the unweighted STORM over the first K = 10 iterates of R = 10⁴ runs, while
/// IS-STORM (trajectory weights) holds.
#[test]
fn tracking_row_flags_a_dropped_weight_at_long_steps() {
    use ilopt_theory::checks::statistical::long_step_tracking_rows;
    let rows = long_step_tracking_rows(&m1_tied(), quick_global_constants(), table_alpha());
    let verdicts: Vec<(&str, Verdict)> = rows.iter().map(|r| (r.id.as_str(), r.verdict)).collect();
    assert_eq!(
        verdicts,
        [
            ("2e.c", Verdict::Holds),
            ("2e.c.unweighted", Verdict::Fails)
        ]
    );
}

/// The table's rows 3d.c and 3d.c.printed5 (Algorithm 5 over short runs with a wide radius,
/// N = 6, δ = 2, R = 4·10⁴): the IL-correct algorithm holds and the printed one (τ_n ∼ θ_n, E11)
/// is flagged by the same statistic.
#[test]
fn tracking_row_flags_the_printed_algorithm_5_at_a_wide_radius() {
    use crate::common::q;
    use ilopt_theory::certify::box_constants::compute;
    use ilopt_theory::checks::statistical::wide_radius_tracking_rows;
    let m1 = m1_tied();
    let k = compute(
        &m1,
        &[q("0")],
        Some(&q("7/8")),
        &[[-400.0, 400.0]],
        1e-2,
        200_000,
    )
    .unwrap();
    let rows = wide_radius_tracking_rows(&m1, &k, quick_global_constants(), table_alpha());
    let verdicts: Vec<(&str, Verdict)> = rows.iter().map(|r| (r.id.as_str(), r.verdict)).collect();
    assert_eq!(
        verdicts,
        [("3d.c", Verdict::Holds), ("3d.c.printed5", Verdict::Fails)]
    );
}
