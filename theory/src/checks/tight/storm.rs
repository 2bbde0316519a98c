//! Rows 2c.tight and 2c.tight.ctl: the IS-STORM bound (eq. 3.60\*, Theorem S with schedule (3.43))
//! at the instance of largest X̄/B found by [`super::search`], with E X enclosed in intervals over
//! every path ([`super::paths::storm_mean`]).
//!
//! The schedule's constant L is the candidate's step parameter: Theorem S holds for any
//! L ≥ max(L_F, L̃), so the row certifies L_F and L̃ on the hull of the iterates and checks that
//! condition before it states the bound with that L.

use super::Sizes;
use super::instance::exact;
use super::paths::storm_mean;
use super::search::{Algorithm, Estimate, Noise, search};
use super::sgd::search_text;
use crate::bounds::upper;
use crate::certify::box_constants::{b_f, l_f, l_tilde, sigma2};
use crate::inputs::{ConstantKind, TableInputs};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::record::constant::Constant;
use ilopt::scalar::{BigRational, Interval, Scalar};

const RESULT: &str = "STORM, eq. (3.60*) (tight instance)";

/// What one certified candidate gives: the enclosure of X̄, the constants on the hull.
#[derive(Debug, Clone)]
pub struct Certified {
    /// The search's estimate for the candidate.
    pub estimate: Estimate,
    /// The schedule's L (the candidate's, or raised to the certified constants).
    pub l: f64,
    /// An enclosure of X̄ = E[Σ_k η_k ‖∇F(θ_k)‖² / Σ_k η_k].
    pub x_bar: Interval,
    /// The hull of the iterates the constants hold on.
    pub hull: Vec<[f64; 2]>,
    /// Number of paths.
    pub paths: u64,
    /// B_F (exact), L_F, L̃ and σ² (rigorous on the hull).
    pub constants: [Constant; 4],
}

/// Rounds of [`certify`]: how often the schedule's L may be raised to the certified
/// max(L_F, L̃) of the previous round's hull.
pub const ROUNDS: usize = 3;

/// The smallest multiple of 2⁻¹⁰ that is ≥ `x` (a short dyadic rational).
fn dyadic_up(x: f64) -> f64 {
    (x * 1024.0).ceil() / 1024.0
}

/// Certify one candidate: X̄ enclosed over every path under `inputs`' oracle, the constants on the
/// hull of those iterates. Theorem S needs the schedule's L ≥ max(L_F, L̃) on that hull; where the
/// certified constants (branch-and-bound upper bounds, above the search's estimates) exceed the
/// candidate's L, L is raised to them (rounded up to a multiple of 2⁻¹⁰) and the run and the
/// constants are redone, for at most [`ROUNDS`] rounds.
///
/// # Errors
/// A message saying why the candidate was passed over.
pub fn certify(e: &Estimate, inputs: &TableInputs, s: &Sizes) -> Result<Certified, String> {
    let inst = &e.candidate.instance;
    let mdp = inst.mdp()?;
    let one = BigRational::from_integer(1.into());
    let mut l_s = e.candidate.step;
    for _ in 0..ROUNDS {
        let l = Interval::from_rational(&exact(l_s));
        let run = storm_mean(
            &mdp,
            &inst.theta1_in::<Interval>(),
            &l,
            inst.k,
            inputs,
            s.storm.max_paths,
        )
        .map_err(|m| format!("{}, L = {l_s}: {m}", inst.describe()))?;
        let lf = l_f(&mdp, &run.hull, s.tol, s.max_boxes).map_err(|e| e.to_string())?;
        let lt = l_tilde(&mdp, run.hull[0], s.tol, s.max_boxes).map_err(|e| e.to_string())?;
        let need = lf.value.max(lt.value);
        if need > l_s {
            l_s = dyadic_up(need);
            continue;
        }
        let v = sigma2(&mdp, &one, &run.hull, s.tol, s.max_boxes).map_err(|e| e.to_string())?;
        let bf = b_f(&mdp, &inst.theta1, None)?;
        return Ok(Certified {
            estimate: e.clone(),
            l: l_s,
            x_bar: run.mean,
            hull: run.hull,
            paths: run.paths,
            constants: [bf, lf, lt, v],
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
pub fn row(c: &Certified, inputs: &TableInputs, scale: f64, s: &Sizes, noise: Noise) -> Check {
    let inst = &c.estimate.candidate.instance;
    let l = c.l;
    let [bf, lf, lt, v] = &c.constants;
    let b_f = inputs.constant_f64(ConstantKind::BF, bf.value);
    let l_f = inputs.constant_f64(ConstantKind::LF, lf.value);
    let l_t = inputs.constant_f64(ConstantKind::LTilde, lt.value);
    let s2 = inputs.constant_f64(ConstantKind::Sigma2, v.value);
    let (id, role, prefix) = if scale == 1.0 {
        (
            format!("2c.tight{}", noise.suffix()),
            Role::Corrected,
            String::new(),
        )
    } else {
        (
            format!("2c.tight{}.ctl", noise.suffix()),
            Role::NegativeControl,
            format!("{scale}·"),
        )
    };
    let claim = format!(
        "Σ_k η_k E‖∇F(θ_k)‖² / Σ_k η_k ≤ {prefix}4[2LB_F + σ²(1 + 14(H_{{K+7}} − H_7))] / Σ_k (7/(k+7))^{{1/3}} for IS-STORM (trajectory weights), schedule (3.43) with L = {}, on the instance of largest X̄/B found: {}",
        exact(l),
        inst.describe()
    );
    let builder = Check::builder(id, RESULT, claim, role)
        .assumptions([
            format!(
                "(A1), (A3), (A4) on the hull {:?} of every iterate θ₁..θ_{{K+1}} of every path",
                c.hull
            ),
            "(A2) E g = ∇F, and the weighted old-point term is unbiased (identity I3)".into(),
            "L ≥ max(L_F, L̃), so (C1) and (C2) hold for schedule (3.43)".into(),
        ])
        .constants(c.constants.to_vec())
        .erratum("E8");
    let x = c.x_bar.mid();
    if l_f.max(l_t) > l {
        return builder
            .measured(Measured::exact(x))
            .details(format!(
                "L = {l} < max(L_F, L̃) = max({l_f}, {l_t}): Theorem S does not apply"
            ))
            .decided(Method::Rigorous, Verdict::Inconclusive);
    }
    let bound = (inputs.formulas.storm_fixed)(l, s2, b_f, inst.k);
    let claimed = upper(bound) * scale;
    let verdict = if c.x_bar.sup() <= claimed {
        Verdict::Holds
    } else if c.x_bar.inf() > claimed {
        Verdict::Fails
    } else {
        Verdict::Inconclusive
    };
    builder
        .bound(bound * scale)
        .measured(Measured::exact(x).with_interval(c.x_bar.inf(), c.x_bar.sup()))
        .tightness(x / (bound * scale))
        .details(format!(
            "X̄ = E X enclosed in intervals over all {} paths, X̄ ∈ [{:.8}, {:.8}], B = {bound:.6} (σ² = {s2:.5}, B_F = {b_f:.5}, σ² term {:.1} % of B), X̄/B = {:.4}; search: {} (estimated X̄/B = {:.4}); max(L_F, L̃) = {:.4} ≤ L",
            c.paths,
            c.x_bar.inf(),
            c.x_bar.sup(),
            100.0 * (1.0 - (inputs.formulas.storm_fixed)(l, 0.0, b_f, inst.k) / bound),
            x / bound,
            search_text(&s.storm),
            c.estimate.ratio,
            l_f.max(l_t)
        ))
        .decided(Method::Rigorous, verdict)
}

/// The search's candidates and the first one certified under an oracle ([`super::Prepared`]).
pub type Prepared = super::Prepared<Certified>;

/// The seeded search's candidates ([`search`]); it reads no input of the table.
pub fn candidates(s: &Sizes, noise: Noise) -> Vec<Estimate> {
    search(Algorithm::Storm, noise, s.storm)
}

/// Certify the best of the [`candidates`] in order until one passes, under `inputs`' oracle.
pub fn prepare_from(found: &[Estimate], inputs: &TableInputs, s: &Sizes) -> Prepared {
    super::first_certified(found, s.tries, |e| certify(e, inputs, s))
}

/// Search (seeded, [`search`]) and certify the best candidates in order until one passes.
pub fn prepare(inputs: &TableInputs, s: &Sizes, noise: Noise) -> Prepared {
    prepare_from(&candidates(s, noise), inputs, s)
}

/// Rows 2c.tight and 2c.tight.ctl (module docs) from [`prepare`]d candidates (made with the same
/// oracle, sizes and noise), or one inconclusive row saying why no candidate could be certified.
pub fn rows_from(inputs: &TableInputs, s: &Sizes, noise: Noise, p: &Prepared) -> Vec<Check> {
    match &p.certified {
        Some(c) => super::with_control(
            |scale| row(c, inputs, scale, s, noise),
            super::control_always(noise, Algorithm::Storm),
            &p.passed_over,
        ),
        None => vec![p.none_certified(
            Check::builder(
                format!("2c.tight{}", noise.suffix()),
                RESULT,
                "a tight instance of eq. (3.60*)",
                Role::Corrected,
            ),
            &s.storm,
            Method::Rigorous,
        )],
    }
}

/// [`prepare`], then [`rows_from`].
pub fn rows(inputs: &TableInputs, s: &Sizes, noise: Noise) -> Vec<Check> {
    rows_from(inputs, s, noise, &prepare(inputs, s, noise))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::storm_fixed;
    use crate::inputs::Formulas;

    fn half(l: f64, s2: f64, b_f: f64, k: u64) -> f64 {
        0.5 * storm_fixed(l, s2, b_f, k)
    }

    /// At the quick size: the tight row holds with X̄/B ≥ ½, its B ÷ 2 control is refuted, and
    /// (3.60\*) halved refutes the theorem's row.
    #[test]
    fn the_tight_row_holds_and_a_halved_bound_turns_it() {
        let s = Sizes::quick();
        let rows = rows(&TableInputs::thesis(), &s, Noise::Any);
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
        let wrong = TableInputs {
            formulas: Formulas {
                storm_fixed: half,
                ..Formulas::THESIS
            },
            ..TableInputs::thesis()
        };
        let turned = super::rows(&wrong, &s, Noise::Any);
        assert_eq!(turned[0].verdict, Verdict::Fails, "{}", turned[0].details);
    }
}
