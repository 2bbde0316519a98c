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
    let mut rows = steps::rows(inputs, mdp, k, &ev, sizes)?;
    rows.extend(close::rows(inputs, k, &ev.runs, sizes)?);
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::box_constants::{self, tied_softmax_g_inf_closed_form};
    use crate::protocol::m1_tied;
    use ilopt::scalar::{Scalar, parse_exact};
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

    #[test]
    fn explore() {
        let (k, domain) = fixture();
        let t0 = std::time::Instant::now();
        let rows = rows(&TableInputs::thesis(), &m1_tied(), k, domain, &StepSizes::QUICK).unwrap();
        eprintln!("rows {:?}", t0.elapsed());
        for r in &rows {
            eprintln!("{} {:?} {:?}\n   {}", r.id, r.verdict, r.role, r.details);
        }
    }
}
