//! The exact and rigorous checks (checks 2 part, 3 part, 4, 5), each with a deliberately
//! wrong claim that the same machinery flags.

use crate::common::q;
use ilopt::problem::Weighting;
use ilopt::scalar::BigRational;
use ilopt::toy::ToyMdp;
use ilopt_theory::check::{Role, Verdict};
use ilopt_theory::checks::{o2nc_formula, schedule, thm31, unbiased};
use ilopt_theory::inputs::{Formulas, TableInputs};

fn example(name: &str) -> ToyMdp {
    ToyMdp::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../examples/toy")
            .join(name),
    )
    .unwrap()
}

fn m1_pairs() -> Vec<(ToyMdp, Vec<BigRational>, Vec<BigRational>)> {
    let m = example("m1-tied.json");
    ["0", "1/3", "-2", "5/2"]
        .iter()
        .flat_map(|a| ["1", "-1/2", "3"].iter().map(move |b| (*a, *b)))
        .map(|(a, b)| (m.clone(), vec![q(a)], vec![q(b)]))
        .chain(std::iter::once((
            example("three-state.json"),
            ["1/2", "-1", "0", "3", "2/3", "-5/4"].map(q).to_vec(),
            ["0", "1", "1", "0", "-1/3", "2"].map(q).to_vec(),
        )))
        .collect()
}

#[test]
fn check4_unbiasedness_and_its_negative_controls() {
    let cases: Vec<_> = m1_pairs().into_iter().map(|(m, a, _)| (m, a)).collect();
    assert_eq!(unbiased::estimator(&cases).verdict, Verdict::Holds);
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        assert_eq!(
            unbiased::old_point(&m1_pairs(), Some(w)).verdict,
            Verdict::Holds
        );
    }
    // The printed Algorithm 4 / 5: biased (E10, E11) — the check must say so.
    let printed = unbiased::old_point(&m1_pairs(), None);
    assert_eq!(printed.verdict, Verdict::Fails);
    assert_eq!(printed.role, Role::Thesis);
    let single = vec![(example("m1-tied.json"), vec![q("0")], vec![q("1")])];
    let b = unbiased::old_point(&single, None);
    assert_eq!(
        b.measured.unwrap().value,
        5.0 / 12.0,
        "bias 5/12 (math.md §1.4)"
    );
    assert_eq!(unbiased::printed_o2nc(&single).verdict, Verdict::Fails);
    // E9: the printed update's mean is (2 − a)∇F.
    let e9 = unbiased::printed_storm_update(&example("m1-tied.json"), &[q("0")], &q("1/2"));
    assert_eq!(e9.verdict, Verdict::Fails);
    assert!(e9.details.contains("3/2"), "{}", e9.details);
    // With a = 1 the printed update happens to be unbiased: the check can also say Holds.
    let a1 = unbiased::printed_storm_update(&example("m1-tied.json"), &[q("0")], &q("1"));
    assert_eq!(a1.verdict, Verdict::Holds);
}

#[test]
fn check5_theorem_3_1_on_the_m_family() {
    let want = [
        ("3/4", "2/3", "1/4"),
        ("3/8", "2/5", "1/6"),
        ("7/20", "5/13", "3/16"),
    ];
    for (inst, (po, ps, kappa)) in thm31::instances().iter().zip(want) {
        let f = thm31::analyse(inst).unwrap();
        // math.md §6's table, an independent hand computation.
        assert_eq!(
            (f.p_po.clone(), f.p_ps.clone(), f.kappa.clone()),
            (q(po), q(ps), q(kappa))
        );
        assert!(f.closed_form_agrees && f.ps_closed_form_agrees);
        // G is affine on all of (0, 1), proved from T points, so rows 5b–5d claim every k.
        assert!(f.g_identity.proved(), "{}", f.g_identity.describe());
        assert_eq!(f.g_identity.points, inst.t);
        assert!(f.dagger_product_agrees);
        // The perturbed map G + p(1 − p)/8 is reported not affine.
        assert!(f.perturbed_identity.first_miss.is_some());
        assert!(!f.perturbed_identity.proved());
        let rows = thm31::rows(inst);
        let ids: Vec<&str> = rows.iter().map(|r| r.id.as_str()).collect();
        assert_eq!(ids, ["5a", "5b", "5c", "5d", "5c.ctl"]);
        for row in &rows {
            let want = if row.role == Role::NegativeControl {
                Verdict::Fails
            } else {
                Verdict::Holds
            };
            assert_eq!(row.verdict, want, "{}: {}", row.claim, row.details);
        }
        for row in &rows[1..4] {
            assert!(row.claim.contains("for all k"), "{}", row.claim);
        }
    }
    let m1 = thm31::analyse(&thm31::instances()[0]).unwrap();
    assert_eq!(m1.df_ps, q("-1/3"), "F′(p_PS) on M1");
    assert_eq!((m1.f_po, m1.f_ps), (q("7/8"), q("8/9")));
    // A wrong claim — "the stable point is optimal" (p_PS = p_PO) — is refuted by the same numbers.
    assert_ne!(m1.p_ps, m1.p_po);
    // An instance with Δ = 0 (actions do not affect the state): PS = PO, and the check says 5a fails.
    let flat = thm31::Instance {
        mu_a: q("1/2"),
        p0: q("1/3"),
        p1: q("1/3"),
        t: 3,
    };
    let rows = thm31::rows(&flat);
    assert_eq!(rows[0].verdict, Verdict::Fails, "{}", rows[0].details);
}

#[test]
fn check2_schedule_rows() {
    let rows = schedule::rows(100);
    let ids: Vec<&str> = rows.iter().map(|r| r.id.as_str()).collect();
    assert_eq!(ids, ["2a", "2a.ctl", "2b"]);
    assert_eq!(rows[0].verdict, Verdict::Holds);
    // The (C1) control (the step without its 1/4 factor) is refuted at k = 1..48 and detected.
    assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
    assert!(!rows[1].undetected_control());
    assert!(
        rows[1].details.contains("false at k = 1..48;"),
        "{}",
        rows[1].details
    );
    assert_eq!(rows[2].verdict, Verdict::Fails);
    assert!(rows[2].details.contains("1..23"), "{}", rows[2].details);
    assert_eq!(schedule::compress(&[1, 2, 3, 7, 9, 10]), "1..3, 7, 9..10");
}

#[test]
fn check3_corollary_follows_from_the_theorem() {
    let row = o2nc_formula::row(&TableInputs::thesis(), 20_000, 1);
    assert_eq!(row.verdict, Verdict::Holds, "{}", row.details);
    let r = o2nc_formula::ratios(&Formulas::THESIS, 20_000, 1, 1.0);
    assert!(r.theorem <= 0.71, "math.md reports ≤ 0.70: {}", r.theorem);
    // A corollary understated by half is violated.
    let half = o2nc_formula::ratios(&Formulas::THESIS, 20_000, 1, 0.5);
    assert!(half.theorem > 1.0 || half.intermediate > 1.0);
}

/// Rows 4e and 4f run the kit's printed Algorithms 5 and 4 and check, exactly, the property each
/// algorithm's analysis needs at the points it visits: both fail; the corrected algorithms
/// (sampling at w_n; IS-STORM) satisfy it exactly at their own points.
#[test]
fn check4_printed_algorithms_at_the_points_they_visit() {
    let m1 = example("m1-tied.json");
    let e = unbiased::printed_algorithm_5_visited(&m1, 0.0, 12, (1, 10), 2.0, 0.5, 0);
    assert_eq!(e.verdict, Verdict::Fails, "{}", e.details);
    assert!(e.measured.unwrap().value > 0.0);
    assert!(e.details.ends_with("max |bias| = 0"), "{}", e.details);
    let f = unbiased::printed_algorithm_4_visited(&m1, &q("0"), (1, 20), (1, 2), 2, 0);
    assert_eq!(f.verdict, Verdict::Fails, "{}", f.details);
    assert!(f.details.ends_with("max |difference| = 0"), "{}", f.details);
}

/// Rows 5c, 5d are proofs on the exact recursion; 5e runs the kit's DAgger: with enough runs its
/// interval lies on p_PS's side on M1, and with too few it cannot decide.
#[test]
fn check5_dagger_rows() {
    let m1 = &thm31::instances()[0];
    let f = thm31::analyse(m1).unwrap();
    assert!(f.g_affine_on_iterates);
    assert_eq!((f.eq_3_37_violated_at, f.eq_3_38_violated_at), (None, None));
    // κ = 1/4 > 0 and p₁ > p_PS: every error has one sign, so (3.38) holds with equality.
    assert_eq!(f.eq_3_38_max_ratio, q("1"));
    let sizes = thm31::DaggerSizes {
        runs: 400,
        iterations: 6,
        trajectories: 10,
        alpha: 1e-3,
    };
    let row = thm31::dagger_row(m1, sizes);
    assert_eq!(row.verdict, Verdict::Holds, "{}", row.details);
    let few = thm31::dagger_row(m1, thm31::DaggerSizes { runs: 10, ..sizes });
    assert_eq!(few.verdict, Verdict::Inconclusive, "{}", few.details);
}
