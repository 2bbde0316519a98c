//! Check 2 (part): the STORM schedule (3.43) satisfies the corrected conditions (C1), (C2) of
//! Theorem S, and the thesis's own route fails for k = 1..23 (erratum E7). Proved with rational
//! cube-root enclosures ([`crate::schedule`]). Control **2a.ctl**: the same (C1) check on the
//! step without its 1/4 factor, where (C1) is false for k ≤ 48.

use crate::record::check::{Check, Method, Role, Verdict};
use crate::schedule::{c1_scaled_failures, check_schedule};
use num_bigint::BigInt;
use num_rational::BigRational;

/// The three rows: corrected conditions (holds), the (C1) control (must be refuted) and the
/// thesis route (fails for k ≤ 23).
pub fn rows(k_max: u64) -> Vec<Check> {
    let r = check_schedule(k_max);
    let (ctl_fails, ctl_undecided) =
        c1_scaled_failures(k_max, &BigRational::from_integer(BigInt::from(1)));
    let corrected_ok = r.c1_not_proved.is_empty() && r.c2_not_proved.is_empty();
    let base = |id: &str, claim: String, role, details: String| {
        Check::builder(id, "STORM, eq. 3.60 (schedule 3.43)", claim, role)
            .assumptions(["η_k = (1/4L)(7/(k+7))^{1/3}, a_{k+1} = 16L²η_k²"])
            .erratum("E7")
            .details(details)
    };
    vec![
        base(
            "2a",
            format!(
                "(C1) Lη_k ≤ 1/2, proved per k from the cube-root enclosure of Lη_k = (7/(k+7))^{{1/3}}/4 (the same check refutes (C1) for the step without its 1/4 factor: row 2a.ctl), and (C2) 4L²η_k² + (1−a_{{k+1}})² ≤ η_k/η_{{k−1}} for k = 1..{k_max}"
            ),
            Role::Corrected,
            format!(
                "C1 not proved at k = {}; C2 not proved at k = {}",
                list_or_none(&r.c1_not_proved),
                list_or_none(&r.c2_not_proved)
            ),
        )
        .decided(Method::Rigorous, Verdict::from_bool(corrected_ok)),
        Check::builder(
            "2a.ctl",
            "STORM, eq. 3.60 (schedule 3.43)",
            format!(
                "(C1) Lη_k ≤ 1/2 for the step without its 1/4 factor, Lη_k = (7/(k+7))^{{1/3}}, k = 1..{k_max} (false for k ≤ 48: the check of row 2a must refute it)"
            ),
            Role::NegativeControl,
        )
        .assumptions(["η_k = (1/L)(7/(k+7))^{1/3}: schedule (3.43) with its 1/4 dropped"])
        .details(format!(
            "C1 proved false at k = {}; undecided at k = {}",
            list_or_none(&ctl_fails),
            list_or_none(&ctl_undecided)
        ))
        .decided(Method::Rigorous, Verdict::from_bool(ctl_fails.is_empty())),
        base(
            "2b",
            format!("the thesis's e_k coefficient after (3.58)/(3.59) is ≤ 0 for k = 1..{k_max}"),
            Role::Thesis,
            format!(
                "proved positive (route fails) at k = {}; undecided at k = {}",
                compress(&r.thesis_route_fails),
                list_or_none(&r.thesis_route_undecided)
            ),
        )
        // E7: the printed claim is false for k = 1..23.
        .refuted_by_erratum()
        .decided(
            Method::Rigorous,
            Verdict::from_bool(
                r.thesis_route_fails.is_empty() && r.thesis_route_undecided.is_empty(),
            ),
        ),
    ]
}

/// [`compress`]ed, or `none` for an empty list.
fn list_or_none(ks: &[u64]) -> String {
    if ks.is_empty() {
        "none".into()
    } else {
        compress(ks)
    }
}

/// `[1, 2, 3, 7]` → `"1..3, 7"`.
pub fn compress(ks: &[u64]) -> String {
    let mut out: Vec<String> = vec![];
    let mut i = 0;
    while i < ks.len() {
        let mut j = i;
        while j + 1 < ks.len() && ks[j + 1] == ks[j] + 1 {
            j += 1;
        }
        out.push(if i == j {
            ks[i].to_string()
        } else {
            format!("{}..{}", ks[i], ks[j])
        });
        i = j + 1;
    }
    out.join(", ")
}
