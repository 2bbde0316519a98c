//! The theorem-check table as Markdown and JSON (for the appendix).

use crate::protocol::{
    FAMILY_ALPHA, FAMILY_CLAIMS, OWN_LEVEL_PREFIXES, STATISTICAL_CLAIMS, family_level,
};
use crate::record::check::{Check, Expected, Method, Role, Verdict};
use crate::stats::min_detectable;

/// A table number: four significant digits, scientific notation outside [10⁻³, 10⁴), `—` for
/// none.
pub fn number(x: Option<f64>) -> String {
    x.map_or_else(
        || "—".into(),
        |v| {
            if v == 0.0 {
                "0".into()
            } else if (1e-3..1e4).contains(&v.abs()) {
                let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
                format!("{v:.digits$}")
            } else {
                format!("{v:.3e}")
            }
        },
    )
}

fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// The paragraph that explains the power of the statistical rows.
pub const POWER_NOTE: &str = "**Power.** Every statistical row states its *minimum detectable \
     effect* at power 0.8, one definition for all (`ilopt_theory::stats::min_detectable`): the \
     smallest violation the row flags with probability at least 0.8 (normal approximation), its \
     interval's width plus z₀.₈ = 0.84 standard errors of X̄. A bound row flags every claimed \
     bound B below its LCB (width X̄ − LCB); its minimum detectable violation is X̄ − LCB + \
     0.84·SE. A two-sided row (each states its H₀ below) flags a mean outside its interval; its \
     minimum detectable bias is the larger half-width plus 0.84·SE. A real-environment \
     unbiasedness row (a z-test at z_crit per coordinate) has minimum detectable bias (z_crit + \
     0.84)·SE per coordinate. A bound row is *uninformative* when its LCB is ≤ 0 or its B is at \
     least the largest value its statistic can take; a two-sided row when its interval spans \
     the statistic's range; a real-environment unbiasedness row when some control's bias lies \
     below the row's minimum detectable bias on every coordinate (the row could not have seen \
     it); rows 7a and 7b when X̄ is within two standard errors of 0. A tracking row also states \
     whether it resolves the error of the wrong algorithm run through the same check (its \
     probe or control), from that row's measured bias and minimum detectable bias. Each row's \
     details say which case it is.";

/// A statistical row's minimum detectable effect ([`crate::stats::min_detectable`] at power
/// [`crate::stats::POWER`]): for a bound row the violation X̄ − LCB + z_{0.8}·SE, for a
/// two-sided row the bias max(X̄ − LCB, UCB − X̄) + z_{0.8}·SE. `None` for rows without an
/// interval or without a recorded standard error.
pub fn min_detectable_effect(c: &Check) -> Option<f64> {
    let m = c.measured.as_ref()?;
    let se = m.se?;
    match (power_width(c), two_sided_width(c)) {
        (Some((_, w)), _) | (None, Some((_, _, w))) => Some(min_detectable(w, se)),
        (None, None) => None,
    }
}

/// Each statistical row's power: the interval and minimum detectable bias of a two-sided row
/// (and what it resolves of a known error, when stated), the smallest flagged bound and minimum
/// detectable violation of a bound row; a row with an interval but no standard error says so.
pub fn power_items(checks: &[Check]) -> Vec<String> {
    let mut items = Vec::new();
    let effect = |c: &Check| {
        min_detectable_effect(c).map_or_else(
            || "not stated (no standard error recorded)".to_string(),
            |e| number(Some(e)),
        )
    };
    for c in checks.iter().filter(|c| c.method == Method::Statistical) {
        let m = c.measured.as_ref();
        if let Some((lcb, ucb, _)) = two_sided_width(c) {
            items.push(format!(
                "**{}** ({}): H₀ {}, X̄ = {}, {}, minimum detectable bias {}{} → **{}**",
                c.id,
                c.role.name(),
                m.and_then(|m| m.null_hypothesis.as_deref())
                    .unwrap_or("mean 0"),
                number(m.map(|m| m.value)),
                interval_text(lcb, ucb),
                effect(c),
                m.and_then(|m| m.resolution.as_deref())
                    .map_or_else(String::new, |r| format!("; {r}")),
                c.verdict.name()
            ));
        }
        if let Some((lcb, _)) = power_width(c) {
            items.push(format!(
                "**{}** ({}): B = {}, flags B < {}, minimum detectable violation {} → **{}**",
                c.id,
                c.role.name(),
                number(c.bound),
                number(Some(lcb)),
                effect(c),
                c.verdict.name()
            ));
        }
    }
    items
}

/// `interval [lcb, ucb]`, or, when the two one-sided bounds cross (each side's bound is valid on
/// its own; a mean that varies along the runs can push the lower above the upper), both with
/// that said.
pub fn interval_text(lcb: f64, ucb: f64) -> String {
    if lcb <= ucb {
        format!("interval [{}, {}]", number(Some(lcb)), number(Some(ucb)))
    } else {
        format!(
            "one-sided bounds that cross (lower {} above upper {}: no constant mean fits the runs)",
            number(Some(lcb)),
            number(Some(ucb))
        )
    }
}

/// `id detected` / `id <missed>` for every row of `role` (detected: the check refuted it).
pub fn detections(checks: &[Check], role: Role, missed: &str) -> Vec<String> {
    checks
        .iter()
        .filter(|c| c.role == role)
        .map(|c| {
            let seen = if c.verdict == Verdict::Fails {
                "detected"
            } else {
                missed
            };
            format!("{} {seen}", c.id)
        })
        .collect()
}

/// The probes' detections and what the checks can resolve of the wrong algorithms.
pub fn probes_note(probes: &[String]) -> String {
    format!(
        "Probes (wrong algorithms run through the checks of the corrected ones at the same \
         sizes, reported, not required): {}. The bound rows (2c, 3b) detect none of these \
         errors: on M1 they do not raise the bounded quantity. The tracking rows (2e, 3d) test \
         the property the proofs rest on along each algorithm's iterates; they detect the \
         printed Algorithm 4, which is therefore a negative control there (2e.printed4, \
         required by the status). The biases of the unweighted STORM (E10) and the printed \
         Algorithm 5 (E11) are proportional to the step (η_k‖d_k‖, resp. ‖θ_n − w_n‖ ≤ δ/T); \
         each tracking row states, in the power list, whether its check resolves them at its \
         size (the default rows 2e and 3d are labelled uninformative for E10 and E11 when the \
         probe's measured bias is below the check's minimum detectable bias; the wide-setting \
         rows 2e.c and 3d.c resolve them, and their wrong algorithms are negative controls). \
         A probe that is not detected is a finding about the check's resolution, not a failure \
         of the table. The exact rows 4d–4f detect all three errors.",
        probes.join("; ")
    )
}

/// A statistical bound check's LCB and its minimum detectable violation at power
/// [`crate::stats::POWER`] (X̄ − LCB + z_{0.8}·SE, [`crate::stats::min_detectable`]): it flags
/// every claimed bound below its LCB. `None` for rows without a bound, an LCB or a standard
/// error.
pub fn power(c: &Check) -> Option<(f64, f64)> {
    let (lcb, _) = power_width(c)?;
    Some((lcb, min_detectable_effect(c)?))
}

/// A bound row's LCB and interval width X̄ − LCB.
fn power_width(c: &Check) -> Option<(f64, f64)> {
    c.bound?;
    let m = c.measured.as_ref()?;
    let lcb = m.lcb?;
    Some((lcb, m.value - lcb))
}

/// A two-sided statistical row's power (H₀: mean 0, or the row's stated H₀, no bound; the
/// tracking rows): its interval [LCB, UCB] and its minimum detectable bias
/// max(X̄ − LCB, UCB − X̄) + z_{0.8}·SE ([`crate::stats::ZeroMeanTest::min_detectable_bias`]).
/// `None` for other rows and rows without a standard error.
pub fn two_sided_power(c: &Check) -> Option<(f64, f64, f64)> {
    let (lcb, ucb, _) = two_sided_width(c)?;
    Some((lcb, ucb, min_detectable_effect(c)?))
}

/// A two-sided statistical row's interval and its larger half-width.
fn two_sided_width(c: &Check) -> Option<(f64, f64, f64)> {
    if c.bound.is_some() || c.method != Method::Statistical {
        return None;
    }
    let m = c.measured.as_ref()?;
    let (lcb, ucb) = (m.lcb?, m.ucb?);
    Some((lcb, ucb, (m.value - lcb).max(ucb - m.value)))
}

/// What the α family of the emitted table is: the family claims emitted (each at
/// [`family_level`]), and the rows with a level of their own.
#[derive(Debug, Clone, PartialEq)]
pub struct AlphaFamily {
    /// Claims of [`FAMILY_CLAIMS`] emitted, in table order.
    pub claims: Vec<String>,
    /// Statistical thesis/corrected rows at a level of their own ([`OWN_LEVEL_PREFIXES`]), with
    /// their stated level (if recorded).
    pub own_level: Vec<(String, Option<f64>)>,
}

/// The statistical thesis and corrected rows the table emits, checked against the α family
/// ([`FAMILY_CLAIMS`]): every emitted one is a family claim run at [`family_level`] or carries a
/// level of its own ([`OWN_LEVEL_PREFIXES`]), and every family claim is emitted. Negative
/// controls and probes take no share.
///
/// # Errors
/// The extra, missing and wrongly-levelled ids, as a message.
pub fn alpha_family(checks: &[Check]) -> Result<AlphaFamily, String> {
    let level = family_level();
    let mut fam = AlphaFamily {
        claims: vec![],
        own_level: vec![],
    };
    let (mut extra, mut wrong_level) = (vec![], vec![]);
    for c in checks.iter().filter(|c| {
        c.method == Method::Statistical && matches!(c.role, Role::Thesis | Role::Corrected)
    }) {
        let alpha = c.measured.as_ref().and_then(|m| m.alpha);
        if FAMILY_CLAIMS.contains(&c.id.as_str()) {
            match alpha {
                Some(a) if (a - level).abs() <= 1e-12 * level => {}
                _ => wrong_level.push(format!(
                    "{} (α = {})",
                    c.id,
                    alpha.map_or_else(|| "not recorded".into(), |a| format!("{a:.3e}"))
                )),
            }
            fam.claims.push(c.id.clone());
        } else if OWN_LEVEL_PREFIXES.iter().any(|p| c.id.starts_with(p)) {
            fam.own_level.push((c.id.clone(), alpha));
        } else {
            extra.push(c.id.clone());
        }
    }
    let missing: Vec<&str> = FAMILY_CLAIMS
        .iter()
        .copied()
        .filter(|id| !fam.claims.iter().any(|c| c == id))
        .collect();
    let mut problems = vec![];
    if !extra.is_empty() {
        problems.push(format!(
            "statistical row(s) outside the α family and not at a level of their own: {}",
            extra.join(", ")
        ));
    }
    if !missing.is_empty() {
        problems.push(format!(
            "α-family claim(s) not emitted: {}",
            missing.join(", ")
        ));
    }
    if !wrong_level.is_empty() {
        problems.push(format!(
            "α-family claim(s) not run at α = {FAMILY_ALPHA}/{STATISTICAL_CLAIMS} = {level:.3e}: {}",
            wrong_level.join(", ")
        ));
    }
    if problems.is_empty() {
        Ok(fam)
    } else {
        Err(problems.join("; "))
    }
}

/// The rows whose verdict contradicts what the table expects of them ([`Check::expected`]):
/// `Err` naming every claim expected to hold that fails, every thesis claim refuted by its
/// erratum that the check did not refute, and every negative control not detected; `Ok`
/// otherwise. An uninformative or inconclusive verdict on a claim expected to hold does not
/// fail the status (it is no evidence either way); it is listed
/// ([`uninformative_and_controls`]). Probes are never required.
///
/// # Errors
/// The offending ids, by kind, as a message.
pub fn expectation_status(checks: &[Check]) -> Result<(), String> {
    let ids = |want: Expected| -> Vec<&str> {
        checks
            .iter()
            .filter(|c| c.expected() == want && c.unexpected())
            .filter(|c| want == Expected::Holds || c.role != Role::NegativeControl)
            .map(|c| c.id.as_str())
            .collect()
    };
    let failed = ids(Expected::Holds);
    let unrefuted = ids(Expected::Fails);
    let missed: Vec<&str> = checks
        .iter()
        .filter(|c| c.undetected_control())
        .map(|c| c.id.as_str())
        .collect();
    let mut problems = vec![];
    if !failed.is_empty() {
        problems.push(format!(
            "claim(s) expected to hold fail: {}",
            failed.join(", ")
        ));
    }
    if !unrefuted.is_empty() {
        problems.push(format!(
            "thesis claim(s) refuted by their erratum not refuted by the check: {}",
            unrefuted.join(", ")
        ));
    }
    if !missed.is_empty() {
        problems.push(format!(
            "negative control(s) not detected: {}",
            missed.join(", ")
        ));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// The table's overall status: [`expectation_status`] (every claim expected to hold holds,
/// every thesis claim its erratum refutes and every negative control is detected) and
/// [`alpha_family`] (the statistical claims emitted are exactly the α family's, each at its
/// level). `Err` names every offending row.
///
/// # Errors
/// Both parts' messages, joined.
pub fn status(checks: &[Check]) -> Result<(), String> {
    let problems: Vec<String> = [expectation_status(checks).err(), alpha_family(checks).err()]
        .into_iter()
        .flatten()
        .collect();
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// The start of the passing status line (what CI checks for).
pub const STATUS_PASSES: &str = "Status: passes";

/// The status line, bold: "Status: passes — …" naming what passed (the expectations and the α
/// family, with its size and level), or "Status: FAILS — …" naming every offending row.
pub fn status_line(checks: &[Check]) -> String {
    match (status(checks), alpha_family(checks)) {
        (Ok(()), Ok(fam)) => format!(
            "**{STATUS_PASSES} — every claim expected to hold holds, every thesis claim its \
             erratum refutes and every negative control is detected, and the statistical claims \
             are the α family's {} (each at α = {FAMILY_ALPHA}/{} = {:.3e}){}**",
            fam.claims.len(),
            STATISTICAL_CLAIMS,
            family_level(),
            own_level_text(&fam)
        ),
        (Err(e), _) | (Ok(()), Err(e)) => format!("**Status: FAILS — {e}**"),
    }
}

/// `; real-environment rows at a level of their own: α = 1e-3 each: 6a, 6a.is-tr, …` (grouped by
/// level; empty when there are none).
fn own_level_text(fam: &AlphaFamily) -> String {
    if fam.own_level.is_empty() {
        return String::new();
    }
    let mut groups: Vec<(String, Vec<&str>)> = vec![];
    for (id, a) in &fam.own_level {
        let level = a.map_or_else(|| "α not recorded".into(), |a| format!("α = {a:.0e} each"));
        match groups.iter_mut().find(|(l, _)| *l == level) {
            Some((_, ids)) => ids.push(id),
            None => groups.push((level, vec![id])),
        }
    }
    let text: Vec<String> = groups
        .into_iter()
        .map(|(level, ids)| format!("{level}: {}", ids.join(", ")))
        .collect();
    format!(
        "; real-environment rows at a level of their own: {}",
        text.join("; ")
    )
}

/// The sentence naming the rows that decided nothing, the thesis claims refuted by their errata,
/// and each negative control's detection: "Uninformative or inconclusive rows (…): ….
/// Thesis claims refuted by their errata (expected to fail): …. Negative controls: …."
pub fn uninformative_and_controls(checks: &[Check]) -> String {
    let undecided: Vec<String> = checks
        .iter()
        .filter(|c| matches!(c.verdict, Verdict::Uninformative | Verdict::Inconclusive))
        .map(|c| {
            if c.verdict == Verdict::Inconclusive {
                format!("{} (inconclusive)", c.id)
            } else {
                c.id.clone()
            }
        })
        .collect();
    let refuted: Vec<String> = checks
        .iter()
        .filter(|c| c.role != Role::NegativeControl && c.expected() == Expected::Fails)
        .map(|c| {
            format!(
                "{} {}",
                c.id,
                if c.verdict == Verdict::Fails {
                    "refuted"
                } else {
                    "NOT refuted"
                }
            )
        })
        .collect();
    let controls = detections(checks, Role::NegativeControl, "NOT detected");
    let or_none = |v: String| if v.is_empty() { "none".into() } else { v };
    format!(
        "Uninformative or inconclusive rows (no evidence either way; not a failure of the \
         status): {}. Thesis claims refuted by their errata (expected to fail): {}. Negative \
         controls: {}.",
        or_none(undecided.join(", ")),
        or_none(refuted.join("; ")),
        or_none(controls.join("; "))
    )
}

/// The statements the table does not check, one list item each with its reason
/// ([`crate::checks::unchecked::UNCHECKED`]).
pub fn unchecked_items() -> Vec<String> {
    crate::checks::unchecked::UNCHECKED
        .iter()
        .map(|u| format!("{}: {}.", u.statement, escape(u.reason)))
        .collect()
}

/// The Markdown table (one row per check), the closing note (every statistical row with its
/// power and verdict, the uninformative rows, the controls and the overall status), then the
/// details with the constants and their provenance.
pub fn markdown(checks: &[Check]) -> String {
    let mut out = String::from(
        "| # | result | claim | role | method | bound B | measured (LCB) | min. detectable violation | X̄/B | verdict | erratum |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for c in checks {
        let measured = c.measured.as_ref().map_or_else(
            || "—".into(),
            |m| match m.lcb {
                Some(l) => format!("{} ({})", number(Some(m.value)), number(Some(l))),
                None => number(Some(m.value)),
            },
        );
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | **{}** | {} |\n",
            c.id,
            escape(&c.result),
            escape(&c.claim),
            c.role.name(),
            c.method.name(),
            number(c.bound),
            measured,
            number(min_detectable_effect(c)),
            number(c.tightness),
            c.verdict.name(),
            c.erratum.as_deref().unwrap_or("—"),
        );
    }
    out += &format!("\n{POWER_NOTE}\n\n");
    for item in power_items(checks) {
        out += &format!("- {item}\n");
    }
    let probes = detections(checks, Role::Probe, "not detected");
    if !probes.is_empty() {
        out += &format!("\n{}\n", probes_note(&probes));
    }
    out += &format!(
        "\n{}\n\n{}\n",
        uninformative_and_controls(checks),
        status_line(checks)
    );
    out += "\n**Not checked, and why.**\n\n";
    for item in unchecked_items() {
        out += &format!("- {item}\n");
    }
    out += "\n**Details.**\n\n";
    for c in checks {
        out += &format!("- **{}** {}\n", c.id, escape(&c.details));
        for k in &c.constants {
            let prov = k.provenance.name();
            out += &format!(
                "  - {} = {:.6} ({prov}; {})\n",
                k.name,
                k.value,
                escape(&k.how)
            );
        }
    }
    out
}

/// The JSON report (every field, certificates included); each statistical bound row also carries
/// `"power": {"flags_bounds_below": LCB, "min_detectable_violation": …}`, each two-sided row
/// `"power": {"interval": [LCB, UCB], "min_detectable_bias": …}` (both at power 0.8,
/// [`min_detectable_effect`]), each negative control `"detected": bool`, and every row
/// `"expected": "holds" | "fails" | "either"` ([`Check::expected`]).
///
/// # Panics
/// Never: every field serialises.
pub fn json(checks: &[Check]) -> serde_json::Value {
    let rows = checks
        .iter()
        .map(|c| {
            let mut v = serde_json::to_value(c).expect("serialisable");
            if let Some(obj) = v.as_object_mut() {
                if let Some((lcb, mdv)) = power(c) {
                    obj.insert(
                        "power".into(),
                        serde_json::json!({
                            "flags_bounds_below": lcb,
                            "min_detectable_violation": mdv,
                        }),
                    );
                }
                if let Some((lcb, ucb, mdb)) = two_sided_power(c) {
                    obj.insert(
                        "power".into(),
                        serde_json::json!({
                            "interval": [lcb, ucb],
                            "min_detectable_bias": mdb,
                        }),
                    );
                }
                if c.role == Role::NegativeControl {
                    obj.insert("detected".into(), (c.verdict == Verdict::Fails).into());
                }
                obj.insert(
                    "expected".into(),
                    serde_json::to_value(c.expected()).expect("serialisable"),
                );
            }
            v
        })
        .collect();
    serde_json::Value::Array(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::check::Measured;

    fn two_sided(id: &str, m: Measured, verdict: Verdict) -> Check {
        Check::builder(id, "r", "c", Role::Corrected)
            .measured(m)
            .decided(Method::Statistical, verdict)
    }

    /// A two-sided row states its own null hypothesis (mean 0 unless the row names another),
    /// and bounds that cross are said to cross rather than printed as an interval.
    #[test]
    fn the_power_list_states_each_rows_hypothesis_and_crossed_bounds() {
        let zero = two_sided(
            "2e",
            Measured::statistic(1e-6).with_interval(-1e-5, 2e-5),
            Verdict::Holds,
        );
        let midpoint = two_sided(
            "5e.1",
            Measured::statistic(0.66)
                .with_interval(0.648, 0.667)
                .with_null_hypothesis("E p_K = 0.54, the midpoint"),
            Verdict::Holds,
        );
        let crossed = two_sided(
            "2e.printed4",
            Measured::statistic(-0.05547).with_interval(-0.05552, -0.05599),
            Verdict::Fails,
        );
        let items = power_items(&[zero, midpoint, crossed]);
        assert!(
            items[0].contains("H₀ mean 0,") && items[0].contains("interval [-1.000e-5, 2.000e-5]")
        );
        assert!(
            items[1].contains("H₀ E p_K = 0.54, the midpoint,") && !items[1].contains("mean 0")
        );
        assert!(
            items[2].contains("cross") && !items[2].contains("interval ["),
            "{}",
            items[2]
        );
        assert_eq!(interval_text(1.0, 1.0), "interval [1.000, 1.000]");
    }

    fn row(id: &str, role: Role, method: Method, verdict: Verdict) -> Check {
        Check::builder(id, "r", "c", role).decided(method, verdict)
    }

    /// A statistical claim of the α family at `alpha`.
    fn claim_at(id: &str, alpha: f64) -> Check {
        Check::builder(id, "r", "c", Role::Corrected)
            .measured(
                Measured::statistic(0.5)
                    .with_interval(0.4, 0.6)
                    .with_se(0.01)
                    .with_alpha(alpha),
            )
            .decided(Method::Statistical, Verdict::Holds)
    }

    /// Every claim of the family at its level, a real-environment row at its own level, a
    /// refuted thesis claim that fails and a detected control: the table passes.
    fn passing_table() -> Vec<Check> {
        let mut rows: Vec<Check> = FAMILY_CLAIMS
            .iter()
            .map(|id| claim_at(id, family_level()))
            .collect();
        rows.push(claim_at("6a", 1e-3));
        rows.push(
            Check::builder("4d", "r", "c", Role::Thesis)
                .erratum("E10")
                .refuted_by_erratum()
                .decided(Method::Exact, Verdict::Fails),
        );
        rows.push(row(
            "1.ctl",
            Role::NegativeControl,
            Method::Statistical,
            Verdict::Fails,
        ));
        rows.push(row(
            "2e.unweighted",
            Role::Probe,
            Method::Statistical,
            Verdict::Holds,
        ));
        rows
    }

    #[test]
    fn a_table_that_meets_every_expectation_passes_and_says_what_passed() {
        let rows = passing_table();
        assert_eq!(status(&rows), Ok(()));
        let line = status_line(&rows);
        assert!(line.starts_with(&format!("**{STATUS_PASSES} —")), "{line}");
        assert!(
            line.contains(&format!("the α family's {STATISTICAL_CLAIMS}")),
            "{line}"
        );
        assert!(line.contains("α = 1e-3 each: 6a"), "{line}");
        // CI checks for exactly this line.
        assert!(
            include_str!("../../.ci/run").contains(&format!("grep -q \"{STATUS_PASSES} —\"")),
            "the CI grep of the status line is out of date"
        );
    }

    /// A claim expected to hold that fails (row 8 failing) fails the status, named; so does a
    /// refuted thesis claim the check did not refute, and an undetected control.
    #[test]
    fn a_failing_corrected_claim_fails_the_status_and_is_named() {
        let mut rows = passing_table();
        rows.push(row("8", Role::Corrected, Method::Rigorous, Verdict::Fails));
        let e = status(&rows).expect_err("row 8 fails");
        assert!(e.contains("claim(s) expected to hold fail: 8"), "{e}");
        assert!(
            status_line(&rows).starts_with("**Status: FAILS — claim(s) expected to hold fail: 8")
        );
        let mut rows = passing_table();
        let d = rows.iter_mut().find(|c| c.id == "4d").expect("4d");
        d.verdict = Verdict::Holds;
        let e = status(&rows).expect_err("4d not refuted");
        assert!(e.contains("not refuted by the check: 4d"), "{e}");
        let mut rows = passing_table();
        rows.iter_mut()
            .find(|c| c.id == "1.ctl")
            .expect("control")
            .verdict = Verdict::Holds;
        let e = status(&rows).expect_err("control missed");
        assert!(e.contains("negative control(s) not detected: 1.ctl"), "{e}");
        assert!(!e.contains("expected to hold"), "{e}");
    }

    /// An uninformative or inconclusive claim does not fail the status but is listed; a probe
    /// that fails or holds is never required.
    #[test]
    fn undecided_claims_are_listed_and_probes_never_required() {
        let mut rows = passing_table();
        rows.push(row(
            "7a",
            Role::Thesis,
            Method::Estimate,
            Verdict::Uninformative,
        ));
        rows.push(row(
            "4e",
            Role::Corrected,
            Method::Exact,
            Verdict::Inconclusive,
        ));
        rows.push(row(
            "2c.printed4",
            Role::Probe,
            Method::Exact,
            Verdict::Fails,
        ));
        assert_eq!(status(&rows), Ok(()));
        let text = uninformative_and_controls(&rows);
        assert!(text.contains("7a, 4e (inconclusive)"), "{text}");
        assert!(text.contains("4d refuted"), "{text}");
        assert!(text.contains("1.ctl detected"), "{text}");
    }

    /// The emitted statistical claims must be the α family's, each at its level: an extra row,
    /// a missing claim and a claim at another level each fail the status, named.
    #[test]
    fn the_alpha_family_is_counted_from_the_emitted_rows() {
        assert_eq!(
            alpha_family(&passing_table()).map(|f| f.claims.len()),
            Ok(STATISTICAL_CLAIMS)
        );
        let mut extra = passing_table();
        extra.push(claim_at("9", family_level()));
        let e = status(&extra).expect_err("an extra statistical claim");
        assert!(e.contains("not at a level of their own: 9"), "{e}");
        let missing: Vec<Check> = passing_table()
            .into_iter()
            .filter(|c| c.id != "2e.c")
            .collect();
        let e = status(&missing).expect_err("a missing claim");
        assert!(e.contains("not emitted: 2e.c"), "{e}");
        let mut wrong = passing_table();
        wrong
            .iter_mut()
            .find(|c| c.id == "3d.c")
            .expect("3d.c")
            .measured = claim_at("x", 0.01 / 11.0).measured;
        let e = status(&wrong).expect_err("a claim at another level");
        assert!(e.contains("3d.c (α = 9.091e-4)"), "{e}");
        // Controls, probes and non-statistical rows take no share.
        let mut more = passing_table();
        more.push(row(
            "9.ctl",
            Role::NegativeControl,
            Method::Statistical,
            Verdict::Fails,
        ));
        more.push(row(
            "9.probe",
            Role::Probe,
            Method::Statistical,
            Verdict::Holds,
        ));
        more.push(row(
            "9.exact",
            Role::Corrected,
            Method::Exact,
            Verdict::Holds,
        ));
        assert_eq!(status(&more), Ok(()));
    }

    /// One minimum detectable effect for bound and two-sided rows: the width plus z₀.₈·SE; a row
    /// without a standard error states none.
    #[test]
    fn the_minimum_detectable_effect_is_the_width_plus_the_power_quantile() {
        let bound = Check::builder("1", "r", "c", Role::Thesis)
            .bound(0.3)
            .measured(
                Measured::statistic(0.014)
                    .with_interval(0.013, 0.02)
                    .with_se(1e-4),
            )
            .decided(Method::Statistical, Verdict::Holds);
        let e = min_detectable_effect(&bound).expect("stated");
        assert!(
            (e - (0.001 + crate::stats::POWER_Z * 1e-4)).abs() < 1e-15,
            "{e}"
        );
        assert_eq!(power(&bound), Some((0.013, e)));
        let two = claim_at("2e", 1e-3);
        let e2 = min_detectable_effect(&two).expect("stated");
        assert!(
            (e2 - (0.1 + crate::stats::POWER_Z * 0.01)).abs() < 1e-12,
            "{e2}"
        );
        let no_se = two_sided(
            "x",
            Measured::statistic(0.0).with_interval(-1.0, 1.0),
            Verdict::Holds,
        );
        assert_eq!(min_detectable_effect(&no_se), None);
        assert!(power_items(&[no_se])[0].contains("not stated"));
    }
}
