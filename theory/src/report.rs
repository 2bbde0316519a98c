//! The theorem-check table as Markdown and JSON (for the appendix).

use crate::check::{Check, Method, Role, Verdict};
use crate::constants::Provenance;

/// Four significant digits, scientific notation outside [10⁻³, 10⁴).
fn fmt(x: Option<f64>) -> String {
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

/// The Markdown table (one row per check) followed by the constants with their provenance.
pub fn markdown(checks: &[Check]) -> String {
    let mut out = String::from(
        "| # | result | claim | role | method | bound B | measured (LCB) | X̄/B | verdict | erratum |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for c in checks {
        let measured = c.measured.as_ref().map_or_else(
            || "—".into(),
            |m| match m.lcb {
                Some(l) => format!("{} ({})", fmt(Some(m.value)), fmt(Some(l))),
                None => fmt(Some(m.value)),
            },
        );
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | **{}** | {} |\n",
            c.id,
            escape(&c.result),
            escape(&c.claim),
            match c.role {
                Role::Thesis => "thesis",
                Role::Corrected => "corrected",
                Role::NegativeControl => "negative control",
            },
            match c.method {
                Method::Exact => "exact",
                Method::Rigorous => "rigorous",
                Method::Statistical => "statistical",
                Method::Estimate => "estimate",
            },
            fmt(c.bound),
            measured,
            fmt(c.tightness),
            match c.verdict {
                Verdict::Holds => "holds",
                Verdict::Fails => "fails",
                Verdict::Inconclusive => "inconclusive",
            },
            c.erratum.as_deref().unwrap_or("—"),
        );
    }
    out += "\n**Details.**\n\n";
    for c in checks {
        out += &format!("- **{}** {}\n", c.id, escape(&c.details));
        for k in &c.constants {
            let prov = match k.provenance {
                Provenance::Exact => "exact",
                Provenance::Rigorous => "rigorous upper bound",
                Provenance::Estimate => "ESTIMATE (not a certificate)",
            };
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

/// The JSON report (every field, certificates included).
///
/// # Panics
/// Never: every field serialises.
pub fn json(checks: &[Check]) -> serde_json::Value {
    serde_json::to_value(checks).expect("serialisable")
}
