//! The whole theorem-check suite, at a quick size (tests, the appendix's default) or the full size.

use crate::check::Check;
use crate::checks::montecarlo::McSettings;
use crate::checks::{constants, o2nc_formula, schedule, second_toy, statistical, thm31, unbiased};
use crate::global::{GlobalConstants, GlobalSizes};
use crate::stats::bonferroni;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, parse_exact};
use ilopt::toy::ToyMdp;

/// How large the suite runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// Minutes on 2 cores at most.
    Quick,
    /// The thesis's scale.
    Full,
}

/// Sizes per profile.
#[derive(Debug, Clone, Copy)]
pub struct Sizes {
    /// Largest k for the schedule conditions.
    pub schedule_k: u64,
    /// Random parameter sets for (3.71).
    pub o2nc_cases: usize,
    /// Branch-and-bound tolerance.
    pub bnb_tol: f64,
    /// Monte-Carlo runs of checks 1 and 3 (and their controls).
    pub runs: usize,
    /// SGD iterations K.
    pub sgd_k: u64,
    /// O2NC budget N.
    pub o2nc_n: u64,
    /// STORM iterations K (check 2c and its controls); (3.60\*) is below sup ‖∇F‖² only for
    /// K ≳ 1.3·10⁴ on M1, so smaller K cannot refute it.
    pub storm_k: u64,
    /// Monte-Carlo runs of check 2 (and its controls).
    pub storm_runs: usize,
    /// Branch-and-bound tolerance on L̃² (½ sup |∂²V_IS/∂θ′²|).
    pub l_tilde_tol: f64,
    /// Branch-and-bound box budget per chart region for L̃.
    pub l_tilde_boxes: usize,
}

/// Family-wise false-alarm probability of the statistical checks (Bonferroni-split).
pub const FAMILY_ALPHA: f64 = 0.01;
/// Number of statistical claims of the thesis in the suite (for Bonferroni): rows 1, 3b, 2c,
/// 2c.pd, 2d, 2e, 2e.pd, 3d. The negative controls take no share (a false alarm cannot occur on a
/// claim that is false); rows 5e carry their own level ([`thm31::DAGGER_QUICK`]).
pub const STATISTICAL_CLAIMS: usize = 8;

impl Profile {
    /// The sizes of this profile.
    pub fn sizes(self) -> Sizes {
        match self {
            Profile::Quick => Sizes {
                schedule_k: 2_000,
                o2nc_cases: 20_000,
                bnb_tol: 1e-2,
                runs: 1000,
                sgd_k: 1000,
                o2nc_n: 2000,
                storm_k: 20_000,
                storm_runs: 100,
                l_tilde_tol: 1.0,
                l_tilde_boxes: 20_000,
            },
            Profile::Full => Sizes {
                schedule_k: 100_000,
                o2nc_cases: 200_000,
                bnb_tol: 1e-4,
                runs: 2000,
                sgd_k: 1000,
                o2nc_n: 20_000,
                storm_k: 30_000,
                storm_runs: 500,
                l_tilde_tol: 0.1,
                l_tilde_boxes: 200_000,
            },
        }
    }
}

fn q(s: &str) -> BigRational {
    parse_exact(s).expect("constant")
}

/// The toy MDP M1 (P2', c = 1/2), as in `examples/toy/m1-tied.json`.
pub fn m1_tied() -> ToyMdp {
    ToyMdp::m_family(
        q("1/2"),
        q("1/2"),
        q("1"),
        3,
        ilopt::toy::PolicyKind::TiedSoftmax,
        Some(q("1/2")),
    )
    .expect("valid")
}

/// The exact, rigorous and toy Monte-Carlo part of the suite (checks 1, 2a–2d, 3, 4, 5, 8, 8b,
/// and the Monte-Carlo negative controls of [`statistical`]).
///
/// # Errors
/// A message if a rigorous constant cannot be enclosed.
pub fn exact_suite(profile: Profile, domain: &[[f64; 2]]) -> Result<Vec<Check>, String> {
    let s = profile.sizes();
    let m1 = m1_tied();
    let mut rows = schedule::rows(s.schedule_k);
    rows.push(o2nc_formula::row(s.o2nc_cases, 1));
    let thetas = ["0", "1/3", "-2", "5/2", "1", "2"];
    let cases: Vec<(ToyMdp, Vec<BigRational>)> =
        thetas.iter().map(|t| (m1.clone(), vec![q(t)])).collect();
    let pairs: Vec<(ToyMdp, Vec<BigRational>, Vec<BigRational>)> = thetas
        .iter()
        .zip(thetas.iter().rev())
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (m1.clone(), vec![q(a)], vec![q(b)]))
        .collect();
    rows.push(unbiased::estimator(&cases));
    rows.push(unbiased::old_point(&pairs, Some(Weighting::Trajectory)));
    rows.push(unbiased::old_point(&pairs, Some(Weighting::PerDecision)));
    rows.push(unbiased::old_point(&pairs, None));
    // Algorithm 5's hyper-parameters G = 2 ≥ √(sup E g²) ≈ 1.87 and Δ₀ = B_F = 1/2; the
    // printed Algorithm 4 in exact rationals for 3 steps (the rationals grow ≈ 8× per step).
    rows.push(unbiased::printed_algorithm_5_visited(
        &m1,
        0.0,
        40,
        (1, 10),
        2.0,
        0.5,
        0,
    ));
    rows.push(unbiased::printed_algorithm_4_visited(
        &m1,
        &q("0"),
        (1, 20),
        (1, 2),
        3,
        0,
    ));
    let dagger = match profile {
        Profile::Quick => thm31::DAGGER_QUICK,
        Profile::Full => thm31::DAGGER_FULL,
    };
    for (i, inst) in thm31::instances().iter().enumerate() {
        rows.extend(
            thm31::rows_with_dagger(inst, dagger)
                .into_iter()
                .map(|mut r| {
                    r.id = format!("{}.{}", r.id, i + 1);
                    r
                }),
        );
    }
    let k = constants::compute(&m1, &[q("0")], Some(&q("7/8")), domain, s.bnb_tol, 200_000)
        .map_err(|e| e.to_string())?;
    let coverage = crate::recheck::coverage_for(profile == Profile::Full);
    rows.push(k.row_with("M1 (P2', c = 1/2, θ₁ = 0)", domain, coverage, "8"));
    let mc = McSettings {
        runs: s.runs,
        alpha: bonferroni(FAMILY_ALPHA, STATISTICAL_CLAIMS),
    };
    let g = global_constants(&m1, s)?;
    rows.extend(statistical::toy_rows(&m1, &k, &g, s, mc));
    rows.push(g.row_with("M1 (P2', c = 1/2, θ₁ = 0)", coverage));
    rows.extend(second_toy::rows(second_toy::sizes(
        profile == Profile::Full,
    ))?);
    rows.extend(statistical::storm_rows(&m1, &g, s, mc.alpha));
    Ok(rows)
}

/// The constants of the STORM checks over all of ℝ (ℝ² for L̃), for M1 at θ₁ = 0.
///
/// # Errors
/// A message if an enclosure fails.
pub fn global_constants(m1: &ToyMdp, s: Sizes) -> Result<GlobalConstants, String> {
    GlobalConstants::compute(
        m1,
        &[q("0")],
        Some(&q("7/8")),
        GlobalSizes {
            tol: s.bnb_tol,
            max_boxes: 200_000,
            l_tilde_tol: s.l_tilde_tol,
            l_tilde_boxes: s.l_tilde_boxes,
        },
    )
    .map_err(|e| e.to_string())
}

/// The whole table: [`exact_suite`] on the box holding every SGD iterate of check 1 (η = 0.05,
/// K = 1000, G_∞ in closed form), then [`real_environments`].
///
/// # Errors
/// As the two parts.
pub fn whole_table(profile: Profile) -> Result<Vec<Check>, String> {
    let r = 1000.0 * 0.05 * crate::constants::tied_softmax_g_inf_closed_form(3, 0.5);
    let mut rows = exact_suite(profile, &[[-r, r]])?;
    rows.extend(real_environments(profile)?);
    Ok(rows)
}

/// Checks 6 and 7 on CartPole (softmax learner, LQR expert; T = 500 with resets) and the
/// obstacle task (speed-limited linear-Gaussian learner, velocity-obstacle expert; T = 200,
/// absorbing), the thesis's fixed-horizon objectives the chapter-4 experiments use, plus the
/// obstacle task's episodic objective as a labelled control. See `checks::real_env`.
///
/// # Errors
/// A message if a task cannot be built or a roll-out fails.
pub fn real_environments(profile: Profile) -> Result<Vec<Check>, String> {
    use crate::checks::estimated::{EstimateSizes, sgd_row};
    use crate::checks::real_env::{
        Mutation, RealSizes, TaskSetup, cartpole_fixed, cartpole_theta, obstacle_problem,
        obstacle_theta, task_rows,
    };
    use ilopt::task::{AfterEnd, Horizon};
    let full = profile == Profile::Full;
    let cp = cartpole_fixed()?;
    let ob = obstacle_problem(REAL_SIGMA, Horizon::fixed(200, AfterEnd::Absorb))?;
    let ob_episodic = obstacle_problem(REAL_SIGMA, Horizon::Episodic)?;
    let (cs, os) = real_sizes(profile);
    let mut rows = vec![];
    let es = |rho: f64, spread: f64, eta0: f64| EstimateSizes {
        m: if full { 400 } else { 100 },
        probes: 4,
        rho,
        spread,
        runs: if full { 20 } else { 4 },
        k: 200,
        stride: 20,
        eta0,
    };
    rows.push(sgd_row(
        "CartPole, fixed-500-reset, softmax learner",
        &cp,
        &cartpole_theta(),
        es(0.1, 0.5, 0.01),
    ));
    rows.push(sgd_row(
        "obstacle, fixed-200-absorb, linear-Gaussian learner",
        &ob,
        &obstacle_theta(),
        es(0.005, 0.01, 0.01),
    ));
    rows.extend(task_rows(
        "a",
        &TaskSetup {
            name: "CartPole, fixed-500-reset".into(),
            problem: &cp,
            theta: cartpole_theta(),
            eta: CARTPOLE_STORM_ETA,
            controls: vec![Mutation::DropCrossReset, Mutation::Reversed],
            note: String::new(),
        },
        cs,
    )?);
    rows.extend(task_rows(
        "b",
        &TaskSetup {
            name: "obstacle, fixed-200-absorb".into(),
            problem: &ob,
            theta: obstacle_theta(),
            eta: OBSTACLE_STORM_ETA,
            controls: vec![Mutation::DropTail, Mutation::DropEndScore],
            note: OBSTACLE_Z_TREND.into(),
        },
        os,
    )?);
    if full {
        rows.extend(task_rows(
            "e",
            &TaskSetup {
                name: "obstacle, episodic (control objective)".into(),
                problem: &ob_episodic,
                theta: obstacle_theta(),
                eta: OBSTACLE_STORM_ETA,
                controls: vec![Mutation::Reversed],
                note: OBSTACLE_Z_TREND.into(),
            },
            // The episodic F is far from quadratic at h = 0.05 (Richardson's O(h²) term ≈ 350
            // of its s.e., and the oracle "fails" with z ≈ 23 growing like √N: the reference's
            // bias); h = 0.01 resolves it.
            RealSizes {
                h: 0.01,
                n_oracle: 8000,
                n_fd: 8000,
                ..os
            },
        )?);
    }
    Ok(rows)
}

/// What the obstacle task's z-trend of the former row 6 was (reproduced by
/// `tests/real_env_explore.rs::explore_old_obstacle`).
pub const OBSTACLE_Z_TREND: &str = "; the former row's z-trend (worst z 1.21 → 2.44 → 3.08 at N = 18, 75, 300; episodic, σ = 0.05, h = 0.005, N′ = 200) was not a bias: re-run with this statistic it recurs at that size (1.79 → 2.15 → 3.20, nested subsamples against one fixed, noisy reference), and vanishes at 16× the size (N = 4800, N′ = 3200: 2.85 → 2.50 → 2.26) and at h/5 (2.61 → 2.49 → 2.18); the reference's own bias shows only at h = 0.02 (2.64 → 2.59 → 4.84), an O(h²)-and-beyond finite-difference bias, not of the oracle. The same signature, larger, on the episodic control row (6e, --full) at h = 0.05 (worst z 5.1 → 12.0 → 22.9 at N = 2000, 8000, 32000, Richardson's O(h²) term 346 of its s.e.): the reference is biased where the episodic F is not smooth at the scale h; at h = 0.01 and 0.002 (N = N′ = 8000) worst z 2.05 and 2.71, no trend. On the fixed-horizon row, h = 0.01 (N = N′ = 8000) gives worst z 1.81 (1.45 → 1.34 → 1.81), agreeing with h = 0.05";

/// The obstacle learner's σ in the real-environment checks (the experiments' fixed-horizon setting).
pub const REAL_SIGMA: f64 = 0.1;
/// The old point of the STORM rows on CartPole: θ′ = θ − η∇F(θ) with this η (‖θ′ − θ‖ ≈ 0.018, inside the
/// range of the chapter-4 STORM steps, η ∈ [10⁻⁶, 10⁻²] times gradients of norm ~10³).
pub const CARTPOLE_STORM_ETA: f64 = 3e-4;
/// The same on the obstacle task (‖θ′ − θ‖ ≈ 0.004; at 10× that step the trajectory weights over
/// 200 decisions degenerate, see the IS rows' effective sample size).
pub const OBSTACLE_STORM_ETA: f64 = 1e-4;

/// Sizes of check 6 per profile: (CartPole, obstacle).
pub fn real_sizes(
    profile: Profile,
) -> (
    crate::checks::real_env::RealSizes,
    crate::checks::real_env::RealSizes,
) {
    use crate::checks::real_env::RealSizes;
    let full = profile == Profile::Full;
    let alpha = 1e-3;
    (
        RealSizes {
            n_oracle: if full { 24_000 } else { 6000 },
            n_fd: if full { 12_000 } else { 3000 },
            h: 0.1,
            alpha,
        },
        RealSizes {
            n_oracle: if full { 32_000 } else { 8000 },
            n_fd: if full { 32_000 } else { 8000 },
            h: 0.05,
            alpha,
        },
    )
}
