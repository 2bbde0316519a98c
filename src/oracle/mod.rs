//! The gradient oracle of eq. 3.15 (math.md §1.1) on a recorded trajectory: the estimator passes
//! and the per-decision kernel they run on.
//!
//! On a trajectory with decisions t = 1..n, losses `l_t = l(s_t, θ)` and scores
//! `ψ_t = ∇_θ log π_θ(a_t|s_t)`:
//!
//! * the causal estimator of eq. 3.15, `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`
//!   ([`EstimatorKernel::causal_sum_validated`], and the weighted pass below);
//! * the full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i` (eq. 3.16);
//! * the importance-weighted old-point estimates of math.md §4, with per-decision ratios
//!   `π_old(a_i|s_i)/π_new(a_i|s_i) = exp(log π_old − log π_new)`;
//! * the per-decision terms from which a baseline `b_i` is subtracted, `g − Σ_i b_i ψ_i`
//!   ([`crate::baseline`]), or entered as shifted losses into the decisions recorded once.
//!
//! One decision's update is `g += w ∇l_t + w l_t Σ_{i<t} ψ_i`, then `Σ_{i<t} ψ_i += ψ_t`: in the
//! generic passes [`kernel`]'s `accumulate`, also over recorded decisions (`accumulate_rows`,
//! with the losses given: a baseline's shifted ones), so that for each policy the plain
//! estimate and every estimate with a baseline fixed before the pass are summed in one order
//! (the learned baselines subtract `Σ_i b_i ψ_i` from the plain estimate, docs/architecture.md);
//! the logistic policy's
//! fixed-dimension loops (its [`EstimatorKernel`] overrides) make the same operations on
//! `[f64; N]` rows, bit for bit. The data the baselines need are here too: a trajectory's [`DecisionTerms`],
//! baselines known before a pass ([`Given`]), decisions recorded to be summed with losses chosen
//! later ([`RecordedPass`]), [`ScoreProducts`], and the linear state-dependent baseline evaluated
//! off feature rows ([`LinearBaseline`]). The toy MDPs' estimators
//! ([`crate::toy::estimator`]) are an independent route: the loss-to-go summed backwards.

mod causal;
mod decision_terms;
mod full;
mod given;
pub mod kernel;
mod linear_baseline;
mod logistic;
mod products;
mod recorded;
mod recorded_pass;
mod terms;

pub use decision_terms::DecisionTerms;
pub use given::Given;
pub use kernel::EstimatorKernel;
pub use linear_baseline::{FixedLinearBaseline, LinearBaseline};
pub use products::{Baselines, ScoreProducts};
pub use recorded_pass::RecordedPass;

pub(crate) use causal::causal_pass;
pub(crate) use full::full_pass;
pub(crate) use logistic::by_feature_count;
pub(crate) use recorded::{record_pass, sum_recorded};
pub(crate) use terms::terms_pass;

use crate::policy::{Policy, PolicyError};
use crate::problem::OracleError;
use crate::scalar::Scalar;

/// A recorded trajectory as the estimator passes read it: per decision t = 1..n the features
/// φ(s_t) (flat, `feature_dim` entries per row), the action a_t and the expert's label, and the
/// absorbing losses after the last decision. The caller has checked that there are as many
/// feature rows, actions and labels, at least one.
#[derive(Debug)]
pub(crate) struct Decisions<'a, S, L, A> {
    /// φ(s_1), …, φ(s_n) concatenated.
    pub(crate) feature_data: &'a [S],
    /// Entries of one φ(s_t).
    pub(crate) feature_dim: usize,
    /// Number of feature rows.
    pub(crate) rows: usize,
    /// `true` when every feature entry is known to be finite (a learner's roll-out).
    pub(crate) features_finite: bool,
    /// a_1, …, a_n.
    pub(crate) actions: &'a [A],
    /// π*(s_1), …, π*(s_n).
    pub(crate) labels: &'a [L],
    /// `Σ_{t>n} l_t` of an absorbing fixed-horizon stream; `None`: no absorbing tail.
    pub(crate) absorbed: Option<&'a S>,
    /// The policy's notes of a learner's roll-out and the θ it sampled at
    /// ([`EstimatorKernel::sample_noting`]); `None`: no notes.
    pub(crate) notes: Option<(&'a [S], &'a [S])>,
}

impl<S, L, A> Decisions<'_, S, L, A> {
    /// Number of decisions n.
    pub(crate) fn len(&self) -> usize {
        self.actions.len()
    }
    /// Number of decisions whose score ψ_i enters the estimate: n − 1, the last action scoring no
    /// loss; n when the trajectory absorbed (its last action led to the absorbing losses).
    pub(crate) fn scored(&self) -> usize {
        match self.absorbed {
            Some(_) => self.len(),
            None => self.len() - 1,
        }
    }
    /// φ(s_t) (0-based `t`).
    fn feature(&self, t: usize) -> &[S] {
        assert!(t < self.rows, "feature row {t} of {}", self.rows);
        &self.feature_data[t * self.feature_dim..(t + 1) * self.feature_dim]
    }
    /// φ(s_1), …, φ(s_n) in order.
    fn feature_rows(&self) -> impl ExactSizeIterator<Item = &[S]> + '_ {
        (0..self.rows).map(|t| self.feature(t))
    }
}

/// A policy's error as an oracle error (out of line: the hot loops only branch to it).
#[cold]
#[inline(never)]
pub(crate) fn policy_error(e: PolicyError) -> OracleError {
    match e {
        PolicyError::Undecidable(u) => OracleError::Undecidable(u),
        other => OracleError::Domain(other.to_string()),
    }
}

/// Whether every feature vector of `t` has the policy's length and only finite entries (the
/// per-call φ check of the policies, done once for the whole trajectory).
pub(crate) fn features_valid<S, P, L, A>(policy: &P, t: &Decisions<'_, S, L, A>) -> bool
where
    S: Scalar,
    P: Policy<S>,
{
    t.feature_dim == policy.feature_dim()
        && (t.features_finite
            || t.feature_data
                .iter()
                .fold(true, |ok, x| ok & Scalar::is_finite(x)))
}

/// Working storage of one estimate: the per-decision ∇l_t and ψ_t and the running `Σ_{i<t} ψ_i`,
/// allocated once per call (one allocation), never per decision.
pub(crate) struct Scratch<S> {
    buf: Vec<S>,
    d: usize,
}

impl<S: Scalar> Scratch<S> {
    pub(crate) fn new(d: usize) -> Self {
        Self {
            buf: vec![S::zero(); 3 * d],
            d,
        }
    }
    /// `(∇l_t, ψ_t, Σ_{i<t} ψ_i)`.
    pub(crate) fn parts(&mut self) -> (&mut [S], &mut [S], &mut [S]) {
        let (grad, rest) = self.buf.split_at_mut(self.d);
        let (score, score_sum) = rest.split_at_mut(self.d);
        (grad, score, score_sum)
    }
}
