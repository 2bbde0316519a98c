//! Check 3 (part): the corollary (3.71) follows from the theorem-level O2NC bound (math.md §5).
//!
//! **Sampled, not proved**: on many seeded random (N, δ, G, Δ₀) evaluated in `f64`, with σ = G, the theorem-level bound
//! Δ₀/(DM) + G/√T + σ/√T (realised T, K, M, D = δ/T) and the thesis's intermediate line
//! 2TΔ₀/(δN) + 3G/√T must both be ≤ the corollary 2Δ₀/(δN) + max(5G^{2/3}Δ₀^{1/3}/(Nδ)^{1/3}, 6G/√N).

use crate::bounds::{o2nc_intermediate, o2nc_params, upper};
use crate::inputs::{Formulas, TableInputs};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use rand::{Rng, SeedableRng};

/// The worst ratios found over `cases` random parameter sets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ratios {
    /// max theorem / corollary.
    pub theorem: f64,
    /// max intermediate / corollary.
    pub intermediate: f64,
}

/// Evaluate the ratios with `formulas`' theorem-level bound and corollary, the corollary scaled by
/// `scale` (1 for the real claim; < 1 to show the check can fail).
pub fn ratios(formulas: &Formulas, cases: usize, seed: u64, scale: f64) -> Ratios {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut worst = Ratios {
        theorem: 0.0,
        intermediate: 0.0,
    };
    for _ in 0..cases {
        let n = rng.random_range(4u64..1_000_000);
        let delta = 10f64.powf(rng.random_range(-4.0..1.0));
        let g = 10f64.powf(rng.random_range(-2.0..2.0));
        let d0 = 10f64.powf(rng.random_range(-3.0..2.0));
        let p = o2nc_params(n, delta, g, d0);
        let cor = (formulas.o2nc_corollary)(d0, delta, g, n) * scale;
        worst.theorem = worst
            .theorem
            .max((formulas.o2nc_theorem)(d0, delta, g, g, p) / cor);
        worst.intermediate = worst
            .intermediate
            .max(o2nc_intermediate(d0, delta, g, n, p.t) / cor);
    }
    worst
}

/// The row of the table, with the bound formulas of `inputs`.
pub fn row(inputs: &TableInputs, cases: usize, seed: u64) -> Check {
    let r = ratios(&inputs.formulas, cases, seed, 1.0);
    let ok = r.theorem <= upper(1.0) && r.intermediate <= upper(1.0);
    let worst = r.theorem.max(r.intermediate);
    Check::builder(
        "3c",
        "Online-to-non-convex, corollary (3.71)",
        format!(
            "theorem-level bound and the thesis's intermediate line are ≤ (3.71) at {cases} sampled (N, δ, G, Δ₀) (no proof for all)"
        ),
        Role::Thesis,
    )
    .assumptions(["σ = G; T = min(⌈(GNδ/Δ₀)^{2/3}⌉, ⌊N/2⌋), K = ⌊N/T⌋"])
    .bound(1.0)
    .measured(Measured::exact(worst))
    .tightness(worst)
    .details(format!(
        "{cases} seeded random parameter sets (log-uniform δ, G, Δ₀; uniform N), evaluated in f64 with a relative slack of 10⁻¹²: max theorem/corollary = {:.4}, max intermediate/corollary = {:.4}",
        r.theorem, r.intermediate
    ))
    .decided(Method::Sampled, Verdict::from_bool(ok))
}
