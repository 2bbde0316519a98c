//! The theorem-check table as Markdown and JSON (for the appendix).

use crate::record::check::{Check, Method, Role, Verdict};

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
pub const POWER_NOTE: &str = "**Power.** A statistical bound row flags every claimed bound B \
     below its LCB; its minimum detectable violation is X̄ − LCB; it is *uninformative* when its \
     LCB is ≤ 0 or its B is at least the largest value its statistic can take. A two-sided row \
     (each states its H₀ below) is uninformative when its interval spans the statistic's range; a \
     real-environment unbiasedness row when some control's bias lies below the row's minimum \
     detectable bias on every coordinate (the row could not have seen it); rows 7a and 7b when X̄ \
     is within two standard errors of 0. Each row's details say which case it is.";

/// Each statistical row's power: the interval and minimum detectable bias of a two-sided row,
/// the smallest flagged bound and minimum detectable violation of a bound row.
pub fn power_items(checks: &[Check]) -> Vec<String> {
    let mut items = Vec::new();
    for c in checks.iter().filter(|c| c.method == Method::Statistical) {
        if let Some((lcb, ucb, bias)) = two_sided_power(c) {
            let m = c.measured.as_ref();
            items.push(format!(
                "**{}** ({}): H₀ {}, X̄ = {}, {}, minimum detectable bias {} → **{}**",
                c.id,
                c.role.name(),
                m.and_then(|m| m.null_hypothesis.as_deref())
                    .unwrap_or("mean 0"),
                number(m.map(|m| m.value)),
                interval_text(lcb, ucb),
                number(Some(bias)),
                c.verdict.name()
            ));
        }
        if let Some((lcb, violation)) = power(c) {
            items.push(format!(
                "**{}** ({}): B = {}, flags B < {}, minimum detectable violation {} → **{}**",
                c.id,
                c.role.name(),
                number(c.bound),
                number(Some(lcb)),
                number(Some(violation)),
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
         Algorithm 5 (E11) are proportional to the step (η_k‖d_k‖, resp. ‖θ_n − w_n‖ ≤ δ/T), \
         below the tracking rows' minimum detectable bias at these sizes, so rows \
         2e.unweighted and 3d.printed5 stay probes; a probe that is not detected is a finding \
         about the check's resolution, not a failure of the table. The exact rows 4d–4f detect \
         all three errors.",
        probes.join("; ")
    )
}

/// A statistical bound check's power: it flags every claimed bound below its LCB, and its
/// minimum detectable violation is X̄ − LCB (see [`crate::stats`]). `None` for rows without a
/// bound or an LCB.
pub fn power(c: &Check) -> Option<(f64, f64)> {
    c.bound?;
    let m = c.measured.as_ref()?;
    let lcb = m.lcb?;
    Some((lcb, m.value - lcb))
}

/// A two-sided statistical row's power (H₀: mean 0, no bound; the tracking rows): its interval
/// [LCB, UCB] and its minimum detectable bias max(X̄ − LCB, UCB − X̄)
/// ([`crate::stats::ZeroMeanTest`]). `None` for other rows.
pub fn two_sided_power(c: &Check) -> Option<(f64, f64, f64)> {
    if c.bound.is_some() || c.method != Method::Statistical {
        return None;
    }
    let m = c.measured.as_ref()?;
    let (lcb, ucb) = (m.lcb?, m.ucb?);
    Some((lcb, ucb, (m.value - lcb).max(ucb - m.value)))
}

/// The table's overall status: `Err` naming every negative control that its check did not
/// detect (a check that cannot flag its control shows no power), `Ok` otherwise.
///
/// # Errors
/// The undetected controls' ids, as a message.
pub fn status(checks: &[Check]) -> Result<(), String> {
    let missed: Vec<&str> = checks
        .iter()
        .filter(|c| c.undetected_control())
        .map(|c| c.id.as_str())
        .collect();
    if missed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "negative control(s) not detected: {}",
            missed.join(", ")
        ))
    }
}

/// The sentence naming the uninformative rows and each negative control's detection:
/// "Uninformative rows: …. Negative controls: …."
pub fn uninformative_and_controls(checks: &[Check]) -> String {
    let uninformative: Vec<&str> = checks
        .iter()
        .filter(|c| c.verdict == Verdict::Uninformative)
        .map(|c| c.id.as_str())
        .collect();
    let controls = detections(checks, Role::NegativeControl, "NOT detected");
    let or_none = |v: String| if v.is_empty() { "none".into() } else { v };
    format!(
        "Uninformative rows: {}. Negative controls: {}.",
        or_none(uninformative.join(", ")),
        or_none(controls.join("; "))
    )
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
            number(power(c).map(|p| p.1).or(two_sided_power(c).map(|p| p.2))),
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
        "\n{}\n\n**Status: {}**\n",
        uninformative_and_controls(checks),
        match status(checks) {
            Ok(()) => "every negative control detected".to_string(),
            Err(e) => format!("FAILS — {e}"),
        }
    );
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
/// `"power": {"flags_bounds_below": LCB, "min_detectable_violation": X̄ − LCB}`, each two-sided
/// row `"power": {"interval": [LCB, UCB], "min_detectable_bias": …}`, and each negative control
/// `"detected": bool`.
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
}
