//! Constants of the bounds for toy MDPs, each computed exactly or bounded rigorously, and labelled
//! so (math.md §7.1).
//!
//! * B_F = F(θ₁) − inf F: exact in rationals (X2), with inf F exact when known, else 0 (F ≥ 0).
//! * L_F ≥ sup ‖∇²F‖₂ over a box: interval branch-and-bound on the forward DP (X2) run in nested
//!   duals over intervals, `Dual<Dual<Interval>>` (‖H‖₂ ≤ ‖mag H‖_F).
//! * σ²(c) ≥ sup [E‖g‖² − c‖∇F‖²], G² ≥ sup E‖g‖², G_F ≥ sup ‖∇F‖, G_∞ ≥ sup_{θ,τ} ‖g(θ, τ)‖:
//!   branch-and-bound on the enumeration (X1) in intervals.
//!
//! Box bounds are only valid for a box that provably contains every iterate; [`sgd_iterate_box`]
//! gives one from an a.s. bound on the estimator.

use crate::certify::bnb::{BnbError, sup_bound};
use crate::certify::charts::SecondOrder;
use crate::certify::recheck::{Coverage, Quantity, Recheck, recheck};
use crate::certify::v_is::{Curvature, ThirdOrder};
use crate::record::certificate::Chart;
use crate::record::constant::Constant;
use ilopt::exact::baseline::baselined_moments;
use ilopt::exact::enumerate::{moments, prefixes};
use ilopt::exact::forward::forward;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};

/// `√max(x, 0)`, for attained values (lower bounds: no upward rounding).
pub(crate) fn attained_sqrt(x: f64) -> f64 {
    x.max(0.0).sqrt()
}

fn interval_theta(b: &[Interval]) -> Vec<Interval> {
    b.to_vec()
}

fn sqrt_up(x: f64) -> f64 {
    // sqrt is correctly rounded; one ulp up makes it an upper bound of the exact root.
    x.max(0.0).sqrt().next_up()
}

/// `‖mag H‖_F` of an interval matrix (an upper bound on the spectral norm of every member).
fn frobenius_mag(h: &[Vec<Interval>]) -> Interval {
    let mut s = Interval::try_from((0.0, 0.0)).expect("0");
    for row in h {
        for x in row {
            let m = x.mag();
            let m = Interval::try_from((m, m)).unwrap_or(Interval::ENTIRE);
            s += m * m;
        }
    }
    Interval::sqrt(s)
}

/// B_F = F(θ₁) − F_inf exactly (F_inf = 0 when not given: F ≥ 0 always).
///
/// # Errors
/// If F cannot be evaluated at θ₁.
pub fn b_f(
    mdp: &ToyMdp,
    theta1: &[BigRational],
    f_inf: Option<&BigRational>,
) -> Result<Constant, String> {
    let f = forward(&ToyProblem::<BigRational>::new(mdp), theta1)
        .map_err(|e| e.to_string())?
        .objective;
    let inf = f_inf.cloned().unwrap_or_else(<BigRational as Scalar>::zero);
    let how = match f_inf {
        Some(q) => format!("F(θ₁) − inf F with inf F = {q} exact"),
        None => "F(θ₁) − 0 (F ≥ 0)".into(),
    };
    Ok(Constant::exact("B_F", &(f - inf), &how))
}

/// L_F ≥ sup_{θ ∈ domain} ‖∇²F(θ)‖₂ (X2 in `Dual<Dual<Interval>>`).
///
/// # Errors
/// [`BnbError`] if the engine fails on a box.
pub fn l_f(
    mdp: &ToyMdp,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    let p = ToyProblem::<Dual<Dual<Interval>>>::new(mdp);
    let d = domain.len();
    let f = |b: &[Interval]| -> Result<Interval, String> {
        let inner = Dual::variables(&interval_theta(b));
        let theta: Vec<Dual<Dual<Interval>>> = inner
            .into_iter()
            .enumerate()
            .map(|(i, x)| Dual::variable(x, i, d))
            .collect();
        let obj = forward(&p, &theta).map_err(|e| e.to_string())?.objective;
        let h: Vec<Vec<Interval>> = obj
            .gradient_padded(d)
            .iter()
            .map(|gi| gi.gradient_padded(d))
            .collect();
        Ok(if d == 1 {
            h[0][0].abs()
        } else {
            frobenius_mag(&h)
        })
    };
    let r = sup_bound(f, domain, tol, max_boxes)?;
    let v = r.upper;
    let how = format!(
        "sup ‖∇²F‖ over {domain:?} by interval branch-and-bound ({} boxes)",
        r.certificate.len()
    );
    Ok(Constant::rigorous("L_F", r, v, |s| s, how))
}

/// σ²(c) ≥ sup_{θ ∈ domain} [E‖g‖² − c‖∇F‖²] (c = 1: sup Var; c = 0: sup E‖g‖² = G²).
///
/// # Errors
/// [`BnbError`] if the engine fails on a box.
pub fn sigma2(
    mdp: &ToyMdp,
    c: &BigRational,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    let p = ToyProblem::<Interval>::new(mdp);
    let ci = Interval::from_rational(c);
    let f = |b: &[Interval]| -> Result<Interval, String> {
        let m = moments(&p, b).map_err(|e| e.to_string())?;
        let g2 = m
            .expected_estimate
            .iter()
            .fold(Interval::zero(), |a, x| a + x * x);
        Ok(m.second_moment - ci * g2)
    };
    let r = sup_bound(f, domain, tol, max_boxes)?;
    let v = r.upper.max(0.0);
    let name = if c.is_certainly_zero() { "G²" } else { "σ²" };
    let how = format!(
        "sup (E‖g‖² − {c}·‖∇F‖²) over {domain:?} by interval branch-and-bound ({} boxes)",
        r.certificate.len()
    );
    Ok(Constant::rigorous(name, r, v, |s| s.max(0.0), how))
}

/// σ²_b ≥ sup_{θ ∈ domain} Var_θ g_b for the baselined estimator `g_b = g − b Σ_i ψ_i` with one
/// constant b for every decision (docs/math.md §9): `E‖g_b‖² − ‖E g_b‖²` by enumeration (X1) in
/// intervals, `E g_b = ∇F`.
///
/// # Errors
/// [`BnbError`] if the engine fails on a box.
pub fn sigma2_baselined(
    mdp: &ToyMdp,
    b: &BigRational,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    let p = ToyProblem::<Interval>::new(mdp);
    let bi = [Interval::from_rational(b)];
    let f = |x: &[Interval]| -> Result<Interval, String> {
        let m = baselined_moments(&p, x, &bi).map_err(|e| e.to_string())?;
        let g2 = m
            .expected_estimate
            .iter()
            .fold(Interval::zero(), |a, x| a + x * x);
        Ok(m.second_moment - g2)
    };
    let r = sup_bound(f, domain, tol, max_boxes)?;
    let v = r.upper.max(0.0);
    let how = format!(
        "sup Var g_b, b = {b} for every decision, over {domain:?} by interval branch-and-bound ({} boxes)",
        r.certificate.len()
    );
    Ok(Constant::rigorous("σ²_b", r, v, |s| s.max(0.0), how))
}

/// Re-check the certificate of a [`sigma2_baselined`] constant by the second route
/// ([`crate::certify::recheck`]); b must be a ratio of 64-bit integers.
pub fn recheck_sigma2_baselined(
    mdp: &ToyMdp,
    b: &BigRational,
    constant: &Constant,
    domain: &[[f64; 2]],
    coverage: Coverage,
) -> Recheck {
    use num_traits::ToPrimitive;
    let mut out = Recheck::empty();
    let (Some(numerator), Some(denominator)) = (b.numer().to_i64(), b.denom().to_i64()) else {
        out.failures
            .push(format!("b = {b} is not a ratio of 64-bit integers"));
        return out;
    };
    let Some(cert) = &constant.certificate else {
        out.failures
            .push(format!("{}: no certificate", constant.name));
        return out;
    };
    let q = Quantity::BaselinedVariance {
        numerator,
        denominator,
    };
    let charts = vec![Chart::Core; domain.len()];
    let mut r = recheck(mdp, q, &charts, domain, cert, cert.upper, coverage);
    if constant
        .value
        .partial_cmp(&r.max_upper.max(0.0))
        .is_none_or(|o| o.is_lt())
    {
        r.failures.push(format!(
            "{} = {} < the re-checked bound {}",
            constant.name, constant.value, r.max_upper
        ));
    }
    r
}

/// G_F ≥ sup_{θ ∈ domain} ‖∇F(θ)‖ (X2 in intervals).
///
/// # Errors
/// [`BnbError`] if the engine fails on a box.
pub fn gradient_norm(
    mdp: &ToyMdp,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    let p = ToyProblem::<Interval>::new(mdp);
    let f = |b: &[Interval]| -> Result<Interval, String> {
        let g = forward(&p, b).map_err(|e| e.to_string())?.gradient;
        Ok(g.iter().fold(Interval::zero(), |a, x| a + x * x))
    };
    let r = sup_bound(f, domain, tol, max_boxes)?;
    let v = sqrt_up(r.upper);
    let how = format!(
        "√ sup ‖∇F‖² over {domain:?} by interval branch-and-bound ({} boxes)",
        r.certificate.len()
    );
    Ok(Constant::rigorous("G_F", r, v, attained_sqrt, how))
}

/// G_∞ ≥ sup_{θ ∈ domain, τ̄} ‖g(θ, τ̄)‖: the almost-sure bound of the estimator.
///
/// # Errors
/// [`BnbError`] if the engine fails on a box.
pub fn estimator_bound(
    mdp: &ToyMdp,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    let p = ToyProblem::<Interval>::new(mdp);
    let f = |b: &[Interval]| -> Result<Interval, String> {
        let pre = prefixes(&p, b).map_err(|e| e.to_string())?;
        // The max over prefixes as an interval, [max of lower ends, max of upper ends] (a hull
        // with 0 would pin the lower end at 0, so the branch-and-bound could never stop early).
        let (mut lo, mut hi) = (0.0f64, 0.0f64);
        for x in pre {
            let n = x.estimate.iter().fold(Interval::zero(), |a, v| a + v * v);
            lo = lo.max(n.inf());
            hi = hi.max(n.sup());
        }
        Interval::try_from((lo, hi)).map_err(|e| format!("{e:?}"))
    };
    let r = sup_bound(f, domain, tol, max_boxes)?;
    let v = sqrt_up(r.upper);
    let how = format!(
        "√ max over prefixes of sup ‖g‖² over {domain:?} ({} boxes)",
        r.certificate.len()
    );
    Ok(Constant::rigorous("G_∞", r, v, attained_sqrt, how))
}

/// A box that provably contains every SGD iterate: |θ_{k+1} − θ_k| ≤ η‖g‖ ≤ ηG_∞ a.s., so after
/// K steps from θ₁ every coordinate stays within K·η·G_∞ (rounded up) of θ₁.
pub fn sgd_iterate_box(theta1: &[f64], eta: f64, k: u64, g_inf: f64) -> Vec<[f64; 2]> {
    let r = (k as f64 * eta * g_inf) * (1.0 + 1e-12);
    theta1.iter().map(|t| [t - r, t + r]).collect()
}

/// The crude closed-form a.s. bound of math.md §7.1 for P2' with the Brier loss and n = 2 actions:
/// `G_∞ ≤ √2 [(T−1)·4/√(nc) + (T−1)(T−2)·(1/√c + 1/√(nc))]` (the √2 is the tie's factor).
pub fn tied_softmax_g_inf_closed_form(horizon: usize, c: f64) -> f64 {
    let (t, n) = (horizon as f64, 2.0);
    let psi = 1.0 / c.sqrt() + 1.0 / (n * c).sqrt();
    (2f64.sqrt() * ((t - 1.0) * 4.0 / (n * c).sqrt() + (t - 1.0) * (t - 2.0) * psi)) * (1.0 + 1e-12)
}

/// L̃ of (A4) for IS-STORM with `weighting`'s importance weights, over the box `domain`²:
/// `V(θ, θ′) = E_{τ∼θ′}(g(θ′, τ) − g̃(θ → θ′, τ))²`, with the old-point term g̃ = w g(θ, τ) and
/// w = p(τ̄;θ)/p(τ̄;θ′) for the trajectory weight, or the per-decision form (math.md §4), vanishes
/// with zero θ′-derivative at θ′ = θ, so by Taylor `L̃² ≤ ½ sup_{θ,ϑ ∈ box} |∂²V/∂θ′²(θ, ϑ)|`, enclosed box by
/// box by 2-D branch-and-bound with the mean-value form of [`crate::certify::v_is`] in the core
/// chart (θ itself). With `baseline` = Some(b) (trajectory weights only) the estimator is the
/// baselined
/// `g_b = g − b Σ_i ψ_i` (one constant b for every decision, the weight on `g_b(θ, τ̄)`,
/// docs/math.md §9) and the constant is L̃_b. (This is the whole-trajectory form of (A4), the one
/// of math.md §3.2.) It holds on the box only; the STORM rows use
/// [`crate::certify::global::l_tilde`] and
/// [`crate::certify::global_baselined::l_tilde_baselined`], which bound it over all of ℝ².
///
/// # Errors
/// [`BnbError`] if the engine fails on a box, or for a policy with more than one parameter.
pub fn l_tilde(
    mdp: &ToyMdp,
    weighting: Weighting,
    baseline: Option<&BigRational>,
    domain: [f64; 2],
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    if mdp.policy.dim() != 1 {
        return Err(BnbError::Evaluation {
            bounds: vec![],
            message: "L̃ is implemented for one parameter".into(),
        });
    }
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    let p3 = ToyProblem::<ThirdOrder>::new(mdp);
    let curvature = Curvature::new(mdp, &pd, &p3, weighting, baseline);
    let f = |x: &[Interval]| -> Result<Interval, String> {
        Ok(curvature.mean_value(&[Chart::Core, Chart::Core], x)?.abs())
    };
    let r = sup_bound(f, &[domain, domain], tol, max_boxes)?;
    let v = sqrt_up(r.upper / 2.0 * (1.0 + 1e-15));
    let (name, estimator) = match (baseline, weighting) {
        (None, Weighting::Trajectory) => ("L̃", String::new()),
        (None, Weighting::PerDecision) => ("L̃_PD", " (per-decision weights)".to_string()),
        (Some(b), _) => ("L̃_b", format!(" (trajectory weight on g_b, b = {b})")),
    };
    let how = format!(
        "√(½ sup |∂²V/∂θ′²|){estimator} over {domain:?}² by 2-D interval branch-and-bound, mean-value form ({} boxes)",
        r.certificate.len()
    );
    Ok(Constant::rigorous(
        name,
        r,
        v,
        |s| attained_sqrt(s / 2.0),
        how,
    ))
}

/// A box that provably contains every IS-STORM iterate under schedule (3.43) for K steps from θ₁:
/// ‖d_1‖ ≤ G_∞ and ‖d_{k+1}‖ ≤ G_∞ + (1 − a_{k+1})(‖d_k‖ + W G_∞), W ≥ the largest importance
/// weight, so |θ_{K+1} − θ₁| ≤ Σ_k η_k ‖d_k‖ (computed with upward-rounded margins). The box grows
/// like K^{4/3} (the a.s. bound on d_k grows like 1/a_k); the STORM checks do not need it, since
/// their constants hold on all of ℝ ([`crate::certify::global`]).
pub fn storm_iterate_box(theta1: f64, l: f64, k: u64, g_inf: f64, w_max: f64) -> [f64; 2] {
    let up = |x: f64| x * (1.0 + 1e-12);
    let mut d = g_inf;
    let mut radius = 0.0;
    for i in 1..=k {
        let (eta, a) = crate::bounds::storm_schedule(l, i);
        radius = up(radius + up(eta * 1.000_001) * d);
        d = up(g_inf + (1.0 - a * 0.999_999).max(0.0) * (d + w_max * g_inf));
    }
    [theta1 - radius, theta1 + radius]
}

/// A rigorous constant, the quantity its certificate bounds, and the map from the certified
/// supremum to the constant.
type Certified<'a> = (&'a Constant, Quantity, fn(f64) -> f64);

/// The constants on a box, and the row that reports them.
#[derive(Debug, Clone)]
pub struct ToyConstants {
    /// B_F (exact).
    pub b_f: Constant,
    /// L_F (rigorous).
    pub l_f: Constant,
    /// σ² = sup Var (c = 1, rigorous).
    pub sigma2: Constant,
    /// G² = sup E‖g‖² (rigorous).
    pub g2: Constant,
    /// G_F = sup ‖∇F‖ (rigorous).
    pub g_f: Constant,
    /// G_∞ = sup ‖g‖ a.s. (rigorous).
    pub g_inf: Constant,
    /// The MDP the constants are for (the second route re-evaluates its certificates on it).
    pub mdp: ToyMdp,
}

/// Compute every constant over `domain` for `mdp` at θ₁.
///
/// # Errors
/// [`BnbError`] if an enclosure fails.
pub fn compute(
    mdp: &ToyMdp,
    theta1: &[BigRational],
    f_inf: Option<&BigRational>,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<ToyConstants, BnbError> {
    let one = BigRational::from_integer(1.into());
    let zero = BigRational::from_integer(0.into());
    Ok(ToyConstants {
        b_f: b_f(mdp, theta1, f_inf).map_err(|m| BnbError::Evaluation {
            bounds: vec![],
            message: m,
        })?,
        l_f: l_f(mdp, domain, tol, max_boxes)?,
        sigma2: sigma2(mdp, &one, domain, tol, max_boxes)?,
        g2: sigma2(mdp, &zero, domain, tol, max_boxes)?,
        g_f: gradient_norm(mdp, domain, tol, max_boxes)?,
        g_inf: estimator_bound(mdp, domain, tol, max_boxes)?,
        mdp: mdp.clone(),
    })
}

impl ToyConstants {
    /// Every constant, in report order.
    pub fn all(&self) -> Vec<Constant> {
        vec![
            self.b_f.clone(),
            self.l_f.clone(),
            self.sigma2.clone(),
            self.g2.clone(),
            self.g_f.clone(),
            self.g_inf.clone(),
        ]
    }

    /// Every rigorous constant with the quantity its certificate bounds and the map from the
    /// certified supremum to the constant.
    fn certified(&self) -> [Certified<'_>; 5] {
        fn id(s: f64) -> f64 {
            s.max(0.0)
        }
        fn root(s: f64) -> f64 {
            s.max(0.0).sqrt()
        }
        // For several parameters the L_F certificate records ‖∇²F‖_F itself (not squared).
        [
            (&self.l_f, Quantity::Hessian, id),
            (&self.sigma2, Quantity::Variance, id),
            (&self.g2, Quantity::SecondMoment, id),
            (&self.g_f, Quantity::GradientSq, root),
            (&self.g_inf, Quantity::MaxEstimateSq, root),
        ]
    }

    /// Re-evaluate every certificate on `domain` by the second route ([`crate::certify::recheck`]).
    pub fn recheck(&self, domain: &[[f64; 2]], coverage: Coverage) -> Vec<(String, Recheck)> {
        let charts = vec![Chart::Core; domain.len()];
        self.certified()
            .iter()
            .map(|(c, q, t)| {
                let mut r = match &c.certificate {
                    Some(cert) => {
                        let mut r =
                            recheck(&self.mdp, *q, &charts, domain, cert, cert.upper, coverage);
                        if c.value
                            .partial_cmp(&t(r.max_upper))
                            .is_none_or(|o| o.is_lt())
                        {
                            r.failures.push(format!(
                                "{} = {} < the re-checked bound {}",
                                c.name,
                                c.value,
                                t(r.max_upper)
                            ));
                        }
                        r
                    }
                    None => {
                        let mut r = Recheck::empty();
                        r.failures.push("no certificate".into());
                        r
                    }
                };
                r.max_in_constant_units = r.max_upper.is_finite().then(|| t(r.max_upper));
                (c.name.clone(), r)
            })
            .collect()
    }
}
