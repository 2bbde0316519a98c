//! Plain text with Unicode mathematics to LaTeX (for pdflatex with `amsmath`/`amssymb`).
//!
//! The appendix's prose, captions and table cells write mathematics the way a reader types it:
//! Greek letters, operators (‖, ∇, ∂, Σ, ℝ, ≤, ′ …), Unicode sub- and superscripts (θ₀, ᵏ, ²),
//! combining accents (σ̂, X̄) and TeX-like scripts (`d_{k+1}`, `u^{⌈n/T⌉}`). [`text`] translates
//! each character class into LaTeX: ordinary text stays text, LaTeX's special characters are
//! escaped, and every mathematical character becomes math mode; neighbouring math pieces share
//! one `$…$` so scripts attach to their base. [`literal`] escapes code (`\texttt`) verbatim.

/// One translated piece: text, or the inside of a math run.
#[derive(Debug, Clone, PartialEq)]
enum Piece {
    Text(String),
    Math(String),
}

/// Math for a character, if it is a mathematical symbol (not a script or accent).
fn math_symbol(c: char) -> Option<&'static str> {
    Some(match c {
        // Greek, lower case.
        'α' => "\\alpha",
        'β' => "\\beta",
        'γ' => "\\gamma",
        'δ' => "\\delta",
        'ε' => "\\varepsilon",
        'ϵ' => "\\epsilon",
        'ζ' => "\\zeta",
        'η' => "\\eta",
        'θ' => "\\theta",
        'ϑ' => "\\vartheta",
        'ι' => "\\iota",
        'κ' => "\\kappa",
        'λ' => "\\lambda",
        'μ' => "\\mu",
        'ν' => "\\nu",
        'ξ' => "\\xi",
        'π' => "\\pi",
        'ρ' => "\\rho",
        'σ' => "\\sigma",
        'ς' => "\\varsigma",
        'τ' => "\\tau",
        'υ' => "\\upsilon",
        'φ' => "\\phi",
        'ϕ' => "\\phi",
        'χ' => "\\chi",
        'ψ' => "\\psi",
        'ω' => "\\omega",
        // Greek, upper case (those that differ from Latin letters).
        'Γ' => "\\Gamma",
        'Δ' => "\\Delta",
        'Θ' => "\\Theta",
        'Λ' => "\\Lambda",
        'Ξ' => "\\Xi",
        'Π' => "\\Pi",
        'Σ' => "\\Sigma",
        'Φ' => "\\Phi",
        'Ψ' => "\\Psi",
        'Ω' => "\\Omega",
        // Sets and letter-like symbols.
        'ℝ' => "\\mathbb{R}",
        'ℕ' => "\\mathbb{N}",
        'ℤ' => "\\mathbb{Z}",
        'ℚ' => "\\mathbb{Q}",
        'ℂ' => "\\mathbb{C}",
        'ℙ' => "\\mathbb{P}",
        'ℓ' => "\\ell",
        'ḡ' => "\\bar{g}",
        '½' => "\\tfrac{1}{2}",
        '¼' => "\\tfrac{1}{4}",
        '¾' => "\\tfrac{3}{4}",
        '∂' => "\\partial",
        '∇' => "\\nabla",
        '∞' => "\\infty",
        '∅' => "\\emptyset",
        // Operators.
        '∑' => "\\sum",
        '∏' => "\\prod",
        '∫' => "\\int",
        '√' => "\\surd",
        '±' => "\\pm",
        '∓' => "\\mp",
        '×' => "\\times",
        '÷' => "\\div",
        '·' => "\\cdot",
        '∘' => "\\circ",
        '−' => "-",
        '∗' => "\\ast",
        '⊗' => "\\otimes",
        '⊕' => "\\oplus",
        '∪' => "\\cup",
        '∩' => "\\cap",
        '∧' => "\\wedge",
        '∨' => "\\vee",
        '¬' => "\\neg",
        // Relations and arrows.
        '≤' => "\\leq",
        '≥' => "\\geq",
        '≪' => "\\ll",
        '≫' => "\\gg",
        '≠' => "\\neq",
        '≈' => "\\approx",
        '≃' => "\\simeq",
        '≅' => "\\cong",
        '≡' => "\\equiv",
        '∼' => "\\sim",
        '∝' => "\\propto",
        '∈' => "\\in",
        '∉' => "\\notin",
        '⊂' => "\\subset",
        '⊆' => "\\subseteq",
        '⊃' => "\\supset",
        '⊇' => "\\supseteq",
        '∀' => "\\forall",
        '∃' => "\\exists",
        '→' => "\\to",
        '←' => "\\leftarrow",
        '↔' => "\\leftrightarrow",
        '⇒' => "\\Rightarrow",
        '⇐' => "\\Leftarrow",
        '⇔' => "\\Leftrightarrow",
        '↦' => "\\mapsto",
        '↑' => "\\uparrow",
        '↓' => "\\downarrow",
        '⊤' => "\\top",
        '⊥' => "\\perp",
        '†' => "\\dagger",
        // Delimiters.
        '‖' => "\\|",
        '|' => "|",
        '<' => "<",
        '>' => ">",
        '⌈' => "\\lceil",
        '⌉' => "\\rceil",
        '⌊' => "\\lfloor",
        '⌋' => "\\rfloor",
        '⟨' => "\\langle",
        '⟩' => "\\rangle",
        // Primes.
        '′' => "'",
        '″' => "''",
        '‴' => "'''",
        '⋯' => "\\cdots",
        '⋮' => "\\vdots",
        _ => return None,
    })
}

/// A Unicode superscript (`true`) or subscript (`false`) and the character it stands for.
fn script(c: char) -> Option<(bool, char)> {
    const SUP: [(char, char); 31] = [
        ('⁰', '0'),
        ('¹', '1'),
        ('²', '2'),
        ('³', '3'),
        ('⁴', '4'),
        ('⁵', '5'),
        ('⁶', '6'),
        ('⁷', '7'),
        ('⁸', '8'),
        ('⁹', '9'),
        ('⁺', '+'),
        ('⁻', '-'),
        ('⁼', '='),
        ('⁽', '('),
        ('⁾', ')'),
        ('ⁱ', 'i'),
        ('ⁿ', 'n'),
        ('ᵃ', 'a'),
        ('ᵇ', 'b'),
        ('ᶜ', 'c'),
        ('ᵈ', 'd'),
        ('ᵉ', 'e'),
        ('ᵍ', 'g'),
        ('ʰ', 'h'),
        ('ʲ', 'j'),
        ('ᵏ', 'k'),
        ('ˡ', 'l'),
        ('ᵐ', 'm'),
        ('ᵗ', 't'),
        ('ᵀ', 'T'),
        ('ˣ', 'x'),
    ];
    const SUB: [(char, char); 28] = [
        ('₀', '0'),
        ('₁', '1'),
        ('₂', '2'),
        ('₃', '3'),
        ('₄', '4'),
        ('₅', '5'),
        ('₆', '6'),
        ('₇', '7'),
        ('₈', '8'),
        ('₉', '9'),
        ('₊', '+'),
        ('₋', '-'),
        ('₌', '='),
        ('₍', '('),
        ('₎', ')'),
        ('ₐ', 'a'),
        ('ₑ', 'e'),
        ('ₒ', 'o'),
        ('ₓ', 'x'),
        ('ₕ', 'h'),
        ('ᵢ', 'i'),
        ('ⱼ', 'j'),
        ('ₖ', 'k'),
        ('ₗ', 'l'),
        ('ₘ', 'm'),
        ('ₙ', 'n'),
        ('ₚ', 'p'),
        ('ₜ', 't'),
    ];
    if let Some(&(_, b)) = SUP.iter().find(|(u, _)| *u == c) {
        return Some((true, b));
    }
    SUB.iter().find(|(u, _)| *u == c).map(|&(_, b)| (false, b))
}

/// The LaTeX accent command of a combining mark.
fn accent(c: char) -> Option<&'static str> {
    Some(match c {
        '\u{0302}' => "\\hat",
        '\u{0303}' => "\\tilde",
        '\u{0304}' | '\u{0305}' => "\\bar",
        '\u{0307}' => "\\dot",
        '\u{0308}' => "\\ddot",
        '\u{030C}' => "\\check",
        '\u{0306}' => "\\breve",
        '\u{20D7}' => "\\vec",
        _ => return None,
    })
}

/// Text-mode LaTeX for a character that is not mathematics (`None`: printable as it is).
fn text_symbol(c: char) -> Option<&'static str> {
    Some(match c {
        '\\' => "\\textbackslash{}",
        '&' => "\\&",
        '%' => "\\%",
        '$' => "\\$",
        '#' => "\\#",
        '_' => "\\_",
        '{' => "\\{",
        '}' => "\\}",
        '~' => "\\textasciitilde{}",
        '^' => "\\textasciicircum{}",
        '–' => "--",
        '—' => "---",
        '‘' => "`",
        '’' => "'",
        '“' => "``",
        '”' => "''",
        '…' => "\\ldots{}",
        '§' => "\\S{}",
        '¶' => "\\P{}",
        '°' => "\\ensuremath{^\\circ}",
        '\u{00A0}' => "~",
        '\u{2009}' | '\u{202F}' => "\\,",
        '•' => "\\textbullet{}",
        '✓' => "\\ensuremath{\\checkmark}",
        _ => return None,
    })
}

/// Whether pdflatex's default UTF-8 input (T1/OT1 text fonts) prints `c` as it is: ASCII, and
/// the accented Latin letters of Latin-1 and Latin Extended-A.
fn plain_ok(c: char) -> bool {
    c.is_ascii() || (('\u{00C0}'..='\u{017F}').contains(&c) && c != '×' && c != '÷')
}

/// Whether [`text`] translates `c` into something pdflatex prints (rather than a placeholder).
pub fn supported(c: char) -> bool {
    plain_ok(c)
        || math_symbol(c).is_some()
        || script(c).is_some()
        || accent(c).is_some()
        || text_symbol(c).is_some()
}

/// Escape `s` verbatim for text mode (code spans): every LaTeX special character escaped, no
/// mathematics. A character pdflatex cannot print becomes `[U+XXXX]`.
pub fn literal(s: &str) -> String {
    let mut o = String::new();
    for c in s.chars() {
        if let Some(t) = text_symbol(c) {
            o += t;
        } else if plain_ok(c) {
            o.push(c);
        } else if let Some(m) = math_symbol(c) {
            o += "\\ensuremath{";
            o += m;
            o.push('}');
        } else {
            o += &format!("[U+{:04X}]", u32::from(c));
        }
    }
    o
}

/// The math-mode form of one character (for scripts and accent bases).
fn as_math(c: char) -> String {
    if let Some(m) = math_symbol(c) {
        return m.to_string();
    }
    match c {
        '{' => "\\{".into(),
        '}' => "\\}".into(),
        '%' | '#' | '&' | '$' | '_' => format!("\\{c}"),
        '\\' => "\\backslash".into(),
        '~' | '^' => String::new(),
        c if c.is_ascii() => c.to_string(),
        c => format!("\\text{{{}}}", literal(&c.to_string())),
    }
}

/// A TeX-like script argument starting at `chars[i]` (just after `_` or `^`): a braced group
/// (balanced) or a run of letters and digits. Returns its math text and the index after it.
fn script_argument(chars: &[char], i: usize) -> Option<(String, usize)> {
    let first = *chars.get(i)?;
    if first == '{' {
        let mut depth = 0;
        for (j, &c) in chars.iter().enumerate().skip(i) {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        return Some((math_of(&chars[i + 1..j]), j + 1));
                    }
                }
                _ => {}
            }
        }
        None
    } else if first.is_alphanumeric() || math_symbol(first).is_some() {
        let mut j = i;
        while j < chars.len()
            && (chars[j].is_ascii_alphanumeric() || (j == i && math_symbol(chars[j]).is_some()))
        {
            j += 1;
        }
        (j > i).then(|| (math_of(&chars[i..j]), j))
    } else {
        None
    }
}

/// Math text for a run of characters (the inside of a script argument).
fn math_of(chars: &[char]) -> String {
    let mut o = String::new();
    for p in pieces(chars) {
        match p {
            Piece::Math(m) => append_math(&mut o, &m),
            Piece::Text(t) if t.is_empty() => {}
            Piece::Text(t) => {
                if t.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "+-=()[],./*':;!?<> ".contains(c))
                {
                    append_math(&mut o, &t.replace(' ', "\\ "));
                } else {
                    append_math(&mut o, &format!("\\text{{{t}}}"));
                }
            }
        }
    }
    o
}

/// Move a variable name (a run of at most two ASCII letters ending `out`'s last text piece, not
/// part of a longer word) into math, so a script attaches to it.
fn take_base(out: &mut [Piece]) -> String {
    let Some(Piece::Text(t)) = out.last_mut() else {
        return String::new();
    };
    let letters = t
        .chars()
        .rev()
        .take_while(char::is_ascii_alphanumeric)
        .count();
    if letters == 0 || letters > 2 {
        return String::new();
    }
    let cut = t.len() - letters;
    let base = t[cut..].to_string();
    t.truncate(cut);
    base
}

/// Append math text, with a space where a letter would otherwise extend a control word
/// (`\lceil` + `n`).
fn append_math(prev: &mut String, m: &str) {
    let word = prev
        .chars()
        .rev()
        .take_while(char::is_ascii_alphabetic)
        .count();
    let ends_in_control_word = word > 0 && prev[..prev.len() - word].ends_with('\\');
    if ends_in_control_word && m.starts_with(|c: char| c.is_ascii_alphabetic()) {
        prev.push(' ');
    }
    prev.push_str(m);
}

fn push_math(out: &mut Vec<Piece>, m: &str) {
    if let Some(Piece::Math(prev)) = out.last_mut() {
        append_math(prev, m);
    } else {
        out.push(Piece::Math(m.to_string()));
    }
}

fn push_text(out: &mut Vec<Piece>, t: &str) {
    if let Some(Piece::Text(prev)) = out.last_mut() {
        prev.push_str(t);
    } else {
        out.push(Piece::Text(t.to_string()));
    }
}

/// Whether `_`/`^` at `chars[i]` is a script: it follows a letter, digit, closing bracket or a
/// math character, and an argument follows.
fn is_script_mark(chars: &[char], i: usize) -> bool {
    let before = i.checked_sub(1).and_then(|k| chars.get(k)).copied();
    let Some(b) = before else { return false };
    let base_ok = b.is_alphanumeric()
        || matches!(b, ')' | ']' | '}' | '\'')
        || math_symbol(b).is_some()
        || accent(b).is_some()
        || script(b).is_some();
    // A word longer than a variable name (`printed_algorithm_5`) is an identifier, not a base.
    let word = chars[..i]
        .iter()
        .rev()
        .take_while(|c| c.is_ascii_alphanumeric())
        .count();
    let identifier = word > 2 && chars[i - word..i].iter().any(char::is_ascii_alphabetic);
    let Some((_, next)) = script_argument(chars, i + 1) else {
        return false;
    };
    base_ok && !identifier && !matches!(chars.get(next), Some('_' | '^'))
}

fn pieces(chars: &[char]) -> Vec<Piece> {
    let mut out: Vec<Piece> = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if (c == '_' || c == '^')
            && is_script_mark(chars, i)
            && let Some((arg, next)) = script_argument(chars, i + 1)
        {
            let base = take_base(&mut out);
            push_math(&mut out, &format!("{base}{c}{{{arg}}}"));
            i = next;
            continue;
        }
        if let Some((sup, b)) = script(c) {
            // A run of scripts of one kind is one group: ⁻¹ → ^{-1}.
            let mut arg = as_math(b);
            let mut j = i + 1;
            while let Some((s2, b2)) = chars.get(j).and_then(|&c2| script(c2)) {
                if s2 != sup {
                    break;
                }
                arg += &as_math(b2);
                j += 1;
            }
            let base = take_base(&mut out);
            push_math(
                &mut out,
                &format!("{base}{}{{{arg}}}", if sup { '^' } else { '_' }),
            );
            i = j;
            continue;
        }
        if let Some(cmd) = accent(c) {
            // The accent applies to the previous character.
            let base = match out.last_mut() {
                Some(Piece::Text(t)) => t.pop().map(as_math),
                Some(Piece::Math(m)) => pop_math_atom(m),
                None => None,
            };
            push_math(&mut out, &format!("{cmd}{{{}}}", base.unwrap_or_default()));
            i += 1;
            continue;
        }
        if let Some(m) = math_symbol(c) {
            push_math(&mut out, m);
        } else if let Some(t) = text_symbol(c) {
            push_text(&mut out, t);
        } else if plain_ok(c) {
            push_text(&mut out, &c.to_string());
        } else {
            push_text(&mut out, &format!("[U+{:04X}]", u32::from(c)));
        }
        i += 1;
    }
    out.retain(|p| !matches!(p, Piece::Text(t) | Piece::Math(t) if t.is_empty()));
    out
}

/// Remove and return the last atom of math text: a control word (`\sigma`), a braced group or
/// one character.
fn pop_math_atom(m: &mut String) -> Option<String> {
    if m.ends_with('}') {
        // A control word with its braced argument(s) (`\mathbb{R}`) or a bare group.
        let bytes: Vec<char> = m.chars().collect();
        let mut depth = 0;
        let mut start = bytes.len();
        for k in (0..bytes.len()).rev() {
            match bytes[k] {
                '}' => depth += 1,
                '{' => {
                    depth -= 1;
                    if depth == 0 {
                        start = k;
                        break;
                    }
                }
                _ => {}
            }
        }
        // Include the command word before the group.
        let mut s = start;
        while s > 0 && bytes[s - 1].is_ascii_alphabetic() {
            s -= 1;
        }
        if s > 0 && bytes[s - 1] == '\\' {
            s -= 1;
        } else {
            s = start;
        }
        let atom: String = bytes[s..].iter().collect();
        m.truncate(bytes[..s].iter().collect::<String>().len());
        return Some(atom);
    }
    let chars: Vec<char> = m.chars().collect();
    let mut s = chars.len();
    while s > 0 && chars[s - 1].is_ascii_alphabetic() {
        s -= 1;
    }
    if s > 0 && chars[s - 1] == '\\' && s < chars.len() {
        s -= 1;
    } else {
        s = chars.len().checked_sub(1)?;
    }
    let atom: String = chars[s..].iter().collect();
    m.truncate(chars[..s].iter().collect::<String>().len());
    Some(atom)
}

/// A break point every 8 digits of a run of more than 16 (exact rationals can be longer than a
/// line).
fn break_long_numbers(t: &str) -> String {
    let mut o = String::new();
    let chars: Vec<char> = t.chars().collect();
    let mut k = 0;
    while k < chars.len() {
        let run = chars[k..].iter().take_while(|c| c.is_ascii_digit()).count();
        if run > 16 {
            for (m, c) in chars[k..k + run].iter().enumerate() {
                if m > 0 && m % 8 == 0 {
                    o += "\\allowbreak{}";
                }
                o.push(*c);
            }
            k += run;
        } else {
            o.push(chars[k]);
            k += 1;
        }
    }
    o
}

/// Translate plain text with Unicode mathematics to LaTeX: text escaped, mathematics in `$…$`
/// (neighbouring pieces share one math run). A character outside every supported class becomes
/// `[U+XXXX]` (see [`supported`]).
pub fn text(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut o = String::new();
    for p in pieces(&chars) {
        match p {
            Piece::Text(t) => o += &break_long_numbers(&t),
            Piece::Math(m) => {
                o.push('$');
                o += &m;
                o.push('$');
            }
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specials_are_escaped() {
        assert_eq!(
            text("5% & $3 # {x} ~ a\\b"),
            "5\\% \\& \\$3 \\# \\{x\\} \\textasciitilde{} a\\textbackslash{}b"
        );
        assert_eq!(
            literal("runs/*.json x_range ^"),
            "runs/*.json x\\_range \\textasciicircum{}"
        );
        // A lone underscore or caret is not a script, nor one inside an identifier.
        assert_eq!(text("a _ b ^ c"), "a \\_ b \\textasciicircum{} c");
        assert_eq!(text("printed_algorithm_5"), "printed\\_algorithm\\_5");
    }

    #[test]
    fn greek_and_symbols_are_math() {
        assert_eq!(text("κ ≤ 1"), "$\\kappa$ $\\leq$ 1");
        assert_eq!(text("θ ∈ ℝ"), "$\\theta$ $\\in$ $\\mathbb{R}$");
        assert_eq!(text("∂F/∂θ"), "$\\partial$F/$\\partial\\theta$");
        assert_eq!(text("Σ_t"), "$\\Sigma_{t}$");
        assert_eq!(text("‖∇F‖"), "$\\|\\nabla$F$\\|$");
        assert_eq!(text("1 − a"), "1 $-$ a");
    }

    #[test]
    fn unicode_scripts_attach_to_their_base() {
        assert_eq!(text("θ₀"), "$\\theta_{0}$");
        assert_eq!(text("10⁻³"), "$10^{-3}$");
        assert_eq!(text("L²"), "$L^{2}$");
        assert_eq!(text("γᵏ x"), "$\\gamma^{k}$ x");
        assert_eq!(text("ηₖ"), "$\\eta_{k}$");
        // A long word keeps its letters in text; the script alone is math.
        assert_eq!(text("norm²"), "norm$^{2}$");
    }

    #[test]
    fn tex_like_scripts_are_math() {
        assert_eq!(text("d_{k+1}"), "$d_{k+1}$");
        assert_eq!(text("a_{k+1}"), "$a_{k+1}$");
        assert_eq!(text("η_k²Δ_k"), "$\\eta_{k}^{2}\\Delta_{k}$");
        assert_eq!(text("L_F-smoothness"), "$L_{F}$-smoothness");
        assert_eq!(text("u^{⌈n/T⌉}"), "$u^{\\lceil n/T\\rceil}$");
        assert_eq!(text("s_{n'}"), "$s_{n'}$");
    }

    #[test]
    fn primes_and_combining_marks() {
        assert_eq!(text("θ′"), "$\\theta'$");
        assert_eq!(text("σ̂/√N"), "$\\hat{\\sigma}$/$\\surd$N");
        assert_eq!(text("X̄/B"), "$\\bar{X}$/B");
        assert_eq!(text("ℝ̂"), "$\\hat{\\mathbb{R}}$");
    }

    #[test]
    fn long_numbers_can_break() {
        assert_eq!(
            text("12345678901234567/3"),
            "12345678\\allowbreak{}90123456\\allowbreak{}7/3"
        );
        assert_eq!(text("1234567890"), "1234567890");
    }

    #[test]
    fn text_punctuation_and_latin_letters() {
        assert_eq!(text("a–b — “q” …"), "a--b --- ``q'' \\ldots{}");
        assert_eq!(text("§3 café"), "\\S{}3 café");
    }

    #[test]
    fn unsupported_characters_are_visible_placeholders() {
        assert!(!supported('☃'));
        assert_eq!(text("☃"), "[U+2603]");
        for c in "ℝ∂Σκ′₀ᵏ\u{0302}\u{0304}‖∇±≤≥θσ·…–—×§½ḡ".chars()
        {
            assert!(supported(c), "{c}");
        }
    }
}
