//! The appendix as one small document model, built once ([`Block`]s) and rendered twice:
//! Markdown ([`markdown`]) and LaTeX with booktabs ([`latex`]). Each table and figure is defined
//! once; the renderers only decide the syntax.
//!
//! Text in paragraphs, list items, captions and table cells is Markdown inline text: `**bold**`,
//! `*emphasis*` and `` `code` `` (the LaTeX renderer converts them and escapes the rest).

use super::tex;
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
}

/// Render as Markdown: every block followed by a blank line.
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
                // The image, then its caption as text (Markdown viewers do not show alt text),
                // numbered with the thesis's number as "Figure 4.3".
                let caption = caption
                    .strip_prefix("Fig. ")
                    .map_or_else(|| caption.clone(), |c| format!("Figure {c}"));
                let _ = writeln!(o, "![{caption}]({path})\n\n*{caption}.*\n");
            }
        }
    }
    o
}

/// The packages [`latex`]'s output needs, as `\usepackage` lines (the standalone document loads
/// them; a thesis that `\input`s the fragment loads them in its preamble).
pub const LATEX_PACKAGES: &str = "\\usepackage{amsmath,amssymb}\n\\usepackage{booktabs,longtable,array}\n\\usepackage{graphicx,pdflscape}\n";

/// Opens [`latex`]'s output: `\FloatBarrier` (unless the preamble defines it, e.g. with the
/// `placeins` package) from the LaTeX kernel alone, so no extra package is needed. With floats
/// still waiting it ends the page (they go to the top of the next one, before what follows) and,
/// if some still wait, clears the page; otherwise it does nothing.
const FLOAT_BARRIER: &str = "\\makeatletter\n\
\\providecommand{\\IloptIfFloatsWait}[2]{\\begingroup\\let\\@elt\\relax\n\
  \\edef\\@tempa{\\@botlist\\@deferlist\\@dbldeferlist}%\n\
  \\ifx\\@tempa\\@empty\\aftergroup\\@secondoftwo\\else\\aftergroup\\@firstoftwo\\fi\n\
  \\endgroup{#1}{#2}}\n\
\\providecommand{\\FloatBarrier}{\\par\\IloptIfFloatsWait{\\newpage\\IloptIfFloatsWait{\\clearpage}{}}{}}\n\
\\makeatother\n";

/// Render as LaTeX after `preamble` (comment lines): `\section*`/`\subsection*` headings,
/// booktabs `longtable`s whose columns are sized to fit the line ([`column_layout`]), and figures
/// as floats (`[htbp]`: here, or at the top or bottom of a page, or on a page of floats, so no
/// page is cut short for a figure), kept inside their section by a `\FloatBarrier` before
/// every heading. A caption that leads with a thesis number ("Table 4.1: …", "Fig. 4.3: …")
/// is numbered with it (the float's `\thetable`/`\thefigure` set locally), so each float
/// carries one number; the others keep the document's numbering. A table without a caption is
/// captioned with its section's heading.
pub fn latex(blocks: &[Block], preamble: &str) -> String {
    let mut o = String::from(preamble);
    o += FLOAT_BARRIER;
    let mut section = String::new();
    let opens = landscape_openings(blocks);
    // Whether a landscape page was opened before the table it is for.
    let mut opened = false;
    for (b, &open) in blocks.iter().zip(&opens) {
        if open && !matches!(b, Block::Table(_)) {
            o += "\\begin{landscape}\n";
            opened = true;
        }
        match b {
            Block::Heading { level, text } => {
                section.clone_from(text);
                let cmd = if *level <= 1 { "section" } else { "subsection" };
                let _ = writeln!(o, "\\FloatBarrier\n\\{cmd}*{{{}}}\n", inline(text));
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
                let c = t.caption.as_deref().unwrap_or(&section);
                let layout = column_layout(&t.header, &t.rows, &t.spec);
                let open_here = layout.landscape && !opened;
                o += &latex_table(t, &layout, &caption_parts(c), open_here);
                opened = false;
            }
            Block::Figure { path, caption } => {
                let svg_note = if path.ends_with(".svg") {
                    "% SVG: needs the svg package or a conversion to PDF\n"
                } else {
                    ""
                };
                let (number, text) = caption_parts(caption);
                let _ = writeln!(
                    o,
                    "\\begin{{figure}}[htbp]\n\\centering\n{svg_note}\\includegraphics[width=\\linewidth]{{{path}}}\n{}\\caption{{{text}}}\n\\end{{figure}}\n",
                    own_number("figure", number.as_deref())
                );
            }
        }
    }
    o
}

/// A caption's LaTeX: the thesis's number, if the caption leads with one ("Table 4.1: x",
/// "Fig. 4.2 (a): x", bold or not), for the float to print as its own number (`4.1`,
/// `4.2\,(a)`), and the text after it without Markdown's trailing colon, first letter
/// capitalised.
pub fn caption_parts(c: &str) -> (Option<String>, String) {
    let c = c.trim().trim_end_matches(':').trim_end();
    let (bold, body) = match c.strip_prefix("**") {
        Some(rest) => (true, rest),
        None => (false, c),
    };
    let mut number = None;
    let mut rest = body.to_string();
    for kind in ["Table ", "Fig. ", "Figure "] {
        if let Some(after) = body.strip_prefix(kind) {
            // The number: digits and dots, then an optional panel "(a)"; then ": ".
            let n_end = after
                .find(|ch: char| !(ch.is_ascii_digit() || ch == '.'))
                .unwrap_or(after.len());
            let mut tail = &after[n_end..];
            let mut num = after[..n_end].to_string();
            if let Some(p) = tail
                .strip_prefix(" (")
                .filter(|p| p.get(1..3) == Some("):"))
            {
                num += &format!("\\,({})", &p[..1]);
                tail = &p[2..];
            }
            if n_end > 0
                && let Some(t) = tail.strip_prefix(':')
            {
                number = Some(num);
                rest = t.trim_start().to_string();
            }
            break;
        }
    }
    let mut text = if bold { format!("**{rest}") } else { rest };
    // Capitalise the first letter of the caption's text (after any markup).
    if let Some(k) = text.find(|ch: char| ch.is_alphanumeric()) {
        let ch = text[k..].chars().next().unwrap_or(' ');
        if ch.is_lowercase() {
            let up: String = ch.to_uppercase().collect();
            text.replace_range(k..k + ch.len_utf8(), &up);
        }
    }
    (number, inline(&text))
}

/// The visible length of Markdown inline text, in characters (markup removed).
fn visible_len(s: &str) -> usize {
    s.replace("**", "")
        .replace("\\|", "|")
        .chars()
        .filter(|c| !matches!(c, '`' | '*') && !('\u{0300}'..='\u{036F}').contains(c))
        .count()
}

/// The longest unbreakable piece of a cell (a word), in characters.
fn longest_word(s: &str) -> usize {
    s.split([' ', '/', '-']).map(visible_len).max().unwrap_or(0)
}

/// How a table is typeset: the font size and each column's LaTeX specification.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnLayout {
    /// `\small`, `\footnotesize` or `\scriptsize`, with a narrower `\tabcolsep` at the
    /// smallest size.
    pub size: &'static str,
    /// Whether the table needs a landscape page (its longest words do not fit across the line
    /// even at the smallest size).
    pub landscape: bool,
    /// Column specifications (`l`, `r`, or a ragged `p{…}` of a fraction of the line).
    pub columns: Vec<String>,
}

/// The text block's width the tables are laid out for: A4 less two 2 cm margins, 170 mm.
const LINE_PT: f64 = 483.7;

/// A landscape page's line over a portrait one's: (297 − 40) / (210 − 40) mm.
const LANDSCAPE_RATIO: f64 = 257.0 / 170.0;

/// Fit a table to the line width (`LINE_PT`). The estimate counts characters: about 64
/// characters of `\small` text fit in 345 pt (10 pt article), less each column's
/// padding (2\tabcolsep ≈ 2.7 characters), more at smaller sizes. A table whose natural widths
/// fit at `\small` or `\footnotesize` keeps `l`/`r` columns at the first of them; otherwise its columns wrap (`shared_widths`) at `\footnotesize` (or the largest
/// size at which the longest words fit, with 3 pt column padding at the smallest), on a
/// landscape page when that shortens rows taller than `LANDSCAPE_LINES` by a third or
/// nothing else fits.
/// Columns are right-aligned where `spec` says `r`.
pub fn column_layout(header: &[String], rows: &[Vec<String>], spec: &str) -> ColumnLayout {
    let n = header.len().max(1);
    let right: Vec<bool> = {
        // The alignment letters of `spec` (ignoring p{…} arguments).
        let mut v = Vec::new();
        let mut depth = 0;
        for ch in spec.chars() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                c if depth == 0 && c.is_ascii_alphabetic() => v.push(c == 'r'),
                _ => {}
            }
        }
        (0..n).map(|j| v.get(j).copied().unwrap_or(false)).collect()
    };
    let cells = |j: usize| {
        std::iter::once(header.get(j).map_or("", String::as_str)).chain(
            rows.iter()
                .map(move |r| r.get(j).map_or("", String::as_str)),
        )
    };
    let natural: Vec<f64> = (0..n)
        .map(|j| cells(j).map(visible_len).max().unwrap_or(0) as f64 + 0.5)
        .collect();
    let minimum: Vec<f64> = (0..n)
        .map(|j| {
            // A header wraps between words; its longest word still has to fit.
            cells(j).map(longest_word).max().unwrap_or(0) as f64 + 1.0
        })
        .collect();
    // (font size command, characters per line, padding of a column in characters): 64, 72 and
    // 82 characters per 345 pt at the three sizes, scaled to the line of LINE_PT.
    let per = LINE_PT / 345.0;
    let sizes = [
        ("\\small", 64.0 * per, 2.7),
        ("\\footnotesize", 72.0 * per, 3.0),
        ("\\scriptsize\\setlength{\\tabcolsep}{3pt}", 82.0 * per, 1.8),
        // A landscape page: the page's height less the margins, across.
        (
            "\\scriptsize\\setlength{\\tabcolsep}{3pt}",
            82.0 * per * LANDSCAPE_RATIO,
            1.8,
        ),
    ];
    let budget = |(_, line, pad): (&str, f64, f64)| line - pad * n as f64;
    // A table whose natural widths fit at \small or \footnotesize keeps l/r columns (one line
    // a row); \scriptsize is kept for tables that cannot be set larger.
    if let Some(&(size, _, _)) = sizes[..2]
        .iter()
        .find(|&&sz| natural.iter().sum::<f64>() <= budget(sz))
    {
        return ColumnLayout {
            landscape: false,
            size,
            columns: right
                .iter()
                .map(|r| if *r { "r" } else { "l" }.to_string())
                .collect(),
        };
    }
    // Otherwise wrapped columns: at \footnotesize when the longest words fit (smaller text is
    // harder to read than an extra line), else the largest size at which they do; a landscape
    // page when even then a row would average more than LANDSCAPE_LINES lines and the wider
    // line saves a third of them.
    let fits = |k: usize| minimum.iter().sum::<f64>() <= budget(sizes[k]);
    let mut pick = (1..sizes.len())
        .find(|&k| fits(k))
        .unwrap_or(sizes.len() - 1);
    let lines = |k: usize| row_lines(&shared_widths(&natural, &minimum, budget(sizes[k])), rows);
    if pick < sizes.len() - 1 {
        let portrait = lines(pick);
        if portrait > LANDSCAPE_LINES && lines(sizes.len() - 1) <= LANDSCAPE_GAIN * portrait {
            pick = sizes.len() - 1;
        }
    }
    let (size, _, pad) = sizes[pick];
    let landscape = pick == sizes.len() - 1;
    let width = shared_widths(&natural, &minimum, budget(sizes[pick]));
    // Each column's share of the line includes its padding (2\tabcolsep, subtracted again
    // in the specification).
    let sum: f64 = width.iter().map(|w| w + pad).sum();
    let columns = (0..n)
        .map(|j| {
            let frac = (width[j] + pad) / sum;
            let align = if right[j] {
                "\\raggedleft"
            } else {
                "\\raggedright"
            };
            format!(
                ">{{{align}\\arraybackslash\\hspace{{0pt}}}}p{{\\dimexpr{frac:.3}\\linewidth-2\\tabcolsep\\relax}}"
            )
        })
        .collect();
    ColumnLayout {
        size,
        landscape,
        columns,
    }
}

/// The float's number set to the thesis's (`\renewcommand{\thefigure}{4.3}`, local to the
/// float's group), so the caption shows that number alone; nothing without one.
fn own_number(counter: &str, number: Option<&str>) -> String {
    number.map_or(String::new(), |n| {
        format!("\\renewcommand{{\\the{counter}}}{{{n}}}")
    })
}

/// Rows of a table average more lines than this (estimated at the portrait size): a landscape
/// page, if it brings them down to [`LANDSCAPE_GAIN`] of that.
const LANDSCAPE_LINES: f64 = 3.0;

/// See `LANDSCAPE_LINES`.
const LANDSCAPE_GAIN: f64 = 0.7;

/// Share `total` characters out among columns of these natural and minimum widths:
/// columns narrower than an equal share keep their natural width, the others share the rest in
/// proportion to their natural widths (never below their longest word).
fn shared_widths(natural: &[f64], minimum: &[f64], total: f64) -> Vec<f64> {
    let n = natural.len();
    // Water-filling: fix the columns that need less than an equal share of what is left.
    let mut width = vec![0.0; n];
    let mut open: Vec<usize> = (0..n).collect();
    let mut left = total;
    loop {
        let share = left / open.len().max(1) as f64;
        let (small, big): (Vec<usize>, Vec<usize>) =
            open.iter().partition(|&&j| natural[j] <= share);
        if small.is_empty() {
            let sum: f64 = big.iter().map(|&j| natural[j]).sum();
            for &j in &big {
                width[j] = left * natural[j] / sum;
            }
            break;
        }
        for &j in &small {
            width[j] = natural[j];
            left -= natural[j];
        }
        open = big;
        if open.is_empty() {
            break;
        }
    }
    // Never below the longest word: take the difference from the widest columns.
    for j in 0..n {
        if width[j] < minimum[j] {
            let need = minimum[j] - width[j];
            width[j] = minimum[j];
            let widest = (0..n)
                .filter(|&k| k != j)
                .max_by(|&a, &b| (width[a] - minimum[a]).total_cmp(&(width[b] - minimum[b])));
            if let Some(k) = widest {
                width[k] = (width[k] - need).max(minimum[k]);
            }
        }
    }
    width
}

/// The part of a ragged-right line that words fill on average (a line breaks before the word
/// that would overflow it).
const RAGGED_FILL: f64 = 0.85;

/// The mean over rows of each row's estimated height in lines (its tallest cell's characters
/// over the characters that fill its column's lines).
fn row_lines(width: &[f64], rows: &[Vec<String>]) -> f64 {
    if rows.is_empty() {
        return 1.0;
    }
    let total: f64 = rows
        .iter()
        .map(|r| {
            r.iter()
                .zip(width)
                .map(|(c, w)| {
                    (visible_len(c) as f64 / (RAGGED_FILL * w).max(1.0))
                        .ceil()
                        .max(1.0)
                })
                .fold(1.0, f64::max)
        })
        .sum();
    total / rows.len() as f64
}

/// For each block, whether it opens a landscape page: a landscape table ([`column_layout`])
/// opens its own, unless a section's opening leads straight into it — its heading and at most
/// [`LEAD_IN`] paragraphs, nothing else — which then opens the page instead, so that the
/// heading and its first words are not left alone on the portrait page before the table.
fn landscape_openings(blocks: &[Block]) -> Vec<bool> {
    let mut open = vec![false; blocks.len()];
    for (j, b) in blocks.iter().enumerate() {
        let Block::Table(t) = b else { continue };
        if !column_layout(&t.header, &t.rows, &t.spec).landscape {
            continue;
        }
        let paras = blocks[..j]
            .iter()
            .rev()
            .take_while(|b| matches!(b, Block::Para(_)))
            .count();
        let heading = j > paras && matches!(blocks[j - paras - 1], Block::Heading { .. });
        open[if heading && paras <= LEAD_IN {
            j - paras - 1
        } else {
            j
        }] = true;
    }
    open
}

/// The most paragraphs between a heading and a landscape table that go onto its page.
const LEAD_IN: usize = 2;

/// A table as a booktabs `longtable` (it breaks across pages and stays where it stands), its
/// columns laid out by `layout` ([`column_layout`]), the header repeated on every page; captioned
/// with `(thesis number, text)` ([`caption_parts`]). A landscape layout ends its page after the
/// table, and opens it before the table when `open` (else [`landscape_openings`] opened it
/// earlier).
fn latex_table(
    t: &Table,
    layout: &ColumnLayout,
    (number, caption): &(Option<String>, String),
    open: bool,
) -> String {
    let mut o = String::new();
    if open {
        o += "\\begin{landscape}\n";
    }
    let _ = writeln!(
        o,
        "\\begingroup{}\\setlength{{\\LTpre}}{{6pt}}\\setlength{{\\LTpost}}{{6pt}}{}",
        layout.size,
        own_number("table", number.as_deref())
    );
    let _ = writeln!(
        o,
        "\\begin{{longtable}}{{@{{}}{}@{{}}}}",
        layout.columns.join("")
    );
    let head: Vec<String> = t.header.iter().map(|h| inline(h)).collect();
    let head = head.join(" & ");
    if caption.trim().is_empty() {
        let _ = writeln!(o, "\\label{{{}}}\\\\", t.label);
    } else {
        let _ = writeln!(o, "\\caption{{{caption}}}\\label{{{}}}\\\\", t.label);
    }
    let _ = writeln!(o, "\\toprule\n{head} \\\\\n\\midrule\n\\endfirsthead");
    let _ = writeln!(
        o,
        "\\multicolumn{{{}}}{{@{{}}l}}{{\\emph{{(continued)}}}}\\\\\n\\toprule\n{head} \\\\\n\\midrule\n\\endhead",
        t.header.len()
    );
    let _ = writeln!(o, "\\bottomrule\n\\endlastfoot");
    for r in &t.rows {
        let cells: Vec<String> = r.iter().map(|c| inline(c)).collect();
        let _ = writeln!(o, "{} \\\\", cells.join(" & "));
    }
    o += "\\end{longtable}\n\\endgroup\n";
    if layout.landscape {
        o += "\\end{landscape}\n";
    }
    o.push('\n');
    o
}

/// Markdown inline text to LaTeX: `**x**` → `\textbf{x}`, `*x*` → `\emph{x}` (a `*` that opens
/// a word and has a closing `*`), `` `x` `` → `\texttt{x}` (escaped verbatim, with break points
/// after `/`, `_`, `.` and `,`), Markdown's `\|` → `|`; the rest through [`tex::text`] (Unicode
/// mathematics to LaTeX math).
pub fn inline(s: &str) -> String {
    let s = s.replace("\\|", "|");
    let chars: Vec<char> = s.chars().collect();
    let mut o = String::new();
    let mut plain = String::new();
    let (mut bold, mut emph, mut code) = (false, false, false);
    let mut i = 0;
    let flush = |o: &mut String, plain: &mut String, code: bool| {
        if code {
            *o += &code_text(plain);
        } else {
            *o += &tex::text(plain);
        }
        plain.clear();
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '`' {
            flush(&mut o, &mut plain, code);
            o += if code { "}" } else { "\\texttt{" };
            code = !code;
        } else if code {
            plain.push(c);
        } else if c == '*' && next == Some('*') {
            flush(&mut o, &mut plain, code);
            o += if bold { "}" } else { "\\textbf{" };
            bold = !bold;
            i += 1;
        } else if c == '*'
            && (emph
                || (next.is_some_and(char::is_alphanumeric)
                    && (i == 0 || !chars[i - 1].is_alphanumeric())
                    && chars[i + 1..].contains(&'*')))
        {
            flush(&mut o, &mut plain, code);
            o += if emph { "}" } else { "\\emph{" };
            emph = !emph;
        } else {
            plain.push(c);
        }
        i += 1;
    }
    flush(&mut o, &mut plain, code);
    for open in [code, bold, emph] {
        if open {
            o.push('}');
        }
    }
    o
}

/// Code escaped verbatim, with a break point after each `/`, `_`, `.`, `,` and `=` (typewriter
/// text does not hyphenate, and paths would run into the margin).
fn code_text(s: &str) -> String {
    let mut o = String::new();
    for c in s.chars() {
        o += &tex::literal(&c.to_string());
        if matches!(c, '/' | '_' | '.' | ',' | '=') {
            o += "\\allowbreak{}";
        }
    }
    o
}

/// Escape plain text for LaTeX: special characters escaped, Unicode mathematics as math
/// ([`tex::text`]).
pub fn escape(s: &str) -> String {
    tex::text(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inline_markup() {
        assert_eq!(
            inline("**a** *b* `c_d` x*y (3.60*) 5%"),
            "\\textbf{a} \\emph{b} \\texttt{c\\_\\allowbreak{}d} x*y (3.60*) 5\\%"
        );
        assert_eq!(inline("\\|E g − ∇F\\|"), "$|$E g $-$ $\\nabla$F$|$");
    }

    #[test]
    fn one_table_two_renderings() {
        let b = [Block::Table(Table {
            caption: Some("**Table 4.1: t** (kit):".into()),
            label: "tab:x".into(),
            header: vec!["a".into(), "b".into()],
            rows: vec![vec!["1".into(), "p|q".into()]],
            spec: "lr".into(),
        })];
        assert_eq!(
            markdown(&b),
            "**Table 4.1: t** (kit):\n\n| a | b |\n|---|---|\n| 1 | p\\|q |\n\n"
        );
        let t = latex(&b, "");
        assert!(
            t.contains("\\renewcommand{\\thetable}{4.1}\n")
                && t.contains("\\caption{\\textbf{T} (kit)}\\label{tab:x}"),
            "{t}"
        );
        assert!(t.contains("1 & p$|$q \\\\"), "{t}");
        assert!(t.contains("\\toprule") && t.contains("\\bottomrule"), "{t}");
    }

    /// A float whose caption leads with a thesis number carries that number alone; others
    /// keep the document's numbering.
    #[test]
    fn floats_carry_the_thesis_number_only() {
        assert_eq!(
            caption_parts("Fig. 4.5 (a): obstacle task, x"),
            (Some("4.5\\,(a)".into()), "Obstacle task, x".into())
        );
        assert_eq!(
            caption_parts("**Table 4.2: runtime** (kit):"),
            (Some("4.2".into()), "\\textbf{Runtime} (kit)".into())
        );
        assert_eq!(caption_parts("RMSE by N"), (None, "RMSE by N".into()));
        let b = [Block::Figure {
            path: "figures/f.png".into(),
            caption: "Fig. 4.3: success".into(),
        }];
        let t = latex(&b, "");
        assert!(
            t.contains("\\renewcommand{\\thefigure}{4.3}\\caption{Success}"),
            "{t}"
        );
        assert!(!t.contains("thesis Fig"), "{t}");
    }

    /// Short tables keep one line a row; a table of long descriptions wraps at \footnotesize,
    /// and goes to a landscape page when its rows would be tall.
    #[test]
    fn tables_wrap_at_a_readable_size_and_turn_when_rows_are_tall() {
        let h = |v: &[&str]| v.iter().map(|s| (*s).to_string()).collect::<Vec<_>>();
        let short = column_layout(&h(&["a", "b"]), &[h(&["1", "2"])], "lr");
        assert_eq!((short.size, short.landscape), ("\\small", false));
        assert_eq!(short.columns, ["l", "r"]);
        let words = "word ".repeat(30);
        let two = column_layout(
            &h(&["#", "text", "verdict"]),
            &[h(&["C1", &words, "not reproduced"])],
            "lll",
        );
        assert_eq!((two.size, two.landscape), ("\\footnotesize", false));
        assert!(two.columns[1].contains("p{"), "{:?}", two.columns);
        let long = "description ".repeat(25);
        let cells: Vec<String> = (0..6).map(|_| long.clone()).collect();
        let tall = column_layout(
            &h(&["a", "b", "c", "d", "e", "f"]),
            &[cells.clone(), cells],
            "llllll",
        );
        assert!(tall.landscape, "{tall:?}");
    }

    /// A landscape table opens its own page, unless a heading and at most two paragraphs lead
    /// straight into it: they then go onto its page, and the page opens once, before them.
    #[test]
    fn a_sections_opening_goes_onto_its_landscape_tables_page() {
        let long = "description ".repeat(25);
        let tall = Block::Table(Table {
            caption: Some("checks".into()),
            label: "tab:x".into(),
            header: (0..6).map(|i| i.to_string()).collect(),
            rows: vec![(0..6).map(|_| long.clone()).collect(); 2],
            spec: "llllll".into(),
        });
        let heading = Block::Heading {
            level: 2,
            text: "Theorem checks".into(),
        };
        let para = |t: &str| Block::Para(t.into());
        let opens_at = |blocks: &[Block]| {
            let t = latex(blocks, "");
            assert_eq!(t.matches("\\begin{landscape}").count(), 1, "{t}");
            assert_eq!(t.matches("\\end{landscape}").count(), 1, "{t}");
            let at = t.find("\\begin{landscape}").unwrap();
            (
                t[..at].contains("Theorem checks"),
                t[..at].contains("intro"),
            )
        };
        let led = [heading.clone(), para("intro"), para("more"), tall.clone()];
        assert_eq!(opens_at(&led), (false, false));
        let long_lead = [
            heading.clone(),
            para("intro"),
            para("more"),
            para("and more"),
            tall.clone(),
        ];
        assert_eq!(opens_at(&long_lead), (true, true));
        let listed = [heading, para("intro"), Block::List(vec!["x".into()]), tall];
        assert_eq!(opens_at(&listed), (true, true));
    }
}
