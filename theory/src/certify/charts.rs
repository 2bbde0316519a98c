//! Two charts of ℝ ∪ {∞} for the tied rational softmax (P2'), so that a supremum over all of ℝ
//! (or ℝ²) is a branch-and-bound over compact domains (math.md §7.1, "tails via θ = 1/u"):
//!
//! * the **core** chart, θ ∈ [−R, R], evaluated with the engine's own policy table;
//! * the **tail** chart, θ = 1/u with u ∈ [−1/R, 1/R], which covers |θ| ≥ R and the point at
//!   infinity. In u the policy is a rational function analytic at u = 0:
//!   `p = (1 + cu²)/(2 − 2u + (1+2c)u²)`, `dp/dθ = u²(−2 + 2u + 2cu²)/(2 − 2u + (1+2c)u²)²`
//!   (multiply numerator and denominator of the θ-formulas of §1.3 by u² and u⁴), and
//!   `d/dθ = −u² d/du`, so `d²/dθ² = u⁴ d²/du² + 2u³ d/du`.
//!
//! Every quantity the bounds need (F″, Var g, ‖∇F‖, ‖g‖, and ∂²V_IS/∂θ′² for (A4)) depends on θ only
//! through the policy table, so the engine's prefix enumeration (X1) and estimator code run
//! unchanged on a table built in either chart ([`tied_table`]). Branch-and-bound on each chart (a
//! product of charts in 2-D) gives a rigorous bound of the supremum over ℝ (ℝ²), with one
//! certificate per region ([`ChartBound`]); together the regions cover ℝ (ℝ²).

use crate::certify::bnb::{BnbError, sup_bound};
use crate::certify::tiling::verify_certificate;
use crate::record::certificate::{CORE_RADIUS, Chart, ChartBound};
use crate::record::constant::Constant;
use ilopt::exact::enumerate::for_each_prefix;
use ilopt::oracle::DecisionTerms;
use ilopt::scalar::{Dual, Interval, Scalar};
use ilopt::toy::estimator::{causal, decision_terms};
use ilopt::toy::policy::brier;
use ilopt::toy::{PolicyKind, PolicyTable, ToyMdp, ToyProblem};

/// Re-check a set of chart certificates: every region's partition covers its domain with
/// enclosures ≤ its bound, each region's domain is its charts' domain, and the regions are every
/// combination of charts (so they cover ℝ^d). Returns the largest region bound, or `None` if any
/// check fails.
pub fn verify_charts(regions: &[ChartBound], dims: usize) -> Option<f64> {
    let combos = 1usize << dims;
    if regions.len() != combos {
        return None;
    }
    let mut seen = vec![false; combos];
    let mut best = f64::NEG_INFINITY;
    for r in regions {
        if r.charts.len() != dims || r.domain.len() != dims {
            return None;
        }
        let idx = r
            .charts
            .iter()
            .enumerate()
            .fold(0, |a, (i, c)| a | (usize::from(*c == Chart::Tail) << i));
        let expected: Vec<[f64; 2]> = r.charts.iter().map(|c| c.domain()).collect();
        if seen[idx] || r.domain != expected || !verify_certificate(&r.bound, &r.domain) {
            return None;
        }
        seen[idx] = true;
        best = best.max(r.bound.upper);
    }
    seen.iter().all(|s| *s).then_some(best)
}

pub(crate) fn is_tied_1d(mdp: &ToyMdp) -> Result<(), BnbError> {
    if mdp.policy.kind == PolicyKind::TiedSoftmax && mdp.policy.group_count() == 1 {
        Ok(())
    } else {
        Err(BnbError::Evaluation {
            bounds: vec![],
            message: "the charts are implemented for the tied softmax with one group".into(),
        })
    }
}

/// (p, dp/dθ) of the tied softmax, p = π(1|·), in the tail coordinate u = 1/θ (module docs).
pub fn tail_jet<S: Scalar>(u: &S, c: &S) -> (S, S) {
    let two = S::from_i64(2);
    let u2 = u.square();
    let den = two.clone() - two.clone() * u + (S::one() + two.clone() * c) * &u2;
    let p = (S::one() + c.clone() * &u2) / &den;
    let dp = u2.clone() * (two.clone() * u - two.clone() + two * c * &u2) / den.square();
    (p, dp)
}

/// The engine's [`PolicyTable`] for a one-group tied softmax, built from `p = π(1|·)` and its
/// θ-derivative `dp`: π = (1 − p, p), ∂π/∂θ = (−dp, dp), ψ = ∂π/π, Brier loss per state.
///
/// # Errors
/// If a probability is not certainly positive (the score would divide by zero).
pub fn tied_table<S: Scalar>(mdp: &ToyMdp, p: S, dp: S) -> Result<PolicyTable<S>, String> {
    let probs = vec![S::one() - &p, p];
    if !probs.iter().all(Scalar::is_certainly_positive) {
        return Err("π(a|s) not certainly positive".into());
    }
    let jac = vec![vec![-dp.clone()], vec![dp]];
    let score = probs
        .iter()
        .zip(&jac)
        .map(|(pa, ja)| vec![ja[0].clone() / pa])
        .collect();
    let (mut loss, mut loss_grad) = (vec![], vec![]);
    for s in 0..mdp.states {
        let (l, g) = brier(&probs, &jac, mdp.expert[s]);
        loss.push(l);
        loss_grad.push(g);
    }
    Ok(PolicyTable {
        probs: vec![probs],
        jacobian: vec![jac],
        score: vec![score],
        loss,
        loss_grad,
        groups: mdp.policy.groups.clone(),
        block: 1,
        dim: 1,
    })
}

/// The policy table at the point `x` of `chart` (x = θ in the core, x = u in the tail). In a dual
/// scalar the table's derivatives are with respect to x.
///
/// # Errors
/// If the table cannot be built.
pub fn table_at<S: Scalar>(
    mdp: &ToyMdp,
    problem: &ToyProblem<S>,
    chart: Chart,
    x: &S,
) -> Result<PolicyTable<S>, String> {
    match chart {
        Chart::Core => problem
            .table(std::slice::from_ref(x))
            .map_err(|e| e.to_string()),
        Chart::Tail => {
            let (p, dp) = tail_jet(x, problem.c());
            tied_table(mdp, p, dp)
        }
    }
}

/// One prefix τ̄ of a 1-D parameter with the terms the constants need.
pub(crate) struct PrefixTerms<S> {
    /// The visited states.
    pub states: Vec<usize>,
    /// The actions taken.
    pub actions: Vec<usize>,
    /// p(τ̄).
    pub prob: S,
    /// L(τ̄), the summed per-state loss.
    pub loss: S,
    /// g(θ, τ̄), the estimator (3.15).
    pub estimate: S,
}

/// Every prefix of `problem` under `table`, with its terms.
pub(crate) fn prefix_terms<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
) -> Result<Vec<PrefixTerms<S>>, String> {
    let mut out = vec![];
    for_each_prefix(problem, table, |states, actions, p| {
        let loss = states.iter().fold(S::zero(), |a, &s| a + &table.loss[s]);
        let g = causal(table, states, actions).swap_remove(0);
        out.push(PrefixTerms {
            states: states.to_vec(),
            actions: actions.to_vec(),
            prob: p.clone(),
            loss,
            estimate: g,
        });
    })
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Every prefix of `problem` under `table` with the **baselined** estimate
/// `g_b = g − b Σ_i ψ_i` in place of g (one constant b for every scored decision; docs/math.md
/// §9), assembled by the engine's own baselined code ([`decision_terms`] and
/// [`DecisionTerms::estimate_into`]), as the oracle does.
pub(crate) fn prefix_terms_baselined<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    b: &S,
) -> Result<Vec<PrefixTerms<S>>, String> {
    let mut out = vec![];
    let mut terms = DecisionTerms::new();
    let mut g = vec![S::zero(); table.dim];
    for_each_prefix(problem, table, |states, actions, p| {
        let loss = states.iter().fold(S::zero(), |a, &s| a + &table.loss[s]);
        let scored = problem.scored_actions(states, actions);
        decision_terms(table, states, scored, None, false, &mut terms);
        terms.estimate_into(|_| Some(b.clone()), &mut g);
        out.push(PrefixTerms {
            states: states.to_vec(),
            actions: actions.to_vec(),
            prob: p.clone(),
            loss,
            estimate: g[0].clone(),
        });
    })
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// [`prefix_terms`], or [`prefix_terms_baselined`] when a baseline is given.
pub(crate) fn prefix_terms_with<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    baseline: Option<&S>,
) -> Result<Vec<PrefixTerms<S>>, String> {
    match baseline {
        None => prefix_terms(problem, table),
        Some(b) => prefix_terms_baselined(problem, table, b),
    }
}

/// A second-order jet in one variable over intervals: (f, f′, f″) enclosures.
pub(crate) type SecondOrder = Dual<Dual<Interval>>;

pub(crate) fn var2(x: Interval) -> SecondOrder {
    Dual::variable(Dual::variable(x, 0, 1), 0, 1)
}

pub(crate) fn lift2(x: &Interval) -> SecondOrder {
    Dual::constant(Dual::constant(*x))
}

/// (f, f_x, f_xx) of a second-order jet in one variable.
pub(crate) fn parts(v: &SecondOrder) -> (Interval, Interval, Interval) {
    let g = v.gradient_padded(1)[0].clone();
    (*v.value().value(), *g.value(), g.gradient_padded(1)[0])
}

/// d²f/dθ² from the x-jet of f in `chart` at the box `x` (chain rule in the tail).
pub(crate) fn theta_second(chart: Chart, x: Interval, f_x: Interval, f_xx: Interval) -> Interval {
    match chart {
        Chart::Core => f_xx,
        Chart::Tail => {
            let u2 = x * x;
            let u3 = u2 * x;
            u2 * u2 * f_xx + Interval::from_i64(2) * u3 * f_x
        }
    }
}

/// d f/dθ from the x-derivative in `chart` (−u² f_u in the tail).
pub(crate) fn theta_first(chart: Chart, x: Interval, f_x: Interval) -> Interval {
    match chart {
        Chart::Core => f_x,
        Chart::Tail => -(x * x) * f_x,
    }
}

/// An enclosure of a function on a box of a region (charts per coordinate).
pub(crate) type RegionFn<'a> = dyn Fn(&[Chart], &[Interval]) -> Result<Interval, String> + 'a;

/// Branch-and-bound of `f` on every region (product of charts), `dims` ∈ {1, 2}.
pub(crate) fn over_charts(
    dims: usize,
    f: &RegionFn<'_>,
    tol: f64,
    max_boxes: usize,
) -> Result<Vec<ChartBound>, BnbError> {
    let mut out = vec![];
    for idx in 0..(1usize << dims) {
        let charts: Vec<Chart> = (0..dims)
            .map(|i| {
                if idx >> i & 1 == 1 {
                    Chart::Tail
                } else {
                    Chart::Core
                }
            })
            .collect();
        let domain: Vec<[f64; 2]> = charts.iter().map(|c| c.domain()).collect();
        let bound = sup_bound(|b: &[Interval]| f(&charts, b), &domain, tol, max_boxes)?;
        out.push(ChartBound {
            charts,
            domain,
            bound,
        });
    }
    Ok(out)
}

/// A constant bounded over all of ℝ (or ℝ²) from chart certificates.
pub(crate) fn global_constant(
    name: &str,
    regions: Vec<ChartBound>,
    dims: usize,
    transform: impl Fn(f64) -> f64,
    attained: impl Fn(f64) -> f64,
    what: &str,
) -> Constant {
    let sup = regions
        .iter()
        .map(|r| r.bound.upper)
        .fold(f64::NEG_INFINITY, f64::max);
    let lower = regions
        .iter()
        .map(|r| r.bound.lower)
        .fold(f64::NEG_INFINITY, f64::max);
    let boxes: usize = regions.iter().map(|r| r.bound.certificate.len()).sum();
    let value = transform(sup);
    let how = format!(
        "{what} over {} by interval branch-and-bound on {} chart region(s) (core |θ| ≤ {CORE_RADIUS}, tail θ = 1/u, |u| ≤ {}; {boxes} boxes; attained ≥ {:.6})",
        if dims == 1 { "ℝ" } else { "ℝ²" },
        regions.len(),
        1.0 / CORE_RADIUS,
        attained(lower)
    );
    Constant::over_charts(name, value, how, regions, attained(lower))
}

pub(crate) fn sqrt_up(x: f64) -> f64 {
    x.max(0.0).sqrt().next_up()
}
