//! One theorem check's result: what was claimed, under which assumptions, with which constants,
//! the bound, what was measured (with its confidence bounds), the tightness, and the verdict.

use crate::constants::Constant;
use serde::{Deserialize, Serialize};

/// The outcome of a check, relative to the claim it states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// The claim holds (exactly, rigorously, or with no evidence against it at the stated level).
    Holds,
    /// The claim is refuted (exactly, rigorously, or with confidence 1 − α).
    Fails,
    /// Neither could be shown.
    Inconclusive,
    /// The check could not have refuted the claim as run: its lower confidence bound is ≤ 0, or the
    /// bound is at least the largest value the statistic can take ([`crate::stats::assess`]).
    /// Not evidence for the claim.
    Uninformative,
}

impl Verdict {
    /// `Holds` if `ok`, else `Fails`.
    pub fn from_bool(ok: bool) -> Self {
        if ok { Verdict::Holds } else { Verdict::Fails }
    }
}

/// What was measured, with confidence bounds for statistical checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    /// The measured value (X̄, or an exact quantity).
    pub value: f64,
    /// Lower confidence bound (statistical checks).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lcb: Option<f64>,
    /// Upper confidence bound (statistical checks).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ucb: Option<f64>,
    /// Number of runs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs: Option<usize>,
    /// False-alarm probability of the decision.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
}

impl Measured {
    /// An exact (or rigorous) measured value.
    pub fn exact(value: f64) -> Self {
        Self {
            value,
            lcb: None,
            ucb: None,
            runs: None,
            alpha: None,
        }
    }
}

/// How the verdict was reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Equalities/inequalities in exact rational arithmetic.
    Exact,
    /// Interval enclosures / rational root enclosures (a proof).
    Rigorous,
    /// Monte Carlo with a stated false-alarm probability.
    Statistical,
    /// Evaluated at sampled points only (no proof, no stated confidence).
    Sampled,
    /// Estimated constants on a real environment (never a certificate).
    Estimate,
}

/// One row of the theorem-check table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// Identifier (math.md numbering: "1a", "2b", …).
    pub id: String,
    /// The thesis result (equation / theorem).
    pub result: String,
    /// The precise claim tested.
    pub claim: String,
    /// Assumptions under which the claim is made.
    pub assumptions: Vec<String>,
    /// Constants used, each exact / rigorous / estimated.
    pub constants: Vec<Constant>,
    /// The bound B (if the claim is a bound).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bound: Option<f64>,
    /// What was measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured: Option<Measured>,
    /// X̄ / B.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tightness: Option<f64>,
    /// How the verdict was reached.
    pub method: Method,
    /// The verdict on the claim.
    pub verdict: Verdict,
    /// The erratum this relates to (math.md E1–E18), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub erratum: Option<String>,
    /// Whether the claim is the thesis's own (possibly wrong) statement, a corrected one, or a
    /// negative control expected to fail.
    pub role: Role,
    /// Free-text details (numbers behind the verdict).
    pub details: String,
}

/// The role of a claim in the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    /// The thesis's statement as printed.
    Thesis,
    /// The corrected statement (math.md).
    Corrected,
    /// A deliberately wrong claim (the true bound scaled down, a mutated estimator) that the check
    /// must refute: its verdict `Fails` means the control was detected, and an undetected control
    /// fails the table.
    NegativeControl,
    /// A wrong algorithm (one the thesis printed, or STORM without the importance weight) run
    /// through a check of the right one, at the same sizes: its verdict says whether that check
    /// resolves the algorithm's error. Reported, never required: an error that does not raise the
    /// bounded quantity is invisible to a bound, one below a row's minimum detectable bias is
    /// invisible to that row, and the exact rows (4d–4f) are what detect it.
    Probe,
}

impl Check {
    /// Whether this row is a negative control that its check did not detect (any verdict but
    /// `Fails`).
    pub fn undetected_control(&self) -> bool {
        self.role == Role::NegativeControl && self.verdict != Verdict::Fails
    }
}
