//! The theorem-check section, built from the Markdown that `ilopt-theory` writes.
//!
//! That Markdown lists the constants of every check under the check's details, so constants
//! shared by several checks (the certified constants of the real-environment rows) repeat under
//! every row. Here each distinct constant appears once, in one table with its certificate (exact,
//! rigorous upper bound or estimate, and how it was obtained) and the checks that use it; each
//! check's details refer to the table's rows. The wide check table is split in two (what is
//! claimed; what was measured), both keyed by the check's id, so each fits a printed page.

use super::doc::{Block, Table, from_markdown};

/// One constant of the details: its name, value, certificate kind and how it was obtained.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Constant {
    /// The constant's name (`L_F`, `σ²`, …).
    pub name: String,
    /// The value as printed.
    pub value: String,
    /// `exact`, `rigorous upper bound` or `ESTIMATE (not a certificate)`.
    pub certificate: String,
    /// How it was obtained.
    pub how: String,
}

/// One check's details: its id, the text, and its constants.
#[derive(Debug, Clone, PartialEq)]
pub struct Details {
    /// The check's id (`1a`, `8`, …).
    pub id: String,
    /// The details' text (Markdown inline).
    pub text: String,
    /// The constants, in the order printed.
    pub constants: Vec<Constant>,
}

/// Parse one constant line's text (`name = value (certificate; how)`).
fn parse_constant(s: &str) -> Option<Constant> {
    // The fields become table cells, which the renderers escape themselves.
    let s = s.replace("\\|", "|");
    let (name, rest) = s.split_once(" = ")?;
    let (value, rest) = rest.split_once(" (")?;
    let inner = rest.strip_suffix(')')?;
    let (certificate, how) = inner.split_once("; ").unwrap_or((inner, ""));
    Some(Constant {
        name: name.trim().to_string(),
        value: value.trim().to_string(),
        certificate: certificate.trim().to_string(),
        how: how.trim().to_string(),
    })
}

/// Split the theorem Markdown at its `**Details.**` paragraph: the text before it and each
/// check's details with its constants (`- **id** text` items, their constants as indented
/// `- name = value (certificate; how)` items).
pub fn split_details(md: &str) -> (String, Vec<Details>) {
    let Some(at) = md.find("**Details.**") else {
        return (md.to_string(), vec![]);
    };
    let (head, tail) = md.split_at(at);
    let mut out: Vec<Details> = Vec::new();
    for line in tail.lines().skip(1) {
        if let Some(item) = line.strip_prefix("- **") {
            let (id, text) = item.split_once("**").unwrap_or((item, ""));
            out.push(Details {
                id: id.to_string(),
                text: text.trim().to_string(),
                constants: vec![],
            });
        } else if let Some(c) = line.trim_start().strip_prefix("- ")
            && let (Some(last), Some(k)) = (out.last_mut(), parse_constant(c))
        {
            last.constants.push(k);
        }
    }
    (head.to_string(), out)
}

/// The constants table (each distinct constant once, `K1`, `K2`, … in order of first use, with
/// the checks using it) and the details list referring to it.
pub fn details_blocks(details: &[Details], label: &str) -> Vec<Block> {
    let mut constants: Vec<(Constant, Vec<String>)> = Vec::new();
    let mut items = Vec::new();
    for d in details {
        let mut refs = Vec::new();
        for k in &d.constants {
            let j = match constants.iter().position(|(c, _)| c == k) {
                Some(j) => j,
                None => {
                    constants.push((k.clone(), vec![]));
                    constants.len() - 1
                }
            };
            if !constants[j].1.contains(&d.id) {
                constants[j].1.push(d.id.clone());
            }
            refs.push(format!("K{}", j + 1));
        }
        let mut item = format!("**{}** {}", d.id, d.text);
        if !refs.is_empty() {
            item += &format!(" Constants: {} (table of constants).", refs.join(", "));
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

/// Split a table whose header has `bound B` into what is claimed (id, result, claim, role,
/// verdict, erratum) and what was measured (id, method, the numbers, verdict); other blocks pass
/// through.
fn split_wide(b: Block) -> Vec<Block> {
    let Block::Table(t) = b else { return vec![b] };
    let col = |name: &str| t.header.iter().position(|h| h == name);
    let Some(bound) = col("bound B") else {
        return vec![Block::Table(t)];
    };
    let numeric_from = bound;
    let verdict = col("verdict");
    let pick = |cols: &[usize], label: &str, caption: &str, spec: &str| {
        Block::Table(Table {
            caption: Some(caption.into()),
            label: label.into(),
            header: cols.iter().map(|&j| t.header[j].clone()).collect(),
            rows: t
                .rows
                .iter()
                .map(|r| {
                    cols.iter()
                        .map(|&j| r.get(j).cloned().unwrap_or_default())
                        .collect()
                })
                .collect(),
            spec: spec.into(),
        })
    };
    let method = col("method");
    let claims: Vec<usize> = (0..t.header.len())
        .filter(|&j| j < numeric_from && Some(j) != method || Some(j) == verdict)
        .chain(col("erratum"))
        .collect();
    let mut numbers: Vec<usize> = vec![0];
    numbers.extend(method);
    numbers.extend((numeric_from..t.header.len()).filter(|&j| Some(j) != col("erratum")));
    let spec_of = |cols: &[usize]| -> String {
        cols.iter()
            .map(|&j| {
                if j >= numeric_from && Some(j) != verdict {
                    'r'
                } else {
                    'l'
                }
            })
            .collect()
    };
    vec![
        pick(
            &claims,
            &format!("{}-claims", t.label),
            "Theorem checks: the claims and their verdicts",
            &spec_of(&claims),
        ),
        pick(
            &numbers,
            &format!("{}-numbers", t.label),
            "Theorem checks: bounds and measurements (same rows)",
            &spec_of(&numbers),
        ),
    ]
}

/// The theorem-check section's blocks from `ilopt-theory`'s Markdown: its tables (the wide one
/// split), notes and status, then the constants once and the details referring to them.
pub fn blocks(md: &str, label: &str) -> Vec<Block> {
    let (head, details) = split_details(md);
    let mut out: Vec<Block> = from_markdown(&head, label)
        .into_iter()
        .flat_map(split_wide)
        .collect();
    out.extend(details_blocks(&details, label));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const MD: &str = "| # | result | claim | role | method | bound B | measured (LCB) | X̄/B | verdict | erratum |\n\
|---|---|---|---|---|---|---|---|---|---|\n\
| 1a | (3.41) | F smooth | thesis | exact | 2 | 1 (0.5) | 0.5 | **holds** | E2 |\n\
\n**Status: every negative control detected**\n\
\n**Details.**\n\n\
- **1a** first\n\
  - L_F = 2.029554 (rigorous upper bound; interval branch-and-bound (727 boxes))\n\
  - B_F = 0.500000 (exact; F(θ₁) − inf F over \\|θ\\| ≤ 1)\n\
- **8** second\n\
  - L_F = 2.029554 (rigorous upper bound; interval branch-and-bound (727 boxes))\n\
- **9** none\n";

    #[test]
    fn constants_parse_with_their_certificates() {
        let (head, d) = split_details(MD);
        assert!(head.contains("**Status"), "{head}");
        assert_eq!(d.len(), 3);
        assert_eq!(d[0].id, "1a");
        assert_eq!(d[0].text, "first");
        assert_eq!(
            d[0].constants[0],
            Constant {
                name: "L_F".into(),
                value: "2.029554".into(),
                certificate: "rigorous upper bound".into(),
                how: "interval branch-and-bound (727 boxes)".into(),
            }
        );
        assert_eq!(d[0].constants[1].how, "F(θ₁) − inf F over |θ| ≤ 1");
        assert!(d[2].constants.is_empty());
    }

    #[test]
    fn each_constant_is_listed_once_and_rows_refer_to_it() {
        let b = blocks(MD, "tab:t");
        let tables: Vec<&Table> = b
            .iter()
            .filter_map(|x| match x {
                Block::Table(t) => Some(t),
                _ => None,
            })
            .collect();
        // The check table split in two, then the constants.
        assert_eq!(tables.len(), 3, "{b:?}");
        assert_eq!(
            tables[0].header,
            ["#", "result", "claim", "role", "verdict", "erratum"]
        );
        assert_eq!(
            tables[1].header,
            ["#", "method", "bound B", "measured (LCB)", "X̄/B", "verdict"]
        );
        assert_eq!(
            tables[1].rows[0],
            ["1a", "exact", "2", "1 (0.5)", "0.5", "**holds**"]
        );
        let k = tables[2];
        assert_eq!(k.rows.len(), 2, "{:?}", k.rows);
        assert_eq!(k.rows[0][0], "K1");
        assert_eq!(k.rows[0][1], "L_F");
        assert_eq!(k.rows[0][5], "1a, 8");
        assert_eq!(k.rows[1][5], "1a");
        let Some(Block::List(items)) = b.last() else {
            panic!("{b:?}")
        };
        assert_eq!(
            items[0],
            "**1a** first Constants: K1, K2 (table of constants)."
        );
        assert_eq!(items[1], "**8** second Constants: K1 (table of constants).");
        assert_eq!(items[2], "**9** none");
        // The constants' text appears once in the Markdown rendering.
        let md = super::super::doc::markdown(&b);
        assert_eq!(
            md.matches("interval branch-and-bound (727 boxes)").count(),
            1,
            "{md}"
        );
    }
}
