//! Rows 8 and 8b: the constants of the bounds for the toy M1 (P2', θ₁ = 0), each exact or a
//! rigorous upper bound with its certificate (math.md §7.1), on a box (row 8; row 8c for the
//! second toy) and over all of ℝ (row 8b). Each row states the values, the provenance and the
//! certificate sizes, and passes only if every certificate passes the independent second route
//! ([`crate::certify::recheck`]); the certificates themselves are in the JSON report.

use crate::certify::box_constants::ToyConstants;
use crate::certify::global::GlobalConstants;
use crate::certify::recheck::{Coverage, Recheck};
use crate::certify::tiling::verify_certificate;
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::record::constant::Provenance;

/// The row of the constants on the box `domain` (row `id`: "8" for M1, "8c" for the second toy):
/// every constant exact or rigorous, each certificate tiling `domain` and re-checked by the second
/// route on the boxes given by `coverage`.
pub fn toy_row(
    k: &ToyConstants,
    name: &str,
    domain: &[[f64; 2]],
    coverage: Coverage,
    id: &str,
) -> Check {
    let all = k.all();
    let verified = all.iter().all(|c| match (&c.provenance, &c.certificate) {
        (Provenance::Exact, _) => true,
        (Provenance::Rigorous, Some(cert)) => verify_certificate(cert, domain),
        _ => false,
    });
    let rechecks = k.recheck(domain, coverage);
    let ok = verified && rechecks.iter().all(|(_, r)| r.passed());
    let details = format!(
        "{}. {}",
        all.iter()
            .map(|c| {
                let gap = match (&c.certificate, c.attained) {
                    (Some(b), Some(a)) => {
                        format!(" (attained ≥ {a:.6}, {} boxes)", b.certificate.len())
                    }
                    _ => String::new(),
                };
                format!("{} ≤ {:.6}{gap}", c.name, c.value)
            })
            .collect::<Vec<_>>()
            .join("; "),
        recheck_summary(&rechecks, coverage)
    );
    Check::builder(
        id,
        "Rigorous constants (math.md §7.1)",
        format!("{name}: B_F exact; L_F, σ², G², G_F, G_∞ rigorous upper bounds on {domain:?}"),
        Role::Corrected,
    )
    .assumptions(["the box contains every iterate (see each check)"])
    .constants(all)
    .measured(Measured::exact(k.l_f.value))
    .details(details)
    .decided(Method::Rigorous, Verdict::from_bool(ok))
}

/// Row 8b: every constant of the STORM checks exact or rigorous over ℝ (ℝ² for L̃), every
/// certificate covering its chart region and re-checked by the second route on the boxes given
/// by `coverage`.
pub fn global_row(g: &GlobalConstants, name: &str, coverage: Coverage) -> Check {
    let all = g.all();
    let rechecks = g.recheck(coverage);
    let ok = g.verified() && rechecks.iter().all(|(_, r)| r.passed());
    let details = format!(
        "{}. {}",
        all.iter()
            .map(|c| {
                let boxes: usize = c.charts.iter().map(|r| r.bound.certificate.len()).sum();
                format!("{} ≤ {:.6} ({boxes} boxes)", c.name, c.value)
            })
            .collect::<Vec<_>>()
            .join("; "),
        recheck_summary(&rechecks, coverage)
    );
    Check::builder(
        "8b",
        "Rigorous constants over ℝ (math.md §7.1, tails by θ = 1/u)",
        format!(
            "{name}: B_F exact; L_F, σ², G_F, G_∞ over ℝ and L̃ of (A4) (trajectory and per-decision weights) over ℝ² rigorous upper bounds"
        ),
        Role::Corrected,
    )
    .assumptions([
        "none on the iterates: the bounds hold for every θ (θ, θ′)",
        "L̃² ≤ ½ sup |∂²V_IS/∂θ′²| since V_IS(θ, θ) = 0 is a minimum (Taylor)",
    ])
    .constants(all)
    .measured(Measured::exact(g.l_tilde.value))
    .erratum("E2")
    .details(details)
    .decided(Method::Rigorous, Verdict::from_bool(ok))
}

/// One sentence per constant: boxes re-checked, pieces, corners, tiling, result.
pub fn recheck_summary(rechecks: &[(String, Recheck)], coverage: Coverage) -> String {
    let scope = match coverage {
        Coverage::All => "every box".to_string(),
        Coverage::Sample(n) => format!(
            "a seeded sample of {n} boxes per region plus every box within 1 % of the certified bound"
        ),
    };
    let each: Vec<String> = rechecks
        .iter()
        .map(|(name, r)| {
            let verdict = if r.passed() {
                "passed".to_string()
            } else {
                format!("FAILED: {}", r.failures.join("; "))
            };
            // The largest re-checked bound in the constant's units, which the constant must
            // not be below (the certificate's own units, G_F² or 2L̃², would not compare).
            let largest = match r.max_in_constant_units {
                Some(v) => format!("largest re-checked {name} {v:.6}"),
                None => format!(
                    "largest re-checked bound {:.6} (certificate units)",
                    r.max_upper
                ),
            };
            format!(
                "{name}: {} boxes, {} pieces, {} corners, tiling {}, {largest}, {verdict}",
                r.boxes,
                r.pieces,
                r.corners,
                if r.tiling { "exact" } else { "broken" },
            )
        })
        .collect();
    format!(
        "Second route (hand-written P2′ closed forms, enumeration and estimator; corner values enclosed at points and a Dual<Interval> gradient bound on each box; {scope}): {}",
        each.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The summary prints the largest re-checked bound in the constant's units (here G_F, not
    /// the certificate's G_F²), so that it reads against the constant it must not exceed.
    #[test]
    fn the_recheck_summary_reads_in_the_constants_units() {
        let r = Recheck {
            boxes: 3,
            pieces: 3,
            corners: 8,
            max_upper: 0.25,
            max_in_constant_units: Some(0.5),
            tiling: true,
            failures: vec![],
        };
        let text = recheck_summary(&[("G_F".into(), r.clone())], Coverage::All);
        assert!(
            text.contains("largest re-checked G_F 0.500000, passed"),
            "{text}"
        );
        assert!(!text.contains("0.250000"), "{text}");
        let unset = Recheck {
            max_in_constant_units: None,
            ..r
        };
        let text = recheck_summary(&[("G_F".into(), unset)], Coverage::All);
        assert!(text.contains("0.250000 (certificate units)"), "{text}");
    }
}
