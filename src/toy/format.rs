//! The toy-MDP JSON format (`docs/formats/toy-mdp.md`), read exactly.
//!
//! Numbers are exact decimal or fraction strings (`"0.25"`, `"1/3"`, `"-7/2"`); plain JSON numbers
//! are accepted only where they are integers. Every violation is a [`ToyError`] that names the
//! field and, where there is one, the index (`transition[1][0]`).
//!
//! Policy kinds: `rational-softmax` (P2, the format's contract) and two extensions from math.md §1.3
//! needed by the M-family of §6: `direct` (P1, simplex) and `tied-softmax` (P2', two actions, one
//! parameter per group). Every kind takes an optional `groups` array (the observation map o(s) of
//! §1.3: states in one group share parameters); without it every state is its own group, which is
//! the format's `θ[s·A + a]` layout for `rational-softmax`.
//!
//! Termination (math.md §8) is a further extension: an optional `terminal` array flags states, and
//! `on_terminal` says what happens on entering one — `{"kind": "reset", "law": […]}` (the stream
//! of decisions continues from a reset law) or `{"kind": "absorb", "loss": …}` (the state absorbs
//! and pays a stated loss per remaining step). A file without both fields is the format's fixed
//! horizon MDP, unchanged. See [`Termination`].

use super::policy::{PolicyKind, PolicySpec};
use crate::scalar::{BigRational, ParseExactError, parse_exact};
use num_traits::{One, Signed, Zero};
use serde_json::Value;
use std::path::Path;

/// Upper limits that keep a hostile file from exhausting memory (generous for toy MDPs).
pub const MAX_STATES: usize = 4096;
/// See [`MAX_STATES`].
pub const MAX_ACTIONS: usize = 256;
/// See [`MAX_STATES`].
pub const MAX_HORIZON: usize = 1 << 20;

/// A finite MDP with a deterministic expert and a learner policy class, held exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct ToyMdp {
    /// |S| ≥ 1.
    pub states: usize,
    /// |A| ≥ 2.
    pub actions: usize,
    /// T ≥ 2: τ = (s_1, a_1, …, a_{T−1}, s_T); losses are paid at t = 1..T−1.
    pub horizon: usize,
    /// μ(s_1).
    pub initial: Vec<BigRational>,
    /// P(s′|s, a) as `transition[s][a][s′]`.
    pub transition: Vec<Vec<Vec<BigRational>>>,
    /// π*(s), the expert's deterministic action.
    pub expert: Vec<usize>,
    /// The learner's policy class.
    pub policy: PolicySpec,
    /// What happens when the chain enters a terminal state ([`Termination::None`] for files
    /// without the `terminal`/`on_terminal` extension).
    pub termination: Termination,
}

/// Fixed-horizon semantics for MDPs that terminate early (math.md §8). Both keep the thesis's
/// objective F(θ) = E Σ_{t=1}^{T−1} l_t (eq. 3.1) on an augmented chain whose kernel is
/// [`ToyMdp::chain_transition`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Termination {
    /// No terminal states: the format's MDP as written.
    None,
    /// Reset: a transition into a terminal state is replaced by a draw from `law`, so the
    /// trajectory is a stream of exactly T − 1 decisions over non-terminal states and eq. 3.15
    /// applies unchanged (its score sum runs across resets). The chain never occupies a terminal
    /// state: `initial` and `law` put no mass on one.
    Reset {
        /// `terminal[s]`: whether s is terminal.
        terminal: Vec<bool>,
        /// The reset law μ (a distribution over non-terminal states).
        law: Vec<BigRational>,
    },
    /// Absorbing: a terminal state z keeps the chain for every remaining step whatever the
    /// action, and each of those steps pays `loss[z]` (≥ 0, constant in θ) instead of the Brier
    /// loss. No decision is taken at z: no action, no score, no gradient evaluation.
    Absorb {
        /// `loss[s]`: `Some(c)` for a terminal state (its loss per remaining step), `None` for
        /// a non-terminal one.
        loss: Vec<Option<BigRational>>,
    },
}

impl Termination {
    /// Whether state `s` is terminal.
    pub fn is_terminal(&self, s: usize) -> bool {
        match self {
            Self::None => false,
            Self::Reset { terminal, .. } => terminal.get(s).copied().unwrap_or(false),
            Self::Absorb { loss } => loss.get(s).is_some_and(Option::is_some),
        }
    }
    /// The loss per remaining step of an absorbing state (`None` unless `s` is terminal under
    /// [`Termination::Absorb`]).
    pub fn absorbing_loss(&self, s: usize) -> Option<&BigRational> {
        match self {
            Self::Absorb { loss } => loss.get(s).and_then(Option::as_ref),
            _ => None,
        }
    }
}

/// Why a toy-MDP file was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ToyError {
    /// The file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The path.
        path: String,
        /// The OS error.
        message: String,
    },
    /// Not JSON.
    #[error("not valid JSON (line {line}, column {column}): {message}")]
    Json {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A required field is absent.
    #[error("missing field `{0}`")]
    Missing(String),
    /// A field this format does not have (typos are not silently ignored).
    #[error("unknown field `{0}`")]
    Unknown(String),
    /// A field of the wrong JSON type.
    #[error("`{field}` must be {expected}")]
    Type {
        /// Field path.
        field: String,
        /// What it must be.
        expected: &'static str,
    },
    /// A number that is not exact.
    #[error("`{field}`: {source}")]
    Number {
        /// Field path.
        field: String,
        /// What is wrong.
        source: ParseExactError,
    },
    /// A plain JSON number that is not an integer.
    #[error(
        "`{field}`: plain JSON numbers must be integers; write {value} as an exact string such as \"1/3\" or \"0.25\""
    )]
    NonIntegerNumber {
        /// Field path.
        field: String,
        /// The number as written.
        value: String,
    },
    /// A size out of its range (`states ≥ 1`, `actions ≥ 2`, `horizon ≥ 2`, and the limits).
    #[error("`{field}` = {value} is out of range: {rule}")]
    Range {
        /// Field.
        field: &'static str,
        /// Value given.
        value: String,
        /// The rule.
        rule: &'static str,
    },
    /// An array of the wrong length.
    #[error("`{field}` has length {got}, expected {expected}")]
    Length {
        /// Field path.
        field: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A negative probability.
    #[error("`{field}` is negative ({value})")]
    NegativeProbability {
        /// Field path.
        field: String,
        /// The value.
        value: BigRational,
    },
    /// A distribution whose entries do not sum exactly to 1.
    #[error("`{field}` sums to {sum}, not exactly 1")]
    RowSum {
        /// Field path of the row.
        field: String,
        /// The exact sum.
        sum: BigRational,
    },
    /// An expert action outside 0..A.
    #[error("`expert[{index}]` = {action} is not an action (0..{actions})")]
    ExpertAction {
        /// State index.
        index: usize,
        /// Action given.
        action: String,
        /// Number of actions.
        actions: usize,
    },
    /// The policy parameter c is not positive.
    #[error("`policy.c` = {0} must be > 0")]
    NonPositiveC(BigRational),
    /// An unknown policy kind.
    #[error("`policy.kind` = {0:?} is not one of rational-softmax, direct, tied-softmax")]
    PolicyKind(String),
    /// A policy that does not fit the MDP (e.g. tied-softmax with more than two actions, a group
    /// map with an unused group).
    #[error("`{field}`: {message}")]
    Policy {
        /// Field path.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Terminal states and `on_terminal` that do not fit together or with the MDP (one without
    /// the other, an unknown kind, a reset law or initial law with mass on a terminal state, an
    /// absorbing loss missing, misplaced or negative).
    #[error("`{field}`: {message}")]
    Termination {
        /// Field path.
        field: String,
        /// What is wrong.
        message: String,
    },
}

fn json_error(e: &serde_json::Error) -> ToyError {
    ToyError::Json {
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    }
}

/// Read an exact number: a string in the exact syntax, or an integral JSON number.
pub(crate) fn exact_number(v: &Value, field: &str) -> Result<BigRational, ToyError> {
    match v {
        Value::String(s) => parse_exact(s).map_err(|source| ToyError::Number {
            field: field.to_string(),
            source,
        }),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                Ok(BigRational::from_integer(i.into()))
            } else if let Some(u) = n.as_u64() {
                Ok(BigRational::from_integer(u.into()))
            } else {
                Err(ToyError::NonIntegerNumber {
                    field: field.to_string(),
                    value: n.to_string(),
                })
            }
        }
        _ => Err(ToyError::Type {
            field: field.to_string(),
            expected: "an exact number (string like \"1/3\" or an integer)",
        }),
    }
}

/// Read a non-negative integer index (JSON integer, or an exact string equal to an integer).
fn index(v: &Value, field: &str) -> Result<BigRational, ToyError> {
    let q = exact_number(v, field)?;
    if !q.is_integer() {
        return Err(ToyError::Type {
            field: field.to_string(),
            expected: "an integer",
        });
    }
    Ok(q)
}

fn array<'a>(v: &'a Value, field: &str) -> Result<&'a Vec<Value>, ToyError> {
    v.as_array().ok_or_else(|| ToyError::Type {
        field: field.to_string(),
        expected: "an array",
    })
}

fn sized_array<'a>(v: &'a Value, field: &str, len: usize) -> Result<&'a Vec<Value>, ToyError> {
    let a = array(v, field)?;
    if a.len() != len {
        return Err(ToyError::Length {
            field: field.to_string(),
            expected: len,
            got: a.len(),
        });
    }
    Ok(a)
}

fn size(
    obj: &serde_json::Map<String, Value>,
    field: &'static str,
    min: usize,
    max: usize,
    rule: &'static str,
) -> Result<usize, ToyError> {
    let v = obj
        .get(field)
        .ok_or_else(|| ToyError::Missing(field.into()))?;
    let q = index(v, field)?;
    let n = q.to_integer();
    let text = n.to_string();
    let range = || ToyError::Range {
        field,
        value: text.clone(),
        rule,
    };
    let n: usize = n.try_into().map_err(|_| range())?;
    if n < min || n > max {
        return Err(range());
    }
    Ok(n)
}

/// A probability distribution of length `len`: entries ≥ 0 summing exactly to 1.
fn distribution(v: &Value, field: &str, len: usize) -> Result<Vec<BigRational>, ToyError> {
    let row = sized_array(v, field, len)?;
    let mut out = Vec::with_capacity(len);
    for (i, x) in row.iter().enumerate() {
        let f = format!("{field}[{i}]");
        let q = exact_number(x, &f)?;
        if q.is_negative() {
            return Err(ToyError::NegativeProbability { field: f, value: q });
        }
        out.push(q);
    }
    let sum: BigRational = out.iter().fold(BigRational::zero(), |a, b| a + b);
    if !sum.is_one() {
        return Err(ToyError::RowSum {
            field: field.to_string(),
            sum,
        });
    }
    Ok(out)
}

fn object<'a>(v: &'a Value, field: &str) -> Result<&'a serde_json::Map<String, Value>, ToyError> {
    v.as_object().ok_or_else(|| ToyError::Type {
        field: field.to_string(),
        expected: "an object",
    })
}

fn policy(v: &Value, states: usize, actions: usize) -> Result<PolicySpec, ToyError> {
    let obj = object(v, "policy")?;
    for key in obj.keys() {
        if !matches!(key.as_str(), "kind" | "c" | "groups") {
            return Err(ToyError::Unknown(format!("policy.{key}")));
        }
    }
    let kind = match obj.get("kind") {
        None => return Err(ToyError::Missing("policy.kind".into())),
        Some(Value::String(s)) => match s.as_str() {
            "rational-softmax" => PolicyKind::RationalSoftmax,
            "direct" => PolicyKind::Direct,
            "tied-softmax" => PolicyKind::TiedSoftmax,
            other => return Err(ToyError::PolicyKind(other.to_string())),
        },
        Some(_) => {
            return Err(ToyError::Type {
                field: "policy.kind".into(),
                expected: "a string",
            });
        }
    };
    let c = match (kind, obj.get("c")) {
        (PolicyKind::Direct, None) => None,
        (PolicyKind::Direct, Some(_)) => {
            return Err(ToyError::Policy {
                field: "policy.c".into(),
                message: "the direct parameterisation has no parameter c".into(),
            });
        }
        (_, None) => return Err(ToyError::Missing("policy.c".into())),
        (_, Some(c)) => {
            let c = exact_number(c, "policy.c")?;
            if !c.is_positive() {
                return Err(ToyError::NonPositiveC(c));
            }
            Some(c)
        }
    };
    if kind == PolicyKind::TiedSoftmax && actions != 2 {
        return Err(ToyError::Policy {
            field: "policy.kind".into(),
            message: format!("tied-softmax needs exactly 2 actions, the MDP has {actions}"),
        });
    }
    let groups = match obj.get("groups") {
        None => (0..states).collect(),
        Some(g) => {
            let g = sized_array(g, "policy.groups", states)?;
            let mut out = Vec::with_capacity(states);
            for (i, x) in g.iter().enumerate() {
                let f = format!("policy.groups[{i}]");
                let q = index(x, &f)?;
                let n: usize = q
                    .to_integer()
                    .try_into()
                    .ok()
                    .filter(|n| *n < states)
                    .ok_or_else(|| ToyError::Policy {
                        field: f.clone(),
                        message: format!("group {q} is not in 0..{states}"),
                    })?;
                out.push(n);
            }
            let count = out.iter().max().map_or(0, |m| m + 1);
            if let Some(unused) = (0..count).find(|o| !out.contains(o)) {
                return Err(ToyError::Policy {
                    field: "policy.groups".into(),
                    message: format!(
                        "groups must be numbered 0..G without gaps; group {unused} is unused"
                    ),
                });
            }
            out
        }
    };
    Ok(PolicySpec::new(kind, c, groups, actions))
}

fn termination_error(field: impl Into<String>, message: impl Into<String>) -> ToyError {
    ToyError::Termination {
        field: field.into(),
        message: message.into(),
    }
}

/// The `terminal` flags (length S, booleans).
fn terminal_flags(v: &Value, states: usize) -> Result<Vec<bool>, ToyError> {
    let flags = sized_array(v, "terminal", states)?;
    flags
        .iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_bool().ok_or_else(|| ToyError::Type {
                field: format!("terminal[{i}]"),
                expected: "a boolean",
            })
        })
        .collect()
}

/// `on_terminal` given the `terminal` flags; `initial` is checked against a reset (the chain
/// never occupies a terminal state).
fn termination(
    v: &Value,
    terminal: Vec<bool>,
    initial: &[BigRational],
) -> Result<Termination, ToyError> {
    let obj = object(v, "on_terminal")?;
    if let Some(k) = obj
        .keys()
        .find(|k| !matches!(k.as_str(), "kind" | "law" | "loss"))
    {
        return Err(ToyError::Unknown(format!("on_terminal.{k}")));
    }
    let states = terminal.len();
    match obj.get("kind") {
        None => Err(ToyError::Missing("on_terminal.kind".into())),
        Some(Value::String(k)) if k == "reset" => {
            if obj.contains_key("loss") {
                return Err(termination_error(
                    "on_terminal.loss",
                    "a reset has no absorbing loss (use \"kind\": \"absorb\" for that)",
                ));
            }
            // The reset law defaults to the initial law (an environment's reset).
            let law = match obj.get("law") {
                Some(l) => distribution(l, "on_terminal.law", states)?,
                None => initial.to_vec(),
            };
            for (field, dist) in [("initial", initial), ("on_terminal.law", &law)] {
                if let Some(s) = (0..states).find(|&s| terminal[s] && !dist[s].is_zero()) {
                    return Err(termination_error(
                        format!("{field}[{s}]"),
                        format!(
                            "mass {} on terminal state {s}; under a reset the chain never occupies a terminal state",
                            dist[s]
                        ),
                    ));
                }
            }
            Ok(Termination::Reset { terminal, law })
        }
        Some(Value::String(k)) if k == "absorb" => {
            if obj.contains_key("law") {
                return Err(termination_error(
                    "on_terminal.law",
                    "an absorbing state has no reset law (use \"kind\": \"reset\" for that)",
                ));
            }
            let raw = obj
                .get("loss")
                .ok_or_else(|| ToyError::Missing("on_terminal.loss".into()))?;
            let check = |q: BigRational, field: &str| {
                if q.is_negative() {
                    Err(termination_error(
                        field,
                        format!("{q} is negative; an absorbing loss is ≥ 0"),
                    ))
                } else {
                    Ok(q)
                }
            };
            let loss = match raw {
                Value::Array(_) => {
                    let items = sized_array(raw, "on_terminal.loss", states)?;
                    let mut out = Vec::with_capacity(states);
                    for (s, (x, &term)) in items.iter().zip(&terminal).enumerate() {
                        let f = format!("on_terminal.loss[{s}]");
                        out.push(match (x, term) {
                            (Value::Null, false) => None,
                            (Value::Null, true) => {
                                return Err(termination_error(
                                    f,
                                    format!("terminal state {s} needs its loss per remaining step"),
                                ));
                            }
                            (_, false) => {
                                return Err(termination_error(
                                    f,
                                    format!("state {s} is not terminal; write null"),
                                ));
                            }
                            (x, true) => Some(check(exact_number(x, &f)?, &f)?),
                        });
                    }
                    out
                }
                x => {
                    let c = check(exact_number(x, "on_terminal.loss")?, "on_terminal.loss")?;
                    terminal.iter().map(|&t| t.then(|| c.clone())).collect()
                }
            };
            Ok(Termination::Absorb { loss })
        }
        Some(Value::String(k)) => Err(termination_error(
            "on_terminal.kind",
            format!("{k:?} is not one of reset, absorb"),
        )),
        Some(_) => Err(ToyError::Type {
            field: "on_terminal.kind".into(),
            expected: "a string",
        }),
    }
}

impl ToyMdp {
    /// Parse and validate a toy MDP from JSON text.
    ///
    /// # Errors
    /// A [`ToyError`] naming the first offending field and index.
    pub fn from_json_str(text: &str) -> Result<Self, ToyError> {
        let v: Value = serde_json::from_str(text).map_err(|e| json_error(&e))?;
        Self::from_json(&v)
    }

    /// Read a toy-MDP file.
    ///
    /// # Errors
    /// [`ToyError::Io`] if unreadable, otherwise as [`ToyMdp::from_json_str`].
    pub fn load(path: &Path) -> Result<Self, ToyError> {
        let text = std::fs::read_to_string(path).map_err(|e| ToyError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_json_str(&text)
    }

    /// Validate a parsed JSON value.
    ///
    /// # Errors
    /// As [`ToyMdp::from_json_str`].
    pub fn from_json(v: &Value) -> Result<Self, ToyError> {
        let obj = object(v, "the top level")?;
        const FIELDS: [&str; 12] = [
            "states",
            "actions",
            "horizon",
            "initial",
            "transition",
            "expert",
            "policy",
            "terminal",
            "on_terminal",
            "name",
            "description",
            "comment",
        ];
        if let Some(k) = obj.keys().find(|k| !FIELDS.contains(&k.as_str())) {
            return Err(ToyError::Unknown(k.clone()));
        }
        let states = size(obj, "states", 1, MAX_STATES, "1 ≤ states ≤ 4096")?;
        let actions = size(obj, "actions", 2, MAX_ACTIONS, "2 ≤ actions ≤ 256")?;
        let horizon = size(obj, "horizon", 2, MAX_HORIZON, "2 ≤ horizon ≤ 2^20")?;
        let get = |f: &str| obj.get(f).ok_or_else(|| ToyError::Missing(f.into()));
        let initial = distribution(get("initial")?, "initial", states)?;
        let rows = sized_array(get("transition")?, "transition", states)?;
        let mut transition = Vec::with_capacity(states);
        for (s, row) in rows.iter().enumerate() {
            let f = format!("transition[{s}]");
            let per_action = sized_array(row, &f, actions)?;
            let mut out = Vec::with_capacity(actions);
            for (a, dist) in per_action.iter().enumerate() {
                out.push(distribution(
                    dist,
                    &format!("transition[{s}][{a}]"),
                    states,
                )?);
            }
            transition.push(out);
        }
        let ex = sized_array(get("expert")?, "expert", states)?;
        let mut expert = Vec::with_capacity(states);
        for (i, x) in ex.iter().enumerate() {
            let q = index(x, &format!("expert[{i}]"))?;
            let a = q
                .to_integer()
                .try_into()
                .ok()
                .filter(|a: &usize| *a < actions)
                .ok_or_else(|| ToyError::ExpertAction {
                    index: i,
                    action: q.to_string(),
                    actions,
                })?;
            expert.push(a);
        }
        let policy = policy(get("policy")?, states, actions)?;
        let termination = match (obj.get("terminal"), obj.get("on_terminal")) {
            (None, None) => Termination::None,
            (Some(_), None) => {
                return Err(termination_error(
                    "terminal",
                    "terminal states need `on_terminal` to say what happens on entering one (\"kind\": \"reset\" or \"absorb\")",
                ));
            }
            (None, Some(_)) => {
                return Err(termination_error(
                    "on_terminal",
                    "there is no `terminal` array marking which states are terminal",
                ));
            }
            (Some(flags), Some(rule)) => {
                termination(rule, terminal_flags(flags, states)?, &initial)?
            }
        };
        Ok(Self {
            states,
            actions,
            horizon,
            initial,
            transition,
            expert,
            policy,
            termination,
        })
    }

    /// The kernel P′(s′|s, a) of the chain the learner runs in (math.md §8), as
    /// `chain_transition()[s][a][s′]`:
    ///
    /// * [`Termination::None`]: P itself;
    /// * [`Termination::Reset`]: `P′(s′|s,a) = 1[s′ not terminal] P(s′|s,a) + P(terminal|s,a) μ(s′)`,
    ///   a terminal transition replaced by a draw from the reset law μ;
    /// * [`Termination::Absorb`]: `P′(·|z,a) = δ_z` for every terminal z and action a; the other
    ///   rows are P's.
    ///
    /// Every row is a distribution, exactly. X1 enumeration and the X2/X3 dynamic programmes run
    /// on this chain unchanged.
    pub fn chain_transition(&self) -> Vec<Vec<Vec<BigRational>>> {
        match &self.termination {
            Termination::None => self.transition.clone(),
            Termination::Reset { terminal, law } => self
                .transition
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|p| {
                            let ended = p
                                .iter()
                                .zip(terminal)
                                .filter(|(_, t)| **t)
                                .fold(BigRational::zero(), |acc, (x, _)| acc + x);
                            p.iter()
                                .zip(terminal)
                                .zip(law)
                                .map(|((x, &t), m)| {
                                    let kept = if t { BigRational::zero() } else { x.clone() };
                                    kept + ended.clone() * m
                                })
                                .collect()
                        })
                        .collect()
                })
                .collect(),
            Termination::Absorb { loss } => self
                .transition
                .iter()
                .enumerate()
                .map(|(z, row)| match loss[z] {
                    None => row.clone(),
                    Some(_) => {
                        let stay: Vec<BigRational> = (0..self.states)
                            .map(|s| {
                                if s == z {
                                    BigRational::one()
                                } else {
                                    BigRational::zero()
                                }
                            })
                            .collect();
                        vec![stay; self.actions]
                    }
                })
                .collect(),
        }
    }

    /// The M-family of math.md §6: states A = 0, B = 1; expert a*(A) = 1, a*(B) = 0;
    /// μ = (μ_A, 1 − μ_A); from any state, action 1 goes to A w.p. `p1` and action 0 w.p. `p0`;
    /// the learner cannot see the state (one group).
    ///
    /// # Errors
    /// [`ToyError`] if the numbers are not probabilities or the horizon is < 2.
    pub fn m_family(
        mu_a: BigRational,
        p0: BigRational,
        p1: BigRational,
        horizon: usize,
        kind: PolicyKind,
        c: Option<BigRational>,
    ) -> Result<Self, ToyError> {
        let s = |q: &BigRational| Value::String(q.to_string());
        let one = BigRational::one();
        let row = |p: &BigRational| Value::Array(vec![s(p), s(&(one.clone() - p))]);
        let mut policy = serde_json::json!({
            "kind": match kind {
                PolicyKind::RationalSoftmax => "rational-softmax",
                PolicyKind::Direct => "direct",
                PolicyKind::TiedSoftmax => "tied-softmax",
            },
            "groups": [0, 0],
        });
        if let Some(c) = c {
            policy["c"] = s(&c);
        }
        let v = serde_json::json!({
            "states": 2,
            "actions": 2,
            "horizon": horizon,
            "initial": [s(&mu_a), s(&(one.clone() - &mu_a))],
            "transition": [[row(&p0), row(&p1)], [row(&p0), row(&p1)]],
            "expert": [1, 0],
            "policy": policy,
        });
        Self::from_json(&v)
    }
}
