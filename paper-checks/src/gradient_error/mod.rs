//! Fig. 4.2: does the mean of N oracle estimates (eq. 3.15) converge to ∇F at the 1/√N rate?
//!
//! Two routes, each with an *independent* reference:
//!
//! - **(a) toy MDP, exact reference.** ∇F(θ) is computed in exact rationals by the exact engine's
//!   forward DP (X2, `ilopt::exact::forward`, the route `ilopt toy eval` prints as `gradient`), and
//!   σ² = E‖g‖² − ‖∇F‖² exactly from the enumeration's second moment (X1). The estimates are
//!   sampled in f64 through the toy's [`IlProblem`](ilopt::problem::IlProblem) oracle (the one the algorithms call). The
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
use crate::stats::fnv1a;
use ilopt::scalar::{Scalar, parse_exact_list};
use ilopt::toy::ToyMdp;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

mod estimate;
mod obstacle;
mod render;
mod result;
#[cfg(test)]
mod tests;
mod toy;

pub use estimate::*;
pub use obstacle::*;
pub use render::*;
pub use result::*;
pub use toy::*;

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
