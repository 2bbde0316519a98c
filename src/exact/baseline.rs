//! Baselines exactly (math.md §9): the mean and second moment of the baselined estimator
//! `g_b = g − Σ_i b_i ψ_i` by enumeration (X1), and the variance-minimising constants in closed
//! form.
//!
//! For constants b_i, `E[g_b] = ∇F` exactly (`E[ψ_i | s_1, a_1, …, s_i] = 0`; module docs of
//! [`crate::baseline`]) and, because `E[ψ_i·ψ_j] = 0` for i ≠ j,
//! `E‖g_b‖² = E‖g‖² − 2 Σ_i b_i E[g·ψ_i] + Σ_i b_i² E‖ψ_i‖²`, minimised by
//! `b*_i = E[g·ψ_i]/E‖ψ_i‖²` per decision index and by `b*_const = Σ_i E[g·ψ_i] / Σ_i E‖ψ_i‖²`
//! for one constant. With one baseline per state, `b_i = w_{s_i}`, the same argument gives
//! `E‖g_b‖² = E‖g‖² − 2 Σ_s w_s c_s + Σ_s w_s² A_ss` (`c_s`, `A_ss` the sums of `g·ψ_i`,
//! `‖ψ_i‖²` over the decisions taken in s), minimised by `w*_s = c_s/A_ss`. Every expectation is a sum over prefixes; each prefix's estimate comes
//! from the oracle's own code ([`crate::toy::estimator::decision_terms`]).

use super::ExactError;
use super::enumerate::for_each_prefix;
use crate::oracle::DecisionTerms;
use crate::scalar::{Scalar, dot, norm_sq};
use crate::toy::estimator::decision_terms;
use crate::toy::{ToyProblem, ToyTrajectory};

/// `E[g_b]` and `E‖g_b‖²` at θ for given baselines.
#[derive(Debug, Clone, PartialEq)]
pub struct BaselineMoments<S> {
    /// E\[g_b\] = Σ p g_b.
    pub expected_estimate: Vec<S>,
    /// E‖g_b‖² = Σ p ‖g_b‖².
    pub second_moment: S,
}

/// The exact ingredients of the optimal baselines at θ (decision indices i = 1..T−2, 0-based in
/// the vectors).
#[derive(Debug, Clone, PartialEq)]
pub struct OptimalBaselines<S> {
    /// E\[g·ψ_i\] (g the plain estimate of eq. 3.15; 0 where decision i is never scored).
    pub cross: Vec<S>,
    /// E‖ψ_i‖².
    pub score_moment: Vec<S>,
    /// E‖g‖².
    pub second_moment: S,
    /// b*_i = E\[g·ψ_i\]/E‖ψ_i‖², 0 where E‖ψ_i‖² = 0 (then b_i does not matter).
    pub time_indexed: Vec<S>,
    /// b*_const = Σ_i E\[g·ψ_i\] / Σ_i E‖ψ_i‖², 0 when every score vanishes.
    pub constant: S,
    /// E‖g_{b*}‖² with the time-indexed b*, by enumeration.
    pub second_moment_time_indexed: S,
    /// E‖g_{b*}‖² with the constant b*_const, by enumeration.
    pub second_moment_constant: S,
}

impl<S: Scalar> OptimalBaselines<S> {
    /// The reduction factor `E‖g‖² / E‖g_{b*}‖²` of the time-indexed optimum (`None` when the
    /// baselined second moment is 0).
    pub fn reduction_time_indexed(&self) -> Option<S> {
        ratio(&self.second_moment, &self.second_moment_time_indexed)
    }
    /// The reduction factor `E‖g‖² / E‖g_{b*const}‖²` of the constant optimum.
    pub fn reduction_constant(&self) -> Option<S> {
        ratio(&self.second_moment, &self.second_moment_constant)
    }
}

fn ratio<S: Scalar>(num: &S, den: &S) -> Option<S> {
    (!den.is_certainly_zero()).then(|| num.clone() / den)
}

/// The baseline of decision i (0-based) from a list: one entry is one constant for every
/// decision, otherwise entry i.
fn pick<S: Scalar>(baseline: &[S], i: usize) -> Option<S> {
    match baseline {
        [b] => Some(b.clone()),
        bs => bs.get(i).cloned(),
    }
}

/// The prefix (s_1..s_{T−1}, a_1..a_{T−2}) completed into a trajectory of the problem (the last
/// action and state do not matter: they are set to 0 and s_{T−1}; labels are the expert's).
pub fn prefix_trajectory<S: Scalar>(
    problem: &ToyProblem<S>,
    states: &[usize],
    actions: &[usize],
) -> ToyTrajectory {
    let mut st = states.to_vec();
    st.push(states[states.len() - 1]);
    let mut ac = actions.to_vec();
    ac.push(0);
    ToyTrajectory {
        labels: states.iter().map(|s| problem.mdp().expert[*s]).collect(),
        states: st,
        actions: ac,
    }
}

/// (X1) `E[g_b]` and `E‖g_b‖²` at θ with `baseline` = one number b (every decision) or
/// T − 2 numbers b_1..b_{T−2}.
///
/// # Errors
/// [`ExactError::NotApplicable`] for a list of another length; as
/// [`crate::exact::enumerate::moments`].
pub fn baselined_moments<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    baseline: &[S],
) -> Result<BaselineMoments<S>, ExactError> {
    let decisions = problem.mdp().horizon - 2;
    if baseline.len() != 1 && baseline.len() != decisions {
        return Err(ExactError::NotApplicable(format!(
            "a baseline is one number or T − 2 = {decisions} numbers, got {}",
            baseline.len()
        )));
    }
    baselined_moments_by(problem, theta, |_, i| pick(baseline, i))
}

/// (X1) `E[g_b]` and `E‖g_b‖²` at θ with the baseline of decision i (0-based) given by
/// `baseline(states, i)` from the prefix's states s_1..s_{T−1} (`None`: b_i = 0). A function of
/// `states[..=i]` keeps the estimator unbiased; one that reads a later state (which depends on
/// a_i) need not.
///
/// # Errors
/// As [`crate::exact::enumerate::moments`].
pub fn baselined_moments_by<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    mut baseline: impl FnMut(&[usize], usize) -> Option<S>,
) -> Result<BaselineMoments<S>, ExactError> {
    let table = problem.table(theta)?;
    let d = table.dim;
    let mut terms = DecisionTerms::new();
    let mut g = vec![S::zero(); d];
    let mut eg = vec![S::zero(); d];
    let mut m2 = S::zero();
    for_each_prefix(problem, &table, |states, actions, p| {
        let actions = problem.scored_actions(states, actions);
        decision_terms(&table, states, actions, None, false, &mut terms);
        terms.estimate_into(|i| baseline(states, i), &mut g);
        m2 += p.clone() * norm_sq(&g);
        for (e, x) in eg.iter_mut().zip(&g) {
            *e += p.clone() * x;
        }
    })?;
    Ok(BaselineMoments {
        expected_estimate: eg,
        second_moment: m2,
    })
}

/// The exact variance-minimising state-dependent baseline at θ, one value per state
/// (`b_i = w_{s_i}`: the one-hot state features of [`crate::baseline::Baseline::StateDependent`]
/// on a toy MDP, where `A = E[Σ_i ‖ψ_i‖² φ_i φ_iᵀ]` is diagonal).
#[derive(Debug, Clone, PartialEq)]
pub struct OptimalStateBaseline<S> {
    /// `c_s = E[Σ_{i: s_i = s} g·ψ_i]` per state s.
    pub cross: Vec<S>,
    /// `A_ss = E[Σ_{i: s_i = s} ‖ψ_i‖²]` per state s.
    pub score_moment: Vec<S>,
    /// `w*_s = c_s / A_ss`, 0 where `A_ss = 0` (no scored decision in s: w_s does not matter).
    pub weights: Vec<S>,
    /// E‖g‖².
    pub second_moment: S,
    /// `E‖g_{b*}‖²` by enumeration with `b_i = w*_{s_i}`.
    pub second_moment_optimal: S,
    /// `E‖g‖² − Σ_s c_s² / A_ss`, the closed form of the same (math.md §9's identity with the
    /// state's statistics).
    pub second_moment_closed_form: S,
}

impl<S: Scalar> OptimalStateBaseline<S> {
    /// The reduction factor `E‖g‖² / E‖g_{b*}‖²` (`None` when the baselined moment is 0).
    pub fn reduction(&self) -> Option<S> {
        ratio(&self.second_moment, &self.second_moment_optimal)
    }
}

/// (X1) `E‖g‖²` and, per slot, `E[Σ g·ψ_i]` and `E[Σ ‖ψ_i‖²]` over the scored decisions i that
/// `slot(states, i)` assigns to it (`slots` of them): decision indices for the time-indexed
/// baselines, states for the per-state one.
fn slot_statistics<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    slots: usize,
    slot: impl Fn(&[usize], usize) -> usize,
) -> Result<(Vec<S>, Vec<S>, S), ExactError> {
    let table = problem.table(theta)?;
    let mut terms = DecisionTerms::new();
    let mut g = vec![S::zero(); table.dim];
    let mut cross = vec![S::zero(); slots];
    let mut score_moment = vec![S::zero(); slots];
    let mut m2 = S::zero();
    for_each_prefix(problem, &table, |states, actions, p| {
        let actions = problem.scored_actions(states, actions);
        decision_terms(&table, states, actions, None, false, &mut terms);
        terms.estimate_into(|_| None, &mut g);
        m2 += p.clone() * norm_sq(&g);
        for i in 0..terms.decisions() {
            let k = slot(states, i);
            cross[k] += p.clone() * dot(&g, terms.score(i));
            score_moment[k] += p.clone() * norm_sq(terms.score(i));
        }
    })?;
    Ok((cross, score_moment, m2))
}

/// (X1) The statistics `c_s`, `A_ss` of every state at θ, the optimal per-state baseline
/// `w*_s = c_s/A_ss` and its second moment by enumeration and in closed form
/// ([`OptimalStateBaseline`]).
///
/// # Errors
/// As [`crate::exact::enumerate::moments`].
pub fn optimal_state_baseline<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<OptimalStateBaseline<S>, ExactError> {
    let (cross, score_moment, m2) =
        slot_statistics(problem, theta, problem.mdp().states, |states, i| states[i])?;
    let weights: Vec<S> = cross
        .iter()
        .zip(&score_moment)
        .map(|(c, m)| ratio(c, m).unwrap_or_else(S::zero))
        .collect();
    let closed_form = cross
        .iter()
        .zip(&weights)
        .fold(m2.clone(), |acc, (c, w)| acc - c.clone() * w);
    let optimal =
        baselined_moments_by(problem, theta, |states, i| Some(weights[states[i]].clone()))?;
    Ok(OptimalStateBaseline {
        cross,
        score_moment,
        weights,
        second_moment: m2,
        second_moment_optimal: optimal.second_moment,
        second_moment_closed_form: closed_form,
    })
}

/// (X1) `E[g·ψ_i]`, `E‖ψ_i‖²`, `E‖g‖²` at θ, the optimal baselines b*_i and b*_const, and the
/// second moments they achieve (math.md §9).
///
/// # Errors
/// As [`crate::exact::enumerate::moments`].
pub fn optimal_baselines<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
) -> Result<OptimalBaselines<S>, ExactError> {
    let decisions = problem.mdp().horizon - 2;
    let (cross, score_moment, m2) = slot_statistics(problem, theta, decisions, |_, i| i)?;
    let time_indexed: Vec<S> = cross
        .iter()
        .zip(&score_moment)
        .map(|(c, m)| ratio(c, m).unwrap_or_else(S::zero))
        .collect();
    let total = |xs: &[S]| xs.iter().fold(S::zero(), |acc, x| acc + x);
    let constant = ratio(&total(&cross), &total(&score_moment)).unwrap_or_else(S::zero);
    let (second_moment_time_indexed, second_moment_constant) = if decisions == 0 {
        (m2.clone(), m2.clone())
    } else {
        (
            baselined_moments(problem, theta, &time_indexed)?.second_moment,
            baselined_moments(problem, theta, &vec![constant.clone(); decisions])?.second_moment,
        )
    };
    Ok(OptimalBaselines {
        cross,
        score_moment,
        second_moment: m2,
        time_indexed,
        constant,
        second_moment_time_indexed,
        second_moment_constant,
    })
}
