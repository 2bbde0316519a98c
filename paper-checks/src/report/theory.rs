//! The theorem-check section, built from `ilopt-theory`'s check records ([`Check`]).
//!
//! The wide check table is split in two (what is claimed; what was measured), both keyed by the
//! check's id, so each fits a printed page. The power notes, the controls and the overall status
//! follow as `ilopt-theory`'s own table states them. Constants shared by several checks (the
//! certified constants of the real-environment rows) appear once, in one table with their
//! certificate (exact, rigorous upper bound or estimate, and how it was obtained) and the checks
//! that use them; each check's details refer to the table's rows.

use super::blocks::{Block, Table};
use crate::config::TheorySize;
use crate::results::TheoryTable;
use ilopt_theory::check::{Check, Role};
use ilopt_theory::report::{
    POWER_NOTE, detections, min_detectable_effect, number, power_items, probes_note, status_line,
    unchecked_items, uninformative_and_controls,
};
use std::collections::BTreeMap;

/// Free text as one table cell or list item: on one line, without surrounding blanks.
fn one_line(s: &str) -> String {
    s.replace('\n', " ").trim().to_string()
}

/// The claim half of a check's row: id, result, claim, role, verdict, erratum.
fn claim_cells(c: &Check) -> Vec<String> {
    vec![
        one_line(&c.id),
        one_line(&c.result),
        one_line(&c.claim),
        c.role.name().into(),
        format!("**{}**", c.verdict.name()),
        one_line(c.erratum.as_deref().unwrap_or("—")),
    ]
}

/// The measurement half of a check's row: id, method, the bound B, the measured value with its
/// lower confidence bound, the minimum detectable violation (or bias), X̄/B, verdict.
fn number_cells(c: &Check) -> Vec<String> {
    let measured = c.measured.as_ref().map_or_else(
        || "—".into(),
        |m| match m.lcb {
            Some(l) => format!("{} ({})", number(Some(m.value)), number(Some(l))),
            None => number(Some(m.value)),
        },
    );
    let detectable = min_detectable_effect(c);
    vec![
        one_line(&c.id),
        c.method.name().into(),
        number(c.bound),
        measured,
        number(detectable),
        number(c.tightness),
        format!("**{}**", c.verdict.name()),
    ]
}

/// The two check tables: the claims with their verdicts, and the bounds and measurements of the
/// same rows.
fn check_tables(checks: &[Check], label: &str) -> [Block; 2] {
    let header = |h: &[&str]| h.iter().map(|s| (*s).to_string()).collect();
    [
        Block::Table(Table {
            caption: Some("Theorem checks: the claims and their verdicts".into()),
            label: format!("{label}-1-claims"),
            header: header(&["#", "result", "claim", "role", "verdict", "erratum"]),
            rows: checks.iter().map(claim_cells).collect(),
            spec: "lllllr".into(),
        }),
        Block::Table(Table {
            caption: Some("Theorem checks: bounds and measurements (same rows)".into()),
            label: format!("{label}-1-numbers"),
            header: header(&[
                "#",
                "method",
                "bound B",
                "measured (LCB)",
                "min. detectable violation",
                "X̄/B",
                "verdict",
            ]),
            rows: checks.iter().map(number_cells).collect(),
            spec: "llrrrrl".into(),
        }),
    ]
}

/// What a statistical row can detect.
/// The notes under the check tables: power, probes, uninformative rows, negative controls and
/// the table's status ([`status_line`]: every row meets its expectation and the α family is the
/// one emitted).
fn notes(checks: &[Check]) -> Vec<Block> {
    let mut out = vec![Block::Para(POWER_NOTE.into())];
    let items = power_items(checks);
    if !items.is_empty() {
        out.push(Block::List(items));
    }
    let probes = detections(checks, Role::Probe, "not detected");
    if !probes.is_empty() {
        out.push(Block::Para(probes_note(&probes)));
    }
    out.push(Block::Para(uninformative_and_controls(checks)));
    out.push(Block::Para(status_line(checks)));
    out.push(Block::Para("**Not checked, and why.**".into()));
    out.push(Block::List(unchecked_items()));
    out
}

/// One constant as the constants table shows it: name, value, certificate kind and how it was
/// obtained.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConstantRow {
    /// The constant's name (`L_F`, `σ²`, …).
    pub name: String,
    /// The value, six decimals.
    pub value: String,
    /// `exact`, `rigorous upper bound` or `ESTIMATE (not a certificate)`.
    pub certificate: String,
    /// How it was obtained.
    pub how: String,
}

impl ConstantRow {
    fn of(k: &ilopt_theory::constants::Constant) -> Self {
        ConstantRow {
            name: k.name.trim().to_string(),
            value: format!("{:.6}", k.value),
            certificate: k.provenance.name().into(),
            how: one_line(&k.how),
        }
    }
}

/// The constants table (each distinct constant once, `K1`, `K2`, … in order of first use, with
/// the checks using it) and the details list referring to it.
fn details_blocks(checks: &[Check], label: &str) -> Vec<Block> {
    let mut constants: Vec<(ConstantRow, Vec<String>)> = Vec::new();
    let mut items = Vec::new();
    for c in checks {
        let id = one_line(&c.id);
        let mut refs = Vec::new();
        for k in c.constants.iter().map(ConstantRow::of) {
            let j = match constants.iter().position(|(seen, _)| *seen == k) {
                Some(j) => j,
                None => {
                    constants.push((k, vec![]));
                    constants.len() - 1
                }
            };
            if !constants[j].1.contains(&id) {
                constants[j].1.push(id.clone());
            }
            refs.push(format!("K{}", j + 1));
        }
        // Details are Markdown inline text: a `|` stays escaped.
        let text = one_line(&c.details.replace('|', "\\|"));
        let mut item = format!("**{id}** {text}");
        if !refs.is_empty() {
            let stop = if item.ends_with('.') { "" } else { "." };
            item += &format!(
                "{stop} Constants: {} (table of constants).",
                refs.join(", ")
            );
        }
        items.push(item);
    }
    let mut blocks = Vec::new();
    if !constants.is_empty() {
        blocks.push(Block::Para(
            "**Constants.** Every constant the checks use, once, with its certificate: *exact*, \
             a *rigorous upper bound* (interval arithmetic), or an *estimate* (not a certificate); \
             the details below refer to the rows by their K numbers."
                .into(),
        ));
        blocks.push(Block::Table(Table {
            caption: Some("Constants of the theorem checks and their certificates".into()),
            label: format!("{label}-constants"),
            header: ["K", "constant", "value", "certificate", "how", "used by"]
                .iter()
                .map(|s| (*s).to_string())
                .collect(),
            rows: constants
                .iter()
                .enumerate()
                .map(|(j, (c, users))| {
                    vec![
                        format!("K{}", j + 1),
                        c.name.clone(),
                        c.value.clone(),
                        c.certificate.clone(),
                        c.how.clone(),
                        users.join(", "),
                    ]
                })
                .collect(),
            spec: "llrlll".into(),
        }));
    }
    if !items.is_empty() {
        blocks.push(Block::Para("**Details.**".into()));
        blocks.push(Block::List(items));
    }
    blocks
}

/// The theorem-check section's blocks: the check tables, the notes and status, then the
/// constants once and the details referring to them; tables are labelled `label-…`.
pub fn blocks(table: &TheoryTable, size: TheorySize, label: &str) -> Vec<Block> {
    let TheoryTable::Checks(checks) = table else {
        return vec![Block::Para(
            "*Not run: `theory_profile = \"none\"` (in the profile, or `--theory none`). Run \
             `cargo run --release -p ilopt-theory`, or this appendix with `--theory quick` or \
             `--theory full`.*"
                .into(),
        )];
    };
    let mut out = vec![Block::Para(size_text(size))];
    out.extend(Vec::<Block>::from(check_tables(checks, label)));
    out.extend(notes(checks));
    out.extend(details_blocks(checks, label));
    out
}

/// Which size of the table this is, with the main sizes that differ between the two (from
/// `ilopt-theory`'s protocol, so that the text follows the code), and how to run the other.
fn size_text(size: TheorySize) -> String {
    use ilopt_theory::certify::recheck::QUICK_SAMPLE;
    use ilopt_theory::protocol::{Profile, real_sizes};
    let of = |p: Profile| {
        let (s, (cp, ob)) = (p.sizes(), real_sizes(p));
        let (recheck, episodic) = match p {
            Profile::Full => ("every box".to_string(), "with"),
            Profile::Quick => (
                format!(
                    "a seeded sample of {QUICK_SAMPLE} boxes per region and every box within 1 % \
                     of the certified bound"
                ),
                "without",
            ),
        };
        format!(
            "the STORM schedule rows (2a, 2b) checked to k = {}; R = {} runs in the toy SGD \
             and O2NC rows (1, 3b, 3d) and {} in the STORM rows (2c, 2e); {} (CartPole) and {} \
             (obstacle) oracle estimates in the real-environment unbiasedness rows (6a, 6b); the \
             rigorous constants' certificates re-checked by the independent second route on {recheck}; \
             {episodic} the rows of the obstacle task's episodic control objective (6e)",
            s.schedule_k, s.runs, s.storm_runs, cp.n_oracle, ob.n_oracle
        )
    };
    let (this, other, other_name, flag) = if size == TheorySize::Full {
        (of(Profile::Full), of(Profile::Quick), "quick", " --full")
    } else {
        (of(Profile::Quick), of(Profile::Full), "full", "")
    };
    format!(
        "This is the **{size}** theorem table, as `ilopt-theory{flag}` prints it, real-environment \
         rows included. Its main sizes (rows that use others give them in their details): {this}. \
         The {other_name} table has {other}; this appendix regenerated with `--theory {other_name}` \
         holds it instead (with `--theory none`, no table)."
    )
}

/// The ids of the checks of each erratum (`E1`, `E2`, …), in table order.
pub fn checks_by_erratum(checks: &[Check]) -> BTreeMap<String, Vec<String>> {
    let mut m: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for c in checks {
        if let Some(e) = c.erratum.as_deref().map(str::trim)
            && e.starts_with('E')
        {
            m.entry(e.to_string())
                .or_default()
                .push(c.id.trim().to_string());
        }
    }
    m
}

#[cfg(test)]
mod size_tests {
    use super::size_text;
    use ilopt_theory::protocol::Profile;

    /// Each size's text names itself, its own command and the other size's flag, with the sizes
    /// of `ilopt-theory`'s protocol.
    #[test]
    fn the_table_says_which_size_it_is() {
        let quick = size_text(crate::config::TheorySize::Quick);
        assert!(quick.starts_with("This is the **quick** theorem table, as `ilopt-theory` prints"));
        let k = |p: Profile| format!("k = {}", p.sizes().schedule_k);
        assert!(quick.contains(&k(Profile::Quick)) && quick.contains("`--theory full`"));
        let full = size_text(crate::config::TheorySize::Full);
        assert!(full.starts_with("This is the **full** theorem table, as `ilopt-theory --full`"));
        assert!(full.contains(&k(Profile::Full)) && full.contains("`--theory quick`"));
        assert!(full.find("on every box") < full.find("a seeded sample"));
        assert!(quick.find("a seeded sample") < quick.find("on every box"));
    }
}
