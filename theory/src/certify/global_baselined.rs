//! The estimator-dependent constants of Theorem S (3.60\*) for the **baselined** estimator
//! `g_b = g − b Σ_i ψ_i` with one constant b for every decision (docs/math.md §9), over the whole
//! real line for the tied rational softmax (P2'):
//!
//! * σ²_b ≥ sup_{θ ∈ ℝ} Var_θ g_b, assumption (A3) for g_b;
//! * L̃_b of (A4) for IS-STORM run on g_b with the trajectory weight on the old-point estimate,
//!   `E_{τ∼θ′}(g_b(θ′, τ) − w g_b(θ, τ))² ≤ L̃_b² (θ′ − θ)²` for all θ, θ′ ∈ ℝ, from
//!   `L̃_b² ≤ ½ sup_{ℝ²} |∂²V_b/∂θ′²|` exactly as for the plain L̃ ([`crate::certify::global`]):
//!   V_b ≥ 0 vanishes at θ′ = θ (w = 1 there), so its θ′-derivative does too.
//!
//! (A2) holds for g_b unchanged: `E_θ g_b = ∇F(θ)` and `E_{τ∼θ′}[w g_b(θ, τ)] = ∇F(θ)`, because
//! `w b ψ_i` has θ′-mean `E_θ[b ψ_i] = 0`. Every other input of (3.60\*) (B_F, L_F) is F's and
//! does not depend on the estimator; the bound contains no a.s. (G-type) constant of the estimator.
//!
//! Both constants are chart branch-and-bounds with one certificate per region, like the plain
//! ones; the first route evaluates g_b with the engine's own baselined code, and
//! [`BaselinedConstants::recheck`] re-evaluates every certificate by the second route
//! ([`crate::certify::recheck`], quantities [`Quantity::BaselinedVariance`] and
//! [`Quantity::VisTrajectoryBaselined`]), which also checks that the boxes tile each region.

use crate::certify::bnb::BnbError;
use crate::certify::box_constants::attained_sqrt;
use crate::certify::charts::{
    SecondOrder, global_constant, is_tied_1d, over_charts, prefix_terms_baselined, sqrt_up,
    table_at, verify_charts,
};
use crate::certify::recheck::{Coverage, Quantity, Recheck, recheck};
use crate::certify::v_is::{Curvature, ThirdOrder};
use crate::record::certificate::Chart;
use crate::record::constant::{Constant, Provenance};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Interval, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};

/// σ²_b ≥ sup_{θ ∈ ℝ} Var_θ g_b = sup (E g_b² − (E g_b)²), by branch-and-bound over both charts.
///
/// # Errors
/// [`BnbError`] if an enclosure fails, or for a policy other than the one-group tied softmax.
pub fn sigma2_baselined(
    mdp: &ToyMdp,
    b: &BigRational,
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    is_tied_1d(mdp)?;
    let pi = ToyProblem::<Interval>::new(mdp);
    let bi = Interval::from_rational(b);
    let var = |charts: &[Chart], x: &[Interval]| -> Result<Interval, String> {
        let table = table_at(mdp, &pi, charts[0], &x[0])?;
        let (mut m2, mut eg) = (Interval::zero(), Interval::zero());
        for r in prefix_terms_baselined(&pi, &table, &bi)? {
            m2 += r.prob * r.estimate * r.estimate;
            eg += r.prob * r.estimate;
        }
        Ok(m2 - eg * eg)
    };
    Ok(global_constant(
        "σ²_b",
        over_charts(1, &var, tol, max_boxes)?,
        1,
        |s| s.max(0.0),
        |s| s.max(0.0),
        &format!("sup Var g_b, g_b = g − b Σ_i ψ_i with b = {b}"),
    ))
}

/// L̃_b of (A4) for IS-STORM on g_b (trajectory weight on `g_b(θ, τ)`), over all of ℝ²:
/// `√(½ sup |∂²V_b/∂θ′²|)` by 2-D branch-and-bound over the four chart regions (module docs).
///
/// # Errors
/// [`BnbError`] if an enclosure fails, or for a policy other than the one-group tied softmax.
pub fn l_tilde_baselined(
    mdp: &ToyMdp,
    b: &BigRational,
    tol: f64,
    max_boxes: usize,
) -> Result<Constant, BnbError> {
    is_tied_1d(mdp)?;
    let pd = ToyProblem::<SecondOrder>::new(mdp);
    let p3 = ToyProblem::<ThirdOrder>::new(mdp);
    let curvature = Curvature::new(mdp, &pd, &p3, Weighting::Trajectory, Some(b));
    let f = |charts: &[Chart], x: &[Interval]| -> Result<Interval, String> {
        Ok(curvature.mean_value(charts, x)?.abs())
    };
    Ok(global_constant(
        "L̃_b",
        over_charts(2, &f, tol, max_boxes)?,
        2,
        |s| sqrt_up(s / 2.0 * (1.0 + 1e-15)),
        |s| attained_sqrt(s / 2.0),
        &format!("√(½ sup |∂²V_b/∂θ′²|) (trajectory weight on g_b, b = {b})"),
    ))
}

/// b as a ratio of 64-bit integers (the second route's form of a baseline).
///
/// # Errors
/// If b's numerator or denominator does not fit.
pub fn ratio_of(b: &BigRational) -> Result<(i64, i64), String> {
    use num_traits::ToPrimitive;
    match (b.numer().to_i64(), b.denom().to_i64()) {
        (Some(n), Some(d)) => Ok((n, d)),
        _ => Err(format!("b = {b} is not a ratio of 64-bit integers")),
    }
}

/// A rigorous constant, the quantity its certificate bounds, its dimension (1: ℝ, 2: ℝ²) and the
/// map from the certified supremum to the constant.
type Certified<'a> = (&'a Constant, Quantity, usize, fn(f64) -> f64);

/// σ²_b and L̃_b for one constant baseline b, over ℝ (ℝ²), with the MDP they are for.
#[derive(Debug, Clone)]
pub struct BaselinedConstants {
    /// The baseline b.
    pub b: BigRational,
    /// σ²_b ≥ sup Var g_b.
    pub sigma2: Constant,
    /// L̃_b of (A4) for the trajectory-weighted g_b.
    pub l_tilde: Constant,
    /// The MDP the constants are for (the second route re-evaluates its certificates on it).
    pub mdp: ToyMdp,
}

impl BaselinedConstants {
    /// Re-evaluate both certificates by the second route ([`crate::certify::recheck`]): every
    /// region's boxes (all, or a sample) and its exact tiling; a constant passes if every region
    /// passes, its regions are the 2^d chart combinations covering ℝ^d, and the constant is ≥ the
    /// transformed largest bound the second route proved.
    pub fn recheck(&self, coverage: Coverage) -> Vec<(String, Recheck)> {
        fn id(s: f64) -> f64 {
            s.max(0.0)
        }
        fn half_root(s: f64) -> f64 {
            (s / 2.0).max(0.0).sqrt()
        }
        let (numerator, denominator) = match ratio_of(&self.b) {
            Ok(x) => x,
            Err(e) => {
                let mut r = Recheck::empty();
                r.failures.push(e);
                return vec![("b".into(), r)];
            }
        };
        let certified: [Certified<'_>; 2] = [
            (
                &self.sigma2,
                Quantity::BaselinedVariance {
                    numerator,
                    denominator,
                },
                1,
                id,
            ),
            (
                &self.l_tilde,
                Quantity::VisTrajectoryBaselined {
                    numerator,
                    denominator,
                },
                2,
                half_root,
            ),
        ];
        certified
            .iter()
            .map(|(c, q, dims, t)| {
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
                if c.provenance != Provenance::Rigorous || c.charts.len() != 1 << dims {
                    all.failures.push(format!(
                        "{}: not a rigorous constant over {} chart regions",
                        c.name,
                        1 << dims
                    ));
                } else if verify_charts(&c.charts, *dims).is_none() {
                    all.failures
                        .push(format!("{}: the regions do not cover ℝ^{dims}", c.name));
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
}
