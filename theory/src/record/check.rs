//! One row of the theorem table: what was claimed, under which assumptions, with which constants,
//! the bound, what was measured (with its confidence bounds), the tightness, and the verdict; and
//! the builder that makes one ([`Check::builder`]).

use crate::record::constant::Constant;
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
    /// The verdict as the table prints it.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Fails => "fails",
            Verdict::Inconclusive => "inconclusive",
            Verdict::Uninformative => "uninformative",
        }
    }

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
    /// The null hypothesis a two-sided interval is set against, as the power list states it
    /// (absent: mean 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub null_hypothesis: Option<String>,
    /// The standard error of `value` (sample standard deviation / √runs), from which the
    /// minimum detectable effect at the table's stated power is computed
    /// ([`crate::stats::min_detectable`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub se: Option<f64>,
    /// What the row's check can resolve of a known error at its size, computed against the same
    /// check run on the wrong algorithm (e.g. "uninformative for E10: …"), as the power list
    /// states it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<String>,
}

impl Measured {
    /// An exact (or rigorous) measured value, with no confidence bounds.
    pub fn exact(value: f64) -> Self {
        Self {
            value,
            lcb: None,
            ucb: None,
            runs: None,
            alpha: None,
            null_hypothesis: None,
            se: None,
            resolution: None,
        }
    }
    /// A statistic `value` (a mean over runs, a worst z-score); add its confidence bounds, runs
    /// and level with the `with_*` methods, or build it from a sample with
    /// [`Measured::from_sample`].
    pub fn statistic(value: f64) -> Self {
        Self::exact(value)
    }
    /// The same with the confidence interval `[lcb, ucb]`.
    #[must_use]
    pub fn with_interval(mut self, lcb: f64, ucb: f64) -> Self {
        self.lcb = Some(lcb);
        self.ucb = Some(ucb);
        self
    }
    /// The same with the number of runs.
    #[must_use]
    pub fn with_runs(mut self, runs: usize) -> Self {
        self.runs = Some(runs);
        self
    }
    /// The same with the false-alarm probability of the decision.
    #[must_use]
    pub fn with_alpha(mut self, alpha: f64) -> Self {
        self.alpha = Some(alpha);
        self
    }
    /// The same with the standard error of the value.
    #[must_use]
    pub fn with_se(mut self, se: f64) -> Self {
        self.se = Some(se);
        self
    }
    /// The same with the null hypothesis its two-sided interval is set against (when it is not
    /// mean 0).
    #[must_use]
    pub fn with_null_hypothesis(mut self, h0: impl Into<String>) -> Self {
        self.null_hypothesis = Some(h0.into());
        self
    }
    /// The same with another point value (e.g. the mean of the runs' midpoints where the
    /// confidence bounds are of their lower ends).
    #[must_use]
    pub fn with_value(mut self, value: f64) -> Self {
        self.value = value;
        self
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
    /// The row states a thesis claim that its erratum (`erratum`) says is false as printed
    /// (e.g. E7's "the first term is negative", E9–E11's printed algorithms): the table expects
    /// it to fail ([`Check::expected`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub refuted_by_erratum: bool,
    /// Free-text details (numbers behind the verdict).
    pub details: String,
}

/// What the table requires of a row's verdict ([`Check::expected`]); the status
/// ([`crate::report::status`]) fails on every row whose verdict contradicts it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Expected {
    /// The claim is true (a thesis claim no erratum refutes, a corrected claim): a `Fails`
    /// verdict fails the table; `Uninformative` or `Inconclusive` does not (no evidence either
    /// way) but is listed.
    Holds,
    /// The claim is false (a negative control, a thesis claim its erratum refutes): any verdict
    /// but `Fails` fails the table (the check did not see an error it must see).
    Fails,
    /// Reported, never required (a probe).
    Either,
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
    /// Start a row: its identifier, the thesis result, the precise claim and the claim's role.
    /// The row exists once [`CheckBuilder::decided`] gives the method and the verdict; every other
    /// field is optional (empty or absent unless set).
    pub fn builder(
        id: impl Into<String>,
        result: impl Into<String>,
        claim: impl Into<String>,
        role: Role,
    ) -> CheckBuilder {
        CheckBuilder {
            id: id.into(),
            result: result.into(),
            claim: claim.into(),
            role,
            assumptions: vec![],
            constants: vec![],
            bound: None,
            measured: None,
            tightness: None,
            erratum: None,
            refuted_by_erratum: false,
            details: String::new(),
        }
    }

    /// The same row with other details.
    #[must_use]
    pub fn with_details(mut self, details: impl Into<String>) -> Self {
        self.details = details.into();
        self
    }

    /// Whether this row is a negative control that its check did not detect (any verdict but
    /// `Fails`).
    pub fn undetected_control(&self) -> bool {
        self.role == Role::NegativeControl && self.verdict != Verdict::Fails
    }

    /// What the table requires of this row's verdict: a negative control must fail, a probe is
    /// never required, a thesis claim that its erratum refutes ([`Check::refuted_by_erratum`])
    /// must fail, and every other thesis or corrected claim must hold.
    pub fn expected(&self) -> Expected {
        match self.role {
            Role::NegativeControl => Expected::Fails,
            Role::Probe => Expected::Either,
            Role::Thesis | Role::Corrected if self.refuted_by_erratum => Expected::Fails,
            Role::Thesis | Role::Corrected => Expected::Holds,
        }
    }

    /// Whether the verdict contradicts [`Check::expected`]: a row expected to hold fails, or a
    /// row expected to fail does not.
    pub fn unexpected(&self) -> bool {
        match self.expected() {
            Expected::Holds => self.verdict == Verdict::Fails,
            Expected::Fails => self.verdict != Verdict::Fails,
            Expected::Either => false,
        }
    }
}

/// A row being built ([`Check::builder`]): the claim is stated, the optional fields are set by name,
/// and [`CheckBuilder::decided`] adds the method and verdict that make it a [`Check`].
#[derive(Debug, Clone)]
#[must_use = "a row is only made by `decided`"]
pub struct CheckBuilder {
    id: String,
    result: String,
    claim: String,
    role: Role,
    assumptions: Vec<String>,
    constants: Vec<Constant>,
    bound: Option<f64>,
    measured: Option<Measured>,
    tightness: Option<f64>,
    erratum: Option<String>,
    refuted_by_erratum: bool,
    details: String,
}

impl CheckBuilder {
    /// The assumptions under which the claim is made.
    pub fn assumptions<S: Into<String>>(mut self, a: impl IntoIterator<Item = S>) -> Self {
        self.assumptions = a.into_iter().map(Into::into).collect();
        self
    }
    /// The constants the bound uses.
    pub fn constants(mut self, c: Vec<Constant>) -> Self {
        self.constants = c;
        self
    }
    /// The bound B.
    pub fn bound(mut self, b: f64) -> Self {
        self.bound = Some(b);
        self
    }
    /// The bound B, if there is one.
    pub fn maybe_bound(mut self, b: Option<f64>) -> Self {
        self.bound = b;
        self
    }
    /// What was measured.
    pub fn measured(mut self, m: Measured) -> Self {
        self.measured = Some(m);
        self
    }
    /// What was measured, if anything.
    pub fn maybe_measured(mut self, m: Option<Measured>) -> Self {
        self.measured = m;
        self
    }
    /// The tightness X̄ / B.
    pub fn tightness(mut self, t: f64) -> Self {
        self.tightness = Some(t);
        self
    }
    /// The erratum the row relates to (math.md E1–E18).
    pub fn erratum(mut self, e: impl Into<String>) -> Self {
        self.erratum = Some(e.into());
        self
    }
    /// The erratum the row relates to, if any.
    pub fn maybe_erratum(mut self, e: Option<String>) -> Self {
        self.erratum = e;
        self
    }
    /// The claim is the thesis's as printed and its erratum says it is false: the table expects
    /// the row to fail ([`Check::expected`]).
    pub fn refuted_by_erratum(mut self) -> Self {
        self.refuted_by_erratum = true;
        self
    }
    /// The numbers behind the verdict, as text.
    pub fn details(mut self, d: impl Into<String>) -> Self {
        self.details = d.into();
        self
    }
    /// The row, decided by `method` with `verdict`.
    pub fn decided(self, method: Method, verdict: Verdict) -> Check {
        Check {
            id: self.id,
            result: self.result,
            claim: self.claim,
            assumptions: self.assumptions,
            constants: self.constants,
            bound: self.bound,
            measured: self.measured,
            tightness: self.tightness,
            method,
            verdict,
            erratum: self.erratum,
            role: self.role,
            refuted_by_erratum: self.refuted_by_erratum,
            details: self.details,
        }
    }
}

impl Method {
    /// The method as the table prints it.
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::Rigorous => "rigorous",
            Method::Statistical => "statistical",
            Method::Sampled => "sampled",
            Method::Estimate => "estimate",
        }
    }
}

impl Role {
    /// The role as the table prints it.
    pub fn name(self) -> &'static str {
        match self {
            Role::Thesis => "thesis",
            Role::Corrected => "corrected",
            Role::NegativeControl => "negative control",
            Role::Probe => "probe (wrong algorithm)",
        }
    }
}
