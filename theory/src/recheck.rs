//! A **second route** to every rigorous constant: each box of a branch-and-bound certificate is
//! re-evaluated by code that shares nothing with the code that produced the enclosures (math.md
//! §7.1, "report every constant with its certificate").
//!
//! The first route ([`crate::constants`], [`crate::global`]) builds the engine's policy table and
//! runs the engine's prefix enumeration and estimator in nested dual numbers over intervals. This
//! module instead writes the tied softmax (P2'), its θ-derivatives, the prefix enumeration, the
//! Brier loss and the estimator (3.15) again from math.md §§1.1–1.4, by hand:
//!
//! * p = π(1|o) as a closed form in the chart coordinate x (core θ = x; tail θ = 1/u,
//!   `p = (1 + cu²)/((1 + cu²) + (u − 1)² + cu²)`), expanded as a truncated Taylor series in x to
//!   third order, from which dp/dθ, d²p/dθ², d³p/dθ³ follow (in the tail through d/dθ = −u² d/du:
//!   `p_θ = −u²p_u`, `p_θθ = u⁴p_uu + 2u³p_u`, `p_θθθ = −(u⁶p_uuu + 6u⁵p_uu + 6u⁴p_u)`);
//! * derivatives in θ by a second-order multivariate jet written here ([`Jet`]), not the kit's
//!   dual numbers;
//! * the Brier loss of two actions in closed form, `l(s) = 2q²`, `∇l = −4q∇π(a*|s)`, with
//!   q = 1 − π(a*(s)|s), and the estimator in the form `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`
//!   (the engine accumulates the equivalent `Σ_i ψ_i Σ_{t>i} l_t` backwards).
//!
//! Each certificate box X (in chart coordinates) is then checked in two ways:
//!
//! 1. **Values at the corners.** The quantity is enclosed at every corner of X (the same code in
//!    [`Interval`] at a point: a rigorous enclosure a few ulps wide; the code also runs in
//!    [`BigRational`], where the tests compare it exactly with math.md's reference values and the
//!    engine). A corner enclosure entirely outside the recorded enclosure is a certain error (so a
//!    recorded bound lowered below a value f takes at a corner is caught).
//! 2. **An upper bound of the box from the corners.** The same code run in `Dual<Interval>` over X
//!    encloses the gradient ∂h/∂x on X by `[d⁻, d⁺]`; for every x ∈ X and every corner c,
//!    `h(x) ≤ h(c) + Σ_i max over x_i of ∂_ih·(x_i − c_i)`, which is `d⁺_i w_i` when c_i is the
//!    lower end and `−d⁻_i w_i` when it is the upper end (positive parts). The minimum over the
//!    corners bounds sup_X h. If it does not prove the box's recorded bound, X is bisected (at most
//!    [`MAX_DEPTH`] times) and every piece must prove it.
//!
//! A box passes if its corner values can lie in its recorded enclosure, its recorded bound is
//! proved to within the certificate's own precision (upper bound minus attained value, capped at
//! 1 % of the certified bound, at least a relative 10⁻⁹) and the bound proved is ≤ the constant's
//! certified bound (no slack); the
//! certificate passes if every box passes and the boxes tile the domain exactly
//! ([`crate::bnb::verify_tiling`]). A core-chart side with |θ| ≥ R is evaluated in the tail
//! coordinate u = 1/θ (same function, smooth there), which keeps wide far-out boxes cheap.

use crate::bnb::{SupBound, verify_tiling};
use crate::global::{CORE_RADIUS, Chart};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// How often a box may be bisected when its corner bound does not prove the recorded bound.
pub const MAX_DEPTH: u32 = 12;

/// Relative slack on a box's own recorded bound (never on the constant's certified bound).
const BOX_SLACK: f64 = 1e-9;

/// The largest slack on a box's own recorded bound, as a share of the certified bound.
const BOX_SHARE: f64 = 0.01;

/// A second-order jet in `d` variables: value, gradient and Hessian (row-major).
#[derive(Debug, Clone)]
pub struct Jet<S> {
    v: S,
    g: Vec<S>,
    h: Vec<S>,
}

impl<S: Scalar> Jet<S> {
    fn constant(v: S, d: usize) -> Self {
        Self {
            v,
            g: vec![S::zero(); d],
            h: vec![S::zero(); d * d],
        }
    }
    /// A function of the single variable θ_o with derivatives (f, f′, f″).
    fn along(f: S, f1: S, f2: S, o: usize, d: usize) -> Self {
        let mut j = Self::constant(f, d);
        if d > 0 {
            j.g[o] = f1;
            j.h[o * d + o] = f2;
        }
        j
    }
    fn d(&self) -> usize {
        self.g.len()
    }
    fn zip(&self, o: &Self, f: impl Fn(&S, &S) -> S) -> Self {
        Self {
            v: f(&self.v, &o.v),
            g: self.g.iter().zip(&o.g).map(|(a, b)| f(a, b)).collect(),
            h: self.h.iter().zip(&o.h).map(|(a, b)| f(a, b)).collect(),
        }
    }
    fn add(&self, o: &Self) -> Self {
        self.zip(o, |a, b| a.clone() + b)
    }
    fn sub(&self, o: &Self) -> Self {
        self.zip(o, |a, b| a.clone() - b)
    }
    /// (fg)′ = f′g + fg′, (fg)″ = f″g + f′g′ᵀ + g′f′ᵀ + fg″.
    fn mul(&self, o: &Self) -> Self {
        let d = self.d();
        let mut r = Self::constant(self.v.clone() * &o.v, d);
        for i in 0..d {
            r.g[i] = self.g[i].clone() * &o.v + self.v.clone() * &o.g[i];
            for j in 0..d {
                let k = i * d + j;
                r.h[k] = self.h[k].clone() * &o.v
                    + self.g[i].clone() * &o.g[j]
                    + self.g[j].clone() * &o.g[i]
                    + self.v.clone() * &o.h[k];
            }
        }
        r
    }
    /// (1/f)′ = −f′/f², (1/f)″ = 2f′f′ᵀ/f³ − f″/f².
    fn recip(&self) -> Self {
        let d = self.d();
        let r = S::one() / &self.v;
        let r2 = r.clone() * &r;
        let r3 = r2.clone() * &r;
        let mut out = Self::constant(r, d);
        for i in 0..d {
            out.g[i] = -(self.g[i].clone() * &r2);
            for j in 0..d {
                let k = i * d + j;
                out.h[k] = S::from_i64(2) * &self.g[i] * &self.g[j] * &r3 - self.h[k].clone() * &r2;
            }
        }
        out
    }
    fn div(&self, o: &Self) -> Self {
        self.mul(&o.recip())
    }
    fn scale(&self, k: &S) -> Self {
        Self {
            v: self.v.clone() * k,
            g: self.g.iter().map(|x| x.clone() * k).collect(),
            h: self.h.iter().map(|x| x.clone() * k).collect(),
        }
    }
}

/// Truncated Taylor series (coefficients f⁽ᵏ⁾/k!, k = 0..=3) in one variable.
type Series<S> = [S; 4];

fn s_mul<S: Scalar>(a: &Series<S>, b: &Series<S>) -> Series<S> {
    std::array::from_fn(|k| (0..=k).fold(S::zero(), |acc, i| acc + a[i].clone() * &b[k - i]))
}

/// a/b by the recurrence c_k = (a_k − Σ_{i<k} c_i b_{k−i}) / b_0.
fn s_div<S: Scalar>(a: &Series<S>, b: &Series<S>) -> Series<S> {
    let mut c: Series<S> = std::array::from_fn(|_| S::zero());
    for k in 0..4 {
        let mut t = a[k].clone();
        for i in 0..k {
            t -= c[i].clone() * &b[k - i];
        }
        c[k] = t / &b[0];
    }
    c
}

/// (p, dp/dθ, d²p/dθ², d³p/dθ³, 1 − p) of the tied softmax at the chart coordinate x (module
/// docs); 1 − p is evaluated on its own so that its enclosure stays positive.
pub fn p_theta_derivatives<S: Scalar>(chart: Chart, x: &S, c: &S) -> [S; 5] {
    let z = || S::zero();
    let xs: Series<S> = [x.clone(), S::one(), z(), z()];
    let cst = |v: S| -> Series<S> { [v, z(), z(), z()] };
    let x2 = s_mul(&xs, &xs);
    let add = |a: &Series<S>, b: &Series<S>| -> Series<S> {
        std::array::from_fn(|k| a[k].clone() + &b[k])
    };
    let cx2 = x2.clone().map(|v| v * c);
    let (num, other) = match chart {
        // θ² + c over (θ² + c) + ((1 − θ)² + c).
        Chart::Core => {
            let one_minus: Series<S> = [S::one() - x, -S::one(), z(), z()];
            (
                add(&x2, &cst(c.clone())),
                add(&s_mul(&one_minus, &one_minus), &cst(c.clone())),
            )
        }
        // (1 + cu²) over (1 + cu²) + ((u − 1)² + cu²).
        Chart::Tail => {
            let u_minus: Series<S> = [x.clone() - S::one(), S::one(), z(), z()];
            (
                add(&cst(S::one()), &cx2),
                add(&s_mul(&u_minus, &u_minus), &cx2),
            )
        }
    };
    // p = 1/(1 + other/num) and 1 − p = 1/(1 + num/other): both ratios are ≥ 0 in any
    // enclosure, so both probabilities are enclosed in (0, 1] (p = num/(num + other) evaluated
    // over a wide box can leave [0, 1]).
    let one = cst(S::one());
    let p = s_div(&one, &add(&one, &s_div(&other, &num)));
    let q0 = s_div(&one, &add(&one, &s_div(&num, &other)))[0].clone();
    let (p1, p2, p3) = (p[1].clone(), S::from_i64(2) * &p[2], S::from_i64(6) * &p[3]);
    match chart {
        Chart::Core => [p[0].clone(), p1, p2, p3, q0],
        Chart::Tail => {
            let u2 = x.clone() * x;
            let (u3, u4) = (u2.clone() * x, u2.clone() * &u2);
            let (u5, u6) = (u4.clone() * x, u4.clone() * &u2);
            [
                p[0].clone(),
                -(u2 * &p1),
                u4.clone() * &p2 + S::from_i64(2) * &u3 * &p1,
                -(u6 * &p3 + S::from_i64(6) * &u5 * &p2 + S::from_i64(6) * &u4 * &p1),
                q0,
            ]
        }
    }
}

/// The MDP's data in a scalar, for the hand-written enumeration.
struct Model<S> {
    mu: Vec<S>,
    /// P(s′|s, a), `None` where it is exactly 0.
    trans: Vec<Vec<Vec<Option<S>>>>,
    expert: Vec<usize>,
    groups: Vec<usize>,
    horizon: usize,
}

impl<S: Scalar> Model<S> {
    fn new(mdp: &ToyMdp) -> Self {
        let zero = <BigRational as Scalar>::zero();
        Self {
            mu: mdp.initial.iter().map(S::from_rational).collect(),
            trans: mdp
                .transition
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|d| {
                            d.iter()
                                .map(|q| (*q != zero).then(|| S::from_rational(q)))
                                .collect()
                        })
                        .collect()
                })
                .collect(),
            expert: mdp.expert.clone(),
            groups: mdp.policy.groups.clone(),
            horizon: mdp.horizon,
        }
    }
}

/// π(a|o) and ∂π(a|o)/∂θ_o, each as a jet in the d variables being differentiated.
struct PolicyJets<S> {
    /// `pi[o][a]`.
    pi: Vec<[Jet<S>; 2]>,
    /// `dpi[o][a]` = ∂π(a|o)/∂θ_o.
    dpi: Vec<[Jet<S>; 2]>,
}

impl<S: Scalar> PolicyJets<S> {
    /// From (p, p′, p″, p‴) per group; `diff` says which groups are the jet's variables (their
    /// index), the others are constants.
    fn new(derivs: &[[S; 5]], diff: &[Option<usize>], d: usize) -> Self {
        let (mut pi, mut dpi) = (vec![], vec![]);
        for (o, [p, p1, p2, p3, q]) in derivs.iter().enumerate() {
            let j = |f: &S, f1: &S, f2: &S| match diff[o] {
                Some(i) => Jet::along(f.clone(), f1.clone(), f2.clone(), i, d),
                None => Jet::constant(f.clone(), d),
            };
            let p_j = j(p, p1, p2);
            let q_j = j(q, &-p1.clone(), &-p2.clone());
            let dp_j = j(p1, p2, p3);
            let zero = Jet::constant(S::zero(), d);
            pi.push([q_j, p_j]);
            dpi.push([zero.sub(&dp_j), dp_j]);
        }
        Self { pi, dpi }
    }
}

/// One prefix τ̄ = (s_1, a_1, …, s_{T−1}) with its probability.
struct Prefix<S> {
    states: Vec<usize>,
    actions: Vec<usize>,
    prob: Jet<S>,
}

fn enumerate<S: Scalar>(m: &Model<S>, pol: &PolicyJets<S>, d: usize) -> Vec<Prefix<S>> {
    fn walk<S: Scalar>(
        m: &Model<S>,
        pol: &PolicyJets<S>,
        states: &mut Vec<usize>,
        actions: &mut Vec<usize>,
        prob: Jet<S>,
        out: &mut Vec<Prefix<S>>,
    ) {
        if states.len() == m.horizon - 1 {
            out.push(Prefix {
                states: states.clone(),
                actions: actions.clone(),
                prob,
            });
            return;
        }
        let s = *states.last().expect("non-empty");
        for a in 0..2 {
            let pa = prob.mul(&pol.pi[m.groups[s]][a]);
            for (s2, t) in m.trans[s][a].iter().enumerate() {
                if let Some(t) = t {
                    states.push(s2);
                    actions.push(a);
                    walk(m, pol, states, actions, pa.scale(t), out);
                    states.pop();
                    actions.pop();
                }
            }
        }
    }
    let mut out = vec![];
    for (s, mu) in m.mu.iter().enumerate() {
        if !mu.is_certainly_zero() {
            let mut states = vec![s];
            walk(
                m,
                pol,
                &mut states,
                &mut vec![],
                Jet::constant(mu.clone(), d),
                &mut out,
            );
        }
    }
    out
}

/// The loss l(s) = 2q², q = π(other action|s), and ∂_o l = −4q ∂π(a*|s)/∂θ_o (o = o(s)).
fn loss<S: Scalar>(m: &Model<S>, pol: &PolicyJets<S>, s: usize) -> (Jet<S>, Jet<S>) {
    let (o, star) = (m.groups[s], m.expert[s]);
    let q = &pol.pi[o][1 - star];
    let two = S::from_i64(2);
    (
        q.mul(q).scale(&two),
        q.mul(&pol.dpi[o][star]).scale(&S::from_i64(-4)),
    )
}

/// `g_o = Σ_t w_t [∂_o l_t + l_t Σ_{i<t} ψ_o(a_i|s_i)]`, ψ_o = ∂_oπ/π, with weights `w_t`
/// (all 1 for the estimator (3.15); the per-decision products otherwise).
fn estimate<S: Scalar>(
    m: &Model<S>,
    pol: &PolicyJets<S>,
    groups: usize,
    pre: &Prefix<S>,
    weights: Option<&[Jet<S>]>,
    d: usize,
) -> Vec<Jet<S>> {
    let zero = Jet::constant(S::zero(), d);
    let mut g = vec![zero.clone(); groups];
    let mut psi = vec![zero; groups];
    for (t, &s) in pre.states.iter().enumerate() {
        let (l, dl) = loss(m, pol, s);
        let o = m.groups[s];
        let mut term: Vec<Jet<S>> = psi.iter().map(|x| x.mul(&l)).collect();
        term[o] = term[o].add(&dl);
        for (gi, ti) in g.iter_mut().zip(term) {
            *gi = gi.add(&match weights {
                Some(w) => ti.mul(&w[t]),
                None => ti,
            });
        }
        if t < pre.actions.len() {
            let a = pre.actions[t];
            psi[o] = psi[o].add(&pol.dpi[o][a].div(&pol.pi[o][a]));
        }
    }
    g
}

/// The quantity a certificate bounds, as a function of the point (in chart coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// |F″| for one parameter; ‖∇²F‖_F (recorded as √ of the sum of squares) for several.
    Hessian,
    /// Var_θ g = E‖g‖² − ‖E g‖² (σ² with c = 1).
    Variance,
    /// E‖g‖² (G², σ² with c = 0).
    SecondMoment,
    /// ‖E g‖² = ‖∇F‖² (G_F²).
    GradientSq,
    /// max over prefixes of ‖g‖² (G_∞²).
    MaxEstimateSq,
    /// |∂²V/∂θ′²| at (θ, θ′), the (A4) quotient's curvature (L̃² · 2), trajectory weights.
    VisTrajectory,
    /// The same with per-decision weights.
    VisPerDecision,
}

impl Quantity {
    /// For [`Weighting`].
    pub fn vis(w: Weighting) -> Self {
        match w {
            Weighting::Trajectory => Quantity::VisTrajectory,
            Weighting::PerDecision => Quantity::VisPerDecision,
        }
    }
    fn is_abs(self, groups: usize) -> bool {
        matches!(self, Quantity::VisTrajectory | Quantity::VisPerDecision)
            || (self == Quantity::Hessian && groups == 1)
    }
    fn is_sqrt(self, groups: usize) -> bool {
        self == Quantity::Hessian && groups > 1
    }
}

/// The pieces of the quantity at a point x (chart coordinates, one per box dimension): one value,
/// or one per prefix for [`Quantity::MaxEstimateSq`] (the quantity is their maximum). Signed: the
/// caller takes |·| or √· as the quantity requires.
///
/// # Errors
/// For a policy other than the tied softmax, or a probability that is not certainly positive.
pub fn pieces<S: Scalar>(
    mdp: &ToyMdp,
    q: Quantity,
    charts: &[Chart],
    x: &[S],
) -> Result<Vec<S>, String> {
    if mdp.policy.kind != PolicyKind::TiedSoftmax || mdp.actions != 2 {
        return Err("the second route is written for the tied softmax (two actions)".into());
    }
    let c = S::from_rational(mdp.policy.c.as_ref().ok_or("no c")?);
    let m = Model::<S>::new(mdp);
    let groups = mdp.policy.group_count();
    let derivs: Vec<[S; 5]> = charts
        .iter()
        .zip(x)
        .map(|(ch, xi)| p_theta_derivatives(*ch, xi, &c))
        .collect();
    let positive = |d: &[S; 5]| d[0].is_certainly_positive() && d[4].is_certainly_positive();
    if !derivs.iter().all(positive) {
        return Err("π(a|s) not certainly positive".into());
    }
    let norm2 = |v: &[Jet<S>]| v.iter().fold(S::zero(), |a, x| a + x.v.clone() * &x.v);
    match q {
        Quantity::VisTrajectory | Quantity::VisPerDecision => {
            if groups != 1 || x.len() != 2 {
                return Err("V_IS is written for one parameter, x = (θ, θ′)".into());
            }
            let old = PolicyJets::new(&derivs[..1], &[None], 1);
            let new = PolicyJets::new(&derivs[1..], &[Some(0)], 1);
            let at_old = enumerate(&m, &old, 1);
            let at_new = enumerate(&m, &new, 1);
            let mut v = Jet::constant(S::zero(), 1);
            for (a, b) in at_old.iter().zip(&at_new) {
                if a.states != b.states || a.actions != b.actions {
                    return Err("prefix order differs".into());
                }
                // w_{1:t} = Π_{i ≤ t} π_θ(a_i|s_i)/π_θ′(a_i|s_i).
                let mut w = vec![Jet::constant(S::one(), 1)];
                for (i, &a_i) in a.actions.iter().enumerate() {
                    let o = m.groups[a.states[i]];
                    let r = old.pi[o][a_i].div(&new.pi[o][a_i]);
                    w.push(w[i].mul(&r));
                }
                let g_old = match q {
                    Quantity::VisTrajectory => {
                        estimate(&m, &old, 1, a, None, 1)[0].mul(&w[a.actions.len()])
                    }
                    _ => estimate(&m, &old, 1, a, Some(&w), 1).swap_remove(0),
                };
                let e = estimate(&m, &new, 1, b, None, 1)[0].sub(&g_old);
                v = v.add(&b.prob.mul(&e).mul(&e));
            }
            Ok(vec![v.h[0].clone()])
        }
        Quantity::Hessian => {
            if x.len() != groups {
                return Err("one coordinate per group".into());
            }
            let diff: Vec<Option<usize>> = (0..groups).map(Some).collect();
            let pol = PolicyJets::new(&derivs, &diff, groups);
            let f = enumerate(&m, &pol, groups).iter().fold(
                Jet::constant(S::zero(), groups),
                |acc, pre| {
                    let l = pre
                        .states
                        .iter()
                        .fold(Jet::constant(S::zero(), groups), |a, &s| {
                            a.add(&loss(&m, &pol, s).0)
                        });
                    acc.add(&pre.prob.mul(&l))
                },
            );
            Ok(vec![if groups == 1 {
                f.h[0].clone()
            } else {
                f.h.iter().fold(S::zero(), |a, x| a + x.clone() * x)
            }])
        }
        _ => {
            if x.len() != groups {
                return Err("one coordinate per group".into());
            }
            let pol = PolicyJets::new(&derivs, &vec![None; groups], 0);
            let mut eg = vec![S::zero(); groups];
            let (mut m2, mut each) = (S::zero(), vec![]);
            for pre in enumerate(&m, &pol, 0) {
                let g = estimate(&m, &pol, groups, &pre, None, 0);
                let n2 = norm2(&g);
                for (e, gi) in eg.iter_mut().zip(&g) {
                    *e += pre.prob.v.clone() * &gi.v;
                }
                m2 += pre.prob.v.clone() * &n2;
                each.push(n2);
            }
            let eg2 = eg.iter().fold(S::zero(), |a, x| a + x.clone() * x);
            Ok(match q {
                Quantity::Variance => vec![m2 - eg2],
                Quantity::SecondMoment => vec![m2],
                Quantity::GradientSq => vec![eg2],
                _ => each,
            })
        }
    }
}

/// The outcome of re-checking one certificate.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Recheck {
    /// Certificate boxes re-checked.
    pub boxes: usize,
    /// Pieces the corner bound was evaluated on (boxes plus bisections).
    pub pieces: usize,
    /// Distinct corners enclosed.
    pub corners: usize,
    /// The largest upper bound the second route proved on a box, in the certificate's units.
    pub max_upper: f64,
    /// Whether the boxes tile the domain exactly.
    pub tiling: bool,
    /// The first failures (at most five), empty if the certificate passed.
    pub failures: Vec<String>,
}

impl Recheck {
    /// Every box passed and the boxes tile the domain.
    pub fn passed(&self) -> bool {
        self.tiling && self.failures.is_empty()
    }
    fn fail(&mut self, msg: String) {
        if self.failures.len() < 5 {
            self.failures.push(msg);
        } else if self.failures.len() == 5 {
            self.failures.push("…".into());
        }
    }
    /// No certificate yet: the identity of [`Recheck::merge`].
    pub fn empty() -> Self {
        Self {
            max_upper: f64::NEG_INFINITY,
            tiling: true,
            ..Self::default()
        }
    }
    /// Merge another certificate's outcome (a constant with several chart regions).
    pub fn merge(&mut self, o: Recheck) {
        self.boxes += o.boxes;
        self.pieces += o.pieces;
        self.corners += o.corners;
        self.max_upper = self.max_upper.max(o.max_upper);
        self.tiling &= o.tiling;
        for f in o.failures {
            self.fail(f);
        }
    }
}

/// Corner enclosures, keyed by the corner's coordinates and the chart each is evaluated in.
type Corners = HashMap<Vec<(u64, bool)>, Result<Vec<Interval>, String>>;

fn point(x: f64) -> Interval {
    Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE)
}

struct Ctx<'a> {
    mdp: &'a ToyMdp,
    q: Quantity,
    charts: &'a [Chart],
    groups: usize,
    cache: Corners,
}

/// One side of a piece in the coordinate it is evaluated in: the chart, the enclosure of the
/// coordinate's range, and the enclosures of its lower and upper ends (with the θ-value each
/// comes from, for the cache).
struct Side {
    chart: Chart,
    range: Interval,
    ends: [(Interval, f64); 2],
}

impl Ctx<'_> {
    /// A core-chart side with |θ| ≥ R on all of it is evaluated in the tail coordinate u = 1/θ,
    /// where every quantity is smooth and small; the same function, so the same supremum. The
    /// end θ = a maps to u = 1/a, the upper end of the u-range on either side of 0.
    fn side(&self, i: usize, [l, h]: [f64; 2]) -> Side {
        let far = self.charts[i] == Chart::Core && (l >= CORE_RADIUS || h <= -CORE_RADIUS);
        if far {
            let one = point(1.0);
            let (lo, hi) = (one / point(h), one / point(l));
            Side {
                chart: Chart::Tail,
                range: lo.convex_hull(hi),
                ends: [(lo, h), (hi, l)],
            }
        } else {
            Side {
                chart: self.charts[i],
                range: Interval::try_from((l, h)).unwrap_or(Interval::ENTIRE),
                ends: [(point(l), l), (point(h), h)],
            }
        }
    }

    fn corner(&mut self, charts: &[Chart], x: &[(Interval, f64)]) -> Result<Vec<Interval>, String> {
        let key: Vec<(u64, bool)> = x
            .iter()
            .zip(charts)
            .map(|((_, t), c)| (t.to_bits(), *c == Chart::Tail))
            .collect();
        if let Some(v) = self.cache.get(&key) {
            return v.clone();
        }
        let xs: Vec<Interval> = x.iter().map(|(v, _)| *v).collect();
        let v = pieces(self.mdp, self.q, charts, &xs);
        self.cache.insert(key, v.clone());
        v
    }

    /// A rigorous upper bound of sup_X (the quantity) from the corners and the gradient
    /// enclosure, in the quantity's own units (|·|, the max, or √·), and the enclosures of the
    /// quantity at the corners.
    fn box_bound(&mut self, b: &[[f64; 2]]) -> Result<(f64, Vec<Interval>), String> {
        let n = b.len();
        let sides: Vec<Side> = b
            .iter()
            .enumerate()
            .map(|(i, s)| self.side(i, *s))
            .collect();
        let charts: Vec<Chart> = sides.iter().map(|s| s.chart).collect();
        let vars: Vec<Dual<Interval>> = sides
            .iter()
            .enumerate()
            .map(|(i, s)| Dual::variable(s.range, i, n))
            .collect();
        let mut corner_vals: Vec<Vec<Interval>> = vec![];
        let mut corner_sides: Vec<Vec<bool>> = vec![];
        for mask in 0..(1usize << n) {
            let upper: Vec<bool> = (0..n).map(|i| mask >> i & 1 == 1).collect();
            let x: Vec<(Interval, f64)> = (0..n)
                .map(|i| sides[i].ends[usize::from(upper[i])])
                .collect();
            corner_vals.push(self.corner(&charts, &x)?);
            corner_sides.push(upper);
        }
        // An enclosure that cannot be formed on X (a probability not certainly positive on a wide
        // box) bounds nothing: the gradient is unbounded and X is bisected.
        let grads: Vec<Vec<Interval>> = match pieces(self.mdp, self.q, &charts, &vars) {
            Ok(p) => p.into_iter().map(|p| p.gradient_padded(n)).collect(),
            Err(_) => vec![vec![Interval::ENTIRE; n]; corner_vals[0].len()],
        };
        let widths: Vec<Interval> = sides.iter().map(|s| s.ends[1].0 - s.ends[0].0).collect();
        let abs = self.q.is_abs(self.groups);
        let bound_piece = |k: usize, sign: f64| -> f64 {
            let mut best = f64::INFINITY;
            for (vals, upper) in corner_vals.iter().zip(&corner_sides) {
                let mut u = vals[k] * point(sign);
                for i in 0..n {
                    let d = grads[k][i] * point(sign);
                    // The slope towards the inside of X from this corner, and its positive part
                    // times the width: max of ∂_ih·(x_i − c_i) over the side.
                    let slope = if upper[i] { -d } else { d };
                    let pos = if slope.is_empty() || slope.sup().is_nan() {
                        Interval::ENTIRE
                    } else {
                        point(slope.sup().max(0.0))
                    };
                    u += pos * point(widths[i].sup());
                }
                best = best.min(if u.is_empty() { f64::INFINITY } else { u.sup() });
            }
            best
        };
        let mut sup = f64::NEG_INFINITY;
        for k in 0..grads.len() {
            sup = sup.max(bound_piece(k, 1.0));
            if abs {
                sup = sup.max(bound_piece(k, -1.0));
            }
        }
        if self.q.is_sqrt(self.groups) {
            sup = sup.max(0.0).sqrt().next_up();
        }
        // The quantity at each corner: |·| and the max over pieces, as enclosures.
        let at_corners: Vec<Interval> = corner_vals
            .iter()
            .map(|vals| {
                let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
                for v in vals {
                    let v = if abs { v.abs() } else { *v };
                    lo = lo.max(v.inf());
                    hi = hi.max(v.sup());
                }
                Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE)
            })
            .collect();
        Ok((sup, at_corners))
    }

    /// Prove sup over the box ≤ `target`, bisecting at most `depth` more times. Returns the
    /// largest bound proved and the number of pieces used, or the bound that failed.
    fn prove(&mut self, b: &[[f64; 2]], target: f64, depth: u32) -> Result<(f64, usize), String> {
        let (sup, _) = self.box_bound(b)?;
        if sup <= target {
            return Ok((sup, 1));
        }
        let (dim, _) = b
            .iter()
            .enumerate()
            .map(|(i, [l, h])| (i, h - l))
            .max_by(|a, c| a.1.total_cmp(&c.1))
            .expect("non-empty");
        let [l, h] = b[dim];
        let m = l + (h - l) / 2.0;
        if depth == 0 || !(l < m && m < h) {
            return Err(format!("the second route bounds it by {sup} only"));
        }
        let (mut best, mut count) = (f64::NEG_INFINITY, 1);
        for half in [[l, m], [m, h]] {
            let mut c = b.to_vec();
            c[dim] = half;
            let (s, k) = self.prove(&c, target, depth - 1)?;
            best = best.max(s);
            count += k;
        }
        Ok((best, count))
    }
}

/// Boxes per region the quick profile re-checks (besides those within 1 % of the bound).
pub const QUICK_SAMPLE: usize = 200;

/// The coverage of a profile: every box at full size, a seeded sample in the quick profile (every
/// box of every L̃ certificate takes minutes on two cores).
pub fn coverage_for(full: bool) -> Coverage {
    if full {
        Coverage::All
    } else {
        Coverage::Sample(QUICK_SAMPLE)
    }
}

/// Which boxes to re-check: all, or a seeded random sample of a given size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Coverage {
    /// Every box.
    All,
    /// This many boxes drawn without replacement (seeded), plus every box whose recorded bound is
    /// within 1 % of the certified bound (the ones the constant rests on).
    Sample(usize),
}

/// Re-check one certificate of `q` on `domain` in `charts` (module docs). `certified` is the
/// constant's bound in the certificate's units (≥ every box's recorded bound).
pub fn recheck(
    mdp: &ToyMdp,
    q: Quantity,
    charts: &[Chart],
    domain: &[[f64; 2]],
    cert: &SupBound,
    certified: f64,
    coverage: Coverage,
) -> Recheck {
    let boxes: Vec<&[[f64; 2]]> = cert
        .certificate
        .iter()
        .map(|b| b.bounds.as_slice())
        .collect();
    let mut out = Recheck::empty();
    if let Err(e) = verify_tiling(&boxes, domain) {
        out.tiling = false;
        out.fail(format!("{charts:?}: not a tiling: {e}"));
    }
    let groups = mdp.policy.group_count();
    let mut ctx = Ctx {
        mdp,
        q,
        charts,
        groups,
        cache: HashMap::new(),
    };
    let chosen: Vec<usize> = match coverage {
        Coverage::All => (0..boxes.len()).collect(),
        Coverage::Sample(n) => sample_indices(cert, certified, n),
    };
    let sqrt = q.is_sqrt(groups);
    for i in chosen {
        let b = &cert.certificate[i];
        out.boxes += 1;
        let [lo, hi] = b.enclosure;
        if hi.is_nan() || hi > certified {
            out.fail(format!(
                "box {:?}: recorded {hi} > certified {certified}",
                b.bounds
            ));
            continue;
        }
        // The quantity at every corner must lie in the recorded enclosure: a corner enclosure
        // entirely outside it is a certain violation. For a recorded √h compare squares.
        // (For ‖∇²F‖_F the first route records ‖mag H‖_F on both ends, an upper bound only, so
        // only the upper end is compared.)
        let (rl, rh) = if sqrt {
            (point(f64::MIN), point(hi).sqr())
        } else {
            (point(lo), point(hi))
        };
        let inside = |v: &Interval| !(v.inf() > rh.sup() || v.sup() < rl.inf());
        // The box's own bound, re-proved to within the certificate's stated precision (its
        // upper bound minus the value it attained) but at most 1 % of the certified bound, never
        // beyond the certified bound.
        let gap = if (cert.upper - cert.lower).is_nan() {
            0.0
        } else {
            (cert.upper - cert.lower).max(0.0)
        };
        let slack = gap
            .min(BOX_SHARE * certified.abs())
            .max(BOX_SLACK * hi.abs());
        let target = (hi + slack).min(certified);
        match ctx.box_bound(&b.bounds) {
            Err(e) => out.fail(format!("box {:?}: {e}", b.bounds)),
            Ok((_, exact)) => {
                if let Some(v) = exact.iter().find(|v| !inside(v)) {
                    out.fail(format!(
                        "box {:?}: the value at a corner, in [{}, {}], is outside the recorded [{lo}, {hi}]",
                        b.bounds,
                        v.inf(),
                        v.sup()
                    ));
                    continue;
                }
                match ctx.prove(&b.bounds, target, MAX_DEPTH) {
                    Ok((s, k)) => {
                        out.pieces += k;
                        out.max_upper = out.max_upper.max(s);
                    }
                    Err(e) => out.fail(format!(
                        "box {:?} of {charts:?}: recorded bound {hi} not proved: {e}",
                        b.bounds
                    )),
                }
            }
        }
    }
    out.corners = ctx.cache.len();
    out
}

/// Indices of a seeded sample of `n` boxes plus every box within 1 % of the certified bound.
fn sample_indices(cert: &SupBound, certified: f64, n: usize) -> Vec<usize> {
    use rand::SeedableRng;
    use rand::seq::index::sample;
    let len = cert.certificate.len();
    let mut rng = rand::rngs::StdRng::seed_from_u64(0x5ec0_4d20);
    let mut idx: Vec<usize> = sample(&mut rng, len, n.min(len)).into_vec();
    let near = certified - 0.01 * certified.abs();
    idx.extend((0..len).filter(|&i| cert.certificate[i].enclosure[1] >= near));
    idx.sort_unstable();
    idx.dedup();
    idx
}
