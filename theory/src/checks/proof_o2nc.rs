//! Check 3b, step by step: the proof of Theorem 3.8 (Cutkosky–Mehta–Orabona's online-to-non-convex
//! conversion, the thesis's (3.64)–(3.70) and the first line of (3.73); math.md §5) checked at the
//! iterates of real runs of the kit's IL-correct Algorithm 5 on a one-parameter toy.
//!
//! Each inequality or identity of the proof is evaluated exactly in ℚ at the recorded f64 iterates
//! (converted exactly), or by interval enclosures where an integral or a root enters, and reported
//! through [`StepSlack`](crate::checks::proof_step::StepSlack):
//!
//! | row | step | errata |
//! |---|---|---|
//! | `3b.s1` (`.printed`) | (3.64)/(3.65): F(θ_n) − F(θ_{n−1}) = ∫₀¹⟨∇F(θ_{n−1} + sΔ_n), Δ_n⟩ds, summed to F(θ_M) − F(θ_0) | E12 |
//! | `3b.s1.d0` | (3.66), first term: F(θ_0) − F(θ_M) ≤ Δ₀ | |
//! | `3b.s2` | Thm 3.7's premise E[g_n \| Δ_n, F_{n−1}] = ∇F(w_n) at every visited w_n (τ_n ∼ p(·; w_n)) | E11 |
//! | `3b.s3`, `3b.s3.e` | OGD: R_T(u^k) ≤ D²/(2η) + (η/2)Σ_t‖g_t‖² per block; E[‖g_t‖² \| F_{t−1}] ≤ G² | |
//! | `3b.s4` (`.printed`) | (3.69): E[‖X_t‖² \| F_{t−1}] ≤ σ², X_t = ∇F(w_t) − g_t; the printed sum of norms | E13 |
//! | `3b.s5` (`.printed`) | (3.67): Σ_n⟨g_n, Δ_n − u_n⟩ = R_T(u^1, …, u^K) with u_n = u^{⌈n/T⌉} | E13 |
//! | `3b.s6` (`.printed`) | (3.72): ‖w_n − w_{n′}‖ ≤ D(n′ − n + 1) within a block; the printed identity | E14 |
//! | `3b.close` (`.printed`), `3b.cor` | the bound assembled from the steps against the table's formulas | E13 |
//!
//! The gradient estimates, the certified constants and the bound formulas are read through
//! [`TableInputs`], so a biased oracle, a wrong constant or a wrong formula turns a verdict.

mod close;
mod path;
mod point;
mod steps;
mod telescoping;

pub use path::{RunPath, Runs, record};
pub use point::{Moments, moments, objective};

use crate::certify::box_constants::ToyConstants;
use crate::inputs::TableInputs;
use crate::record::check::Check;
use ilopt::scalar::BigRational;
use ilopt::toy::{ToyMdp, ToyProblem};

/// The result column of every row of this module.
pub const RESULT: &str = "Online-to-non-convex, proof of Thm 3.7/3.8 step by step";

/// The runs the rows are checked at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSizes {
    /// Budget N of Algorithm 5.
    pub budget: u64,
    /// Seeded runs (seeds 0, 1, …).
    pub runs: usize,
    /// Radius δ = n/d.
    pub delta: (i64, i64),
    /// Start θ₀.
    pub theta0: f64,
    /// Sub-segments of the interval Riemann sum enclosing ∫₀¹⟨∇F(θ_{n−1} + sΔ_n), Δ_n⟩ds.
    pub pieces: usize,
}

impl StepSizes {
    /// The quick size: three runs of N = 200 from θ₀ = 0 with δ = 1/10 (the radius of row 3b).
    pub const QUICK: StepSizes = StepSizes {
        budget: 200,
        runs: 3,
        delta: (1, 10),
        theta0: 0.0,
        pieces: 8,
    };
}

/// The exact values the steps are checked with: per run, F(θ_n) for n = 0..M and the oracle's
/// conditional moments at w_n for n = 1..M.
#[derive(Debug, Clone)]
pub struct Evaluated {
    /// The recorded runs.
    pub runs: Runs,
    /// `objective[r][n]` = F(θ_n) on run r.
    pub objective: Vec<Vec<BigRational>>,
    /// `moments[r][n − 1]` at w_n on run r.
    pub moments: Vec<Vec<Moments>>,
}

impl Evaluated {
    /// The runs as a row's details state them.
    pub fn describe(&self) -> String {
        let p = &self.runs.params;
        format!(
            "{} seeded runs of the kit's Algorithm 5 (IL-correct), T = {}, K = {}, M = {}, D = δ/T = {}",
            self.runs.paths.len(),
            p.t,
            p.k,
            p.m,
            p.d
        )
    }
}

/// Evaluate F along every run and the oracle's moments (through `inputs`) at every w_n.
///
/// # Errors
/// If the engine cannot evaluate a point.
pub fn evaluate(inputs: &TableInputs, mdp: &ToyMdp, runs: Runs) -> Result<Evaluated, String> {
    let p = ToyProblem::<BigRational>::new(mdp);
    let objective = runs
        .paths
        .iter()
        .map(|r| r.theta.iter().map(|t| objective(&p, t)).collect())
        .collect::<Result<Vec<Vec<_>>, String>>()?;
    let moments = runs
        .paths
        .iter()
        .map(|r| r.w.iter().map(|w| moments(&p, inputs, w)).collect())
        .collect::<Result<Vec<Vec<_>>, String>>()?;
    Ok(Evaluated {
        runs,
        objective,
        moments,
    })
}

/// The proof-step rows of Theorem 3.8 (module table) at `sizes.runs` seeded runs of Algorithm 5
/// on `mdp` (one parameter), with G², σ², Δ₀ = B_F from the certified box constants `k` (valid on
/// `domain`, which every iterate must stay in), all read through `inputs`.
///
/// # Errors
/// A message if a run fails, an iterate leaves `domain`, or a point cannot be evaluated.
pub fn rows(
    inputs: &TableInputs,
    mdp: &ToyMdp,
    k: &ToyConstants,
    domain: &[[f64; 2]],
    sizes: &StepSizes,
) -> Result<Vec<Check>, String> {
    let runs = record(inputs, mdp, k, domain, sizes)?;
    let ev = evaluate(inputs, mdp, runs)?;
    rows_from(inputs, mdp, k, &ev, sizes)
}

/// [`rows`] from runs already recorded and evaluated (by [`record`] and [`evaluate`] with the
/// same `inputs`, `mdp` and `sizes`).
///
/// # Errors
/// If an enclosure cannot be computed.
pub fn rows_from(
    inputs: &TableInputs,
    mdp: &ToyMdp,
    k: &ToyConstants,
    ev: &Evaluated,
    sizes: &StepSizes,
) -> Result<Vec<Check>, String> {
    let mut rows = steps::rows(inputs, mdp, k, ev, sizes)?;
    rows.extend(close::rows(inputs, k, &ev.runs, sizes)?);
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::{self, O2ncParams};
    use crate::certify::box_constants::{self, tied_softmax_g_inf_closed_form};
    use crate::inputs::ConstantKind;
    use crate::protocol::m1_tied;
    use crate::record::check::Verdict;
    use ilopt::scalar::parse_exact;
    use std::sync::OnceLock;

    /// The suite's domain and box constants for M1 at the quick profile's tolerance.
    fn fixture() -> &'static (ToyConstants, Vec<[f64; 2]>) {
        static K: OnceLock<(ToyConstants, Vec<[f64; 2]>)> = OnceLock::new();
        K.get_or_init(|| {
            let r = 1000.0 * 0.05 * tied_softmax_g_inf_closed_form(3, 0.5);
            let domain = vec![[-r, r]];
            let k = box_constants::compute(
                &m1_tied(),
                &[parse_exact("0").unwrap()],
                Some(&parse_exact("7/8").unwrap()),
                &domain,
                1e-2,
                200_000,
            )
            .unwrap();
            (k, domain)
        })
    }

    /// The runs of the quick size, evaluated with the table's own inputs.
    fn thesis_runs() -> &'static Evaluated {
        static E: OnceLock<Evaluated> = OnceLock::new();
        E.get_or_init(|| {
            let (k, domain) = fixture();
            let inputs = TableInputs::thesis();
            let runs = record(&inputs, &m1_tied(), k, domain, &StepSizes::QUICK).unwrap();
            evaluate(&inputs, &m1_tied(), runs).unwrap()
        })
    }

    fn verdict(rows: &[Check], id: &str) -> Verdict {
        rows.iter()
            .find(|r| r.id == id)
            .unwrap_or_else(|| panic!("row {id}"))
            .verdict
    }

    fn scaled(kind: ConstantKind, factor: &str) -> TableInputs {
        TableInputs {
            constant_scale: Some((kind, parse_exact(factor).unwrap())),
            ..TableInputs::thesis()
        }
    }

    /// At the quick size every corrected step holds and every printed version fails.
    #[test]
    fn the_corrected_steps_hold_and_the_printed_ones_fail() {
        let (k, _) = fixture();
        let inputs = TableInputs::thesis();
        let rows = rows_from(&inputs, &m1_tied(), k, thesis_runs(), &StepSizes::QUICK).unwrap();
        for id in [
            "3b.s1", "3b.s1.d0", "3b.s2", "3b.s3", "3b.s3.e", "3b.s4", "3b.s5", "3b.s6",
            "3b.close", "3b.cor",
        ] {
            assert_eq!(verdict(&rows, id), Verdict::Holds, "{id}");
        }
        for id in [
            "3b.s1.printed",
            "3b.s4.printed",
            "3b.s5.printed",
            "3b.s6.printed",
            "3b.close.printed",
        ] {
            assert_eq!(verdict(&rows, id), Verdict::Fails, "{id}");
        }
        assert_eq!(rows.len(), 15);
    }

    /// An oracle bias of 1/1000 on every estimate fails Thm 3.7's premise exactly.
    #[test]
    fn an_oracle_bias_fails_the_premise() {
        let (k, domain) = fixture();
        let inputs = TableInputs {
            oracle_bias: Some(parse_exact("1/1000").unwrap()),
            ..TableInputs::thesis()
        };
        let rows = rows(&inputs, &m1_tied(), k, domain, &StepSizes::QUICK).unwrap();
        assert_eq!(verdict(&rows, "3b.s2"), Verdict::Fails);
    }

    /// A halved G (G²/4, also configuring the runs) fails E‖g_t‖² ≤ G² at the visited points.
    #[test]
    fn a_halved_g_fails_the_second_moment_step() {
        let (k, domain) = fixture();
        let inputs = scaled(ConstantKind::G2, "1/4");
        let rows = rows(&inputs, &m1_tied(), k, domain, &StepSizes::QUICK).unwrap();
        assert_eq!(verdict(&rows, "3b.s3.e"), Verdict::Fails);
    }

    /// A halved σ (σ²/4; σ enters neither the runs nor the moments) fails E‖X_t‖² ≤ σ².
    #[test]
    fn a_halved_sigma_fails_the_martingale_step() {
        let (k, _) = fixture();
        let inputs = scaled(ConstantKind::Sigma2, "1/4");
        let rows = rows_from(&inputs, &m1_tied(), k, thesis_runs(), &StepSizes::QUICK).unwrap();
        assert_eq!(verdict(&rows, "3b.s4"), Verdict::Fails);
    }

    /// A halved Δ₀ in the check (the runs as configured with the certified one) fails
    /// F(θ_0) − F(θ_M) ≤ Δ₀.
    #[test]
    fn a_halved_delta0_fails_the_descent_step() {
        let (k, _) = fixture();
        let inputs = scaled(ConstantKind::BF, "1/2");
        let row = telescoping::descent(&inputs, k, thesis_runs()).unwrap();
        assert_eq!(row.verdict, Verdict::Fails, "{}", row.details);
    }

    fn theorem_without_sigma(d0: f64, delta: f64, g: f64, _sigma: f64, p: O2ncParams) -> f64 {
        bounds::o2nc_theorem(d0, delta, g, 0.0, p)
    }

    fn theorem_without_d(d0: f64, _delta: f64, g: f64, sigma: f64, p: O2ncParams) -> f64 {
        let t = (p.t as f64).sqrt();
        d0 / p.m as f64 + g / t + sigma / t
    }

    fn corollary_without_first_term(d0: f64, delta: f64, g: f64, n: u64) -> f64 {
        bounds::o2nc_corollary(d0, delta, g, n) - 2.0 * d0 / (delta * n as f64)
    }

    /// A theorem formula with σ/√T dropped, or with D dropped from Δ₀/(DM), fails row 3b.close; a
    /// corollary without its 2Δ₀/(δN) fails row 3b.cor.
    #[test]
    fn a_formula_with_a_dropped_factor_fails_the_closing_rows() {
        let (k, _) = fixture();
        let runs = &thesis_runs().runs;
        for theorem in [
            theorem_without_sigma as fn(f64, f64, f64, f64, O2ncParams) -> f64,
            theorem_without_d,
        ] {
            let mut inputs = TableInputs::thesis();
            inputs.formulas.o2nc_theorem = theorem;
            let rows = close::rows(&inputs, k, runs, &StepSizes::QUICK).unwrap();
            assert_eq!(verdict(&rows, "3b.close"), Verdict::Fails);
            assert_eq!(verdict(&rows, "3b.cor"), Verdict::Holds);
        }
        let mut inputs = TableInputs::thesis();
        inputs.formulas.o2nc_corollary = corollary_without_first_term;
        let rows = close::rows(&inputs, k, runs, &StepSizes::QUICK).unwrap();
        assert_eq!(verdict(&rows, "3b.close"), Verdict::Holds);
        assert_eq!(verdict(&rows, "3b.cor"), Verdict::Fails);
    }

    /// The pathwise steps can fail: the regret bound when the check sees estimates other than the
    /// ones OGD ran with (an oracle bias of −1/100), the spread bound with D/2 for the radius.
    #[test]
    fn the_pathwise_steps_fail_on_other_estimates_or_radius() {
        let (k, _) = fixture();
        let biased = TableInputs {
            oracle_bias: Some(parse_exact("-1/100").unwrap()),
            ..TableInputs::thesis()
        };
        let rows = steps::regret(&biased, k, thesis_runs()).unwrap();
        assert_eq!(verdict(&rows, "3b.s3"), Verdict::Fails);
        let mut ev = thesis_runs().clone();
        ev.runs.radius = ev.runs.radius.clone() / parse_exact("2").unwrap();
        assert_eq!(verdict(&steps::spread(&ev), "3b.s6"), Verdict::Fails);
    }
}
