//! Constants over the **whole real line** for the tied rational softmax (P2'), by compactifying ℝ
//! with two charts (math.md §7.1, "tails via θ = 1/u"):
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
//!
//! Every certificate is re-evaluated in the table, box by box, by a second route that shares no code
//! with this module ([`crate::recheck`]), and the regions' boxes must tile them exactly
//! ([`crate::bnb::verify_tiling`]); row 8b fails if any box fails.
//!
//! The point of this module is that no box has to contain the iterates: the constants hold
//! everywhere, so they apply to STORM, whose iterates have no useful a.s. box (the direction d_k
//! has no a.s. bound that stays small as a_k → 0).
//!
//! **Why (A4) needs no strip here.** The proof of Theorem S uses (A4) only at consecutive iterates
//! (θ_k, θ_{k+1}) (math.md §3.2, step 1), so a strip |θ′ − θ| ≤ δ with a certified δ ≥ η_k‖d_k‖
//! would do. For the rational softmax it is not needed: every probability lies in
//! [(3−√3)/6, (3+√3)/6] for all θ, so the prefix weight is ≤ 2 + √3 everywhere, V_IS is smooth
//! and bounded on ℝ², and its θ′-derivatives decay at infinity; hence ½ sup_{ℝ²} |∂²V_IS/∂θ′²| is
//! finite and (A4) holds as stated, for all θ, θ′. (For an exponential softmax the weights grow like
//! e^{|θ′−θ|} and a global L̃ would be infinite; there the strip route would be required.)

use crate::bnb::{BnbError, SupBound, sup_bound, verify_certificate};
use crate::check::{Check, Measured, Method, Role, Verdict};
use crate::constants::{Constant, Provenance, attained_sqrt};
use crate::recheck::{Coverage, Quantity, Recheck, recheck};
use ilopt::exact::enumerate::for_each_prefix;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::toy::estimator::{causal, per_decision};
use ilopt::toy::policy::brier;
use ilopt::toy::{PolicyKind, PolicyTable, ToyMdp, ToyProblem};
use serde::{Deserialize, Serialize};

/// A chart of ℝ ∪ {∞} (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Chart {
    /// θ ∈ [−R, R].
    Core,
    /// θ = 1/u, u ∈ [−1/R, 1/R].
    Tail,
}

/// The core radius R (a power of two, so 1/R is exact).
pub const CORE_RADIUS: f64 = 4.0;

impl Chart {
    /// The chart's coordinate domain.
    pub fn domain(self) -> [f64; 2] {
        match self {
            Chart::Core => [-CORE_RADIUS, CORE_RADIUS],
            Chart::Tail => [-1.0 / CORE_RADIUS, 1.0 / CORE_RADIUS],
        }
    }
}

/// A supremum bound on one region (a product of charts), with its branch-and-bound certificate in
/// the charts' coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChartBound {
    /// The chart of each coordinate.
    pub charts: Vec<Chart>,
    /// The region in chart coordinates.
    pub domain: Vec<[f64; 2]>,
    /// The bound and its partition.
    pub bound: SupBound,
}

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

fn is_tied_1d(mdp: &ToyMdp) -> Result<(), BnbError> {
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

/// One prefix: (states, actions, p(τ̄), L(τ̄), g(τ̄)) for a 1-D parameter.
type Row<S> = (Vec<usize>, Vec<usize>, S, S, S);

fn rows<S: Scalar>(problem: &ToyProblem<S>, table: &PolicyTable<S>) -> Result<Vec<Row<S>>, String> {
    let mut out = vec![];
    for_each_prefix(problem, table, |states, actions, p| {
        let loss = states.iter().fold(S::zero(), |a, &s| a + &table.loss[s]);
        let g = causal(table, states, actions).swap_remove(0);
        out.push((states.to_vec(), actions.to_vec(), p.clone(), loss, g));
    })
    .map_err(|e| e.to_string())?;
    Ok(out)
}

type D2 = Dual<Dual<Interval>>;

fn var2(x: Interval) -> D2 {
    Dual::variable(Dual::variable(x, 0, 1), 0, 1)
}

fn lift2(x: &Interval) -> D2 {
    Dual::constant(Dual::constant(*x))
}

/// (f, f_x, f_xx) of a second-order jet in one variable.
fn parts(v: &D2) -> (Interval, Interval, Interval) {
    let g = v.gradient_padded(1)[0].clone();
    (*v.value().value(), *g.value(), g.gradient_padded(1)[0])
}

/// d²f/dθ² from the x-jet of f in `chart` at the box `x` (chain rule in the tail).
fn theta_second(chart: Chart, x: Interval, f_x: Interval, f_xx: Interval) -> Interval {
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
fn theta_first(chart: Chart, x: Interval, f_x: Interval) -> Interval {
    match chart {
        Chart::Core => f_x,
        Chart::Tail => -(x * x) * f_x,
    }
}

/// An enclosure of a function on a box of a region (charts per coordinate).
type RegionFn<'a> = dyn Fn(&[Chart], &[Interval]) -> Result<Interval, String> + 'a;

/// Branch-and-bound of `f` on every region (product of charts), `dims` ∈ {1, 2}.
fn over_charts(
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
fn global_constant(
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
    Constant {
        name: name.into(),
        value,
        rational: BigRational::from_float(value).map_or_else(|| "inf".into(), |q| q.to_string()),
        provenance: Provenance::Rigorous,
        how,
        certificate: None,
        charts: regions,
        attained: Some(attained(lower)),
    }
}

fn sqrt_up(x: f64) -> f64 {
    x.max(0.0).sqrt().next_up()
}

/// L_F ≥ sup_{θ ∈ ℝ} |F″(θ)|, F = Σ_τ̄ p(τ̄)L(τ̄) differentiated twice in dual numbers (X1).
///
/// # Errors
/// [`BnbError`] if an enclosure fails, or for a policy other than the one-group tied softmax.
pub fn l_f(mdp: &ToyMdp, tol: f64, max_boxes: usize) -> Result<Constant, BnbError> {
    is_tied_1d(mdp)?;
    let pd = ToyProblem::<D2>::new(mdp);
    let f = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        let x = b[0];
        let table = table_at(mdp, &pd, charts[0], &var2(x))?;
        let obj = rows(&pd, &table)?
            .into_iter()
            .fold(D2::zero(), |a, r| a + r.2 * &r.3);
        let (_, fx, fxx) = parts(&obj);
        Ok(theta_second(charts[0], x, fx, fxx).abs())
    };
    let regions = over_charts(1, &f, tol, max_boxes)?;
    Ok(global_constant(
        "L_F",
        regions,
        1,
        |s| s,
        |s| s,
        "sup |F″| (F = Σ p·L in second-order duals)",
    ))
}

/// Interval-valued per-θ moments: (E‖g‖², E g, max ‖g‖²) in `chart` at the box `x`.
fn moments(
    mdp: &ToyMdp,
    pi: &ToyProblem<Interval>,
    chart: Chart,
    x: Interval,
) -> Result<(Interval, Interval, Interval), String> {
    let table = table_at(mdp, pi, chart, &x)?;
    let (mut m2, mut eg) = (Interval::zero(), Interval::zero());
    // max over prefixes of g², as an interval: [max of the lower ends, max of the upper ends].
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for r in rows(pi, &table)? {
        m2 += r.2 * r.4 * r.4;
        eg += r.2 * r.4;
        let g2 = r.4 * r.4;
        lo = lo.max(g2.inf());
        hi = hi.max(g2.sup());
    }
    let gmax = Interval::try_from((lo, hi)).map_err(|e| format!("{e:?}"))?;
    Ok((m2, eg, gmax))
}

/// σ² ≥ sup_{θ ∈ ℝ} Var_θ g (c = 1), G_F ≥ sup_{θ ∈ ℝ} |∇F(θ)| (∇F = E g, identity I2) and
/// G_∞ ≥ sup_{θ ∈ ℝ, τ̄} |g(θ, τ̄)|, each by branch-and-bound over both charts.
///
/// # Errors
/// [`BnbError`] if an enclosure fails, or for a policy other than the one-group tied softmax.
pub fn moment_constants(
    mdp: &ToyMdp,
    tol: f64,
    max_boxes: usize,
) -> Result<(Constant, Constant, Constant), BnbError> {
    is_tied_1d(mdp)?;
    let pi = ToyProblem::<Interval>::new(mdp);
    let var = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        let (m2, eg, _) = moments(mdp, &pi, charts[0], b[0])?;
        Ok(m2 - eg * eg)
    };
    let gf = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        let (_, eg, _) = moments(mdp, &pi, charts[0], b[0])?;
        Ok(eg * eg)
    };
    let ginf = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        Ok(moments(mdp, &pi, charts[0], b[0])?.2)
    };
    Ok((
        global_constant(
            "σ²",
            over_charts(1, &var, tol, max_boxes)?,
            1,
            |s| s.max(0.0),
            |s| s.max(0.0),
            "sup Var g = sup (E g² − (E g)²)",
        ),
        global_constant(
            "G_F",
            over_charts(1, &gf, tol, max_boxes)?,
            1,
            sqrt_up,
            attained_sqrt,
            "√ sup (E g)² = √ sup F′²",
        ),
        global_constant(
            "G_∞",
            over_charts(1, &ginf, tol, max_boxes)?,
            1,
            sqrt_up,
            attained_sqrt,
            "√ sup over prefixes of g²",
        ),
    ))
}

/// `∂²V_IS/∂θ′²` at (θ in `charts[0]` at `b[0]`, θ′ in `charts[1]` at `b[1]`), where
/// `V_IS(θ, θ′) = Σ_τ̄ [p′ g′² − 2p g′ g + p²/p′ g²]` (p = p(τ̄; θ), g = g(θ, τ̄), primes at θ′)
/// is E_{τ∼θ′} (g(θ′, τ) − w g(θ, τ))² with the trajectory (prefix) weight w = p/p′.
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second(
    mdp: &ToyMdp,
    pd: &ToyProblem<D2>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    let total = v_is_total(mdp, pd, weighting, charts, &lift2(&b[0]), &var2(b[1]))?;
    let (_, vx, vxx) = parts(&total);
    Ok(theta_second(charts[1], b[1], vx, vxx))
}

/// `V(θ, θ′) = Σ_τ̄ p(τ̄; θ′) (g(θ′, τ̄) − g̃(θ → θ′, τ̄))²` with θ at `x_old` in `charts[0]` and θ′
/// at `x_new` in `charts[1]`, in any scalar. The old-point term g̃ is `w g(θ, τ̄)` with the
/// prefix weight w = p(τ̄; θ)/p(τ̄; θ′) (trajectory), or the engine's per-decision form
/// ([`per_decision`]). The factored square keeps enclosures tight near θ′ = θ, where an expanded
/// form would cancel.
fn v_is_total<S: Scalar>(
    mdp: &ToyMdp,
    problem: &ToyProblem<S>,
    weighting: Weighting,
    charts: &[Chart],
    x_old: &S,
    x_new: &S,
) -> Result<S, String> {
    let t_old = table_at(mdp, problem, charts[0], x_old)?;
    let t_new = table_at(mdp, problem, charts[1], x_new)?;
    let at = rows(problem, &t_old)?;
    let prime = rows(problem, &t_new)?;
    if at.len() != prime.len() {
        return Err("prefix sets differ".into());
    }
    let mut total = S::zero();
    for (a, q) in at.iter().zip(&prime) {
        if a.0 != q.0 || a.1 != q.1 {
            return Err("prefix order differs".into());
        }
        let old = match weighting {
            Weighting::Trajectory => a.2.clone() / &q.2 * &a.4,
            Weighting::PerDecision => {
                let ratios: Vec<S> =
                    a.0.iter()
                        .zip(&a.1)
                        .map(|(&s, &act)| t_old.prob(s, act).clone() / t_new.prob(s, act))
                        .collect();
                per_decision(&t_old, &a.0, &a.1, &ratios).swap_remove(0)
            }
        };
        let e = q.4.clone() - old;
        total += q.2.clone() * &e * &e;
    }
    Ok(total)
}

type D3 = Dual<D2>;

/// Enclosures of `h = ∂²V_IS/∂θ′²` and of its chart-coordinate derivatives `∂₁h`, `∂₂h` on a box
/// (see [`v_is_second_mean_value`]).
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second_jet(
    mdp: &ToyMdp,
    p3: &ToyProblem<D3>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<[Interval; 3], String> {
    let x1 = Dual::variable(lift2(&b[0]), 0, 2);
    let x2 = Dual::variable(var2(b[1]), 1, 2);
    let total = v_is_total(mdp, p3, weighting, charts, &x1, &x2)?;
    let (_, v2, v22) = parts(total.value());
    let grad = total.gradient_padded(2);
    let (_, v12, v122) = parts(&grad[0]);
    let (_, _, v222) = parts(&grad[1]);
    let natural = theta_second(charts[1], b[1], v2, v22);
    let (d1, d2) = match charts[1] {
        Chart::Core => (v122, v222),
        Chart::Tail => {
            let u = b[1];
            let (u2, six) = (u * u, Interval::from_i64(6));
            let u3 = u2 * u;
            (
                u2 * u2 * v122 + Interval::from_i64(2) * u3 * v12,
                u2 * u2 * v222 + six * u3 * v22 + six * u2 * v2,
            )
        }
    };
    Ok([natural, d1, d2])
}

/// A tighter enclosure of `∂²V_IS/∂θ′²` on a box, in chart coordinates (x₁, x₂): the natural
/// interval extension intersected with the mean-value form
/// `h(X) ⊆ h(m) + ∂₁h(X)(X₁ − m₁) + ∂₂h(X)(X₂ − m₂)`, whose overestimation shrinks
/// quadratically with the box. The derivatives of h come from third-order nested duals (outer level
/// in (x₁, x₂), the two inner levels in x₂); in the tail chart h = u⁴V_uu + 2u³V_u, so
/// `∂_u h = u⁴V_uuu + 6u³V_uu + 6u²V_u` and `∂₁h = u⁴∂₁V_uu + 2u³∂₁V_u`.
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second_mean_value(
    mdp: &ToyMdp,
    pd: &ToyProblem<D2>,
    p3: &ToyProblem<D3>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    let [natural, d1, d2] = v_is_second_jet(mdp, p3, weighting, charts, b)?;
    let point = |x: Interval| {
        let m = x.mid();
        Interval::try_from((m, m)).map_err(|e| format!("{e:?}"))
    };
    let m = [point(b[0])?, point(b[1])?];
    let at_mid = v_is_second(mdp, pd, weighting, charts, &m)?;
    let mv = at_mid + d1 * (b[0] - m[0]) + d2 * (b[1] - m[1]);
    let both = natural.intersection(mv);
    Ok(if both.is_empty() { natural } else { both })
}

/// L̃ of (A4), over all of ℝ²: `V_IS(θ, θ′) ≤ L̃² (θ′ − θ)²` for **every** θ, θ′, from
/// `V_IS(θ, θ) = 0`, `∂V_IS/∂θ′(θ, θ) = 0` (a minimum of a non-negative smooth function) and
/// Taylor's theorem along the segment: `L̃² ≤ ½ sup_{ℝ²} |∂²V_IS/∂θ′²|`.
///
/// This is finite for the rational softmax because its probabilities are bounded away from 0
/// (p ∈ [(3−√3)/6, (3+√3)/6] for P2', so every prefix weight is ≤ 2 + √3) and every θ-derivative
/// decays like 1/θ² at infinity (the tail chart is smooth at u = 0).
///
/// # Errors
/// [`BnbError`] if an enclosure fails, or for a policy other than the one-group tied softmax.
pub fn l_tilde(
    mdp: &ToyMdp,
    weighting: Weighting,
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    is_tied_1d(mdp)?;
    let pd = ToyProblem::<D2>::new(mdp);
    let p3 = ToyProblem::<D3>::new(mdp);
    let f = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        Ok(v_is_second_mean_value(mdp, &pd, &p3, weighting, charts, b)?.abs())
    };
    let regions = over_charts(2, &f, tol, max_boxes)?;
    let (name, what) = match weighting {
        Weighting::Trajectory => ("L̃", "√(½ sup |∂²V_IS/∂θ′²|) (trajectory weights)"),
        Weighting::PerDecision => ("L̃_PD", "√(½ sup |∂²V_PD/∂θ′²|) (per-decision weights)"),
    };
    Ok(global_constant(
        name,
        regions,
        2,
        |s| sqrt_up(s / 2.0 * (1.0 + 1e-15)),
        |s| attained_sqrt(s / 2.0),
        what,
    ))
}

/// Re-run the first route on the certificate of an L̃ from [`l_tilde`] (a consistency check of the
/// recorded enclosures with the same code; the independent re-check the table runs is
/// [`crate::recheck`], through [`GlobalConstants::recheck`]):
/// the regions cover ℝ² ([`verify_charts`]), the enclosure of |∂²V_IS/∂θ′²| is **re-evaluated** on
/// every certificate box and must not exceed the recorded one, and the constant must be
/// ≥ √(½ · the re-evaluated supremum). Returns the re-evaluated supremum.
///
/// # Errors
/// A message naming the first box or condition that fails.
pub fn recheck_l_tilde(mdp: &ToyMdp, weighting: Weighting, c: &Constant) -> Result<f64, String> {
    verify_charts(&c.charts, 2).ok_or("the regions do not cover ℝ² or a partition is invalid")?;
    let pd = ToyProblem::<D2>::new(mdp);
    let p3 = ToyProblem::<D3>::new(mdp);
    let mut sup = f64::NEG_INFINITY;
    for r in &c.charts {
        for b in &r.bound.certificate {
            let iv: Vec<Interval> = b
                .bounds
                .iter()
                .map(|[l, h]| Interval::try_from((*l, *h)).map_err(|e| format!("{e:?}")))
                .collect::<Result<_, _>>()?;
            let e = v_is_second_mean_value(mdp, &pd, &p3, weighting, &r.charts, &iv)?.abs();
            if e.sup().is_nan() || e.sup() > b.enclosure[1] {
                return Err(format!(
                    "box {:?} of {:?}: re-evaluated sup {} > recorded {}",
                    b.bounds,
                    r.charts,
                    e.sup(),
                    b.enclosure[1]
                ));
            }
            sup = sup.max(e.sup());
        }
    }
    if c.value * c.value < sup / 2.0 {
        return Err(format!("L̃ = {} < √(½ · {sup})", c.value));
    }
    Ok(sup)
}

/// ∇F(θ) enclosure at a point of the tail chart (for tests): −u² F_u.
///
/// # Errors
/// If a table cannot be built.
pub fn gradient_in_chart(mdp: &ToyMdp, chart: Chart, x: Interval) -> Result<Interval, String> {
    let pd = ToyProblem::<D2>::new(mdp);
    let table = table_at(mdp, &pd, chart, &var2(x))?;
    let obj = rows(&pd, &table)?
        .into_iter()
        .fold(D2::zero(), |a, r| a + r.2 * &r.3);
    let (_, fx, _) = parts(&obj);
    Ok(theta_first(chart, x, fx))
}

/// A rigorous constant, the quantity its certificate bounds, its dimension (1: ℝ, 2: ℝ²) and the
/// map from the certified supremum to the constant.
type Certified<'a> = (&'a Constant, Quantity, usize, fn(f64) -> f64);

/// The global constants of the STORM checks: B_F exact, the rest rigorous over ℝ (ℝ² for L̃).
#[derive(Debug, Clone)]
pub struct GlobalConstants {
    /// B_F = F(θ₁) − inf F (exact).
    pub b_f: Constant,
    /// L_F ≥ sup |F″|.
    pub l_f: Constant,
    /// L̃ of (A4) for trajectory weights.
    pub l_tilde: Constant,
    /// L̃ of (A4) for per-decision weights.
    pub l_tilde_pd: Constant,
    /// σ² ≥ sup Var g.
    pub sigma2: Constant,
    /// G_F ≥ sup |F′|.
    pub g_f: Constant,
    /// G_∞ ≥ sup |g|.
    pub g_inf: Constant,
    /// The MDP the constants are for (the second route re-evaluates its certificates on it).
    pub mdp: ToyMdp,
}

/// Branch-and-bound sizes: (tolerance, box budget per region) for the 1-D constants and for L̃.
#[derive(Debug, Clone, Copy)]
pub struct GlobalSizes {
    /// Tolerance of the 1-D constants.
    pub tol: f64,
    /// Box budget per region of the 1-D constants.
    pub max_boxes: usize,
    /// Tolerance on ½ sup |∂²V_IS/∂θ′²| (L̃²).
    pub l_tilde_tol: f64,
    /// Box budget per region of L̃ (a smaller budget gives a larger, still rigorous, L̃).
    pub l_tilde_boxes: usize,
}

impl GlobalConstants {
    /// Compute all of them for a one-group tied softmax MDP.
    ///
    /// # Errors
    /// [`BnbError`] if an enclosure fails.
    pub fn compute(
        mdp: &ToyMdp,
        theta1: &[BigRational],
        f_inf: Option<&BigRational>,
        sizes: GlobalSizes,
    ) -> Result<Self, BnbError> {
        let GlobalSizes {
            tol,
            max_boxes,
            l_tilde_tol,
            l_tilde_boxes,
        } = sizes;
        let (sigma2, g_f, g_inf) = moment_constants(mdp, tol, max_boxes)?;
        Ok(Self {
            b_f: crate::constants::b_f(mdp, theta1, f_inf).map_err(|m| BnbError::Evaluation {
                bounds: vec![],
                message: m,
            })?,
            l_f: l_f(mdp, tol, max_boxes)?,
            l_tilde: l_tilde(mdp, Weighting::Trajectory, l_tilde_tol, l_tilde_boxes)?,
            l_tilde_pd: l_tilde(mdp, Weighting::PerDecision, l_tilde_tol, l_tilde_boxes)?,
            sigma2,
            g_f,
            g_inf,
            mdp: mdp.clone(),
        })
    }

    /// L = max(L_F, L̃) for the given weighting.
    pub fn l(&self, weighting: Weighting) -> f64 {
        self.l_f.value.max(match weighting {
            Weighting::Trajectory => self.l_tilde.value,
            Weighting::PerDecision => self.l_tilde_pd.value,
        })
    }

    /// Every constant, in report order.
    pub fn all(&self) -> Vec<Constant> {
        vec![
            self.b_f.clone(),
            self.l_f.clone(),
            self.l_tilde.clone(),
            self.l_tilde_pd.clone(),
            self.sigma2.clone(),
            self.g_f.clone(),
            self.g_inf.clone(),
        ]
    }

    /// Every constant without its chart certificates (they are in the constants row, 8b).
    pub fn summary(&self) -> Vec<Constant> {
        self.all()
            .into_iter()
            .map(|mut c| {
                if !c.charts.is_empty() {
                    c.how += "; certificate in row 8b";
                    c.charts.clear();
                }
                c
            })
            .collect()
    }

    /// Every rigorous constant with the quantity its certificate bounds, the constant's
    /// dimension (1: ℝ, 2: ℝ²) and the map from the certified supremum to the constant.
    fn certified(&self) -> [Certified<'_>; 6] {
        fn id(s: f64) -> f64 {
            s
        }
        fn root(s: f64) -> f64 {
            s.max(0.0).sqrt()
        }
        fn half_root(s: f64) -> f64 {
            (s / 2.0).max(0.0).sqrt()
        }
        [
            (&self.l_f, Quantity::Hessian, 1, id),
            (&self.sigma2, Quantity::Variance, 1, id),
            (&self.g_f, Quantity::GradientSq, 1, root),
            (&self.g_inf, Quantity::MaxEstimateSq, 1, root),
            (&self.l_tilde, Quantity::VisTrajectory, 2, half_root),
            (&self.l_tilde_pd, Quantity::VisPerDecision, 2, half_root),
        ]
    }

    /// Re-evaluate every certificate by the second route ([`crate::recheck`]): each region's
    /// boxes (all, or a sample) and its exact tiling; a constant passes if every region passes
    /// and the constant is ≥ the transformed largest bound the second route proved.
    pub fn recheck(&self, coverage: Coverage) -> Vec<(String, Recheck)> {
        self.certified()
            .iter()
            .map(|(c, q, _, t)| {
                let mut all = Recheck::empty();
                for r in &c.charts {
                    all.merge(recheck(
                        &self.mdp,
                        *q,
                        &r.charts,
                        &r.domain,
                        &r.bound,
                        r.bound.upper,
                        coverage,
                    ));
                }
                if c.charts.is_empty() {
                    all.failures.push("no certificate".into());
                } else if c
                    .value
                    .partial_cmp(&t(all.max_upper))
                    .is_none_or(|o| o.is_lt())
                {
                    all.failures.push(format!(
                        "{} = {} < the re-checked bound {}",
                        c.name,
                        c.value,
                        t(all.max_upper)
                    ));
                }
                (c.name.clone(), all)
            })
            .collect()
    }

    /// The report row (8b): every constant exact or rigorous over ℝ, every certificate re-checked
    /// box by box by the second route.
    pub fn row(&self, name: &str) -> Check {
        self.row_with(name, Coverage::All)
    }

    /// [`GlobalConstants::row`] re-checking the boxes given by `coverage`.
    pub fn row_with(&self, name: &str, coverage: Coverage) -> Check {
        let all = self.all();
        let rechecks = self.recheck(coverage);
        let ok = self.verified() && rechecks.iter().all(|(_, r)| r.passed());
        Check {
            id: "8b".into(),
            result: "Rigorous constants over ℝ (math.md §7.1, tails by θ = 1/u)".into(),
            claim: format!(
                "{name}: B_F exact; L_F, σ², G_F, G_∞ over ℝ and L̃ of (A4) (trajectory and per-decision weights) over ℝ² rigorous upper bounds"
            ),
            assumptions: vec![
                "none on the iterates: the bounds hold for every θ (θ, θ′)".into(),
                "L̃² ≤ ½ sup |∂²V_IS/∂θ′²| since V_IS(θ, θ) = 0 is a minimum (Taylor)".into(),
            ],
            details: format!(
                "{}. {}",
                all.iter()
                    .map(|c| {
                        let boxes: usize = c.charts.iter().map(|r| r.bound.certificate.len()).sum();
                        format!("{} ≤ {:.6} ({boxes} boxes)", c.name, c.value)
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
                recheck_summary(&rechecks, coverage)
            ),
            constants: all,
            bound: None,
            measured: Some(Measured::exact(self.l_tilde.value)),
            tightness: None,
            method: Method::Rigorous,
            verdict: Verdict::from_bool(ok),
            erratum: Some("E2".into()),
            role: Role::Corrected,
        }
    }

    /// Re-check every certificate (B_F is exact): each tiles ℝ (ℝ² for L̃) and the constant is
    /// at least the transformed supremum it certifies.
    pub fn verified(&self) -> bool {
        self.b_f.provenance == Provenance::Exact
            && self.certified().iter().all(|(c, _, d, t)| {
                c.provenance == Provenance::Rigorous
                    && verify_charts(&c.charts, *d).is_some_and(|sup| c.value >= t(sup))
            })
    }
}

/// One sentence per constant: boxes re-checked, pieces, corners, tiling, result.
pub fn recheck_summary(rechecks: &[(String, Recheck)], coverage: Coverage) -> String {
    let scope = match coverage {
        Coverage::All => "every box".to_string(),
        Coverage::Sample(n) => format!(
            "a seeded sample of {n} boxes per region plus every box within 1 % of the certified bound"
        ),
    };
    let each: Vec<String> = rechecks
        .iter()
        .map(|(name, r)| {
            let verdict = if r.passed() {
                "passed".to_string()
            } else {
                format!("FAILED: {}", r.failures.join("; "))
            };
            format!(
                "{name}: {} boxes, {} pieces, {} corners, tiling {}, max re-checked {:.6}, {verdict}",
                r.boxes,
                r.pieces,
                r.corners,
                if r.tiling { "exact" } else { "broken" },
                r.max_upper
            )
        })
        .collect();
    format!(
        "Second route (hand-written P2′ closed forms, enumeration and estimator; corner values enclosed at points and a Dual<Interval> gradient bound on each box; {scope}): {}",
        each.join("; ")
    )
}
