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
/// 2c.pd, 2d. The negative controls take no share (a false alarm cannot occur on a claim that is
/// false); rows 5e carry their own level ([`thm31::DAGGER_QUICK`]).
pub const STATISTICAL_CLAIMS: usize = 5;

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
    rows.extend(statistical::toy_rows(&m1, &k, s, mc));
    let g = global_constants(&m1, s)?;
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

/// Check 6 on CartPole (softmax learner, LQR expert) and the obstacle task (linear-Gaussian
/// learner, velocity-obstacle expert), plus the obstacle task's negative control.
///
/// # Errors
/// A message if a task cannot be built.
pub fn real_environments(profile: Profile) -> Result<Vec<Check>, String> {
    use crate::checks::real_env::{RealSizes, row};
    use ilopt::policy::{LinearGaussian, Softmax};
    use ilopt::task::TaskProblem;
    use ilopt::task::cartpole::{self, CartPoleTask};
    use ilopt::task::obstacle::{self, ObstacleTask};
    use nalgebra::DVector;
    let scale = if profile == Profile::Full { 10 } else { 1 };
    let cp = TaskProblem {
        task: CartPoleTask::with_lqr().map_err(|e| e.to_string())?,
        policy: Softmax::new(2, cartpole::FEATURES).map_err(|e| e.to_string())?,
        horizon: ilopt::task::Horizon::Episodic,
    };
    let cp_theta = DVector::from_vec(vec![0.0, 0.0, -2.0, -0.5, 0.0, 0.0, 0.0, 2.0, 0.5, 0.0]);
    let ob = TaskProblem {
        task: ObstacleTask::thesis().map_err(|e| e.to_string())?,
        policy: LinearGaussian::new(2, obstacle::FEATURES, 0.05).map_err(|e| e.to_string())?,
        horizon: ilopt::task::Horizon::Episodic,
    };
    let mut ob_theta = DVector::zeros(2 * obstacle::FEATURES);
    ob_theta[0] = 0.02;
    ob_theta[obstacle::FEATURES + 1] = 0.02;
    let alpha = 1e-3;
    let cs = RealSizes {
        n_oracle: 400 * scale,
        n_fd: 300 * scale,
        h: 0.05,
        alpha,
    };
    let os = RealSizes {
        n_oracle: 300 * scale,
        n_fd: 200 * scale,
        h: 0.005,
        alpha,
    };
    use crate::checks::estimated::{EstimateSizes, sgd_row};
    let es = |rho: f64, spread: f64, eta0: f64| EstimateSizes {
        m: 100 * scale,
        probes: 4,
        rho,
        spread,
        runs: 4 * scale,
        k: 200,
        stride: 20,
        eta0,
    };
    Ok(vec![
        sgd_row(
            "CartPole, softmax learner",
            &cp,
            &cp_theta,
            es(0.1, 0.5, 0.01),
        ),
        sgd_row(
            "obstacle, linear-Gaussian learner",
            &ob,
            &ob_theta,
            es(0.005, 0.01, 0.01),
        ),
        row("CartPole, softmax learner", &cp, &cp_theta, None, cs),
        row(
            "obstacle, linear-Gaussian learner",
            &ob,
            &ob_theta,
            None,
            os,
        ),
        row(
            "obstacle, linear-Gaussian learner",
            &ob,
            &ob_theta,
            Some(&DVector::zeros(ob_theta.len())),
            os,
        ),
    ])
}
