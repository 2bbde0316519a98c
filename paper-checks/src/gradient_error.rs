//! Fig. 4.2: does the mean of N oracle estimates (eq. 3.15) converge to ∇F at the 1/√N rate?
//!
//! Two routes, each with an *independent* reference:
//!
//! - **(a) toy MDP, exact reference.** ∇F(θ) is computed in exact rationals by the exact engine's
//!   forward DP (X2, `ilopt::exact::forward`, the route `ilopt toy eval` prints as `gradient`), and
//!   σ² = E‖g‖² − ‖∇F‖² exactly from the enumeration's second moment (X1). The estimates are
//!   sampled in f64 through the toy's [`IlProblem`] oracle (the one the algorithms call). The
//!   reference has no noise.
//! - **(b) the obstacle task** under the thesis's fixed-horizon objective (T = 200 decisions,
//!   absorbing ends: success 0, crash (2·v_max)² per remaining step), the linear-Gaussian learner
//!   over the 9 basic features at the profile's σ and θ. The reference is the mean of M
//!   independent estimates (its own seed stream); σ² is estimated from the same M estimates
//!   (unbiased sample variance, trace), and the reference's own error variance σ̂²/M is shown as a
//!   floor and subtracted from the mean squared error before the slope is fitted
//!   (E‖ḡ_N − R‖² = σ²/N + σ²/M for an independent reference R).
//!
//! **Repetitions.** Repetition r draws one stream of estimates from its own derived seed; the
//! error at N is that of the mean of the stream's first N estimates (nested means, as an
//! experimenter adding samples would see). RMSE(N) = √(mean over repetitions of ‖ḡ_N − ref‖²),
//! with a 95% Student-t interval on the mean squared error (over repetitions) mapped through √.
//!
//! **Slope.** The least-squares slope of log RMSE vs log N over the profile's N, with a 95%
//! percentile-bootstrap interval over repetitions (the repetitions are resampled whole, so the
//! correlation between the nested N of one stream is kept). The reference's own realised error is
//! a single draw shared by every repetition: the bootstrap does not resample it; its expected size
//! σ̂²/M is subtracted (and is ≤ 1% of σ²/N for N ≤ M/100).
//!
//! **Reproducibility.** Every repetition and every reference chunk has its own seed derived from
//! the route's configuration and its index; results are collected and summed in index order, so
//! they do not depend on the thread count.

use crate::error::Error;
use crate::stats::{Summary, derive_seed, fnv1a};
use ilopt::env::obstacle::ObstacleConfig;
use ilopt::exact::enumerate::moments;
use ilopt::exact::forward::forward;
use ilopt::expert::vo_policy::VoExpertParams;
use ilopt::policy::{LinearGaussian, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::scalar::{BigRational, Scalar, parse_exact_list};
use ilopt::task::obstacle::{ObstacleFeatures, ObstacleTask};
use ilopt::task::{AfterEnd, TaskProblem};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The `[gradient_error]` section of a profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradientError {
    /// Independent repetitions (streams of estimates) per route (≥ 2; the protocol uses ≥ 100).
    pub repetitions: u32,
    /// Bootstrap resamples of the repetitions for the slope's interval (≥ 100).
    pub bootstrap: u32,
    /// Route (a): a toy MDP against its exact ∇F.
    pub toy: ToyRoute,
    /// Route (b): the obstacle task against a high-M reference.
    pub obstacle: ObstacleRoute,
}

/// Route (a)'s settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToyRoute {
    /// The toy-MDP file, relative to the repository root (e.g. `examples/toy/three-state.json`).
    pub mdp: String,
    /// θ as exact numbers (`"1/2"`, `"-3"`, `"0.25"`), one per policy parameter.
    pub theta: Vec<String>,
    /// The sample sizes N (increasing, ≥ 1).
    pub ns: Vec<u64>,
}

/// Route (b)'s settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleRoute {
    /// σ_π of the linear-Gaussian learner.
    pub sigma: f64,
    /// θ (2 × 9 = 18 entries, row-major: x-row then y-row).
    pub theta: Vec<f64>,
    /// Decisions per trajectory of the fixed-horizon objective (absorbing ends).
    pub horizon: usize,
    /// Trajectories of the reference mean M (≥ 100 × the largest N).
    pub reference_trajectories: u64,
    /// The sample sizes N (increasing, ≥ 1).
    pub ns: Vec<u64>,
}

impl ToyRoute {
    /// The toy-MDP file's path: a relative path names the repository's file while the source
    /// tree the binary was built from exists, else a file relative to the current directory.
    pub fn mdp_path(&self) -> PathBuf {
        let p = Path::new(&self.mdp);
        let in_repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p);
        if p.is_absolute() || !in_repo.exists() {
            p.to_path_buf()
        } else {
            in_repo
        }
    }
}

fn check_ns(ns: &[u64]) -> bool {
    !ns.is_empty() && !ns.contains(&0) && ns.windows(2).all(|w| w[0] < w[1])
}

impl GradientError {
    /// Check the section; on failure `(field, reason)` with the field's dotted name.
    ///
    /// # Errors
    /// The first invalid field.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, r: &str| Err((format!("gradient_error.{f}"), r.to_string()));
        if self.repetitions < 2 {
            return bad(
                "repetitions",
                "must be at least 2 (a CI needs 2 repetitions)",
            );
        }
        if self.bootstrap < 100 {
            return bad("bootstrap", "must be at least 100");
        }
        for (f, ns) in [("toy.ns", &self.toy.ns), ("obstacle.ns", &self.obstacle.ns)] {
            if !check_ns(ns) {
                return bad(
                    f,
                    "must be a non-empty increasing list of positive integers",
                );
            }
            if ns.len() < 3 {
                return bad(
                    f,
                    "needs at least 3 sample sizes (a slope with an interval)",
                );
            }
        }
        let o = &self.obstacle;
        if !(o.sigma.is_finite() && o.sigma > 0.0) {
            return bad("obstacle.sigma", "must be finite and > 0");
        }
        let d = 2 * ilopt::task::obstacle::FEATURES;
        if o.theta.len() != d || o.theta.iter().any(|x| !x.is_finite()) {
            return bad("obstacle.theta", &format!("must hold {d} finite numbers"));
        }
        if o.horizon == 0 {
            return bad("obstacle.horizon", "must be ≥ 1");
        }
        if o.reference_trajectories < 100 * o.ns.last().copied().unwrap_or(1) {
            return bad(
                "obstacle.reference_trajectories",
                "must be at least 100 × the largest N (the reference's variance ≤ 1% of the error's)",
            );
        }
        let mdp = ToyMdp::load(&self.toy.mdp_path()).map_err(|e| {
            (
                "gradient_error.toy.mdp".to_string(),
                format!("{}: {e}", self.toy.mdp_path().display()),
            )
        })?;
        let theta = parse_exact_list(&self.toy.theta.join(",")).map_err(|(i, e)| {
            (
                "gradient_error.toy.theta".to_string(),
                format!("entry {i}: {e}"),
            )
        })?;
        if theta.len() != mdp.policy.dim() {
            return bad(
                "toy.theta",
                &format!(
                    "the MDP's policy has {} parameters, got {}",
                    mdp.policy.dim(),
                    theta.len()
                ),
            );
        }
        Ok(())
    }

    /// The reuse key: the section and the toy file's bytes.
    pub fn key_hash(&self) -> String {
        let file = std::fs::read_to_string(self.toy.mdp_path()).unwrap_or_default();
        format!(
            "{:016x}",
            fnv1a(&format!(
                "v3|{}|{:016x}",
                serde_json::to_string(self).unwrap_or_default(),
                fnv1a(&file)
            ))
        )
    }
}

/// A slope with its 95% interval: what claim O1 reads.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlopeCi {
    /// Least-squares slope of log RMSE vs log N on all repetitions.
    pub estimate: f64,
    /// 2.5% bootstrap percentile.
    pub lo: f64,
    /// 97.5% bootstrap percentile.
    pub hi: f64,
    /// Repetitions (the units resampled).
    pub n: usize,
}

impl SlopeCi {
    /// The rule suggested for O1: the interval contains −1/2 and excludes 0.
    pub fn consistent_with_inverse_sqrt(&self) -> bool {
        self.lo <= -0.5 && -0.5 <= self.hi && self.hi < 0.0
    }
}

/// One route's data and summaries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RouteResult {
    /// The sample sizes.
    pub ns: Vec<u64>,
    /// Names of the gradient blocks whose squared errors are recorded (obstacle: x-row, y-row;
    /// toy: the whole gradient).
    pub blocks: Vec<String>,
    /// Per repetition, per N, per block: ‖block of (ḡ_N − reference)‖².
    pub squared_errors: Vec<Vec<Vec<f64>>>,
    /// The reference (∇F exactly, rounded to f64; or the M-trajectory mean).
    pub reference: Vec<f64>,
    /// σ² = E‖g‖² − ‖∇F‖² (exact, rounded; or estimated from the reference's estimates).
    pub sigma2: f64,
    /// σ² exactly, as a fraction (toy route only).
    pub sigma2_exact: Option<String>,
    /// Variance of the reference's error, E‖R − ∇F‖² (0 for the exact reference; σ̂²/M).
    pub reference_variance: f64,
    /// The exact standard deviation of ‖g − ∇F‖² (one estimate's squared error: the spread of
    /// the N = 1 column), toy route only.
    pub squared_error_sd_n1: Option<f64>,
    /// Trajectories behind the reference (None: exact).
    pub reference_trajectories: Option<u64>,
    /// RMSE(N) per N, with the reference's variance subtracted from the MSE, and its 95% interval.
    pub rmse: Vec<RmsePoint>,
    /// The fitted slope.
    pub slope: SlopeCi,
    /// Per gradient block (obstacle: the x and y rows, the thesis's panels (a) and (b)): its name
    /// and the slope of its own RMSE (σ² and the reference variance of that block).
    pub block_slopes: Vec<(String, SlopeCi)>,
    /// Wall time of the route in seconds (0 when reused; kept out of the deterministic data,
    /// written to `timings/gradient-error.json`).
    #[serde(skip)]
    pub seconds: f64,
}

/// RMSE at one N.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RmsePoint {
    /// N.
    pub n: u64,
    /// √(mean squared error against the reference), uncorrected.
    pub raw: f64,
    /// √ of its 95% interval's ends (lower end clamped at 0).
    pub raw_lo: f64,
    /// Upper end.
    pub raw_hi: f64,
    /// √(MSE − reference variance) (= raw for the exact reference).
    pub corrected: f64,
    /// Interval of the corrected value.
    pub corrected_lo: f64,
    /// Upper end.
    pub corrected_hi: f64,
    /// σ/√N.
    pub line: f64,
}

/// Both routes: the Fig. 4.2 data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GradientErrorResult {
    /// Reuse key.
    pub key_hash: String,
    /// Route (a).
    pub toy: RouteResult,
    /// Route (b).
    pub obstacle: RouteResult,
}

/// Least-squares slope of log y vs log x over the points with y > 0.
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| **a > 0.0 && **b > 0.0 && b.is_finite())
        .map(|(a, b)| (a.ln(), b.ln()))
        .collect();
    if pts.len() < 2 {
        return f64::NAN;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// The nested-mean errors of `repetitions` streams: for repetition r (seed derived from `key`
/// and r), the squared error of each block of (mean of the first N draws of `sample`) −
/// `reference`, for every N of `ns`. Blocks are `(start, len)` ranges of the gradient.
///
/// # Errors
/// The first failing draw.
pub fn repetition_errors<F>(
    ns: &[u64],
    repetitions: u32,
    key: &str,
    blocks: &[(usize, usize)],
    reference: &[f64],
    sample: F,
) -> Result<Vec<Vec<Vec<f64>>>, Error>
where
    F: Fn(&mut KitRng) -> Result<DVector<f64>, Error> + Sync,
{
    (0..repetitions)
        .into_par_iter()
        .map(|r| {
            let mut rng = KitRng::seed_from_u64(derive_seed(key, u64::from(r)));
            let mut sum = DVector::<f64>::zeros(reference.len());
            let mut k = 0u64;
            let mut out = Vec::with_capacity(ns.len());
            for &n in ns {
                while k < n {
                    let g = sample(&mut rng)?;
                    if g.len() != reference.len() {
                        return Err(Error::experiment(
                            "gradient error",
                            format!("estimate of length {} for {}", g.len(), reference.len()),
                        ));
                    }
                    sum += g;
                    k += 1;
                }
                let inv = 1.0 / n as f64;
                out.push(
                    blocks
                        .iter()
                        .map(|&(s, l)| {
                            (s..s + l)
                                .map(|i| (sum[i] * inv - reference[i]).powi(2))
                                .sum::<f64>()
                        })
                        .collect(),
                );
            }
            Ok(out)
        })
        .collect()
}

/// Total squared error per repetition and N (the blocks summed).
fn totals(sq: &[Vec<Vec<f64>>]) -> Vec<Vec<f64>> {
    sq.iter()
        .map(|rep| rep.iter().map(|b| b.iter().sum()).collect())
        .collect()
}

fn corrected_rmse(mse: f64, reference_variance: f64) -> f64 {
    (mse - reference_variance).max(0.0).sqrt()
}

/// RMSE per N with intervals, and the slope with its bootstrap interval.
///
/// # Panics
/// Never for ≥ 1 repetition (the bootstrap indexes within the repetitions).
pub fn summarise(
    ns: &[u64],
    squared_errors: &[Vec<Vec<f64>>],
    sigma2: f64,
    reference_variance: f64,
    bootstrap: u32,
    key: &str,
) -> (Vec<RmsePoint>, SlopeCi) {
    let tot = totals(squared_errors);
    let reps = tot.len();
    let x: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    let mut points = Vec::with_capacity(ns.len());
    for (i, &n) in ns.iter().enumerate() {
        let col: Vec<f64> = tot.iter().map(|r| r[i]).collect();
        let s = Summary::of(&col);
        let sq = |v: f64| v.max(0.0).sqrt();
        points.push(RmsePoint {
            n,
            raw: sq(s.mean),
            raw_lo: sq(s.lo()),
            raw_hi: sq(s.hi()),
            corrected: corrected_rmse(s.mean, reference_variance),
            corrected_lo: corrected_rmse(s.lo(), reference_variance),
            corrected_hi: corrected_rmse(s.hi(), reference_variance),
            line: (sigma2 / n as f64).sqrt(),
        });
    }
    let curve = |idx: &mut dyn Iterator<Item = usize>| -> Vec<f64> {
        let mut acc = vec![0.0; ns.len()];
        let mut m = 0usize;
        for r in idx {
            for (a, v) in acc.iter_mut().zip(&tot[r]) {
                *a += v;
            }
            m += 1;
        }
        acc.iter()
            .map(|a| corrected_rmse(a / m.max(1) as f64, reference_variance))
            .collect()
    };
    let estimate = loglog_slope(&x, &curve(&mut (0..reps)));
    let mut rng = KitRng::seed_from_u64(derive_seed(&format!("{key}|bootstrap"), 0));
    let mut slopes: Vec<f64> = (0..bootstrap)
        .map(|_| {
            let draws: Vec<usize> = (0..reps).map(|_| rng.random_range(0..reps)).collect();
            loglog_slope(&x, &curve(&mut draws.into_iter()))
        })
        .filter(|s| s.is_finite())
        .collect();
    slopes.sort_by(f64::total_cmp);
    let q = |p: f64| -> f64 {
        if slopes.is_empty() {
            return f64::NAN;
        }
        let i = ((slopes.len() - 1) as f64 * p).round() as usize;
        slopes[i]
    };
    (
        points,
        SlopeCi {
            estimate,
            lo: q(0.025),
            hi: q(0.975),
            n: reps,
        },
    )
}

/// The toy route's exact quantities at θ: (∇F by the forward DP X2, E‖g‖² by enumeration X1,
/// σ² = E‖g‖² − ‖∇F‖²), all in exact rationals.
///
/// # Errors
/// [`Error::Experiment`] if the file, θ or the exact engine fails.
pub fn toy_exact(
    route: &ToyRoute,
) -> Result<(ToyMdp, Vec<BigRational>, BigRational, BigRational), Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("Fig. 4.2 (toy, exact)", x);
    let mdp = ToyMdp::load(&route.mdp_path()).map_err(|x| e(&x))?;
    let theta = parse_exact_list(&route.theta.join(","))
        .map_err(|(i, x)| e(&format!("θ entry {i}: {x}")))?;
    let p = ToyProblem::<BigRational>::new(&mdp);
    let x2 = forward(&p, &theta).map_err(|x| e(&x))?;
    let x1 = moments(&p, &theta).map_err(|x| e(&x))?;
    let norm2 = x2
        .gradient
        .iter()
        .fold(<BigRational as Scalar>::zero(), |a, g| a + g.clone() * g);
    let sigma2 = x1.second_moment.clone() - norm2;
    Ok((mdp, x2.gradient, x1.second_moment, sigma2))
}

/// The exact standard deviation of ‖g − ∇F‖² over trajectories: √(E‖g − ∇F‖⁴ − σ⁴), by
/// enumerating every trajectory in rationals.
///
/// # Errors
/// As [`toy_exact`].
pub fn squared_error_sd(
    mdp: &ToyMdp,
    route: &ToyRoute,
    grad: &[BigRational],
    sigma2: &BigRational,
) -> Result<f64, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("Fig. 4.2 (toy, exact)", x);
    let theta = parse_exact_list(&route.theta.join(","))
        .map_err(|(i, x)| e(&format!("θ entry {i}: {x}")))?;
    let p = ToyProblem::<BigRational>::new(mdp);
    let mut m4 = <BigRational as Scalar>::zero();
    for q in ilopt::exact::enumerate::prefixes(&p, &theta).map_err(|x| e(&x))? {
        let sq = q
            .estimate
            .iter()
            .zip(grad)
            .fold(<BigRational as Scalar>::zero(), |a, (x, y)| {
                let d = x.clone() - y;
                a + d.clone() * d
            });
        m4 += q.prob * sq.clone() * sq;
    }
    Ok((m4 - sigma2.clone() * sigma2).to_f64().max(0.0).sqrt())
}

/// Route (a): the toy MDP against its exact ∇F.
///
/// # Errors
/// As [`toy_exact`], or a failing draw.
pub fn toy_route(g: &GradientError) -> Result<RouteResult, Error> {
    let start = std::time::Instant::now();
    let (mdp, grad, _m2, sigma2) = toy_exact(&g.toy)?;
    let reference: Vec<f64> = grad.iter().map(Scalar::to_f64).collect();
    let p = ToyProblem::<f64>::new(&mdp);
    let theta = DVector::from_vec(
        parse_exact_list(&g.toy.theta.join(","))
            .map_err(|(i, x)| Error::experiment("Fig. 4.2 (toy)", format!("θ entry {i}: {x}")))?
            .iter()
            .map(<f64 as Scalar>::from_rational)
            .collect::<Vec<f64>>(),
    );
    // The streams' seeds depend on the route's own settings only (not on the other route's).
    let key = format!(
        "gradient-error|toy|{}|{}|{:016x}",
        serde_json::to_string(&g.toy).unwrap_or_default(),
        g.repetitions,
        fnv1a(&std::fs::read_to_string(g.toy.mdp_path()).unwrap_or_default())
    );
    let sq = repetition_errors(
        &g.toy.ns,
        g.repetitions,
        &key,
        &[(0, reference.len())],
        &reference,
        |rng| toy_draw(&p, &theta, rng),
    )?;
    let s2 = sigma2.to_f64();
    let (rmse, slope) = summarise(&g.toy.ns, &sq, s2, 0.0, g.bootstrap, &key);
    Ok(RouteResult {
        ns: g.toy.ns.clone(),
        blocks: vec!["all".into()],
        squared_errors: sq,
        reference,
        sigma2: s2,
        sigma2_exact: Some(sigma2.to_string()),
        squared_error_sd_n1: Some(squared_error_sd(&mdp, &g.toy, &grad, &sigma2)?),
        reference_variance: 0.0,
        reference_trajectories: None,
        rmse,
        slope,
        block_slopes: vec![],
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// One eq. 3.15 estimate (causal form) on the toy MDP at θ, in f64.
///
/// # Errors
/// If the oracle fails.
pub fn toy_draw(
    p: &ToyProblem<f64>,
    theta: &DVector<f64>,
    rng: &mut KitRng,
) -> Result<DVector<f64>, Error> {
    let mut cost = Cost::default();
    let t = p
        .rollout(&Behaviour::Learner(theta), rng, &mut cost)
        .map_err(|e| Error::experiment("Fig. 4.2 (toy)", e))?;
    p.estimate(theta, &t, EstimatorForm::Causal, &mut cost)
        .map_err(|e| Error::experiment("Fig. 4.2 (toy)", e))
}

/// The obstacle task's IL problem of route (b): linear-Gaussian learner (σ) over the 9 basic
/// features with the executed (speed-clipped) velocity's loss, fixed horizon, absorbing ends.
pub type ObstacleFixed = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

/// Build route (b)'s problem.
///
/// # Errors
/// [`Error::Experiment`] if the task or policy cannot be built.
pub fn obstacle_problem(route: &ObstacleRoute) -> Result<ObstacleFixed, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("Fig. 4.2 (obstacle)", x);
    let env = ObstacleConfig::default();
    let task = ObstacleTask::new(env.clone(), VoExpertParams::default())
        .and_then(|t| t.with_features(ObstacleFeatures::Basic))
        .map_err(|x| e(&x))?
        .with_actions::<[f64; 2]>();
    let inner = LinearGaussian::new(2, task.feature_dim(), route.sigma)
        .and_then(LinearGaussian::with_actions::<[f64; 2]>)
        .map_err(|x| e(&x))?;
    let policy = SpeedLimitedGaussian::new(inner, env.agent_max_speed).map_err(|x| e(&x))?;
    TaskProblem::fixed(task, policy, route.horizon, AfterEnd::Absorb).map_err(|x| e(&x))
}

/// One eq. 3.15 estimate (causal form) on any problem at θ.
///
/// # Errors
/// If the oracle fails.
pub fn draw<P: IlProblem<f64>>(
    p: &P,
    theta: &DVector<f64>,
    rng: &mut KitRng,
) -> Result<DVector<f64>, Error> {
    let mut cost = Cost::default();
    let t = p
        .rollout(&Behaviour::Learner(theta), rng, &mut cost)
        .map_err(|e| Error::experiment("Fig. 4.2", e))?;
    p.estimate(theta, &t, EstimatorForm::Causal, &mut cost)
        .map_err(|e| Error::experiment("Fig. 4.2", e))
}

/// Mean and per-component sum of squared deviations of `m` draws (Chan et al.'s merge of
/// chunks, in chunk order: the same numbers for any thread count).
#[derive(Debug, Clone)]
pub struct Moments {
    /// Draws.
    pub count: u64,
    /// Mean per component.
    pub mean: DVector<f64>,
    /// Σ (g_i − mean)² per component.
    pub m2: DVector<f64>,
}

impl Moments {
    fn merge(&mut self, o: &Moments) {
        if o.count == 0 {
            return;
        }
        let (na, nb) = (self.count as f64, o.count as f64);
        let n = na + nb;
        let delta = &o.mean - &self.mean;
        self.m2 += &o.m2 + delta.component_mul(&delta) * (na * nb / n);
        self.mean += delta * (nb / n);
        self.count += o.count;
    }

    /// Unbiased sample variance of one draw, summed over the components in `range`.
    pub fn variance(&self, range: std::ops::Range<usize>) -> f64 {
        self.m2.rows(range.start, range.len()).sum() / (self.count.saturating_sub(1)).max(1) as f64
    }
}

/// The moments of `m` draws of `sample`, in chunks of `chunk` with seeds derived from `key` and
/// the chunk index.
///
/// # Errors
/// The first failing draw.
pub fn reference_moments<F>(
    m: u64,
    dim: usize,
    chunk: u64,
    key: &str,
    sample: F,
) -> Result<Moments, Error>
where
    F: Fn(&mut KitRng) -> Result<DVector<f64>, Error> + Sync,
{
    let parts = (0..m.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let n = chunk.min(m - chunk * c);
            let mut rng = KitRng::seed_from_u64(derive_seed(key, c));
            let draws = (0..n)
                .map(|_| sample(&mut rng))
                .collect::<Result<Vec<_>, Error>>()?;
            let mut mean = DVector::zeros(dim);
            for g in &draws {
                mean += g;
            }
            mean /= n as f64;
            let mut m2 = DVector::zeros(dim);
            for g in &draws {
                let d = g - &mean;
                m2 += d.component_mul(&d);
            }
            Ok(Moments { count: n, mean, m2 })
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let mut all = Moments {
        count: 0,
        mean: DVector::zeros(dim),
        m2: DVector::zeros(dim),
    };
    for p in &parts {
        all.merge(p);
    }
    Ok(all)
}

/// Route (b): the obstacle task against an M-trajectory reference.
///
/// # Errors
/// If the problem cannot be built or a draw fails.
pub fn obstacle_route(g: &GradientError) -> Result<RouteResult, Error> {
    let start = std::time::Instant::now();
    let o = &g.obstacle;
    let p = obstacle_problem(o)?;
    let theta = DVector::from_vec(o.theta.clone());
    let d = theta.len();
    let key = format!(
        "gradient-error|obstacle|{}|{}",
        serde_json::to_string(o).unwrap_or_default(),
        g.repetitions
    );
    let mom = reference_moments(
        o.reference_trajectories,
        d,
        1024,
        &format!("{key}|reference"),
        |rng| draw(&p, &theta, rng),
    )?;
    let reference: Vec<f64> = mom.mean.iter().copied().collect();
    let sigma2 = mom.variance(0..d);
    let reference_variance = sigma2 / o.reference_trajectories as f64;
    let h = d / 2;
    let sq = repetition_errors(
        &o.ns,
        g.repetitions,
        &key,
        &[(0, h), (h, h)],
        &reference,
        |rng| draw(&p, &theta, rng),
    )?;
    let (rmse, slope) = summarise(&o.ns, &sq, sigma2, reference_variance, g.bootstrap, &key);
    let block_slopes = [("x-row", 0..h), ("y-row", h..d)]
        .into_iter()
        .enumerate()
        .map(|(b, (name, range))| {
            let only: Vec<Vec<Vec<f64>>> = sq
                .iter()
                .map(|rep| rep.iter().map(|v| vec![v[b]]).collect())
                .collect();
            let s2 = mom.variance(range);
            let (_, slope) = summarise(
                &o.ns,
                &only,
                s2,
                s2 / o.reference_trajectories as f64,
                g.bootstrap,
                &format!("{key}|{name}"),
            );
            (name.to_string(), slope)
        })
        .collect();
    Ok(RouteResult {
        ns: o.ns.clone(),
        blocks: vec!["x-row".into(), "y-row".into()],
        squared_errors: sq,
        reference,
        sigma2,
        sigma2_exact: None,
        squared_error_sd_n1: None,
        reference_variance,
        reference_trajectories: Some(o.reference_trajectories),
        rmse,
        slope,
        block_slopes,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Both routes (each parallel inside).
///
/// # Errors
/// As [`toy_route`] and [`obstacle_route`].
pub fn run(g: &GradientError) -> Result<GradientErrorResult, Error> {
    Ok(GradientErrorResult {
        key_hash: g.key_hash(),
        toy: toy_route(g)?,
        obstacle: obstacle_route(g)?,
    })
}

/// Fig. 4.2's figures: (file stem, figure), (a) toy, (b) obstacle.
pub fn figures(r: &GradientErrorResult) -> Vec<(&'static str, crate::plots::Figure)> {
    use crate::plots::{Figure, Series};
    let x = |route: &RouteResult| route.rmse.iter().map(|p| p.n as f64).collect::<Vec<_>>();
    let band = |route: &RouteResult, label: &str, corrected: bool| {
        let mut s = Series::new(label);
        s.x = x(route);
        for p in &route.rmse {
            let (m, lo, hi) = if corrected {
                (p.corrected, p.corrected_lo, p.corrected_hi)
            } else {
                (p.raw, p.raw_lo, p.raw_hi)
            };
            s.mean.push(m);
            s.lo.push(lo);
            s.hi.push(hi);
        }
        s
    };
    let dashed = |label: String, xs: Vec<f64>, ys: Vec<f64>| {
        let mut s = Series::new(label);
        s.x = xs;
        s.lo.clone_from(&ys);
        s.hi.clone_from(&ys);
        s.mean = ys;
        s.reference = true;
        s
    };
    let line = |route: &RouteResult, label: &str| {
        dashed(
            label.into(),
            x(route),
            route.rmse.iter().map(|p| p.line).collect(),
        )
    };
    let t = &r.toy;
    let o = &r.obstacle;
    let reps = t.squared_errors.len();
    let mut out = vec![(
        "fig4-2a-gradient-error-toy",
        Figure {
            title: format!(
                "Fig. 4.2 (a): toy MDP, RMSE of the mean of N gradient estimates against the exact ∇F over {reps} repetitions (95% CI band; dashed: σ/√N); fitted slope {} [{}, {}]",
                fmt3(t.slope.estimate),
                fmt3(t.slope.lo),
                fmt3(t.slope.hi)
            ),
            x_label: "N, trajectories averaged (log scale)".into(),
            y_label: "RMSE of mean gradient (log scale)".into(),
            log_x: true,
            log_y: true,
            y_range: Some((0.0, f64::INFINITY)),
            series: vec![band(t, "RMSE (95% CI)", false), line(t, "σ/√N (exact σ)")],
            panels: None,
        },
    )];
    let m = o.reference_trajectories.unwrap_or(0);
    let floor = o.reference_variance.sqrt();
    let (x0, x1) = (
        o.ns.first().copied().unwrap_or(1) as f64,
        o.ns.last().copied().unwrap_or(1) as f64,
    );
    out.push((
        "fig4-2b-gradient-error-obstacle",
        Figure {
            title: format!(
                "Fig. 4.2 (b): obstacle task, RMSE of the mean of N gradient estimates against an M = {m} trajectory reference over {} repetitions (95% CI bands; dashed: σ̂/√N and the reference's standard error); fitted slope {} [{}, {}]",
                o.squared_errors.len(),
                fmt3(o.slope.estimate),
                fmt3(o.slope.lo),
                fmt3(o.slope.hi)
            ),
            x_label: "N, trajectories averaged (log scale)".into(),
            y_label: "RMSE of mean gradient (log scale)".into(),
            log_x: true,
            log_y: true,
            y_range: Some((0.0, f64::INFINITY)),
            series: vec![
                band(o, "vs reference (95% CI)", false),
                band(o, "− ref. variance (95% CI)", true),
                line(o, "σ̂/√N"),
                dashed("reference SE σ̂/√M".into(), vec![x0, x1], vec![floor, floor]),
            ],
            // The two estimates and σ̂/√N nearly coincide: one panel each, side by side.
            panels: Some(2),
        },
    ));
    out
}

fn fmt3(v: f64) -> String {
    format!("{v:.3}")
}

/// The per-repetition data as CSV: `route,repetition,n,block,squared_error`.
pub fn csv(r: &GradientErrorResult) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("route,repetition,n,block,squared_error\n");
    for (name, route) in [("toy", &r.toy), ("obstacle", &r.obstacle)] {
        for (rep, rows) in route.squared_errors.iter().enumerate() {
            for (n, blocks) in route.ns.iter().zip(rows) {
                for (b, v) in route.blocks.iter().zip(blocks) {
                    let _ = writeln!(s, "{name},{rep},{n},{b},{v}");
                }
            }
        }
    }
    s
}

/// One route's slope as text: `−0.501 [−0.52, −0.48] (n = 100 repetitions, N = 1…10000)`.
pub fn slope_text(route: &RouteResult) -> String {
    format!(
        "{} [{}, {}] (95% bootstrap CI, n = {} repetitions, N = {}…{})",
        fmt3(route.slope.estimate),
        fmt3(route.slope.lo),
        fmt3(route.slope.hi),
        route.slope.n,
        route.ns.first().copied().unwrap_or(0),
        route.ns.last().copied().unwrap_or(0)
    )
}

/// The rows of a route's table: N, RMSE \[CI\], corrected RMSE \[CI\] (obstacle), σ/√N, ratio.
pub fn table_rows(route: &RouteResult) -> Vec<Vec<String>> {
    let g = |v: f64| {
        if v.is_finite() {
            format!("{v:.4e}")
        } else {
            "—".into()
        }
    };
    route
        .rmse
        .iter()
        .map(|p| {
            let mut row = vec![
                p.n.to_string(),
                format!("{} [{}, {}]", g(p.raw), g(p.raw_lo), g(p.raw_hi)),
            ];
            if route.reference_trajectories.is_some() {
                row.push(format!(
                    "{} [{}, {}]",
                    g(p.corrected),
                    g(p.corrected_lo),
                    g(p.corrected_hi)
                ));
            }
            row.push(g(p.line));
            row.push(format!("{:.3}", p.corrected / p.line));
            row
        })
        .collect()
}

/// The N whose 95% interval (reference variance removed) misses σ/√N, said in words, with the
/// exact spread of one squared error when known (toy route).
fn coverage_note(route: &RouteResult, reps: u32) -> String {
    let missed: Vec<&RmsePoint> = route
        .rmse
        .iter()
        .filter(|p| !(p.corrected_lo <= p.line && p.line <= p.corrected_hi))
        .collect();
    if missed.is_empty() {
        return String::new();
    }
    let which = if route.reference_trajectories.is_some() {
        "(b)"
    } else {
        "(a)"
    };
    let list: Vec<String> = missed
        .iter()
        .map(|p| format!("{} ({:.3} × σ/√N)", p.n, p.corrected / p.line))
        .collect();
    let exact = match (route.squared_error_sd_n1, route.rmse.first()) {
        (Some(sd), Some(p)) if p.n == 1 => format!(
            " One squared error ‖g − ∇F‖² has the exact standard deviation {sd:.3} against its mean \
             σ² = {:.3}; the N = 1 mean over the {reps} streams is {:+.1} exact standard errors from σ².",
            route.sigma2,
            (p.raw * p.raw - route.sigma2) / (sd / f64::from(reps).sqrt())
        ),
        _ => String::new(),
    };
    format!(
        "Coverage, route {which}: σ/√N lies outside the 95% interval at {} of {} sample sizes: N = {}. \
         The squared error is right-skewed, so the t interval can undercover at small N, and the \
         N of one stream are nested (its first draws enter every N), so neighbouring N err \
         together; the slope's bootstrap resamples whole streams and keeps that dependence.{exact} ",
        missed.len(),
        route.rmse.len(),
        list.join(", ")
    )
}

/// The appendix's text for Fig. 4.2 (Markdown inline).
pub fn description(g: &GradientError, r: &GradientErrorResult) -> String {
    let (t, o) = (&r.toy, &r.obstacle);
    format!(
        "The thesis claims that the mean of N eq. 3.15 estimates approaches ∇F at the rate 1/√N. \
         Each route draws {reps} independent streams of estimates (causal form, f64, each stream \
         from its own derived seed); the RMSE at N is √(mean over the streams of ‖mean of the first \
         N estimates − reference‖²), with a 95% Student-t interval on the mean squared error mapped \
         through √. The dashed line is σ/√N, with σ² = E‖g‖² − ‖∇F‖² — not fitted, not anchored at \
         N = 1. The slope is the least-squares slope of log RMSE vs log N over every N; its 95% \
         interval is the percentile bootstrap over the streams ({boot} resamples). \
         **(a) Toy MDP** (`{mdp}`, θ = ({theta})): the reference is ∇F computed in exact rationals \
         by the exact engine's forward DP (the `gradient` of `ilopt toy eval`), with no noise; \
         σ² = {s2e} ≈ {s2:.6} exactly (E‖g‖² by enumerating every trajectory). Slope {ts}. \
         **(b) Obstacle task** under the thesis's fixed-horizon objective (T = {h} decisions, \
         absorbing ends: success 0, crash (2·v_max)² per remaining step), linear-Gaussian learner \
         (σ_π = {sigma}) over the 9 basic features at a fixed θ (a proportional pull towards the \
         goal): the reference is the mean of M = {m} independent estimates (its own seed stream), \
         σ̂² = {os2:.6e} is their sample variance (trace), and the reference's own standard error \
         σ̂/√M = {se:.4e} is drawn as a floor. Because the reference is independent of the streams, \
         E‖ḡ_N − R‖² = σ²/N + σ²/M; the band \"− ref. variance\" and the slope use \
         √(MSE − σ̂²/M) (the two bands coincide to the eye when M ≫ N). Slope {os}; by row of the gradient (the thesis's panels (a) and (b)): {blocks}. {times}\
         {n1}(Data: `gradient_error.csv`, one row per stream, N and gradient block.)",
        reps = g.repetitions,
        boot = g.bootstrap,
        mdp = g.toy.mdp,
        theta = g.toy.theta.join(", "),
        s2e = t.sigma2_exact.as_deref().unwrap_or("—"),
        s2 = t.sigma2,
        ts = slope_text(t),
        h = g.obstacle.horizon,
        sigma = g.obstacle.sigma,
        m = g.obstacle.reference_trajectories,
        os2 = o.sigma2,
        se = o.reference_variance.sqrt(),
        os = slope_text(o),
        blocks = o
            .block_slopes
            .iter()
            .map(|(b, s)| format!("{b} {} [{}, {}]", fmt3(s.estimate), fmt3(s.lo), fmt3(s.hi)))
            .collect::<Vec<_>>()
            .join(", "),
        n1 = coverage_note(t, g.repetitions) + &coverage_note(o, g.repetitions),
        times = if t.seconds > 0.0 {
            format!(
                "Run times: toy {:.1} s, obstacle {:.1} s. ",
                t.seconds, o.seconds
            )
        } else {
            "Reused from an earlier run (times in `timings/gradient-error.json`). ".into()
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use ilopt::exact::backward::backward;
    use ilopt::exact::enumerate::gradient_by_duals;

    fn toy_section(ns: Vec<u64>, repetitions: u32) -> GradientError {
        GradientError {
            repetitions,
            bootstrap: 400,
            toy: ToyRoute {
                mdp: "examples/toy/three-state.json".into(),
                theta: ["1/2", "-1", "1", "1/3", "-1/2", "2"]
                    .map(String::from)
                    .to_vec(),
                ns,
            },
            obstacle: ObstacleRoute {
                sigma: 0.1,
                theta: vec![0.0; 18],
                horizon: 200,
                reference_trajectories: 100_000,
                ns: vec![1, 10, 100, 1000],
            },
        }
    }

    /// The toy route's reference (forward DP, X2) equals ∇F by dual numbers over the enumeration
    /// (no score formula) and by the backward DP, exactly; its σ² equals the enumeration's
    /// Var = E‖g‖² − ‖E g‖² (E g = ∇F: the oracle is unbiased).
    #[test]
    fn toy_reference_is_the_exact_gradient_by_independent_routes() {
        let g = toy_section(vec![1, 2, 4], 2);
        assert_eq!(g.validate(), Ok(()));
        let (mdp, grad, m2, sigma2) = toy_exact(&g.toy).unwrap();
        let p = ToyProblem::<BigRational>::new(&mdp);
        let theta = parse_exact_list(&g.toy.theta.join(",")).unwrap();
        let (_, by_duals) = gradient_by_duals(&p, &theta).unwrap();
        let (_, by_backward) = backward(&p, &theta).unwrap();
        assert_eq!(grad, by_duals);
        assert_eq!(grad, by_backward);
        let mom = moments(&p, &theta).unwrap();
        assert_eq!(mom.expected_estimate, grad);
        assert_eq!(mom.second_moment, m2);
        assert_eq!(mom.variance, sigma2);
        assert!(sigma2 > <BigRational as Scalar>::zero());
        assert!(grad.iter().any(|x| *x != <BigRational as Scalar>::zero()));
        // The library route of `ilopt toy eval` prints the same gradient.
        let json = ilopt::cli::toy::evaluate::<BigRational>(&mdp, &theta).unwrap();
        let printed: Vec<String> = json["gradient"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        let ours: Vec<String> = grad.iter().map(ToString::to_string).collect();
        assert_eq!(printed, ours);
    }

    fn toy_sampler(g: &GradientError) -> (ToyProblem<f64>, DVector<f64>, Vec<f64>, f64) {
        let (mdp, grad, _, sigma2) = toy_exact(&g.toy).unwrap();
        let theta = parse_exact_list(&g.toy.theta.join(",")).unwrap();
        (
            ToyProblem::<f64>::new(&mdp),
            DVector::from_vec(theta.iter().map(<f64 as Scalar>::from_rational).collect()),
            grad.iter().map(Scalar::to_f64).collect(),
            sigma2.to_f64(),
        )
    }

    /// At N = 1 the MSE is E‖g − ∇F‖² = σ²: the RMSE's interval holds σ; and the slope's interval
    /// contains −1/2 and excludes 0.
    #[test]
    fn unbiased_oracle_rmse_starts_at_sigma_and_decays_at_the_inverse_square_root() {
        let g = toy_section(vec![1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024], 200);
        let r = toy_route(&g).unwrap();
        let s = r.sigma2.sqrt();
        let p = r.rmse[0];
        assert!(p.raw_lo <= s && s <= p.raw_hi, "{p:?} vs σ = {s}");
        assert!((p.line - s).abs() < 1e-12);
        assert!(r.slope.hi < 0.0, "{:?}", r.slope);
        assert!(r.slope.consistent_with_inverse_sqrt(), "{:?}", r.slope);
        assert_eq!(r.slope.n, 200);
    }

    /// A biased oracle (a constant added to every estimate) flattens the RMSE at ‖b‖: the slope
    /// test rejects it — the claim can fail.
    #[test]
    fn biased_oracle_is_caught_by_the_slope_test() {
        let g = toy_section(vec![1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024], 200);
        let (p, theta, reference, sigma2) = toy_sampler(&g);
        let d = reference.len();
        // ‖b‖ = σ/10: the error flattens from N ≈ 100 on.
        let b = DVector::from_element(d, (sigma2 / 100.0 / d as f64).sqrt());
        let key = "biased";
        let blocks = [(0, d)];
        let sq = repetition_errors(&g.toy.ns, 200, key, &blocks, &reference, |rng| {
            toy_draw(&p, &theta, rng).map(|x| x + &b)
        })
        .unwrap();
        let (pts, slope) = summarise(&g.toy.ns, &sq, sigma2, 0.0, 400, key);
        assert!(!slope.consistent_with_inverse_sqrt(), "{slope:?}");
        assert!(slope.lo > -0.5, "{slope:?}");
        let last = pts.last().unwrap();
        assert!(last.raw_lo > 2.0 * last.line, "{last:?}");
        // The same streams without the bias pass.
        let sq = repetition_errors(&g.toy.ns, 200, key, &blocks, &reference, |rng| {
            toy_draw(&p, &theta, rng)
        })
        .unwrap();
        let (_, slope) = summarise(&g.toy.ns, &sq, sigma2, 0.0, 400, key);
        assert!(slope.consistent_with_inverse_sqrt(), "{slope:?}");
    }

    /// Repetitions and reference chunks do not depend on the thread count; the chunked moments
    /// equal the direct two-pass ones.
    #[test]
    fn streams_and_reference_are_thread_count_independent() {
        let g = toy_section(vec![1, 3, 9], 6);
        let (p, theta, reference, _) = toy_sampler(&g);
        let d = reference.len();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let sq = repetition_errors(
                    &g.toy.ns,
                    6,
                    "t",
                    &[(0, 2), (2, d - 2)],
                    &reference,
                    |rng| toy_draw(&p, &theta, rng),
                )
                .unwrap();
                let m =
                    reference_moments(1000, d, 64, "r", |rng| toy_draw(&p, &theta, rng)).unwrap();
                (sq, m.mean, m.m2)
            })
        };
        let (a, b) = (run(1), run(3));
        assert_eq!(a, b);
        // Direct moments of the same 1000 draws (chunk c draws from seed derive_seed("r", c)).
        let mut draws = Vec::new();
        for c in 0..1000u64.div_ceil(64) {
            let mut rng = KitRng::seed_from_u64(derive_seed("r", c));
            for _ in 0..64.min(1000 - 64 * c) {
                draws.push(toy_draw(&p, &theta, &mut rng).unwrap());
            }
        }
        let mean = draws.iter().fold(DVector::zeros(d), |s, x| s + x) / 1000.0;
        let m2 = draws.iter().fold(DVector::zeros(d), |s, x| {
            let e: DVector<f64> = x - &mean;
            s + e.component_mul(&e)
        });
        assert!((&a.1 - &mean).norm() < 1e-12 * (1.0 + a.1.norm()));
        assert!((&a.2 - &m2).norm() < 1e-9 * (1.0 + m2.norm()));
    }

    /// The exact spread of one squared error equals its f64 value by enumerating the prefixes
    /// directly.
    #[test]
    fn exact_spread_of_one_squared_error() {
        let g = toy_section(vec![1, 2, 4], 2);
        let (mdp, grad, _, sigma2) = toy_exact(&g.toy).unwrap();
        let sd = squared_error_sd(&mdp, &g.toy, &grad, &sigma2).unwrap();
        let (p, theta, reference, s2) = toy_sampler(&g);
        let (mut m2, mut m4) = (0.0, 0.0);
        for q in ilopt::exact::enumerate::prefixes(&p, theta.as_slice()).unwrap() {
            let e: f64 = q
                .estimate
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).powi(2))
                .sum();
            m2 += q.prob * e;
            m4 += q.prob * e * e;
        }
        assert!((m2 - s2).abs() < 1e-9 * s2);
        assert!((sd - (m4 - m2 * m2).sqrt()).abs() < 1e-9 * sd);
    }

    #[test]
    fn the_slope_rule_on_synthetic_intervals() {
        let s = |lo, hi| SlopeCi {
            estimate: (lo + hi) / 2.0,
            lo,
            hi,
            n: 100,
        };
        assert!(s(-0.55, -0.45).consistent_with_inverse_sqrt());
        assert!(!s(-0.45, -0.35).consistent_with_inverse_sqrt());
        assert!(!s(-0.6, 0.1).consistent_with_inverse_sqrt());
        assert!(!s(-0.7, -0.55).consistent_with_inverse_sqrt());
    }

    #[test]
    fn slope_of_a_power_law() {
        let x = [1.0, 10.0, 100.0];
        let y = x.map(|v: f64| 3.0 * v.powf(-0.5));
        assert!((loglog_slope(&x, &y) + 0.5).abs() < 1e-12);
    }
}
