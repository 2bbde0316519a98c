//! The config's integer keys in the user's words: `run.budget_calls` = -5 is "must be an integer
//! ≥ 1, got -5", not the deserialiser's "expected u64". The schema's own integer keys
//! ([`SCHEMA_INTEGERS`]) are checked against their ranges before the file is deserialised; an
//! integer out of its type's range anywhere else (the `[algorithm]` table, `policy.features`,
//! `run.baseline`) is named from the deserialiser's error.

use super::error::{RunError, invalid};
use std::path::Path;
use toml::de::{DeTable, DeValue};

/// Largest fixed horizon accepted (decisions per trajectory).
pub const MAX_STEPS: usize = 100_000;
/// Largest number of seeds in one config.
pub const MAX_SEEDS: usize = 10_000;
/// Largest number of evaluation episodes per checkpoint.
pub const MAX_EPISODES: u32 = 1_000_000;
/// Largest number of trajectories per gradient.
pub const MAX_TRAJECTORIES: usize = 100_000;

/// An integer key of the schema and its range (inclusive).
#[derive(Debug, Clone, Copy)]
pub struct IntegerKey {
    /// The dotted key.
    pub key: &'static str,
    /// The least value accepted.
    pub min: i64,
    /// The largest value accepted.
    pub max: i64,
    /// Whether the key holds an array of such integers (`run.seeds`).
    pub array: bool,
}

const fn key(key: &'static str, min: i64, max: i64) -> IntegerKey {
    IntegerKey {
        key,
        min,
        max,
        array: false,
    }
}

/// The schema's integer keys outside `[algorithm]`, with their ranges; `evaluation.every_calls`
/// is also checked against `run.budget_calls` once both are known.
pub const SCHEMA_INTEGERS: [IntegerKey; 6] = [
    key("task.steps", 1, MAX_STEPS as i64),
    key("run.budget_calls", 1, i64::MAX),
    key("run.trajectories_per_gradient", 1, MAX_TRAJECTORIES as i64),
    IntegerKey {
        key: "run.seeds",
        min: 0,
        max: i64::MAX,
        array: true,
    },
    key("evaluation.every_calls", 1, i64::MAX),
    key("evaluation.episodes", 1, MAX_EPISODES as i64),
];

/// "an integer ≥ 1" or "an integer in 1..=100000".
fn range_words(min: i64, max: i64) -> String {
    if max == i64::MAX {
        format!("an integer ≥ {min}")
    } else {
        format!("an integer in {min}..={max}")
    }
}

/// Check every key of [`SCHEMA_INTEGERS`] that `raw` sets to a number (a value of another type
/// is left to the deserialiser, whose message names the type expected).
///
/// # Errors
/// [`RunError::Invalid`] naming the key, its range and the value given.
pub(super) fn check_schema_integers(raw: &toml::Table, path: &Path) -> Result<(), RunError> {
    for k in &SCHEMA_INTEGERS {
        let (section, name) = k.key.split_once('.').unwrap_or(("", k.key));
        let Some(value) = raw
            .get(section)
            .and_then(toml::Value::as_table)
            .and_then(|t| t.get(name))
        else {
            continue;
        };
        let words = range_words(k.min, k.max);
        let check = |v: &toml::Value, what: &str| -> Result<(), RunError> {
            let ok = match v {
                toml::Value::Integer(i) => (k.min..=k.max).contains(i),
                toml::Value::Float(_) => false,
                _ => return Ok(()),
            };
            if ok {
                Ok(())
            } else {
                Err(invalid(
                    path,
                    k.key,
                    format!("{what}must be {words}, got {v}"),
                ))
            }
        };
        match (k.array, value) {
            (true, toml::Value::Array(items)) => {
                for (i, v) in items.iter().enumerate() {
                    check(v, &format!("entry {i} (0-based) "))?;
                }
            }
            (false, v) => check(v, "")?,
            _ => {}
        }
    }
    Ok(())
}

/// The deserialiser's "invalid value: integer `-5`, expected u64" (or u32, usize, …) as a
/// [`RunError::Invalid`] naming the key that holds the integer and the type's range; `None` for
/// any other error.
pub(super) fn integer_error(text: &str, error: &toml::de::Error, path: &Path) -> Option<RunError> {
    let message = error.message();
    let rest = message.strip_prefix("invalid value: integer `")?;
    let (value, rest) = rest.split_once("`, expected ")?;
    let value: i64 = value.parse().ok()?;
    let max: i64 = match rest.trim() {
        "u8" => u8::MAX.into(),
        "u16" => u16::MAX.into(),
        "u32" => u32::MAX.into(),
        "u64" | "usize" => i64::MAX,
        _ => return None,
    };
    let key = error
        .span()
        .and_then(|span| key_of_integer(text, span, value))
        .unwrap_or_else(|| "?".into());
    Some(invalid(
        path,
        &key,
        format!("must be {}, got {value}", range_words(0, max)),
    ))
}

/// The dotted key (with `[i]` for array entries) of the value holding the integer `value` at
/// `span`: the innermost value whose span contains it, or, when the deserialiser could only
/// point at a whole table (the `[algorithm]` table is read through a buffer), the one key inside
/// it that holds `value`.
fn key_of_integer(text: &str, span: std::ops::Range<usize>, value: i64) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    let mut at = String::new();
    let mut node: &DeValue<'_> = &DeValue::Table(doc.into_inner());
    'down: loop {
        let children: Vec<(String, &toml::Spanned<DeValue<'_>>)> = match node {
            DeValue::Table(t) => t.iter().map(|(k, v)| (join(&at, k.get_ref()), v)).collect(),
            DeValue::Array(a) => a
                .iter()
                .enumerate()
                .map(|(i, v)| (format!("{at}[{i}]"), v))
                .collect(),
            _ => return Some(at),
        };
        for (name, child) in children {
            let s = child.span();
            if s.start <= span.start && span.end <= s.end {
                at = name;
                node = child.get_ref();
                continue 'down;
            }
        }
        break;
    }
    let mut found = Vec::new();
    holding(node, &at, value, &mut found);
    match found.len() {
        1 => found.pop(),
        _ => (!at.is_empty()).then_some(at),
    }
}

fn join(at: &str, k: &str) -> String {
    if at.is_empty() {
        k.to_string()
    } else {
        format!("{at}.{k}")
    }
}

/// Every key under `node` whose value is the integer `value`.
fn holding(node: &DeValue<'_>, at: &str, value: i64, found: &mut Vec<String>) {
    match node {
        DeValue::Integer(i) if i64::from_str_radix(i.as_str(), i.radix()).ok() == Some(value) => {
            found.push(at.to_string());
        }
        DeValue::Table(t) => {
            for (k, v) in t {
                holding(v.get_ref(), &join(at, k.get_ref()), value, found);
            }
        }
        DeValue::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                holding(v.get_ref(), &format!("{at}[{i}]"), value, found);
            }
        }
        _ => {}
    }
}
