//! The committed TOML profiles (`configs/quick.toml`, `configs/full.toml`): every size, seed count,
//! hyper-parameter and convergence threshold of the appendix, read once and validated.
//!
//! Algorithms are given as ilopt's own [`AlgorithmConfig`] (the same JSON/serde format the core's
//! `replay` uses), written as TOML tables, so the appendix runs exactly what a user can replay.

use crate::error::Error;
use ilopt::algo::AlgorithmConfig;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A whole profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// A short name (`"quick"`, `"full"`); recorded in the provenance.
    pub name: String,
    /// Seeds per configuration (≥ 2 for a confidence interval; issue 6 asks for ≥ 10).
    pub seeds: u32,
    /// Which size of the theorem-check suite to run: `"quick"`, `"full"` or `"none"` (skip it).
    pub theory_profile: String,
    /// Fig. 4.2.
    pub gradient_error: GradientError,
    /// Figs. 4.3–4.6, Tables 4.1/4.2.
    pub obstacle: TaskSection,
    /// Figs. 4.8–4.10, Tables 4.3/4.4.
    pub cartpole: TaskSection,
}

pub use crate::gradient_error::GradientError;

/// One task's experiment: the learner, the evaluation, the convergence criterion, the algorithms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSection {
    /// σ_π of the linear-Gaussian learner (obstacle task only; must be absent for CartPole).
    #[serde(default)]
    pub sigma: Option<f64>,
    /// The obstacle learner's features (obstacle task only; default: the 9 basic features).
    #[serde(default)]
    pub features: Option<ilopt::task::obstacle::ObstacleFeatures>,
    /// CartPole's expert (must be absent for the obstacle task, whose expert is the
    /// velocity-obstacle expert of eq. 4.1): `"ppo"` (the thesis's, default) or `"lqr"`.
    #[serde(default)]
    pub expert: Option<CartPoleExpertChoice>,
    /// Iterations per run (each algorithm may override).
    pub iterations: u64,
    /// Evaluate every this many iterations (each algorithm may override).
    pub eval_every: u64,
    /// Deterministic evaluation episodes per checkpoint.
    pub eval_episodes: u32,
    /// Learner trajectories for the checkpoint gradient estimate (Fig. 4.5; 0 = skip).
    #[serde(default)]
    pub grad_trajectories: u32,
    /// The convergence threshold on the evaluation score (success rate for the obstacle task,
    /// mean episode reward / 500 for CartPole), in [0, 1].
    pub converge_score: f64,
    /// The algorithms, in table order.
    pub algorithms: Vec<AlgorithmEntry>,
}

/// Which expert labels CartPole's states.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CartPoleExpertChoice {
    /// The committed PPO expert `experts/cartpole-ppo.json` (thesis §4.2.1: "We use PPO as
    /// expert"), acting greedily.
    #[default]
    Ppo,
    /// The kit's LQR controller on the linearised dynamics.
    Lqr,
}

impl CartPoleExpertChoice {
    /// The committed PPO expert's file (in the repository, next to this package).
    pub fn ppo_file() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../experts/cartpole-ppo.json")
    }

    /// `"PPO"` / `"LQR"`.
    pub fn name(self) -> &'static str {
        match self {
            CartPoleExpertChoice::Ppo => "PPO",
            CartPoleExpertChoice::Lqr => "LQR",
        }
    }

    /// What determines the expert's labels, for the reuse key: the choice and, for PPO, a hash
    /// of the expert file's bytes (a retrained expert invalidates the cached results).
    pub fn identity(self) -> String {
        match self {
            CartPoleExpertChoice::Lqr => "lqr".into(),
            CartPoleExpertChoice::Ppo => format!(
                "ppo:{:016x}",
                std::fs::read_to_string(Self::ppo_file())
                    .map(|t| crate::stats::fnv1a(&t))
                    .unwrap_or(0)
            ),
        }
    }
}

/// One algorithm of a task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlgorithmEntry {
    /// The label in tables and figures (`"STORM"`, `"IS-STORM"`, …).
    pub label: String,
    /// Overrides the task's `iterations`.
    #[serde(default)]
    pub iterations: Option<u64>,
    /// Overrides the task's `eval_every`.
    #[serde(default)]
    pub eval_every: Option<u64>,
    /// The algorithm and its hyper-parameters (ilopt's [`AlgorithmConfig`]).
    pub config: AlgorithmConfig,
}

impl AlgorithmEntry {
    /// Iterations of this algorithm's runs.
    pub fn iterations(&self, task: &TaskSection) -> u64 {
        self.iterations.unwrap_or(task.iterations)
    }
    /// Evaluation period of this algorithm's runs.
    pub fn eval_every(&self, task: &TaskSection) -> u64 {
        self.eval_every.unwrap_or(task.eval_every)
    }
}

fn field(file: &Path, name: &str, reason: impl Into<String>) -> Error {
    Error::Config {
        file: file.display().to_string(),
        message: format!("field `{name}`: {}", reason.into()),
    }
}

impl Profile {
    /// Parse and validate a profile from TOML text; `file` names it in errors.
    ///
    /// # Errors
    /// [`Error::Config`] naming the file and the field (TOML syntax, unknown or missing fields,
    /// wrong types, invalid values, and the algorithm's own hyper-parameter checks).
    pub fn from_toml(text: &str, file: &Path) -> Result<Self, Error> {
        let p: Profile = toml::from_str(text).map_err(|e| Error::Config {
            file: file.display().to_string(),
            message: e.to_string(),
        })?;
        p.validate(file)?;
        Ok(p)
    }

    /// Read a profile from a file.
    ///
    /// # Errors
    /// [`Error::Io`] if unreadable, else as [`Profile::from_toml`].
    pub fn load(file: &Path) -> Result<Self, Error> {
        let text = std::fs::read_to_string(file).map_err(|e| Error::Io {
            path: file.display().to_string(),
            source: e,
        })?;
        Self::from_toml(&text, file)
    }

    fn validate(&self, file: &Path) -> Result<(), Error> {
        if self.seeds < 2 {
            return Err(field(
                file,
                "seeds",
                "must be at least 2 (a CI needs 2 seeds)",
            ));
        }
        if !matches!(self.theory_profile.as_str(), "quick" | "full" | "none") {
            return Err(field(
                file,
                "theory_profile",
                "must be \"quick\", \"full\" or \"none\"",
            ));
        }
        self.gradient_error
            .validate()
            .map_err(|(name, reason)| field(file, &name, reason))?;
        for (name, t) in [("obstacle", &self.obstacle), ("cartpole", &self.cartpole)] {
            if name == "obstacle" && !t.sigma.is_some_and(|s| s.is_finite() && s > 0.0) {
                return Err(field(file, "obstacle.sigma", "must be set, finite and > 0"));
            }
            if name == "obstacle" && t.expert.is_some() {
                return Err(field(
                    file,
                    "obstacle.expert",
                    "the obstacle task's expert is the velocity-obstacle expert; remove the field",
                ));
            }
            if name == "cartpole" && t.features.is_some() {
                return Err(field(
                    file,
                    "cartpole.features",
                    "CartPole's features are the state and a bias; remove the field",
                ));
            }
            if let Some(f) = &t.features {
                f.validate()
                    .map_err(|e| field(file, &format!("{name}.features"), e.to_string()))?;
            }
            if name == "cartpole" && t.sigma.is_some() {
                return Err(field(
                    file,
                    "cartpole.sigma",
                    "CartPole's learner is a softmax (no σ); remove the field",
                ));
            }
            if t.iterations == 0 {
                return Err(field(file, &format!("{name}.iterations"), "must be ≥ 1"));
            }
            if t.eval_every == 0 {
                return Err(field(file, &format!("{name}.eval_every"), "must be ≥ 1"));
            }
            if t.eval_episodes == 0 {
                return Err(field(file, &format!("{name}.eval_episodes"), "must be ≥ 1"));
            }
            if !(0.0..=1.0).contains(&t.converge_score) {
                return Err(field(
                    file,
                    &format!("{name}.converge_score"),
                    "must lie in [0, 1]",
                ));
            }
            if t.algorithms.is_empty() {
                return Err(field(
                    file,
                    &format!("{name}.algorithms"),
                    "must not be empty",
                ));
            }
            let mut labels = std::collections::BTreeSet::new();
            for (i, a) in t.algorithms.iter().enumerate() {
                let here = format!("{name}.algorithms[{i}] ({})", a.label);
                if !labels.insert(a.label.clone()) {
                    return Err(field(file, &format!("{here}.label"), "duplicate label"));
                }
                if a.iterations == Some(0) || a.eval_every == Some(0) {
                    return Err(field(file, &here, "iterations and eval_every must be ≥ 1"));
                }
                // The algorithm's own validation (names the hyper-parameter).
                type Obs = ilopt::task::TaskProblem<
                    ilopt::task::obstacle::ObstacleTask,
                    ilopt::policy::LinearGaussian<f64>,
                >;
                a.config
                    .build::<f64, Obs>()
                    .map_err(|e| field(file, &format!("{here}.config"), e.to_string()))?;
            }
        }
        Ok(())
    }
}
