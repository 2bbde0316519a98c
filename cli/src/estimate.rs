//! `ilopt estimate --config FILE.toml --theta JSON --trajectories M --seed S`: one draw of the
//! oracle's estimate of eq. 3.15 (causal form) at θ, on the config's task, policy and baseline.
//!
//! Prints one JSON object: `task`, `policy`, `dim`, `trajectories`, `seed` and `estimate`, the
//! mean of the estimates of M roll-outs of π_θ (each number in shortest round-trip form, so the
//! printed values are the computed ones bit for bit). The roll-outs draw from one RNG seeded
//! with S; the oracle is the one a run with `run.trajectories_per_gradient = M` samples
//! ([`crate::run::oracle::with_oracle`]).

use crate::run::RunError;
use crate::run::config::{LoadedConfig, MAX_TRAJECTORIES, RunFile};
use crate::run::oracle::{OnOracle, with_oracle};
use crate::run::runnable::RunTask;
use crate::run::task::task_learner;
use clap::Args;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use nalgebra::DVector;
use rand::SeedableRng;
use serde_json::{Value, json};
use std::path::PathBuf;

/// Arguments of `ilopt estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    /// The config file whose task, policy and `run.baseline` define the oracle.
    #[arg(long, value_name = "FILE.toml")]
    pub config: PathBuf,
    /// θ as a JSON array of numbers, e.g. "[0.5, -1, 0]".
    #[arg(long, value_name = "JSON", allow_hyphen_values = true)]
    pub theta: String,
    /// Roll-outs averaged into the estimate (1..=100000).
    #[arg(long, value_name = "M", default_value_t = 1)]
    pub trajectories: u64,
    /// Seed of the roll-outs.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
}

/// Why an estimate could not be computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EstimateError {
    /// The config, or the oracle built from it.
    #[error(transparent)]
    Config(#[from] RunError),
    /// θ is not a list of finite numbers of the policy's dimension.
    #[error("theta: {0}")]
    Theta(String),
    /// The number of roll-outs is out of range.
    #[error("trajectories must lie in 1..={MAX_TRAJECTORIES}, got {0}")]
    Trajectories(u64),
    /// A roll-out or the estimator failed.
    #[error("the estimate: {0}")]
    Oracle(String),
}

/// Run `ilopt estimate`.
///
/// # Errors
/// [`EstimateError`] naming the input at fault.
pub fn run(args: &EstimateArgs) -> Result<Value, EstimateError> {
    let config = RunFile::load(&args.config)?;
    let theta: Vec<f64> =
        serde_json::from_str(&args.theta).map_err(|e| EstimateError::Theta(e.to_string()))?;
    let learner = task_learner(&config)?;
    let estimate = ilopt::with_task_learner!(&learner, t => estimate(t, &config, &theta, args.trajectories, args.seed))?;
    let (task, policy, dim) =
        ilopt::with_task_learner!(&learner, t => (t.task_name(), t.policy_name(), t.dim()));
    Ok(json!({
        "task": task,
        "policy": policy,
        "dim": dim,
        "trajectories": args.trajectories,
        "seed": args.seed,
        "estimate": estimate,
    }))
}

/// [`estimate`] on the config's built-in task: the route of `ilopt estimate` and of the Python
/// package's `ilopt.oracle_estimate`.
///
/// # Errors
/// As [`estimate`], and [`RunError`] if the task cannot be built.
pub fn estimate_config(
    config: &LoadedConfig,
    theta: &[f64],
    trajectories: u64,
    seed: u64,
) -> Result<Vec<f64>, EstimateError> {
    let learner = task_learner(config)?;
    ilopt::with_task_learner!(&learner, t => estimate(t, config, theta, trajectories, seed))
}

/// The oracle's estimate of ∇F(θ) (eq. 3.15, causal form, the config's baseline): the mean over
/// `trajectories` roll-outs of π_θ drawn from one RNG seeded with `seed`.
///
/// # Errors
/// [`EstimateError::Theta`] for θ of the wrong length or with a non-finite entry,
/// [`EstimateError::Trajectories`] out of 1..=[`MAX_TRAJECTORIES`], the oracle's construction
/// error, or [`EstimateError::Oracle`] for a failing roll-out or estimate.
pub fn estimate<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
    theta: &[f64],
    trajectories: u64,
    seed: u64,
) -> Result<Vec<f64>, EstimateError> {
    let d = task.dim();
    if theta.len() != d {
        return Err(EstimateError::Theta(format!(
            "has {} entries, the {} policy has {d} parameters",
            theta.len(),
            task.policy_name()
        )));
    }
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(EstimateError::Theta(format!(
            "entry {i} (0-based) is not finite"
        )));
    }
    let m = usize::try_from(trajectories)
        .ok()
        .filter(|m| (1..=MAX_TRAJECTORIES).contains(m))
        .ok_or(EstimateError::Trajectories(trajectories))?;
    /// One roll-out and its estimate at θ.
    struct Draw<'a> {
        theta: &'a DVector<f64>,
        seed: u64,
    }
    impl OnOracle for Draw<'_> {
        type Output = Result<Vec<f64>, String>;
        fn on<P: IlProblem<f64>>(self, oracle: &mut P) -> Result<Self::Output, RunError> {
            let mut rng = KitRng::seed_from_u64(self.seed);
            let mut cost = Cost::default();
            Ok(oracle
                .rollout(&Behaviour::Learner(self.theta), &mut rng, &mut cost)
                .and_then(|t| oracle.estimate(self.theta, &t, EstimatorForm::Causal, &mut cost))
                .map(|g| g.iter().copied().collect())
                .map_err(|e| e.to_string()))
        }
    }
    let theta = DVector::from_column_slice(theta);
    let draw = Draw {
        theta: &theta,
        seed,
    };
    with_oracle(task, config, m, draw)?.map_err(EstimateError::Oracle)
}
