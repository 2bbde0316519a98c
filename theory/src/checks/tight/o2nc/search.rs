//! The seeded search for the tight instance of Theorem 3.8's bound: candidates (an instance of
//! the M family, the budget N, the algorithm's G and x = GNδ/Δ₀), their exact inputs to
//! Algorithm 5, and their X̄/B estimated in `f64`.

use super::bound;
use super::setting::Setting;
use super::walk::o2nc_mean;
use crate::checks::tight::instance::{Instance, exact};
use crate::checks::tight::search::{
    Budget, GRID, MARGIN, MAX_WIDTH, NOISE_SHARE, Noise, SPACING, dyadic, list_moves, nudged,
    random_instance, random_then_pattern,
};
use crate::inputs::TableInputs;
use ilopt::algo::ConfigNumber;
use ilopt::algo::o2nc::O2ncConfig;
use ilopt::exact::enumerate::moments;
use ilopt::exact::forward::forward;
use ilopt::problem::EstimatorForm;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use rand::Rng;
use rand::rngs::StdRng;

/// Cells of the search's midpoint rule (an estimate that only ranks candidates).
pub const SEARCH_CELLS: usize = 8;
/// The largest x = GNδ/Δ₀ the search draws: 181/64, the largest multiple of 2⁻⁶ with T ≤ 2
/// (T = ⌈x^{2/3}⌉ ≤ 2 iff x ≤ 2√2 ≈ 2.8284).
pub const X_MAX: f64 = 2.828125;

/// A candidate: an instance of the M family (its `k` is the budget N), the algorithm's G and
/// x = GNδ/Δ₀, both short dyadic rationals stored as `f64`.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The instance; `instance.k` is Algorithm 5's budget N.
    pub instance: Instance,
    /// G > 0, the algorithm's bound on √E‖g‖².
    pub g: f64,
    /// x = GNδ/Δ₀, which sets δ (T ≤ 2 iff x ≤ 2√2).
    pub x: f64,
}

impl Candidate {
    /// Algorithm 5's exact inputs.
    ///
    /// # Errors
    /// If F(θ₁) = 0 (nothing to descend), the configuration is invalid, or T > 2.
    pub fn setting(&self) -> Result<Setting, String> {
        let mdp = self.instance.mdp()?;
        let delta0 = forward(&ToyProblem::<BigRational>::new(&mdp), &self.instance.theta1)
            .map_err(|e| e.to_string())?
            .objective;
        if !delta0.is_certainly_positive() {
            return Err(format!("F(θ₁) = {delta0}: Δ₀ must be positive"));
        }
        let g = exact(self.g);
        let n = BigRational::from_i64(self.instance.k as i64);
        let delta = exact(self.x) * &delta0 / (g.clone() * n);
        let config = O2ncConfig {
            budget: self.instance.k,
            delta: ConfigNumber::Exact(delta.clone()),
            g: ConfigNumber::Exact(g.clone()),
            delta0: ConfigNumber::Exact(delta0.clone()),
            form: EstimatorForm::Causal,
        };
        let params = config.parameters().map_err(|e| e.to_string())?;
        if params.t > 2 {
            return Err(format!(
                "T = {}: blocks longer than 2 are not enumerable",
                params.t
            ));
        }
        Ok(Setting {
            delta0,
            delta,
            g,
            params,
        })
    }

    /// `M(…), c, θ₁, N, G, x` as the rows print it.
    pub fn describe(&self) -> String {
        self.instance.describe().replace(", K = ", ", N = ")
            + &format!(", G = {}, x = GNδ/Δ₀ = {}", exact(self.g), exact(self.x))
    }
}

/// A candidate's estimated X̄/B: X̄ over every path by the midpoint rule, B with σ² estimated on
/// the hull (one coordinate).
pub type Estimate = crate::checks::tight::search::Estimate<Candidate>;

/// max E‖g‖² and max Var g on the grid of the hull (X1, in `f64`).
fn moment_estimates(mdp: &ToyMdp, hull: [f64; 2]) -> Result<(f64, f64), String> {
    let p = ToyProblem::<f64>::new(mdp);
    let n = GRID.max(((hull[1] - hull[0]) / SPACING).ceil() as usize + 1);
    let (mut g2, mut v) = (0.0f64, 0.0f64);
    for i in 0..n {
        let x = hull[0] + (hull[1] - hull[0]) * i as f64 / (n - 1) as f64;
        let m = moments(&p, &[x]).map_err(|e| e.to_string())?;
        g2 = g2.max(m.second_moment);
        v = v.max(m.variance);
    }
    Ok((g2, v))
}

/// Evaluate a candidate: X̄ over every path by the midpoint rule, B with σ² estimated on the
/// hull; `None` if it cannot be run (T > 2, too many paths, a hull wider than [`MAX_WIDTH`]), its
/// G is below the estimated √max E‖g‖² on the hull (with [`MARGIN`]), or `noise` is
/// [`Noise::Required`] and the run is not noisy: it needs T = 2 and K ≥ 2 blocks (so that the
/// oracle's noise moves the iterates X̄ averages over) and the σ term at least [`NOISE_SHARE`]
/// of B.
pub fn evaluate(c: &Candidate, noise: Noise, max_paths: u64) -> Option<Estimate> {
    let setting = c.setting().ok()?;
    if noise == Noise::Required && (setting.params.t < 2 || setting.params.k < 2) {
        return None;
    }
    let mdp = c.instance.mdp().ok()?;
    let theta1 = Scalar::to_f64(&c.instance.theta1[0]);
    let inputs = TableInputs::thesis();
    let run = o2nc_mean(&mdp, &theta1, &setting, &inputs, max_paths, SEARCH_CELLS).ok()?;
    let hull = run.hull[0];
    let width = hull[1] - hull[0];
    if width.is_nan() || width > MAX_WIDTH {
        return None;
    }
    let (g2, var) = moment_estimates(&mdp, hull).ok()?;
    if g2 * MARGIN > c.g * c.g {
        return None;
    }
    let delta0 = Scalar::to_f64(&setting.delta0);
    let b = bound(&inputs, &setting, delta0, var.max(0.0).sqrt());
    let share = (b - bound(&inputs, &setting, delta0, 0.0)) / b;
    if noise == Noise::Required && (share.is_nan() || share < NOISE_SHARE) {
        return None;
    }
    let ratio = run.mean / b;
    ratio.is_finite().then(|| Estimate {
        candidate: c.clone(),
        x_bar: run.mean,
        bound: b,
        ratio,
        hull: run.hull,
        paths: run.paths,
        sigma2: var,
    })
}

/// The budgets N drawn and moved between (T = 2 gives K = ⌊N/2⌋ blocks).
const NS: [u64; 9] = [4, 5, 6, 8, 12, 16, 24, 32, 64];

/// A random candidate: an instance as the other tight searches draw it ([`random_instance`]),
/// then N from [`NS`], G = u·√max E‖g‖² on [θ₁ − 1, θ₁ + 1] with u ∈ [1, 3/2], and
/// x ∈ [1/2, [`X_MAX`]].
fn random_candidate(rng: &mut StdRng) -> Option<Candidate> {
    let mut instance = random_instance(rng, 0, 2..=3, 1);
    instance.k = NS[rng.random_range(0..NS.len())];
    let t = Scalar::to_f64(&instance.theta1[0]);
    let (g2, _) = moment_estimates(&instance.mdp().ok()?, [t - 1.0, t + 1.0]).ok()?;
    let g = dyadic(rng.random_range(1.0..1.5) * g2.sqrt());
    let x = dyadic(rng.random_range(0.5..X_MAX));
    Some(Candidate { instance, g, x })
}

/// The pattern search's moves at scale h: θ₁ ± h, G and x × (1 ± h/4), the adjacent N and c.
fn moves(c: &Candidate, h: f64) -> Vec<Candidate> {
    let mut out = vec![];
    for t in nudged(&c.instance.theta1[0], h) {
        let mut n = c.clone();
        n.instance.theta1[0] = t;
        out.push(n);
    }
    for f in [1.0 - h / 4.0, 1.0 + h / 4.0] {
        let mut n = c.clone();
        n.g = dyadic(c.g * f);
        out.push(n);
        let mut n = c.clone();
        n.x = dyadic(c.x * f).min(X_MAX);
        out.push(n);
    }
    out.extend(
        list_moves(&c.instance, &NS)
            .into_iter()
            .map(|instance| Candidate {
                instance,
                ..c.clone()
            }),
    );
    out
}

/// The seeded search ([`random_then_pattern`]) over the M family, N, G and x, among the
/// instances `noise` admits.
pub fn search(noise: Noise, budget: Budget) -> Vec<Estimate> {
    random_then_pattern(
        budget,
        random_candidate,
        |c| evaluate(c, noise, budget.max_paths),
        moves,
        |e| (e.ratio, &e.candidate),
    )
}
