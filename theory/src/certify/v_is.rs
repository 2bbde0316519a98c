//! The curvature of the importance-weighted variance `V_IS(θ, θ′)` of assumption (A4) in θ′,
//! `∂²V_IS/∂θ′²`, enclosed on a box of two chart coordinates (math.md §3.2, §7.1): the natural
//! interval extension and the tighter mean-value form the L̃ certificates use.

use crate::certify::charts::{
    PrefixTerms, SecondOrder, lift2, parts, prefix_terms_with, table_at, theta_second, var2,
};
use crate::record::certificate::Chart;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::toy::estimator::per_decision;
use ilopt::toy::{PolicyTable, ToyMdp, ToyProblem};
use std::cell::{Ref, RefCell};

/// `∂²V_IS/∂θ′²` at (θ in `charts[0]` at `b[0]`, θ′ in `charts[1]` at `b[1]`), where
/// `V_IS(θ, θ′) = Σ_τ̄ [p′ g′² − 2p g′ g + p²/p′ g²]` (p = p(τ̄; θ), g = g(θ, τ̄), primes at θ′)
/// is E_{τ∼θ′} (g(θ′, τ) − w g(θ, τ))² with the trajectory (prefix) weight w = p/p′.
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    // p3 is never evaluated by the natural enclosure.
    let p3 = ToyProblem::<ThirdOrder>::new(mdp);
    Curvature::new(mdp, pd, &p3, weighting, None).natural(charts, b)
}

/// The terms of one point (θ or θ′) that [`v_is_total`] needs: its policy table and its
/// prefixes' terms.
struct PointTerms<S> {
    table: PolicyTable<S>,
    terms: Vec<PrefixTerms<S>>,
}

impl<S: Scalar> PointTerms<S> {
    /// The table and prefix terms at `x` in `chart`, with the estimator `g_b` when a `baseline`
    /// is given.
    fn new(
        mdp: &ToyMdp,
        problem: &ToyProblem<S>,
        baseline: Option<&S>,
        chart: Chart,
        x: &S,
    ) -> Result<Self, String> {
        let table = table_at(mdp, problem, chart, x)?;
        let terms = prefix_terms_with(problem, &table, baseline)?;
        Ok(Self { table, terms })
    }
}

/// `V(θ, θ′) = Σ_τ̄ p(τ̄; θ′) (g(θ′, τ̄) − g̃(θ → θ′, τ̄))²` from the terms `old` at θ and `new`
/// at θ′, in any scalar. The old-point term g̃ is `w g(θ, τ̄)` with the
/// prefix weight w = p(τ̄; θ)/p(τ̄; θ′) (trajectory), or the engine's per-decision form
/// ([`per_decision`]). If `baselined`, both points' terms are of the estimator
/// `g_b = g − b Σ_i ψ_i` with the same constant b, and the trajectory weight multiplies
/// `g_b(θ, τ̄)` (docs/math.md §9; trajectory weights only). The factored square keeps enclosures
/// tight near θ′ = θ, where an expanded form would cancel.
fn v_is_total<S: Scalar>(
    weighting: Weighting,
    baselined: bool,
    old: &PointTerms<S>,
    new: &PointTerms<S>,
) -> Result<S, String> {
    let (t_old, t_new) = (&old.table, &new.table);
    if baselined && weighting != Weighting::Trajectory {
        return Err("the baselined (A4) quantity is written for trajectory weights".into());
    }
    let (at, prime) = (&old.terms, &new.terms);
    if at.len() != prime.len() {
        return Err("prefix sets differ".into());
    }
    let mut total = S::zero();
    for (a, q) in at.iter().zip(prime) {
        if a.states != q.states || a.actions != q.actions {
            return Err("prefix order differs".into());
        }
        let old = match weighting {
            Weighting::Trajectory => a.prob.clone() / &q.prob * &a.estimate,
            Weighting::PerDecision => {
                let ratios: Vec<S> = a
                    .states
                    .iter()
                    .zip(&a.actions)
                    .map(|(&s, &act)| t_old.prob(s, act).clone() / t_new.prob(s, act))
                    .collect();
                per_decision(t_old, &a.states, &a.actions, &ratios).swap_remove(0)
            }
        };
        let e = q.estimate.clone() - old;
        total += q.prob.product(&e) * &e;
    }
    Ok(total)
}

/// `max |∂²V/∂θ′²(θ, θ′)|` over every pair (θ, θ′) of `points`, evaluated in `f64` second-order
/// duals by the sum the certificates enclose ([`v_is_total`]; θ in the core chart): the (A4)
/// quantity of `weighting`'s old-point term, of the baselined estimator g_b when a `baseline` is
/// given. Each point's terms are built once. The tight instances' search ranks its candidates
/// with it ([`crate::checks::tight::search`]); the rows certify the constant by
/// [`crate::certify::box_constants::l_tilde`].
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub(crate) fn max_v_is_second_at(
    mdp: &ToyMdp,
    weighting: Weighting,
    baseline: Option<&BigRational>,
    points: &[f64],
) -> Result<f64, String> {
    type Point = Dual<Dual<f64>>;
    let p = ToyProblem::<Point>::new(mdp);
    let b = baseline.map(Point::from_rational);
    let terms = |x: Point| PointTerms::new(mdp, &p, b.as_ref(), Chart::Core, &x);
    let old: Vec<PointTerms<Point>> = points
        .iter()
        .map(|&x| terms(Dual::constant(Dual::constant(x))))
        .collect::<Result<_, _>>()?;
    let new: Vec<PointTerms<Point>> = points
        .iter()
        .map(|&y| terms(Dual::variable(Dual::variable(y, 0, 1), 0, 1)))
        .collect::<Result<_, _>>()?;
    let mut m = 0.0f64;
    for o in &old {
        for n in &new {
            let total = v_is_total(weighting, baseline.is_some(), o, n)?;
            m = m.max(total.gradient_padded(1)[0].gradient_padded(1)[0].abs());
        }
    }
    Ok(m)
}

/// A third-order jet: [`SecondOrder`] differentiated once more, in both chart coordinates.
pub(crate) type ThirdOrder = Dual<SecondOrder>;

/// The exact bits of an interval, a key under which a result computed from it is kept.
fn bits(x: &Interval) -> [u64; 2] {
    [x.inf().to_bits(), x.sup().to_bits()]
}

/// The last point's terms, kept under its chart and bits (see [`Curvature`]).
type Kept<S> = RefCell<Option<((Chart, [u64; 2]), PointTerms<S>)>>;

/// A point of a chart region (charts and the bits of the two coordinates).
type PointKey = ([Chart; 2], [[u64; 2]; 2]);

/// The enclosures of `∂²V_IS/∂θ′²` of one MDP, weighting and baseline, box after box.
///
/// Consecutive boxes of a branch-and-bound often share their θ or their θ′ interval (the two
/// halves of a split box) and a box's midpoint is often the point at which its lower bound was
/// just evaluated, so the last terms at θ and at θ′ (in each jet order) and the last point value
/// are kept under the exact bits of their inputs and reused: every result is the one computed
/// afresh, bit for bit.
pub(crate) struct Curvature<'a> {
    mdp: &'a ToyMdp,
    pd: &'a ToyProblem<SecondOrder>,
    p3: &'a ToyProblem<ThirdOrder>,
    weighting: Weighting,
    base2: Option<SecondOrder>,
    base3: Option<ThirdOrder>,
    old2: Kept<SecondOrder>,
    new2: Kept<SecondOrder>,
    old3: Kept<ThirdOrder>,
    new3: Kept<ThirdOrder>,
    at_point: RefCell<Option<(PointKey, Interval)>>,
}

impl<'a> Curvature<'a> {
    /// The curvature of the (A4) quantity of `mdp` with `weighting` weights and, when given, the
    /// baselined estimator `g_b` with the constant `baseline` (trajectory weights only).
    pub(crate) fn new(
        mdp: &'a ToyMdp,
        pd: &'a ToyProblem<SecondOrder>,
        p3: &'a ToyProblem<ThirdOrder>,
        weighting: Weighting,
        baseline: Option<&BigRational>,
    ) -> Self {
        Self {
            mdp,
            pd,
            p3,
            weighting,
            base2: baseline.map(SecondOrder::from_rational),
            base3: baseline.map(ThirdOrder::from_rational),
            old2: RefCell::new(None),
            new2: RefCell::new(None),
            old3: RefCell::new(None),
            new3: RefCell::new(None),
            at_point: RefCell::new(None),
        }
    }

    /// The terms at `x` in `chart` (the point `seed(x)`), built only if the kept ones are not
    /// for (`chart`, `x`).
    fn terms<'c, S: Scalar>(
        &self,
        kept: &'c Kept<S>,
        problem: &ToyProblem<S>,
        baseline: Option<&S>,
        chart: Chart,
        x: &Interval,
        seed: impl FnOnce(&Interval) -> S,
    ) -> Result<Ref<'c, PointTerms<S>>, String> {
        let key = (chart, bits(x));
        if kept.borrow().as_ref().is_none_or(|(k, _)| *k != key) {
            let terms = PointTerms::new(self.mdp, problem, baseline, chart, &seed(x))?;
            *kept.borrow_mut() = Some((key, terms));
        }
        Ok(Ref::map(kept.borrow(), |k| {
            &k.as_ref().expect("just kept").1
        }))
    }

    /// The natural interval extension of `∂²V_IS/∂θ′²` on the box `b` of the chart region
    /// `charts` (θ in `charts[0]` at `b[0]`, θ′ in `charts[1]` at `b[1]`).
    fn natural(&self, charts: &[Chart], b: &[Interval]) -> Result<Interval, String> {
        let base = self.base2.as_ref();
        let old = self.terms(&self.old2, self.pd, base, charts[0], &b[0], lift2)?;
        let new = self.terms(&self.new2, self.pd, base, charts[1], &b[1], |x| var2(*x))?;
        let total = v_is_total(self.weighting, base.is_some(), &old, &new)?;
        let (_, vx, vxx) = parts(&total);
        Ok(theta_second(charts[1], b[1], vx, vxx))
    }

    /// [`Curvature::natural`] at the point `m`, reusing the last point's value.
    fn at_point(&self, charts: &[Chart], m: &[Interval]) -> Result<Interval, String> {
        let key = ([charts[0], charts[1]], [bits(&m[0]), bits(&m[1])]);
        if let Some((k, v)) = *self.at_point.borrow()
            && k == key
        {
            return Ok(v);
        }
        let v = self.natural(charts, m)?;
        *self.at_point.borrow_mut() = Some((key, v));
        Ok(v)
    }

    /// Enclosures of `h = ∂²V_IS/∂θ′²` and of its chart-coordinate derivatives `∂₁h`, `∂₂h` on
    /// the box `b` (see [`v_is_second_mean_value`]).
    fn jet(&self, charts: &[Chart], b: &[Interval]) -> Result<[Interval; 3], String> {
        let base = self.base3.as_ref();
        let old_seed = |x: &Interval| Dual::variable(lift2(x), 0, 2);
        let new_seed = |x: &Interval| Dual::variable(var2(*x), 1, 2);
        let old = self.terms(&self.old3, self.p3, base, charts[0], &b[0], old_seed)?;
        let new = self.terms(&self.new3, self.p3, base, charts[1], &b[1], new_seed)?;
        let total = v_is_total(self.weighting, base.is_some(), &old, &new)?;
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

    /// The enclosure of [`v_is_second_mean_value`] on the box `b` of the region `charts`.
    ///
    /// # Errors
    /// If a table cannot be built or the prefix sets differ.
    pub(crate) fn mean_value(&self, charts: &[Chart], b: &[Interval]) -> Result<Interval, String> {
        // On a point box (the branch-and-bound's lower bounds at box midpoints) X − m = 0, so
        // the mean-value form is h(m) itself, and the natural enclosure, the value part of the
        // third-order jet, is h(m) computed by the same operations: both are the natural
        // enclosure at the point, and the third-order jet is not needed.
        if b.iter().all(|x| x.inf() == x.sup()) {
            return self.at_point(charts, b);
        }
        self.mean_value_form(charts, b)
    }

    /// The natural enclosure of `∂²V_IS/∂θ′²` on the box `b` intersected with its mean-value
    /// form (see [`v_is_second_mean_value`]).
    fn mean_value_form(&self, charts: &[Chart], b: &[Interval]) -> Result<Interval, String> {
        let [natural, d1, d2] = self.jet(charts, b)?;
        let point = |x: Interval| {
            let m = x.mid();
            Interval::try_from((m, m)).map_err(|e| format!("{e:?}"))
        };
        let m = [point(b[0])?, point(b[1])?];
        let at_mid = self.at_point(charts, &m)?;
        let mv = at_mid + d1 * (b[0] - m[0]) + d2 * (b[1] - m[1]);
        let both = natural.intersection(mv);
        Ok(if both.is_empty() { natural } else { both })
    }
}

/// Enclosures of `h = ∂²V_IS/∂θ′²` and of its chart-coordinate derivatives `∂₁h`, `∂₂h` on a box
/// (see [`v_is_second_mean_value`]).
///
/// # Errors
/// If a table cannot be built or the prefix sets differ.
pub fn v_is_second_jet(
    mdp: &ToyMdp,
    p3: &ToyProblem<ThirdOrder>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<[Interval; 3], String> {
    // pd is never evaluated by the jet.
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    Curvature::new(mdp, &pd, p3, weighting, None).jet(charts, b)
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
    pd: &ToyProblem<SecondOrder>,
    p3: &ToyProblem<ThirdOrder>,
    weighting: Weighting,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    Curvature::new(mdp, pd, p3, weighting, None).mean_value(charts, b)
}

/// [`v_is_second_mean_value`] for the baselined estimator `g_b = g − b Σ_i ψ_i` with one constant
/// b for every decision and the trajectory weight on `g_b(θ, τ̄)` (docs/math.md §9): the curvature
/// of `V_b(θ, θ′) = E_{τ∼θ′}(g_b(θ′, τ) − w g_b(θ, τ))²`, the (A4) quantity of IS-STORM run on g_b.
///
/// # Errors
/// As [`v_is_second_mean_value`].
pub fn v_is_second_mean_value_baselined(
    mdp: &ToyMdp,
    pd: &ToyProblem<SecondOrder>,
    p3: &ToyProblem<ThirdOrder>,
    baseline: &BigRational,
    charts: &[Chart],
    b: &[Interval],
) -> Result<Interval, String> {
    Curvature::new(mdp, pd, p3, Weighting::Trajectory, Some(baseline)).mean_value(charts, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::m1_tied;

    /// On a point box the shortcut of [`Curvature::mean_value`] gives the interval the
    /// full mean-value form gives there, in every chart pair, for both weightings and with a
    /// baseline.
    #[test]
    fn point_boxes_skip_the_jet_without_changing_the_enclosure() {
        let m1 = m1_tied();
        let pd = ToyProblem::<SecondOrder>::new(&m1);
        let p3 = ToyProblem::<ThirdOrder>::new(&m1);
        let b = BigRational::new(3.into(), 8.into());
        let point = |x: f64| Interval::try_from((x, x)).unwrap();
        let cases = [
            (Weighting::Trajectory, None),
            (Weighting::PerDecision, None),
            (Weighting::Trajectory, Some(&b)),
        ];
        for charts in [
            [Chart::Core, Chart::Core],
            [Chart::Core, Chart::Tail],
            [Chart::Tail, Chart::Core],
            [Chart::Tail, Chart::Tail],
        ] {
            for (x1, x2) in [(0.0, 0.0), (0.1875, -0.0625), (-0.2, 0.24), (3.5, -1.25)] {
                let at = [point(x1), point(x2)];
                for (w, base) in cases {
                    let full = Curvature::new(&m1, &pd, &p3, w, base)
                        .mean_value_form(&charts, &at)
                        .unwrap();
                    let short = Curvature::new(&m1, &pd, &p3, w, base)
                        .mean_value(&charts, &at)
                        .unwrap();
                    assert_eq!(
                        (full.inf().to_bits(), full.sup().to_bits()),
                        (short.inf().to_bits(), short.sup().to_bits()),
                        "{charts:?} at ({x1}, {x2}), {w:?}, baseline {base:?}"
                    );
                }
            }
        }
    }
}
