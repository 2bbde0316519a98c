//! The appendix as one small document model, built once ([`Block`]s) and rendered twice:
//! Markdown ([`markdown`]) and LaTeX with booktabs ([`latex`]). Each table and figure is defined
//! once; the renderers only decide the syntax.
//!
//! Text in paragraphs, list items, captions and table cells is Markdown inline text: `**bold**`,
//! `*emphasis*` and `` `code` `` (the LaTeX renderer converts them and escapes the rest).

use std::fmt::Write as _;

/// A table: an optional caption (a paragraph above it in Markdown, the float's caption in
/// LaTeX), a header and rows of cells.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Caption, Markdown inline text (in Markdown, printed as a paragraph above the table).
    pub caption: Option<String>,
    /// LaTeX label (`tab:…`).
    pub label: String,
    /// Column headers.
    pub header: Vec<String>,
    /// Rows of cells (as many as headers).
    pub rows: Vec<Vec<String>>,
    /// LaTeX column specification (`lrr`, `lp{5cm}`, …).
    pub spec: String,
}

/// One block of the document.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A heading: level 1 is the document's title, level 2 a section.
    Heading {
        /// 1 or 2.
        level: u8,
        /// Markdown inline text.
        text: String,
    },
    /// A paragraph (Markdown inline text).
    Para(String),
    /// A bullet list (items are Markdown inline text).
    List(Vec<String>),
    /// A table.
    Table(Table),
    /// A figure: its file (relative to the document) and caption.
    Figure {
        /// Path relative to the document's directory.
        path: String,
        /// Caption (plain text).
        caption: String,
    },
    /// Text already rendered for each format (e.g. the theorem-check table that `ilopt-theory`
    /// writes as Markdown): printed verbatim.
    Raw {
        /// The Markdown text.
        markdown: String,
        /// The LaTeX text.
        latex: String,
    },
}

/// Render as Markdown: every block followed by a blank line (raw blocks verbatim).
pub fn markdown(blocks: &[Block]) -> String {
    let mut o = String::new();
    for b in blocks {
        match b {
            Block::Heading { level, text } => {
                let _ = writeln!(o, "{} {text}\n", "#".repeat(usize::from(*level)));
            }
            Block::Para(t) => {
                let _ = writeln!(o, "{t}\n");
            }
            Block::List(items) => {
                for i in items {
                    let _ = writeln!(o, "- {i}");
                }
                o.push('\n');
            }
            Block::Table(t) => {
                if let Some(c) = &t.caption {
                    let _ = writeln!(o, "{c}\n");
                }
                let _ = writeln!(o, "| {} |", t.header.join(" | "));
                let _ = writeln!(o, "|{}", "---|".repeat(t.header.len()));
                for r in &t.rows {
                    let cells: Vec<String> = r.iter().map(|c| c.replace('|', "\\|")).collect();
                    let _ = writeln!(o, "| {} |", cells.join(" | "));
                }
                o.push('\n');
            }
            Block::Figure { path, caption } => {
                let _ = writeln!(o, "![{caption}]({path})\n");
            }
            Block::Raw { markdown, .. } => o += markdown,
        }
    }
    o
}

/// Render as LaTeX (`\section*`/`\subsection*`, booktabs tables, `graphicx` figures) after
/// `preamble` (comment lines). A table without a caption is captioned with its section's heading.
pub fn latex(blocks: &[Block], preamble: &str) -> String {
    let mut o = String::from(preamble);
    let mut section = String::new();
    for b in blocks {
        match b {
            Block::Heading { level, text } => {
                section.clone_from(text);
                let cmd = if *level <= 1 { "section" } else { "subsection" };
                let _ = writeln!(o, "\\{cmd}*{{{}}}\n", inline(text));
            }
            Block::Para(t) => {
                let _ = writeln!(o, "{}\n", inline(t));
            }
            Block::List(items) => {
                o += "\\begin{itemize}\n";
                for i in items {
                    let _ = writeln!(o, "\\item {}", inline(i));
                }
                o += "\\end{itemize}\n\n";
            }
            Block::Table(t) => {
                o += "\\begin{table}[htbp]\n\\centering\\small\n";
                // A table without a caption takes its section's heading.
                let c = t.caption.as_deref().unwrap_or(&section);
                let c = c.trim_end().trim_end_matches(':');
                let _ = writeln!(o, "\\caption{{{}}}\\label{{{}}}", inline(c), t.label);
                let _ = writeln!(o, "\\begin{{tabular}}{{{}}}\n\\toprule", t.spec);
                let head: Vec<String> = t.header.iter().map(|h| inline(h)).collect();
                let _ = writeln!(o, "{} \\\\\n\\midrule", head.join(" & "));
                for r in &t.rows {
                    let cells: Vec<String> = r.iter().map(|c| inline(c)).collect();
                    let _ = writeln!(o, "{} \\\\", cells.join(" & "));
                }
                o += "\\bottomrule\n\\end{tabular}\n\\end{table}\n\n";
            }
            Block::Figure { path, caption } => {
                let svg_note = if path.ends_with(".svg") {
                    "% SVG: needs the svg package or a conversion to PDF\n"
                } else {
                    ""
                };
                let _ = writeln!(
                    o,
                    "\\begin{{figure}}[htbp]\n\\centering\n{svg_note}\\includegraphics[width=0.8\\linewidth]{{{path}}}\n\\caption{{{}}}\n\\end{{figure}}\n",
                    escape(caption)
                );
            }
            Block::Raw { latex, .. } => o += latex,
        }
    }
    o
}

/// Markdown inline text to LaTeX: `**x**` → `\textbf{x}`, `*x*` → `\emph{x}` (a `*` that opens
/// a word and has a closing `*`), `` `x` `` → `\texttt{x}`, Markdown's `\|` → `|`; everything
/// else escaped ([`escape`]).
pub fn inline(s: &str) -> String {
    let s = s.replace("\\|", "|");
    let chars: Vec<char> = s.chars().collect();
    let mut o = String::new();
    let mut plain = String::new();
    let (mut bold, mut emph, mut code) = (false, false, false);
    let mut i = 0;
    let flush = |o: &mut String, plain: &mut String| {
        *o += &escape(plain);
        plain.clear();
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '`' {
            flush(&mut o, &mut plain);
            o += if code { "}" } else { "\\texttt{" };
            code = !code;
        } else if code {
            plain.push(c);
        } else if c == '*' && next == Some('*') {
            flush(&mut o, &mut plain);
            o += if bold { "}" } else { "\\textbf{" };
            bold = !bold;
            i += 1;
        } else if c == '*'
            && (emph
                || (next.is_some_and(char::is_alphanumeric)
                    && (i == 0 || !chars[i - 1].is_alphanumeric())
                    && chars[i + 1..].contains(&'*')))
        {
            flush(&mut o, &mut plain);
            o += if emph { "}" } else { "\\emph{" };
            emph = !emph;
        } else {
            plain.push(c);
        }
        i += 1;
    }
    flush(&mut o, &mut plain);
    for open in [code, bold, emph] {
        if open {
            o.push('}');
        }
    }
    o
}

/// Escape text for LaTeX (special characters, and the symbols the appendix uses as math).
pub fn escape(s: &str) -> String {
    let mut o = String::new();
    for ch in s.chars() {
        match ch {
            '\\' => o += "\\textbackslash{}",
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                o.push('\\');
                o.push(ch);
            }
            '~' => o += "\\textasciitilde{}",
            '^' => o += "\\textasciicircum{}",
            '±' => o += "$\\pm$",
            '≥' => o += "$\\geq$",
            '≤' => o += "$\\leq$",
            '≈' => o += "$\\approx$",
            '√' => o += "$\\surd$",
            '−' => o.push('-'),
            '‖' => o += "$\\|$",
            '∇' => o += "$\\nabla$",
            'θ' => o += "$\\theta$",
            'σ' => o += "$\\sigma$",
            'τ' => o += "$\\tau$",
            'η' => o += "$\\eta$",
            'Δ' => o += "$\\Delta$",
            'φ' => o += "$\\phi$",
            'π' => o += "$\\pi$",
            'β' => o += "$\\beta$",
            'ε' => o += "$\\varepsilon$",
            'γ' => o += "$\\gamma$",
            'α' => o += "$\\alpha$",
            '∼' => o += "$\\sim$",
            '·' => o += "$\\cdot$",
            '…' => o += "\\ldots{}",
            '⌈' => o += "$\\lceil$",
            '⌉' => o += "$\\rceil$",
            '⁻' => o += "$^{-}$",
            '¹' => o += "$^{1}$",
            '²' => o += "$^{2}$",
            '³' => o += "$^{3}$",
            '→' => o += "$\\to$",
            '∈' => o += "$\\in$",
            '≠' => o += "$\\neq$",
            '×' => o += "$\\times$",
            '§' => o += "\\S{}",
            c => o.push(c),
        }
    }
    o
}

/// Blocks from simple Markdown (`## ` headings, paragraphs, `- ` lists with indented
/// continuation items, pipe tables): enough for the theorem-check section, so the LaTeX
/// rendering carries it too. Tables get `label` and a column specification of `l`s.
pub fn from_markdown(md: &str, label: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut lines = md.lines().peekable();
    let cells = |line: &str| -> Vec<String> {
        let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
        // Split on `|` not preceded by a backslash.
        let mut v = Vec::new();
        let mut cur = String::new();
        let mut prev = ' ';
        for c in inner.chars() {
            if c == '|' && prev != '\\' {
                v.push(cur.trim().to_string());
                cur.clear();
            } else {
                cur.push(c);
            }
            prev = c;
        }
        v.push(cur.trim().to_string());
        v
    };
    let mut k = 0;
    while let Some(line) = lines.next() {
        let t = line.trim_end();
        if t.is_empty() {
            continue;
        }
        if let Some(h) = t.strip_prefix("## ") {
            out.push(Block::Heading {
                level: 2,
                text: h.to_string(),
            });
        } else if t.starts_with('|') {
            let header = cells(t);
            let mut rows = Vec::new();
            while let Some(l) = lines.peek() {
                if !l.trim_start().starts_with('|') {
                    break;
                }
                let l = lines.next().unwrap_or_default();
                if l.contains("---") && l.chars().all(|c| matches!(c, '|' | '-' | ':' | ' ')) {
                    continue;
                }
                rows.push(cells(l));
            }
            k += 1;
            // The column with the longest text wraps (p{4cm}); the others are `l`.
            let wide = (0..header.len())
                .max_by_key(|&j| {
                    rows.iter()
                        .map(|r: &Vec<String>| r.get(j).map_or(0, String::len))
                        .sum::<usize>()
                })
                .filter(|_| header.len() > 4);
            let spec: String = (0..header.len())
                .map(|j| if Some(j) == wide { "p{4cm}" } else { "l" })
                .collect();
            out.push(Block::Table(Table {
                caption: None,
                label: format!("{label}-{k}"),
                spec,
                header,
                rows,
            }));
        } else if let Some(item) = t.strip_prefix("- ") {
            let mut items = vec![item.to_string()];
            while let Some(l) = lines.peek() {
                let lt = l.trim_start();
                if let Some(more) = lt.strip_prefix("- ") {
                    if l.starts_with(' ') {
                        if let Some(last) = items.last_mut() {
                            *last += "; ";
                            *last += more;
                        }
                    } else {
                        items.push(more.to_string());
                    }
                    lines.next();
                } else {
                    break;
                }
            }
            out.push(Block::List(items));
        } else {
            let mut p = t.to_string();
            while let Some(l) = lines.peek() {
                let lt = l.trim();
                if lt.is_empty()
                    || lt.starts_with('|')
                    || lt.starts_with("- ")
                    || lt.starts_with('#')
                {
                    break;
                }
                p.push(' ');
                p += lt;
                lines.next();
            }
            out.push(Block::Para(p));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inline_markup() {
        assert_eq!(
            inline("**a** *b* `c_d` x*y (3.60*) 5%"),
            "\\textbf{a} \\emph{b} \\texttt{c\\_d} x*y (3.60*) 5\\%"
        );
        assert_eq!(inline("\\|E g − ∇F\\|"), "|E g - $\\nabla$F|");
    }

    #[test]
    fn one_table_two_renderings() {
        let b = [Block::Table(Table {
            caption: Some("**Table X: t** (kit):".into()),
            label: "tab:x".into(),
            header: vec!["a".into(), "b".into()],
            rows: vec![vec!["1".into(), "p|q".into()]],
            spec: "lr".into(),
        })];
        assert_eq!(
            markdown(&b),
            "**Table X: t** (kit):\n\n| a | b |\n|---|---|\n| 1 | p\\|q |\n\n"
        );
        let t = latex(&b, "");
        assert!(
            t.contains("\\caption{\\textbf{Table X: t} (kit)}\\label{tab:x}"),
            "{t}"
        );
        assert!(t.contains("1 & p|q \\\\"), "{t}");
        assert!(t.contains("\\toprule") && t.contains("\\bottomrule"), "{t}");
    }

    #[test]
    fn markdown_tables_and_lists_parse() {
        let md = "| # | x |\n|---|---|\n| 1 | a \\| b |\n\n**Details.**\n\n- one\n  - sub\n- two\n";
        let b = from_markdown(md, "tab:t");
        assert_eq!(b.len(), 3, "{b:?}");
        match &b[0] {
            Block::Table(t) => {
                assert_eq!(t.header, vec!["#", "x"]);
                assert_eq!(t.rows, vec![vec!["1".to_string(), "a \\| b".to_string()]]);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(b[1], Block::Para("**Details.**".into()));
        assert_eq!(b[2], Block::List(vec!["one; sub".into(), "two".into()]));
    }
}
