//! Rows 3b.close, 3b.close.printed and 3b.cor: the bound of Theorem 3.8 assembled from the checked
//! steps, Δ₀/(DM) + E R/(DM) + σ/√T with E R ≤ K(D²/(2η) + ηTG²/2) = KDG√T at η = D/(G√T),
//! compared with the formula the table uses, then the chain (3.73) to the corollary (3.71).

use super::path::{Runs, delta0_of, g_of};
use super::{RESULT, StepSizes};
use crate::bounds::{O2ncParams, upper};
use crate::certify::box_constants::ToyConstants;
use crate::checks::proof_step::StepSlack;
use crate::inputs::{ConstantKind, TableInputs};
use crate::record::check::{Check, Method, Role};
use ilopt::scalar::{BigRational, Interval, Scalar, enclose_rational};

type Q = BigRational;

/// The relative agreement the assembled bound must have with the table's formula.
pub const AGREEMENT: f64 = 1e-12;

/// The point interval [x, x].
fn point(x: f64) -> Result<Interval, String> {
    Interval::try_from((x, x)).map_err(|e| format!("{x}: {e:?}"))
}

/// The constants of the closing algebra: exact where they are rational, enclosed where a root
/// enters.
struct Parts {
    delta0: Interval,
    delta: Interval,
    d: Interval,
    t: Interval,
    k: Interval,
    m: Interval,
    n: Interval,
    g: Interval,
    sigma: Interval,
    root_t: Interval,
}

impl Parts {
    /// The bound on E R = E R_T(u^1, …, u^K): K(D²/(2η) + ηTG²/2) with η = D/(G√T) (enclosed),
    /// from the pathwise regret (row 3b.s3) and E‖g_t‖² ≤ G² (row 3b.s3.e).
    fn expected_regret(&self) -> Interval {
        let two = Interval::from_i64(2);
        let eta = self.d / (self.g * self.root_t);
        self.k * (self.d * self.d / (two * eta) + eta * self.t * self.g * self.g / two)
    }

    /// (Δ₀ + E R)/divisor + σ/√T: the bound of (3.66) with E R bounded as above, divided by DM
    /// (corrected) or by KM (as printed).
    fn assembled(&self, divisor: Interval) -> Interval {
        (self.delta0 + self.expected_regret()) / divisor + self.sigma / self.root_t
    }
}

/// Rows 3b.close, 3b.close.printed and 3b.cor.
///
/// # Errors
/// If a constant is not finite.
pub fn rows(
    inputs: &TableInputs,
    k: &ToyConstants,
    runs: &Runs,
    sizes: &StepSizes,
) -> Result<Vec<Check>, String> {
    let p = &runs.params;
    let q = |x: f64, what: &str| Q::from_float(x).ok_or(format!("{what} is not finite"));
    let g2 = inputs.constant(ConstantKind::G2, q(k.g2.value, "G²")?);
    let sigma2 = inputs.constant(ConstantKind::Sigma2, q(k.sigma2.value, "σ²")?);
    let delta0 = delta0_of(inputs, k)?;
    let n = sizes.budget;
    let parts = Parts {
        delta0: enclose_rational(&delta0),
        delta: enclose_rational(&runs.delta),
        d: enclose_rational(&p.d),
        t: Interval::from_i64(p.t as i64),
        k: Interval::from_i64(p.k as i64),
        m: Interval::from_i64(p.m as i64),
        n: Interval::from_i64(n as i64),
        g: enclose_rational(&g2).sqrt(),
        sigma: enclose_rational(&sigma2).sqrt(),
        root_t: Interval::from_i64(p.t as i64).sqrt(),
    };
    let (g_f, sigma_f, delta0_f, delta_f) = (
        g_of(inputs, k),
        sigma2.to_f64().sqrt().next_up(),
        delta0.to_f64(),
        runs.delta.to_f64(),
    );
    let o2 = O2ncParams {
        t: p.t,
        k: p.k,
        m: p.m,
    };
    let theorem = (inputs.formulas.o2nc_theorem)(delta0_f, delta_f, g_f, sigma_f, o2);
    let agree = |x: Interval| -> Result<StepSlack, String> {
        let mut s = StepSlack::new();
        s.enclosed(x, point(theorem * (1.0 + AGREEMENT))?);
        s.enclosed(point(theorem * (1.0 - AGREEMENT))?, x);
        Ok(s)
    };
    let corrected = parts.assembled(parts.d * parts.m);
    let printed_divisor = parts.assembled(parts.k * parts.m);
    let close = agree(corrected)?;
    let close_printed = agree(printed_divisor)?;
    let consts = format!(
        "Δ₀ = {delta0_f:.6}, δ = {delta_f}, G = √G² = {g_f:.6}, σ = √σ² = {sigma_f:.6}, T = {}, K = {}, M = {}, N = {n}",
        p.t, p.k, p.m
    );
    let close_row = close
        .row(
            "3b.close",
            RESULT,
            "the bound assembled from the checked steps, Δ₀/(DM) + E R/(DM) + σ/√T with E R ≤ K(D²/(2η) + ηTG²/2) = KDG√T (η = D/(G√T)), equals the table's o2nc_theorem to a relative 10⁻¹²",
            Role::Corrected,
        )
        .constants(vec![k.b_f.clone(), k.sigma2.clone(), k.g2.clone()])
        .bound(theorem)
        .erratum("E13")
        .details(format!(
            "{}; assembled ∈ [{:.15e}, {:.15e}] (intervals for the roots) against the formula's {theorem:.15e}; E R/(DM) ∈ [{:.6e}, {:.6e}] = G/√T; {consts}",
            close.summary(),
            corrected.inf(),
            corrected.sup(),
            (parts.expected_regret() / (parts.d * parts.m)).inf(),
            (parts.expected_regret() / (parts.d * parts.m)).sup()
        ))
        .decided(Method::Rigorous, close.verdict());
    let close_printed_row = close_printed
        .row(
            "3b.close.printed",
            RESULT,
            "Thm 3.8's proof as printed, \"dividing by KDT = KM\": (Δ₀ + E R)/(KM) + σ/√T equals the theorem's bound",
            Role::Thesis,
        )
        .bound(theorem)
        .erratum("E13")
        .refuted_by_erratum()
        .details(format!(
            "{}; assembled with KM ∈ [{:.6e}, {:.6e}] against {theorem:.6e} (KDT = DM, not KM); {consts}",
            close_printed.summary(),
            printed_divisor.inf(),
            printed_divisor.sup()
        ))
        .decided(Method::Rigorous, close_printed.verdict());
    // (3.73): theorem level ≤ line 1 (M ≥ N/2, σ ≤ G) ≤ line 2 (D = δ/T, KT ≤ N) ≤ (3.71).
    let two = Interval::from_i64(2);
    let line1 = two * parts.delta0 / (parts.d * parts.n)
        + two * parts.k * parts.d * parts.g * parts.root_t / (parts.d * parts.n)
        + parts.g / parts.root_t;
    let line2 = two * parts.t * parts.delta0 / (parts.delta * parts.n)
        + Interval::from_i64(3) * parts.g / parts.root_t;
    let corollary = (inputs.formulas.o2nc_corollary)(delta0_f, delta_f, g_f, n);
    let mut chain = StepSlack::new();
    chain.exact(&sigma2, &g2);
    chain.exact(
        &Q::from_integer(n.into()),
        &Q::from_integer((2 * p.m).into()),
    );
    chain.enclosed(corrected, line1);
    chain.enclosed(line1, line2);
    chain.enclosed(line2, point(upper(corollary))?);
    let cor = chain
        .row(
            "3b.cor",
            RESULT,
            "(3.73): σ² ≤ G², N ≤ 2M, theorem level ≤ 2Δ₀/(DN) + 2KDG√T/(DN) + G/√T ≤ 2TΔ₀/(δN) + 3G/√T ≤ (3.71), the table's o2nc_corollary",
            Role::Thesis,
        )
        .constants(vec![k.b_f.clone(), k.sigma2.clone(), k.g2.clone()])
        .bound(corollary)
        .details(format!(
            "{}; points in order: σ² ≤ G², N ≤ 2M, theorem ≤ line 1 ∈ [{:.6e}, {:.6e}], line 1 ≤ line 2 ∈ [{:.6e}, {:.6e}], line 2 ≤ (3.71) = {corollary:.6e} (·(1 + 10⁻¹²)); {consts}",
            chain.summary(),
            line1.inf(),
            line1.sup(),
            line2.inf(),
            line2.sup()
        ))
        .decided(Method::Rigorous, chain.verdict());
    Ok(vec![close_row, close_printed_row, cor])
}
