//! Constants over the **whole real line** for the tied rational softmax (P2'): L_F, σ², G_F, G_∞
//! over ℝ and L̃ of (A4) over ℝ², each a branch-and-bound over the two charts of
//! [`crate::certify::charts`] with one certificate per region (math.md §7.1).
//!
//! Every certificate is re-evaluated in the table, box by box, by a second route that shares no code
//! with this module ([`crate::certify::recheck`]), and the regions' boxes must tile them exactly
//! ([`crate::certify::tiling::verify_tiling`]).
//!
//! No box has to contain the iterates: the constants hold everywhere, so they apply to STORM,
//! whose iterates have no useful a.s. box (the direction d_k has no a.s. bound that stays small as
//! a_k → 0).
//!
//! **Why (A4) needs no strip here.** The proof of Theorem S uses (A4) only at consecutive iterates
//! (θ_k, θ_{k+1}) (math.md §3.2, step 1), so a strip |θ′ − θ| ≤ δ with a certified δ ≥ η_k‖d_k‖
//! would do. For the rational softmax it is not needed: every probability lies in
//! [(3−√3)/6, (3+√3)/6] for all θ, so the prefix weight is ≤ 2 + √3 everywhere, V_IS is smooth
//! and bounded on ℝ², and its θ′-derivatives decay at infinity; hence ½ sup_{ℝ²} |∂²V_IS/∂θ′²| is
//! finite and (A4) holds as stated, for all θ, θ′. (For an exponential softmax the weights grow like
//! e^{|θ′−θ|} and a global L̃ would be infinite; there the strip route would be required.)

use crate::certify::bnb::BnbError;
use crate::certify::box_constants::{attained_sqrt, b_f};
use crate::certify::charts::{
    SecondOrder, global_constant, is_tied_1d, over_charts, parts, prefix_terms, sqrt_up, table_at,
    theta_first, theta_second, var2, verify_charts,
};
use crate::certify::recheck::{Coverage, Quantity, Recheck, recheck};
use crate::certify::v_is::{Curvature, ThirdOrder};
use crate::record::certificate::Chart;
use crate::record::constant::{Constant, Provenance};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Interval, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};

/// L_F ≥ sup_{θ ∈ ℝ} |F″(θ)|, F = Σ_τ̄ p(τ̄)L(τ̄) differentiated twice in dual numbers (X1).
///
/// # Errors
/// [`BnbError`] if an enclosure fails, or for a policy other than the one-group tied softmax.
pub fn l_f(mdp: &ToyMdp, tol: f64, max_boxes: usize) -> Result<Constant, BnbError> {
    is_tied_1d(mdp)?;
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    let f = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        let x = b[0];
        let table = table_at(mdp, &pd, charts[0], &var2(x))?;
        let obj = prefix_terms(&pd, &table)?
            .into_iter()
            .fold(SecondOrder::zero(), |a, r| a + r.prob * &r.loss);
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
    for r in prefix_terms(pi, &table)? {
        m2 += r.prob * r.estimate * r.estimate;
        eg += r.prob * r.estimate;
        let g2 = r.estimate * r.estimate;
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
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    let p3 = ToyProblem::<ThirdOrder>::new(mdp);
    let curvature = Curvature::new(mdp, &pd, &p3, weighting, None);
    let f = |charts: &[Chart], b: &[Interval]| -> Result<Interval, String> {
        Ok(curvature.mean_value(charts, b)?.abs())
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
/// [`crate::certify::recheck`], through [`GlobalConstants::recheck`]):
/// the regions cover ℝ² ([`verify_charts`]), the enclosure of |∂²V_IS/∂θ′²| is **re-evaluated** on
/// every certificate box and must not exceed the recorded one, and the constant must be
/// ≥ √(½ · the re-evaluated supremum). Returns the re-evaluated supremum.
///
/// # Errors
/// A message naming the first box or condition that fails.
pub fn recheck_l_tilde(mdp: &ToyMdp, weighting: Weighting, c: &Constant) -> Result<f64, String> {
    verify_charts(&c.charts, 2).ok_or("the regions do not cover ℝ² or a partition is invalid")?;
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    let p3 = ToyProblem::<ThirdOrder>::new(mdp);
    let curvature = Curvature::new(mdp, &pd, &p3, weighting, None);
    let mut sup = f64::NEG_INFINITY;
    for r in &c.charts {
        for b in &r.bound.certificate {
            let iv: Vec<Interval> = b
                .bounds
                .iter()
                .map(|[l, h]| Interval::try_from((*l, *h)).map_err(|e| format!("{e:?}")))
                .collect::<Result<_, _>>()?;
            let e = curvature.mean_value(&r.charts, &iv)?.abs();
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
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    let table = table_at(mdp, &pd, chart, &var2(x))?;
    let obj = prefix_terms(&pd, &table)?
        .into_iter()
        .fold(SecondOrder::zero(), |a, r| a + r.prob * &r.loss);
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
            b_f: b_f(mdp, theta1, f_inf).map_err(|m| BnbError::Evaluation {
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

    /// Re-evaluate every certificate by the second route ([`crate::certify::recheck`]): each region's
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
                all.max_in_constant_units = all.max_upper.is_finite().then(|| t(all.max_upper));
                (c.name.clone(), all)
            })
            .collect()
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
