//! Rows 2c.tight and 2c.tight.ctl: the IS-STORM bound (eq. 3.60\*, Theorem S with schedule (3.43))
//! at the instance of largest X̄/B found by [`super::search`], with E X enclosed in intervals over
//! every path ([`super::paths::storm_mean`]); rows 2.b.tight.noisy and its control the same for
//! row 2.b's baselined estimator g_b = g − bψ ([`Algorithm::StormBaselined`]), with σ²_b and
//! L̃_b of (A4) for the trajectory-weighted g_b certified on the hull.
//!
//! The schedule's constant L is the candidate's step parameter: Theorem S holds for any
//! L ≥ max(L_F, L̃), so the row certifies L_F and L̃ (L̃_b) on the hull of the iterates and checks
//! that condition before it states the bound with that L.

use super::Sizes;
use super::bound::Bound;
use super::instance::exact;
use super::paths::storm_mean;
use super::search::{Algorithm, Estimate, Noise};
use super::sgd::search_text;
use crate::bounds::upper;
use crate::certify::box_constants::{b_f, l_f, l_tilde, sigma2, sigma2_baselined};
use crate::inputs::{ConstantKind, TableInputs};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::record::constant::Constant;
use ilopt::scalar::{BigRational, Interval, Scalar};

const RESULT: &str = "STORM, eq. (3.60*) (tight instance)";
const RESULT_BASELINED: &str =
    "STORM, eq. (3.60*), with a baseline (tight instance, beyond the thesis)";
const RESULT_PER_DECISION: &str = "STORM, eq. (3.60*), per-decision weights (tight instance)";

/// The row id's stem and the result of `algorithm`'s rows: "2c" (trajectory weights), "2c.pd"
/// (per-decision weights) or "2.b" (baselined).
fn stem(algorithm: Algorithm) -> (&'static str, &'static str) {
    match algorithm {
        Algorithm::StormBaselined => ("2.b", RESULT_BASELINED),
        Algorithm::StormPerDecision => ("2c.pd", RESULT_PER_DECISION),
        _ => ("2c", RESULT),
    }
}

/// What one certified candidate gives: the enclosure of X̄, the constants on the hull.
#[derive(Debug, Clone)]
pub struct Certified {
    /// The search's estimate for the candidate.
    pub estimate: Estimate,
    /// The estimator the candidate was searched and certified for.
    pub algorithm: Algorithm,
    /// The schedule's L (the candidate's, or raised to the certified constants).
    pub l: f64,
    /// An enclosure of X̄ = E[Σ_k η_k ‖∇F(θ_k)‖² / Σ_k η_k].
    pub x_bar: Interval,
    /// The hull of the iterates the constants hold on.
    pub hull: Vec<[f64; 2]>,
    /// Number of paths.
    pub paths: u64,
    /// B_F (exact), L_F, L̃ and σ² (L̃_b and σ²_b for the baselined estimator; rigorous on the
    /// hull).
    pub constants: [Constant; 4],
    /// The baseline b of the estimator g_b = g − bψ, or `None` for the plain estimator.
    pub baseline: Option<BigRational>,
}

/// Rounds of [`Storm`]'s certification ([`Bound::certify`]): how often the schedule's L may be
/// raised to the certified max(L_F, L̃) of the previous round's hull.
pub const ROUNDS: usize = 3;

/// The smallest multiple of 2⁻¹⁰ that is ≥ `x` (a short dyadic rational).
fn dyadic_up(x: f64) -> f64 {
    (x * 1024.0).ceil() / 1024.0
}

/// The tight rows of eq. (3.60\*) ([`Bound`]): how a candidate is certified and its rows read.
pub struct Storm;

impl Bound for Storm {
    type Certified = Certified;
    const EQUATION: &'static str = "eq. (3.60*)";
    const METHOD: Method = Method::Rigorous;

    /// Certify one candidate: X̄ enclosed over every path under `inputs`' oracle, the constants on the
    /// hull of those iterates. Theorem S needs the schedule's L ≥ max(L_F, L̃) on that hull; where the
    /// certified constants (branch-and-bound upper bounds, above the search's estimates) exceed the
    /// candidate's L, L is raised to them (rounded up to a multiple of 2⁻¹⁰) and the run and the
    /// constants are redone, for at most [`ROUNDS`] rounds. For [`Algorithm::StormBaselined`] the run,
    /// L̃ and σ² are those of g_b.
    ///
    /// # Errors
    /// A message saying why the candidate was passed over.
    fn certify(
        e: &Estimate,
        inputs: &TableInputs,
        s: &Sizes,
        algorithm: Algorithm,
    ) -> Result<Self::Certified, String> {
        let inst = &e.candidate.instance;
        let mdp = inst.mdp()?;
        let one = BigRational::from_integer(1.into());
        let b = algorithm.baseline();
        let mut l_s = e.candidate.step;
        for _ in 0..ROUNDS {
            let l = Interval::from_rational(&exact(l_s));
            let run = storm_mean(
                &mdp,
                &inst.theta1_in::<Interval>(),
                &l,
                inst.k,
                inputs,
                s.budget(algorithm).max_paths,
                algorithm.weighting(),
                b.as_ref(),
            )
            .map_err(|m| format!("{}, L = {l_s}: {m}", inst.describe()))?;
            let lf = l_f(&mdp, &run.hull, s.tol, s.max_boxes).map_err(|e| e.to_string())?;
            let lt = l_tilde(
                &mdp,
                algorithm.weighting(),
                b.as_ref(),
                run.hull[0],
                s.tol,
                s.max_boxes,
            )
            .map_err(|e| e.to_string())?;
            let need = lf.value.max(lt.value);
            if need > l_s {
                l_s = dyadic_up(need);
                continue;
            }
            let v = match &b {
                None => sigma2(&mdp, &one, &run.hull, s.tol, s.max_boxes),
                Some(b) => sigma2_baselined(&mdp, b, &run.hull, s.tol, s.max_boxes),
            }
            .map_err(|e| e.to_string())?;
            let bf = b_f(&mdp, &inst.theta1, None)?;
            return Ok(Certified {
                estimate: e.clone(),
                algorithm,
                l: l_s,
                x_bar: run.mean,
                hull: run.hull,
                paths: run.paths,
                constants: [bf, lf, lt, v],
                baseline: b,
            });
        }
        Err(format!(
            "{}, L = {}: the certified max(L_F, L̃) still exceeds L after {ROUNDS} rounds",
            inst.describe(),
            e.candidate.step
        ))
    }

    /// The row for `X̄ ≤ scale · B` at a certified candidate (scale 1: the theorem; ½: the negative
    /// control), B read through `inputs`: holds if the enclosure of X̄ is ≤ scale · upper(B), fails if
    /// it is above, inconclusive if it straddles.
    fn row(c: &Certified, inputs: &TableInputs, scale: f64, s: &Sizes, noise: Noise) -> Check {
        let inst = &c.estimate.candidate.instance;
        let l = c.l;
        let [bf, lf, lt, v] = &c.constants;
        let b_f = inputs.constant_f64(ConstantKind::BF, bf.value);
        let l_f = inputs.constant_f64(ConstantKind::LF, lf.value);
        let l_t = inputs.constant_f64(ConstantKind::LTilde, lt.value);
        let s2 = inputs.constant_f64(ConstantKind::Sigma2, v.value);
        let (lt_name, v_name) = (&lt.name, &v.name);
        let (stem, result) = stem(c.algorithm);
        let (id, role, prefix) = super::row_names(stem, noise, scale, Role::Corrected);
        let weights = if c.algorithm == Algorithm::StormPerDecision {
            "per-decision weights"
        } else {
            "trajectory weights"
        };
        let (estimator, unbiased) = match &c.baseline {
            None => (
                String::new(),
                format!(
                    "(A2) E g = ∇F, and the {} old-point term is unbiased (identity I3)",
                    if c.algorithm == Algorithm::StormPerDecision {
                        "per-decision weighted"
                    } else {
                        "trajectory-weighted"
                    }
                ),
            ),
            Some(b) => (
                format!(" on g_b = g − bψ, b = {b}, with σ²_b and L̃_b"),
                format!(
                    "(A2) for g_b, b = {b} fixed before any run: E g_b = ∇F and E_{{τ∼θ′}}[w g_b(θ, τ)] = ∇F(θ) (docs/math.md §9)"
                ),
            ),
        };
        let claim = format!(
            "Σ_k η_k E‖∇F(θ_k)‖² / Σ_k η_k ≤ {prefix}4[2LB_F + σ²(1 + 14(H_{{K+7}} − H_7))] / Σ_k (7/(k+7))^{{1/3}} for IS-STORM ({weights}){estimator}, schedule (3.43) with L = {}, on the instance of largest X̄/B found: {}",
            exact(l),
            inst.describe()
        );
        let builder = Check::builder(id, result, claim, role)
            .assumptions([
                format!(
                    "(A1), (A3), (A4) on the hull {:?} of every iterate θ₁..θ_{{K+1}} of every path",
                    c.hull
                ),
                unbiased,
                "L ≥ max(L_F, L̃), so (C1) and (C2) hold for schedule (3.43)".into(),
            ])
            .constants(c.constants.to_vec())
            .erratum("E8");
        let x = c.x_bar.mid();
        if l_f.max(l_t) > l {
            return builder
                .measured(Measured::exact(x))
                .details(format!(
                    "L = {l} < max(L_F, {lt_name}) = max({l_f}, {l_t}): Theorem S does not apply"
                ))
                .decided(Method::Rigorous, Verdict::Inconclusive);
        }
        let bound = (inputs.formulas.storm_fixed)(l, s2, b_f, inst.k);
        let claimed = upper(bound) * scale;
        let verdict = super::enclosure_verdict(&c.x_bar, claimed);
        builder
            .bound(bound * scale)
            .measured(Measured::exact(x).with_interval(c.x_bar.inf(), c.x_bar.sup()))
            .tightness(x / (bound * scale))
            .details(format!(
                "X̄ = E X enclosed in intervals over all {} paths, X̄ ∈ [{:.8}, {:.8}], B = {bound:.6} ({v_name} = {s2:.5}, B_F = {b_f:.5}, {v_name} term {:.1} % of B), X̄/B = {:.4}; search: {} (estimated X̄/B = {:.4}); max(L_F, {lt_name}) = {:.4} ≤ L",
                c.paths,
                c.x_bar.inf(),
                c.x_bar.sup(),
                100.0 * (1.0 - (inputs.formulas.storm_fixed)(l, 0.0, b_f, inst.k) / bound),
                x / bound,
                search_text(&s.budget(c.algorithm)),
                c.estimate.ratio,
                l_f.max(l_t)
            ))
            .decided(Method::Rigorous, verdict)
    }

    fn names(algorithm: Algorithm) -> (&'static str, &'static str, Role) {
        let (stem, result) = stem(algorithm);
        (stem, result, Role::Corrected)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::storm_fixed;
    use crate::checks::tight::bound;
    use crate::inputs::Formulas;

    fn half(l: f64, s2: f64, b_f: f64, k: u64) -> f64 {
        0.5 * storm_fixed(l, s2, b_f, k)
    }

    /// The table's inputs with (3.60\*) computed by `storm_fixed`.
    fn with_bound(storm_fixed: fn(f64, f64, f64, u64) -> f64) -> TableInputs {
        TableInputs {
            formulas: Formulas {
                storm_fixed,
                ..Formulas::THESIS
            },
            ..TableInputs::thesis()
        }
    }

    fn control_scaled(l: f64, s2: f64, b_f: f64, k: u64) -> f64 {
        crate::checks::statistical::STORM_CONTROL_SCALE * storm_fixed(l, s2, b_f, k)
    }

    /// At the quick size: the tight row holds with X̄/B ≥ ½, its B ÷ 2 control is refuted, and
    /// (3.60\*) halved refutes the theorem's row.
    #[test]
    fn the_tight_row_holds_and_a_halved_bound_turns_it() {
        let s = Sizes::quick();
        let rows = bound::rows::<Storm>(&TableInputs::thesis(), &s, Noise::Any, Algorithm::Storm);
        for r in &rows {
            println!(
                "{} {:?} {:?}: {}\n  {}",
                r.id, r.verdict, r.tightness, r.claim, r.details
            );
        }
        let ids: Vec<&str> = rows.iter().map(|r| r.id.as_str()).collect();
        assert_eq!(ids, ["2c.tight", "2c.tight.ctl"], "{rows:#?}");
        assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
        assert!(rows[0].tightness.unwrap() >= 0.5, "{}", rows[0].details);
        assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
        let wrong = with_bound(half);
        let turned = bound::rows::<Storm>(&wrong, &s, Noise::Any, Algorithm::Storm);
        assert_eq!(turned[0].verdict, Verdict::Fails, "{}", turned[0].details);
    }

    /// `algorithm`'s noisy tight rows at the quick size, printed, with its certified candidate:
    /// the main row holds, and (3.60\*) scaled as the Monte-Carlo row 2c.ctl's control refutes it
    /// (X̄/B ≥ 0.01 there, so B × 1/200 lies below X̄): the row can fail at its size.
    fn noisy_rows(algorithm: Algorithm, id: &str) -> (Certified, Vec<Check>) {
        let s = Sizes::quick();
        let n = Noise::Required;
        let p = bound::prepare::<Storm>(&TableInputs::thesis(), &s, n, algorithm);
        let rows = bound::rows_from::<Storm>(&TableInputs::thesis(), &s, n, algorithm, &p);
        for r in &rows {
            println!(
                "{} {:?} {:?}: {}\n  {}",
                r.id, r.verdict, r.tightness, r.claim, r.details
            );
        }
        assert_eq!(rows[0].id, id, "{rows:#?}");
        assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
        let turned = bound::rows_from::<Storm>(&with_bound(control_scaled), &s, n, algorithm, &p);
        assert_eq!(turned[0].verdict, Verdict::Fails, "{}", turned[0].details);
        if rows[0].tightness.unwrap() >= 0.5 {
            assert_eq!(rows[1].id, format!("{id}.ctl"));
            assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
            let turned = bound::rows_from::<Storm>(&with_bound(half), &s, n, algorithm, &p);
            assert_eq!(turned[0].verdict, Verdict::Fails, "{}", turned[0].details);
        }
        (p.certified.expect("a certified candidate"), rows)
    }

    /// Row 2c.pd.tight.noisy ([`noisy_rows`]): IS-STORM with per-decision weights, L̃_PD
    /// certified on the hull (and σ², the estimator being g).
    #[test]
    fn the_per_decision_tight_row_holds_and_an_understated_bound_turns_it() {
        let (c, rows) = noisy_rows(Algorithm::StormPerDecision, "2c.pd.tight.noisy");
        let names: Vec<&str> = c.constants.iter().map(|k| k.name.as_str()).collect();
        assert_eq!(names, ["B_F", "L_F", "L̃_PD", "σ²"], "{names:?}");
        assert!(
            rows[0].claim.contains("per-decision weights"),
            "{}",
            rows[0].claim
        );
    }

    /// Row 2.b.tight.noisy ([`noisy_rows`]): IS-STORM on row 2.b's g_b, σ²_b and L̃_b certified
    /// on the hull.
    #[test]
    fn the_baselined_tight_row_holds_with_its_certified_constants() {
        let (c, rows) = noisy_rows(Algorithm::StormBaselined, "2.b.tight.noisy");
        assert_eq!(c.baseline, Some(super::super::search::baseline()));
        let names: Vec<&str> = c.constants.iter().map(|k| k.name.as_str()).collect();
        assert_eq!(names, ["B_F", "L_F", "L̃_b", "σ²_b"], "{names:?}");
        assert!(rows[0].claim.contains("g_b = g − bψ"), "{}", rows[0].claim);
    }
}
