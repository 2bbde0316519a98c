//! Check 8: the constants of the bounds for the toy M1 (P2', θ₁ = 0), each exact or a rigorous
//! upper bound with its certificate (math.md §7.1). The rows state the value, the provenance and
//! the certificate size; the certificate itself is in the JSON report.

use crate::bnb::BnbError;
use crate::check::{Check, Measured, Method, Role, Verdict};
use crate::constants::{self, Constant, Provenance};
use crate::global::{Chart, recheck_summary};
use crate::recheck::{Coverage, Quantity, Recheck, recheck};
use ilopt::scalar::BigRational;
use ilopt::toy::ToyMdp;

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
        b_f: constants::b_f(mdp, theta1, f_inf).map_err(|m| BnbError::Evaluation {
            bounds: vec![],
            message: m,
        })?,
        l_f: constants::l_f(mdp, domain, tol, max_boxes)?,
        sigma2: constants::sigma2(mdp, &one, domain, tol, max_boxes)?,
        g2: constants::sigma2(mdp, &zero, domain, tol, max_boxes)?,
        g_f: constants::gradient_norm(mdp, domain, tol, max_boxes)?,
        g_inf: constants::estimator_bound(mdp, domain, tol, max_boxes)?,
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

    /// Re-evaluate every certificate on `domain` by the second route ([`crate::recheck`]).
    pub fn recheck(&self, domain: &[[f64; 2]], coverage: Coverage) -> Vec<(String, Recheck)> {
        let charts = vec![Chart::Core; domain.len()];
        self.certified()
            .iter()
            .map(|(c, q, t)| {
                let r = match &c.certificate {
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
                (c.name.clone(), r)
            })
            .collect()
    }

    /// The report row: every constant exact or rigorous, each certificate re-checked box by box
    /// by the second route.
    pub fn row(&self, name: &str, domain: &[[f64; 2]]) -> Check {
        self.row_with(name, domain, Coverage::All, "8")
    }

    /// [`ToyConstants::row`] re-checking the boxes given by `coverage`, under the row id `id`.
    pub fn row_with(&self, name: &str, domain: &[[f64; 2]], coverage: Coverage, id: &str) -> Check {
        let all = self.all();
        let verified = all.iter().all(|c| match (&c.provenance, &c.certificate) {
            (Provenance::Exact, _) => true,
            (Provenance::Rigorous, Some(cert)) => crate::bnb::verify_certificate(cert, domain),
            _ => false,
        });
        let rechecks = self.recheck(domain, coverage);
        let ok = verified && rechecks.iter().all(|(_, r)| r.passed());
        Check {
            id: id.into(),
            result: "Rigorous constants (math.md §7.1)".into(),
            claim: format!(
                "{name}: B_F exact; L_F, σ², G², G_F, G_∞ rigorous upper bounds on {domain:?}"
            ),
            assumptions: vec!["the box contains every iterate (see each check)".into()],
            details: format!(
                "{}. {}",
                all.iter()
                    .map(|c| {
                        let gap = match (&c.certificate, c.attained) {
                            (Some(b), Some(a)) => {
                                format!(" (attained ≥ {a:.6}, {} boxes)", b.certificate.len())
                            }
                            _ => String::new(),
                        };
                        format!("{} ≤ {:.6}{gap}", c.name, c.value)
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
                recheck_summary(&rechecks, coverage)
            ),
            constants: all,
            bound: None,
            measured: Some(Measured::exact(self.l_f.value)),
            tightness: None,
            method: Method::Rigorous,
            verdict: Verdict::from_bool(ok),
            erratum: None,
            role: Role::Corrected,
        }
    }
}
