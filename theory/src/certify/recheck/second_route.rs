//! The second route's evaluator: the tied softmax (P2′), its θ-derivatives, the prefix
//! enumeration, the Brier loss and the estimator (3.15), written again from math.md §§1.1–1.4
//! by hand, and the [`Quantity`] each certificate bounds as a function of the point.

use super::jet::{Jet, Series, s_div, s_mul};
use crate::record::certificate::Chart;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp};
use serde::{Deserialize, Serialize};

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

/// The per-state and per-decision terms of the estimator under one policy: they depend on the
/// state (or the group and action) only, so they are formed once per point and shared by every
/// prefix (each is the same computation as at its first use, so the enclosures are unchanged).
struct Terms<S> {
    /// `loss[s]` = (l(s), ∂l(s)), as [`loss`].
    loss: Vec<(Jet<S>, Jet<S>)>,
    /// `psi[o][a]` = ψ_o(a|o) = ∂_oπ(a|o)/π(a|o).
    psi: Vec<[Jet<S>; 2]>,
}

impl<S: Scalar> Terms<S> {
    fn new(m: &Model<S>, pol: &PolicyJets<S>) -> Self {
        Self {
            loss: (0..m.trans.len()).map(|s| loss(m, pol, s)).collect(),
            psi: pol
                .pi
                .iter()
                .zip(&pol.dpi)
                .map(|(pi, dpi)| [dpi[0].div(&pi[0]), dpi[1].div(&pi[1])])
                .collect(),
        }
    }
}

/// `g_o = Σ_t w_t [∂_o l_t + l_t Σ_{i<t} ψ_o(a_i|s_i)]`, ψ_o = ∂_oπ/π, with weights `w_t`
/// (all 1 for the estimator (3.15); the per-decision products otherwise).
fn estimate<S: Scalar>(
    m: &Model<S>,
    terms: &Terms<S>,
    groups: usize,
    pre: &Prefix<S>,
    weights: Option<&[Jet<S>]>,
    d: usize,
) -> Vec<Jet<S>> {
    let zero = Jet::constant(S::zero(), d);
    let mut g = vec![zero.clone(); groups];
    let mut psi = vec![zero; groups];
    for (t, &s) in pre.states.iter().enumerate() {
        let (l, dl) = &terms.loss[s];
        let o = m.groups[s];
        let mut term: Vec<Jet<S>> = psi.iter().map(|x| x.mul(l)).collect();
        term[o] = term[o].add(dl);
        for (gi, ti) in g.iter_mut().zip(term) {
            *gi = gi.add(&match weights {
                Some(w) => ti.mul(&w[t]),
                None => ti,
            });
        }
        if t < pre.actions.len() {
            let a = pre.actions[t];
            psi[o] = psi[o].add(&terms.psi[o][a]);
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
    /// Var_θ g_b of the baselined estimator `g_b = g − b Σ_i ψ_i` with one constant
    /// b = `numerator/denominator` for every decision (docs/math.md §9).
    BaselinedVariance {
        /// b's numerator.
        numerator: i64,
        /// b's denominator (> 0).
        denominator: i64,
    },
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
    /// |∂²V_b/∂θ′²| for the baselined estimator `g_b = g − b Σ_i ψ_i`, b =
    /// `numerator/denominator` for every decision, with the trajectory weight on `g_b(θ, τ̄)`:
    /// `V_b(θ, θ′) = E_{τ∼θ′}(g_b(θ′, τ) − w g_b(θ, τ))²` (docs/math.md §9).
    VisTrajectoryBaselined {
        /// b's numerator.
        numerator: i64,
        /// b's denominator (> 0).
        denominator: i64,
    },
}

impl Quantity {
    /// For [`Weighting`].
    pub fn vis(w: Weighting) -> Self {
        match w {
            Weighting::Trajectory => Quantity::VisTrajectory,
            Weighting::PerDecision => Quantity::VisPerDecision,
        }
    }
    pub(super) fn is_abs(self, groups: usize) -> bool {
        matches!(
            self,
            Quantity::VisTrajectory
                | Quantity::VisPerDecision
                | Quantity::VisTrajectoryBaselined { .. }
        ) || (self == Quantity::Hessian && groups == 1)
    }
    pub(super) fn is_sqrt(self, groups: usize) -> bool {
        self == Quantity::Hessian && groups > 1
    }
}

/// The constant b of a baselined quantity as a jet in `d` variables (`None` for the others).
fn baseline_jet<S: Scalar>(q: Quantity, d: usize) -> Result<Option<Jet<S>>, String> {
    match q {
        Quantity::BaselinedVariance {
            numerator,
            denominator,
        }
        | Quantity::VisTrajectoryBaselined {
            numerator,
            denominator,
        } => {
            if denominator <= 0 {
                return Err("a baseline's denominator must be positive".into());
            }
            Ok(Some(
                Jet::constant(S::from_i64(numerator), d)
                    .div(&Jet::constant(S::from_i64(denominator), d)),
            ))
        }
        _ => Ok(None),
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
        Quantity::VisTrajectory
        | Quantity::VisPerDecision
        | Quantity::VisTrajectoryBaselined { .. } => {
            if groups != 1 || x.len() != 2 {
                return Err("V_IS is written for one parameter, x = (θ, θ′)".into());
            }
            let old = PolicyJets::new(&derivs[..1], &[None], 1);
            let new = PolicyJets::new(&derivs[1..], &[Some(0)], 1);
            let at_old = enumerate(&m, &old, 1);
            let at_new = enumerate(&m, &new, 1);
            let baseline = baseline_jet::<S>(q, 1)?;
            // Σ_i ψ(a_i|s_i) of a prefix under a policy, every action of the prefix a scored
            // decision.
            let score_sum = |pol: &PolicyJets<S>, pre: &Prefix<S>| {
                pre.actions
                    .iter()
                    .enumerate()
                    .fold(Jet::constant(S::zero(), 1), |acc, (t, &a)| {
                        let o = m.groups[pre.states[t]];
                        acc.add(&pol.dpi[o][a].div(&pol.pi[o][a]))
                    })
            };
            let (old_terms, new_terms) = (Terms::new(&m, &old), Terms::new(&m, &new));
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
                        estimate(&m, &old_terms, 1, a, None, 1)[0].mul(&w[a.actions.len()])
                    }
                    // w · g_b(θ, τ̄), g_b = g − b Σ_i ψ_i: the weight multiplies the baselined
                    // estimate (docs/math.md §9).
                    Quantity::VisTrajectoryBaselined { .. } => {
                        let b_old = score_sum(&old, a).mul(baseline.as_ref().expect("a baseline"));
                        estimate(&m, &old_terms, 1, a, None, 1)[0]
                            .sub(&b_old)
                            .mul(&w[a.actions.len()])
                    }
                    _ => estimate(&m, &old_terms, 1, a, Some(&w), 1).swap_remove(0),
                };
                let mut g_new = estimate(&m, &new_terms, 1, b, None, 1).swap_remove(0);
                if let Some(base) = &baseline {
                    g_new = g_new.sub(&score_sum(&new, b).mul(base));
                }
                let e = g_new.sub(&g_old);
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
            let terms = Terms::new(&m, &pol);
            let f = enumerate(&m, &pol, groups).iter().fold(
                Jet::constant(S::zero(), groups),
                |acc, pre| {
                    let l = pre
                        .states
                        .iter()
                        .fold(Jet::constant(S::zero(), groups), |a, &s| {
                            a.add(&terms.loss[s].0)
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
            let baseline = baseline_jet::<S>(q, 0)?;
            let mut eg = vec![S::zero(); groups];
            let (mut m2, mut each) = (S::zero(), vec![]);
            let terms = Terms::new(&m, &pol);
            for pre in enumerate(&m, &pol, 0) {
                let mut g = estimate(&m, &terms, groups, &pre, None, 0);
                if let Some(b) = &baseline {
                    // g_b = g − b Σ_i ψ(a_i|s_i), every action of the prefix a scored decision.
                    for (t, &a) in pre.actions.iter().enumerate() {
                        let o = m.groups[pre.states[t]];
                        g[o] = g[o].sub(&terms.psi[o][a].mul(b));
                    }
                }
                let n2 = norm2(&g);
                for (e, gi) in eg.iter_mut().zip(&g) {
                    *e += pre.prob.v.clone() * &gi.v;
                }
                m2 += pre.prob.v.clone() * &n2;
                each.push(n2);
            }
            let eg2 = eg.iter().fold(S::zero(), |a, x| a + x.clone() * x);
            Ok(match q {
                Quantity::Variance | Quantity::BaselinedVariance { .. } => vec![m2 - eg2],
                Quantity::SecondMoment => vec![m2],
                Quantity::GradientSq => vec![eg2],
                _ => each,
            })
        }
    }
}
