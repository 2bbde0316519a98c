//! Rows 3b.tight, 3b.tight.noisy and their B ÷ 2 controls: the theorem-level O2NC bound (Theorem 3.8 with the realised
//! T, K, D, M; [`crate::bounds::o2nc_theorem`]) for Algorithm 5 with IL-correct sampling
//! (τ_n ∼ p(·; w_n), E11) at the instance of largest X̄/B a seeded search finds, with
//! E X **enclosed** over every outcome of the run.
//!
//! Why the runs are enumerable. Algorithm 5 draws s_n ∼ U[0, 1] at every step, so its outcomes
//! are not finitely many. With blocks of length T ≤ 2 the walk still has a closed form:
//!
//! * at t = 1 the restart gives Δ_n = 0, so w_n = θ_{n−1} and θ_n = θ_{n−1}; the prefix τ̄ drawn
//!   there sets Δ = Π_{|·|≤D}(−η ĝ(θ, τ̄));
//! * at t = 2, θ_n = θ_{n−1} + Δ and w_n = θ_{n−1} + s_n Δ; the prefix drawn at w_n enters only the
//!   next Δ, which the next block's restart discards.
//!
//! So the iterates θ depend on the prefixes drawn at the blocks' first steps alone (finitely many
//! paths, each with its probability), s_n enters only through w_n, and the statistic
//! `X = (1/K) Σ_k |(1/T) Σ_t ∇F(wᵏ_t)|` has the expectation
//!
//! ```text
//! E X = Σ_paths p(path) (1/K) Σ_k ∫₀¹ |∇F(θ_k) + ∇F(θ_k + sΔ_k)|/2 ds      (T = 2)
//! E X = |∇F(θ₁)|                                                              (T = 1)
//! ```
//!
//! The integral is enclosed by an interval Riemann sum over [`CELLS`] cells of s (each cell's
//! |∇F(θ + [s_j, s_{j+1}]Δ) + ∇F(θ)| enclosed by the mean-value form, [`Quadrature`]), so the
//! decision is a proof, not a test. It holds for the kit's draw of s as well: a dyadic uniform
//! k/2⁵³ ([`ilopt::sampling::dyadic_uniform`]), of which every cell holds the same number of
//! values, all inside it. T ≤ 2 means GNδ/Δ₀ ≤ 2√2: the search's parameter x = GNδ/Δ₀ ranges up
//! to that, and a candidate whose blocks are longer is refused.
//!
//! The algorithm's inputs are exact rationals: G (a dyadic, the candidate's), Δ₀ = F(θ₁) (F ≥ 0,
//! so Δ₀ ≥ F(θ₁) − F*) and δ = xΔ₀/(GN); T, K, M and D come from the kit's own
//! [`ilopt::algo::o2nc::O2ncConfig::parameters`]. The theorem needs G² ≥ E‖g‖² and σ² ≥ Var g
//! at every point the run visits: both are certified by interval branch-and-bound on the hull
//! of every iterate (which holds every w_n), and a candidate whose certified G² exceeds its G²
//! is passed over.
//!
//! Files: `walk` (the path walk and its quadrature), `search` (candidates, their exact inputs
//! and the seeded search); here the certification and the rows.
//! Every gradient estimate that moves an iterate is the oracle's own, read through
//! [`TableInputs::estimate`].

mod search;
mod setting;
mod walk;

pub use search::{Candidate, Estimate, X_MAX, evaluate, search};
pub use setting::Setting;
pub use walk::{CELLS, Quadrature, o2nc_mean};

use super::search::{Budget, Noise, STARTS};
use super::{Prepared, first_certified, with_control};
use crate::bounds::{O2ncParams, upper};
use crate::certify::box_constants::sigma2;
use crate::inputs::{ConstantKind, TableInputs};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::record::constant::Constant;
use ilopt::scalar::{BigRational, Interval, Scalar};

const RESULT: &str = "Online-to-non-convex (Alg. 5, IL-correct), Thm 3.8 (tight instance)";

/// The theorem's B = Δ₀/(DM) + (G + σ)/√T through `inputs`' formula, with every input rounded
/// the way that makes B larger (B falls with δ and grows with Δ₀, G and σ).
fn bound(inputs: &TableInputs, s: &Setting, delta0: f64, sigma: f64) -> f64 {
    let p = &s.params;
    let delta = Scalar::to_f64(&s.delta).next_down();
    let g = Scalar::to_f64(&s.g).next_up();
    upper((inputs.formulas.o2nc_theorem)(
        delta0.next_up(),
        delta,
        g,
        sigma.next_up(),
        O2ncParams {
            t: p.t,
            k: p.k,
            m: p.m,
        },
    ))
}

/// What one certified candidate gives.
#[derive(Debug, Clone)]
pub struct Certified {
    /// The search's estimate.
    pub estimate: Estimate,
    /// Algorithm 5's exact inputs.
    pub setting: Setting,
    /// The enclosure of X̄.
    pub x_bar: Interval,
    /// The hull of the iterates the constants hold on.
    pub hull: [f64; 2],
    /// Number of paths.
    pub paths: u64,
    /// Δ₀ = F(θ₁) (exact), G² = sup E‖g‖² and σ² = sup Var g on the hull (rigorous).
    pub constants: [Constant; 3],
}

/// Certify a candidate: X̄ enclosed over every path under `inputs`' oracle, G² and σ² certified on
/// the hull of the iterates.
///
/// # Errors
/// Why the candidate was passed over: the walk fails, or the certified G² exceeds the algorithm's
/// G², so the theorem does not apply.
pub fn certify(
    e: &Estimate,
    inputs: &TableInputs,
    budget: &Budget,
    tol: f64,
    max_boxes: usize,
) -> Result<Certified, String> {
    let c = &e.candidate;
    let mdp = c.instance.mdp()?;
    let setting = c.setting()?;
    let theta1 = Interval::from_rational(&c.instance.theta1[0]);
    let run = o2nc_mean(&mdp, &theta1, &setting, inputs, budget.max_paths, CELLS)
        .map_err(|m| format!("{}: {m}", c.describe()))?;
    let hull = run.hull[0];
    let zero = BigRational::from_i64(0);
    let g2 = sigma2(&mdp, &zero, &[hull], tol, max_boxes).map_err(|e| e.to_string())?;
    let g2_value = inputs.constant_f64(ConstantKind::G2, g2.value);
    if g2_value > c.g * c.g {
        return Err(format!(
            "{}: the certified G² = {g2_value} on the hull exceeds G² = {}",
            c.describe(),
            c.g * c.g
        ));
    }
    let v = sigma2(&mdp, &BigRational::from_i64(1), &[hull], tol, max_boxes)
        .map_err(|e| e.to_string())?;
    let d0 = Constant::exact("Δ₀", &setting.delta0, "F(θ₁) − 0 (F ≥ 0)");
    Ok(Certified {
        estimate: e.clone(),
        setting,
        x_bar: run.mean,
        hull,
        paths: run.paths,
        constants: [d0, g2, v],
    })
}

/// The row `X̄ ≤ scale · B` at a certified candidate (scale 1: the theorem's; ½: its negative
/// control), B through `inputs`: holds if the enclosure of X̄ is ≤ scale · B, fails if it lies
/// above, inconclusive if it straddles.
pub fn row(
    c: &Certified,
    inputs: &TableInputs,
    scale: f64,
    budget: &Budget,
    noise: Noise,
) -> Check {
    let cand = &c.estimate.candidate;
    let [d0, g2, v] = &c.constants;
    let delta0 = inputs.constant_f64(ConstantKind::BF, d0.value);
    let s2 = inputs.constant_f64(ConstantKind::Sigma2, v.value);
    let g2_value = inputs.constant_f64(ConstantKind::G2, g2.value);
    let s = &c.setting;
    let p = &s.params;
    let (id, role, prefix) = super::row_names("3b", noise, scale, Role::Corrected);
    let claim = format!(
        "E[(1/K) Σ_k ‖(1/T) Σ_t ∇F(wᵏ_t)‖] ≤ {prefix}(Δ₀/(DM) + (G + σ)/√T) for Algorithm 5 (IL-correct sampling τ_n ∼ p(·; w_n)), Δ₀ = F(θ₁) ≈ {:.6}, δ = xΔ₀/(GN) ≈ {:.6} (exact rationals in the details), on the instance of largest X̄/B found: {}",
        Scalar::to_f64(&s.delta0),
        Scalar::to_f64(&s.delta),
        cand.describe()
    );
    let builder = Check::builder(id, RESULT, claim, role)
        .assumptions([
            format!(
                "G² ≥ E‖g‖² and σ² ≥ Var g on the hull {:?} of every iterate (it holds every w_n)",
                c.hull
            ),
            "E[g_n | w_n] = ∇F(w_n): τ_n ∼ p(·; w_n) (E11)".into(),
            "Δ₀ ≥ F(θ₁) − F* (F ≥ 0)".into(),
        ])
        .constants(c.constants.to_vec())
        .erratum("E11, E12, E13");
    let x = c.x_bar.mid();
    if g2_value > cand.g * cand.g {
        return builder
            .measured(Measured::exact(x))
            .details(format!(
                "G² = {} < the certified sup E‖g‖² = {g2_value}: the theorem does not apply",
                cand.g * cand.g
            ))
            .decided(Method::Rigorous, Verdict::Inconclusive);
    }
    let b = bound(inputs, s, delta0, s2.max(0.0).sqrt());
    let claimed = b * scale;
    let verdict = super::enclosure_verdict(&c.x_bar, claimed);
    let sigma_share = bound(inputs, s, delta0, s2.max(0.0).sqrt()) - bound(inputs, s, delta0, 0.0);
    builder
        .bound(claimed)
        .measured(Measured::exact(x).with_interval(c.x_bar.inf(), c.x_bar.sup()))
        .tightness(x / claimed)
        .details(format!(
            "Δ₀ = {}, δ = {}; T = {}, K = {}, M = {}, D = δ/T; X̄ = E X enclosed over {} of the blocks' first draws, each block's integral over s by a {CELLS}-cell interval Riemann sum: X̄ ∈ [{:.8}, {:.8}]; B = {b:.6} (σ² = {s2:.3e}, σ term {:.1} % of B), X̄/B = {:.4}; search: seeded random search, seed {}, {} random candidates, then {} pattern-search evaluations from the best {STARTS}, at most {} paths each (estimated X̄/B = {:.4})",
            s.delta0,
            s.delta,
            p.t,
            p.k,
            p.m,
            match c.paths {
                1 => "the one path".to_string(),
                n => format!("all {n} paths"),
            },
            c.x_bar.inf(),
            c.x_bar.sup(),
            100.0 * sigma_share / b,
            x / b,
            budget.seed,
            budget.random,
            budget.refine,
            budget.max_paths,
            c.estimate.ratio,
        ))
        .decided(Method::Rigorous, verdict)
}

/// The search's candidates and the first one certified (of the best `tries`), under `inputs`'
/// oracle.
pub fn prepare_from(
    found: &[Estimate],
    inputs: &TableInputs,
    budget: &Budget,
    tol: f64,
    max_boxes: usize,
    tries: usize,
) -> Prepared<Certified> {
    first_certified(found, tries, |e| certify(e, inputs, budget, tol, max_boxes))
}

/// Row 3b.tight (3b.tight.noisy) and its B ÷ 2 control (stated always over every instance, where
/// X̄/B ≥ ½ was reached over the noisy ones), or one inconclusive row saying why no candidate was
/// certified.
pub fn rows_from(
    inputs: &TableInputs,
    budget: &Budget,
    noise: Noise,
    p: &Prepared<Certified>,
) -> Vec<Check> {
    match &p.certified {
        Some(c) => with_control(
            |scale| row(c, inputs, scale, budget, noise),
            noise == Noise::Any,
            &p.passed_over,
        ),
        None => vec![
            Check::builder(
                format!("3b.tight{}", noise.suffix()),
                RESULT,
                "a tight instance of Theorem 3.8's bound",
                Role::Corrected,
            )
            .details(format!(
                "no candidate certified ({} feasible found): {}",
                p.found,
                p.passed_over.join("; ")
            ))
            .decided(Method::Rigorous, Verdict::Inconclusive),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::walk::grad;
    use super::*;
    use crate::bounds::o2nc_theorem;
    use crate::checks::statistical::CONTROL_SCALE;
    use crate::checks::tight::Sizes;
    use crate::checks::tight::instance::Instance;
    use crate::inputs::Formulas;
    use ilopt::algo::ConfigNumber;
    use ilopt::algo::config::{AlgorithmConfig, RunConfig};
    use ilopt::algo::o2nc::O2ncConfig;
    use ilopt::algo::{IterationMetrics, Runner, StoppingRule};
    use ilopt::exact::forward::forward;
    use ilopt::problem::EstimatorForm;
    use ilopt::toy::ToyProblem;
    use std::cell::RefCell;

    fn q(n: i64, d: i64) -> BigRational {
        BigRational::from_ratio(n, d)
    }

    /// A noisy candidate with T = 2 and K = 3 blocks: M(0, 0, 0, 3), c = 1, θ₁ = 3/2 (the
    /// family of the noisy search's winner).
    fn noisy() -> Candidate {
        Candidate {
            instance: Instance {
                mu_a: q(0, 1),
                p0: q(0, 1),
                p1: q(0, 1),
                horizon: 3,
                c: q(1, 1),
                theta1: vec![q(3, 2)],
                k: 6,
            },
            g: 2.0,
            x: 2.5,
        }
    }

    /// The walk is the kit's Algorithm 5: R = 40,000 seeded runs of `ilopt::algo::o2nc` with the
    /// same exact inputs, X computed from ∇F at the w_n the runs report, average within 4
    /// standard errors of the walk's enclosure of E X. The comparison can fail: the walk with a
    /// radius D four times too large leaves that band.
    #[test]
    fn the_walk_agrees_with_seeded_runs_of_the_kits_algorithm_5() {
        let c = noisy();
        let setting = c.setting().unwrap();
        assert_eq!((setting.params.t, setting.params.k), (2, 3));
        let mdp = c.instance.mdp().unwrap();
        let inputs = TableInputs::thesis();
        let theta1 = Interval::from_rational(&c.instance.theta1[0]);
        let walk = o2nc_mean(&mdp, &theta1, &setting, &inputs, 1296, CELLS).unwrap();
        let config = O2ncConfig {
            budget: c.instance.k,
            delta: ConfigNumber::Exact(setting.delta.clone()),
            g: ConfigNumber::Exact(setting.g.clone()),
            delta0: ConfigNumber::Exact(setting.delta0.clone()),
            form: EstimatorForm::Causal,
        };
        let fp = ToyProblem::<f64>::new(&mdp);
        let mut pf = ToyProblem::<f64>::new(&mdp);
        let runs = 40_000u64;
        let (mut sum, mut sum_sq) = (0.0, 0.0);
        for seed in 0..runs {
            let cfg = RunConfig {
                algorithm: AlgorithmConfig::O2nc(config.clone()),
                theta0: vec![ConfigNumber::Exact(c.instance.theta1[0].clone())],
                seed,
                stop: StoppingRule::iterations(setting.params.m + 1),
            };
            let ws = RefCell::new(vec![]);
            let observer = |m: &IterationMetrics<f64>| {
                if let Some(w) = &m.evaluated_at {
                    ws.borrow_mut().push(w[0]);
                }
            };
            Runner::new(cfg.stop.clone())
                .unwrap()
                .keep_history(false)
                .with_observer(observer)
                .run_config(&cfg, &mut pf)
                .unwrap();
            let ws = ws.into_inner();
            assert_eq!(ws.len() as u64, setting.params.m);
            let x = ws
                .chunks(2)
                .map(|b| (grad(&fp, &b[0]).unwrap() + grad(&fp, &b[1]).unwrap()).abs() / 2.0)
                .sum::<f64>()
                / 3.0;
            sum += x;
            sum_sq += x * x;
        }
        let mean = sum / runs as f64;
        let se = ((sum_sq / runs as f64 - mean * mean) / (runs - 1) as f64).sqrt();
        println!(
            "walk X̄ ∈ [{:.6}, {:.6}], runs {mean:.6} ± {se:.6}",
            walk.mean.inf(),
            walk.mean.sup()
        );
        assert!(
            walk.mean.inf() - 4.0 * se <= mean && mean <= walk.mean.sup() + 4.0 * se,
            "{mean} {se} {:?}",
            walk.mean
        );
        // The walk's value with the errors above is far outside the band.
        let at_end = {
            let mut s2 = setting.clone();
            s2.params.d = s2.params.d.clone() * q(4, 1);
            o2nc_mean(&mdp, &1.5f64, &s2, &inputs, 1296, CELLS)
                .unwrap()
                .mean
        };
        assert!((at_end - mean).abs() > 10.0 * se, "{at_end} {mean} {se}");
    }

    /// With T = 1 (x ≤ 1) Δ_n = 0 at every step, so E X = |∇F(θ₁)| on one path.
    #[test]
    fn one_step_blocks_never_move() {
        let c = Candidate { x: 0.75, ..noisy() };
        let setting = c.setting().unwrap();
        assert_eq!(setting.params.t, 1);
        let mdp = c.instance.mdp().unwrap();
        let run = o2nc_mean::<f64>(&mdp, &1.5, &setting, &TableInputs::thesis(), 1, CELLS).unwrap();
        let exact_grad = forward(&ToyProblem::<BigRational>::new(&mdp), &[q(3, 2)])
            .unwrap()
            .gradient[0]
            .clone();
        assert_eq!(run.paths, 1);
        assert_eq!(run.hull, vec![[1.5, 1.5]]);
        assert!((run.mean - Scalar::to_f64(&exact_grad).abs()).abs() < 1e-15);
        // x = 8: T = min(⌈8^{2/3}⌉, ⌊6/2⌋) = 3, refused.
        let longer = Candidate { x: 8.0, ..noisy() };
        assert!(longer.setting().unwrap_err().contains("T = 3"));
    }

    fn with_theorem(o2nc_theorem: fn(f64, f64, f64, f64, O2ncParams) -> f64) -> TableInputs {
        TableInputs {
            formulas: Formulas {
                o2nc_theorem,
                ..Formulas::THESIS
            },
            ..TableInputs::thesis()
        }
    }

    fn half(d0: f64, d: f64, g: f64, s: f64, p: O2ncParams) -> f64 {
        0.5 * o2nc_theorem(d0, d, g, s, p)
    }

    fn control_scaled(d0: f64, d: f64, g: f64, s: f64, p: O2ncParams) -> f64 {
        CONTROL_SCALE * o2nc_theorem(d0, d, g, s, p)
    }

    /// At the quick size both rows (every instance, and the noisy ones) hold with X̄/B ≥ ½ and
    /// their B ÷ 2 controls are refuted; Theorem 3.8's bound halved, or scaled as row 3b.ctl's
    /// control, refutes both rows: they can fail at their size.
    #[test]
    fn the_quick_rows_hold_their_controls_are_refuted_and_a_halved_bound_turns_them() {
        let s = Sizes::quick();
        let thesis = TableInputs::thesis();
        for noise in [Noise::Any, Noise::Required] {
            let found = search(noise, s.o2nc);
            let p = prepare_from(&found, &thesis, &s.o2nc, s.tol, s.max_boxes, s.tries);
            let rows = rows_from(&thesis, &s.o2nc, noise, &p);
            for r in &rows {
                println!(
                    "{} {:?} {:?}: {}\n  {}",
                    r.id, r.verdict, r.tightness, r.claim, r.details
                );
            }
            let id = format!("3b.tight{}", noise.suffix());
            let ids: Vec<&str> = rows.iter().map(|r| r.id.as_str()).collect();
            assert_eq!(ids, [id.clone(), format!("{id}.ctl")], "{rows:#?}");
            assert_eq!(rows[0].verdict, Verdict::Holds, "{}", rows[0].details);
            assert!(rows[0].tightness.unwrap() >= 0.5, "{}", rows[0].details);
            assert_eq!(rows[1].verdict, Verdict::Fails, "{}", rows[1].details);
            for wrong in [half, control_scaled] {
                let turned = rows_from(&with_theorem(wrong), &s.o2nc, noise, &p);
                assert_eq!(turned[0].verdict, Verdict::Fails, "{}", turned[0].details);
            }
        }
    }
}
