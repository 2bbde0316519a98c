//! The `ilopt run` config file (TOML; every key in `docs/run.md`): the schema, its defaults and
//! its validation. [`RunFile::load`] reads a file and returns it *resolved*: every default filled
//! in, every relative path made absolute against the config file's directory, every range
//! checked (the `resolve` module). Each failure is one [`RunError`] naming the file and the key.

use super::algorithm_keys::{check_known_keys, overlay};
use super::error::{RunError, invalid};
use super::integer_keys::{check_schema_integers, integer_error};
use ilopt::algo::AlgorithmConfig;
use ilopt::task::AfterEnd;
pub use ilopt::task::cartpole::CartPoleExpertChoice;
use ilopt::task::obstacle::ObstacleFeatures;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::path::{Path, PathBuf};

pub use super::integer_keys::{MAX_EPISODES, MAX_SEEDS, MAX_STEPS, MAX_TRAJECTORIES};
/// Default standard deviation of the obstacle task's linear-Gaussian learner.
pub const DEFAULT_SIGMA: f64 = 0.1;
/// Default number of evaluation episodes per checkpoint.
pub const DEFAULT_EPISODES: u32 = 10;
/// Default bound on ‖θ‖₂ beyond which a run is diverged (the paper-checks profiles' bound).
pub const DEFAULT_NORM_BOUND: f64 = 1e4;

/// A whole config file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunFile {
    /// The task, its expert and the objective (left out: a plug-in task, `name = "custom"`).
    #[serde(default)]
    pub task: TaskSection,
    /// The learner's policy class.
    #[serde(default)]
    pub policy: PolicySection,
    /// The algorithm and its hyper-parameters (the schema of [`AlgorithmConfig`]).
    pub algorithm: AlgorithmConfig,
    /// Budget, seeds, θ₀.
    pub run: RunSection,
    /// When and how the learner is evaluated.
    #[serde(default)]
    pub evaluation: EvaluationSection,
}

/// Which task.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskName {
    /// CartPole-v1 with the PPO or LQR expert (thesis §4.2).
    Cartpole,
    /// The obstacle-avoidance task with the velocity-obstacle expert (thesis §4.1).
    Obstacle,
    /// A toy MDP file (docs/formats/toy-mdp.md).
    Toy,
    /// A task a program passes with the config (`ilopt_cli::run::run_task`, Python's
    /// `ilopt.run(config, task=...)`): it brings its own expert, policy and objective.
    Custom,
}

impl TaskName {
    /// `"cartpole"`, `"obstacle"`, `"toy"`.
    pub fn name(self) -> &'static str {
        match self {
            TaskName::Cartpole => "cartpole",
            TaskName::Obstacle => "obstacle",
            TaskName::Toy => "toy",
            TaskName::Custom => "custom",
        }
    }
}

/// The objective's kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HorizonKind {
    /// A stream of exactly `task.steps` decisions (the thesis's F).
    Fixed,
    /// One episode per trajectory.
    Episodic,
}

/// `[task]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSection {
    /// `cartpole`, `obstacle`, `toy`, or `custom` for a plug-in task.
    pub name: TaskName,
    /// CartPole: `ppo` (default) or `lqr`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expert: Option<CartPoleExpertChoice>,
    /// CartPole with `expert = "ppo"`: a PPO expert file instead of the built-in one (relative
    /// to the config file's directory).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expert_file: Option<PathBuf>,
    /// Toy: the MDP file (relative to the config file's directory).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mdp: Option<PathBuf>,
    /// CartPole and obstacle: `fixed` (default) or `episodic`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon: Option<HorizonKind>,
    /// Fixed horizon: decisions per trajectory (default CartPole 500, obstacle 200).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<usize>,
    /// Fixed horizon: `reset` (CartPole's default) or `absorb` (the obstacle task's default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after_end: Option<AfterEnd>,
}

/// A config without `[task]`: a plug-in task's.
impl Default for TaskSection {
    fn default() -> Self {
        TaskSection {
            name: TaskName::Custom,
            expert: None,
            expert_file: None,
            mdp: None,
            horizon: None,
            steps: None,
            after_end: None,
        }
    }
}

/// The CartPole learner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PolicyKind {
    /// Two-action softmax over φ(s) (10 parameters; the thesis's).
    Softmax,
    /// Logistic policy over φ(s) (5 parameters).
    Logistic,
}

/// `[policy]`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolicySection {
    /// CartPole: `softmax` (default) or `logistic`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<PolicyKind>,
    /// Obstacle: σ of the linear-Gaussian learner (> 0, finite; default 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// Obstacle: the feature map (`{ kind = "basic" }`, default, or `{ kind = "rbf", … }`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub features: Option<ObstacleFeatures>,
}

/// The initial parameter θ₀: `"zero"` or a list of numbers.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Theta0 {
    /// θ₀ = 0.
    #[default]
    Zero,
    /// The given values (their count must be the policy's dimension).
    Values(Vec<f64>),
}

impl Serialize for Theta0 {
    fn serialize<Se: Serializer>(&self, s: Se) -> Result<Se::Ok, Se::Error> {
        match self {
            Theta0::Zero => s.serialize_str("zero"),
            Theta0::Values(v) => v.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Theta0 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Theta0;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(r#""zero" or an array of numbers"#)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Theta0, E> {
                if v == "zero" {
                    Ok(Theta0::Zero)
                } else {
                    Err(E::invalid_value(de::Unexpected::Str(v), &self))
                }
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Theta0, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = seq.next_element::<f64>()? {
                    v.push(x);
                }
                Ok(Theta0::Values(v))
            }
        }
        d.deserialize_any(V)
    }
}

/// `[run]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// Budget in gradient calls (per-state gradient evaluations); ≥ 1.
    pub budget_calls: u64,
    /// Trajectories averaged per gradient (oracle methods; 1 for dataset learners); ≥ 1.
    #[serde(default = "one")]
    pub trajectories_per_gradient: usize,
    /// A baseline subtracted from every decision's loss-to-go in eq. 3.15 (oracle methods;
    /// [`ilopt::baseline::Baseline`], e.g. `{ kind = "leave-one-out" }`); absent: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline: Option<ilopt::baseline::Baseline>,
    /// The seeds, one run each (non-empty, distinct).
    pub seeds: Vec<u64>,
    /// θ₀ (default `"zero"`).
    #[serde(default)]
    pub theta0: Theta0,
    /// A run whose ‖θ‖₂ exceeds this bound (checked at θ₀ and after every step) ends as
    /// diverged, as the appendix judges its runs; finite and > 0 (default 1e4).
    #[serde(default = "default_norm_bound")]
    pub norm_bound: f64,
}

fn one() -> usize {
    1
}

fn default_norm_bound() -> f64 {
    DEFAULT_NORM_BOUND
}

/// `[evaluation]`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvaluationSection {
    /// Checkpoints at 0, `every_calls`, 2·`every_calls`, …, the budget (default budget / 10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_calls: Option<u64>,
    /// Deterministic evaluation episodes per checkpoint (CartPole, obstacle; default 10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub episodes: Option<u32>,
}

/// A loaded and resolved config with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedConfig {
    /// The resolved config (defaults filled, paths absolute).
    pub file: RunFile,
    /// The config file.
    pub path: PathBuf,
    /// The `[algorithm]` table as written in the file (its numbers as the user wrote them).
    pub raw_algorithm: Option<toml::Value>,
}

impl LoadedConfig {
    /// The resolved config as TOML (what `config.toml` in the output directory holds): every
    /// default filled in, the algorithm's numbers as the file wrote them (the kit writes a number
    /// it did not read as an exact fraction, e.g. `"1/2"`).
    ///
    /// # Errors
    /// A message if the config cannot be written as TOML.
    pub fn to_toml(&self) -> Result<String, String> {
        #[derive(Serialize)]
        struct Out<'a> {
            task: &'a TaskSection,
            policy: &'a PolicySection,
            algorithm: toml::Value,
            run: &'a RunSection,
            evaluation: &'a EvaluationSection,
        }
        let f = &self.file;
        let mut algorithm = toml::Value::try_from(&f.algorithm).map_err(|e| e.to_string())?;
        if let Some(raw) = &self.raw_algorithm {
            overlay(&mut algorithm, raw);
        }
        toml::to_string(&Out {
            task: &f.task,
            policy: &f.policy,
            algorithm,
            run: &f.run,
            evaluation: &f.evaluation,
        })
        .map_err(|e| e.to_string())
    }

    /// An [`RunError::Invalid`] for `key` of this config.
    pub fn invalid(&self, key: &str, message: impl std::fmt::Display) -> RunError {
        invalid(&self.path, key, message)
    }
}

impl RunFile {
    /// Read, parse, resolve and validate a config file.
    ///
    /// # Errors
    /// [`RunError::Io`], [`RunError::Parse`] (syntax, unknown key, wrong type) or
    /// [`RunError::Invalid`] (a value out of range, an integer key included, or not allowed for
    /// the task).
    pub fn load(path: &Path) -> Result<LoadedConfig, RunError> {
        let text = std::fs::read_to_string(path).map_err(|e| RunError::io(path, e))?;
        Self::parse(&text, path)
    }

    /// [`RunFile::load`] on a text, `path` naming it (its directory resolves relative paths).
    ///
    /// # Errors
    /// As [`RunFile::load`], without [`RunError::Io`].
    pub fn parse(text: &str, path: &Path) -> Result<LoadedConfig, RunError> {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Self::from_toml_str(text, path, &dir)
    }

    /// [`RunFile::parse`] with relative paths resolved against `base_dir` rather than the
    /// directory of `path`, which only names the config in messages (a config built in memory,
    /// e.g. from a Python dict, names itself and resolves against the current directory).
    ///
    /// # Errors
    /// As [`RunFile::parse`].
    pub fn from_toml_str(
        text: &str,
        path: &Path,
        base_dir: &Path,
    ) -> Result<LoadedConfig, RunError> {
        let parse_error = |message: String| RunError::Parse {
            path: path.to_path_buf(),
            message,
        };
        let raw: toml::Table = toml::from_str(text).map_err(|e| parse_error(e.to_string()))?;
        check_schema_integers(&raw, path)?;
        let mut file: RunFile = toml::from_str(text).map_err(|e| {
            integer_error(text, &e, path).unwrap_or_else(|| parse_error(e.to_string()))
        })?;
        if let Some(alg) = raw.get("algorithm") {
            check_known_keys(alg, &file.algorithm, path)?;
        }
        file.resolve(base_dir, path)?;
        Ok(LoadedConfig {
            file,
            path: path.to_path_buf(),
            raw_algorithm: raw.get("algorithm").cloned(),
        })
    }

    /// Whether the algorithm is one of the dataset learners (BC, DAgger, RRM, SMILe, forward
    /// training), which roll out their own trajectories and report no gradient estimate.
    pub fn is_dataset_learner(&self) -> bool {
        matches!(
            self.algorithm,
            AlgorithmConfig::Bc(_)
                | AlgorithmConfig::Dagger(_)
                | AlgorithmConfig::Rrm(_)
                | AlgorithmConfig::Smile(_)
                | AlgorithmConfig::ForwardTraining(_)
        )
    }
}
