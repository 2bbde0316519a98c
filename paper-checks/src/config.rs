//! The committed TOML profiles (`configs/quick.toml`, `configs/full.toml`): every size, seed count,
//! hyper-parameter and convergence threshold of the appendix, read once and validated.
//!
//! Algorithms are given as ilopt's own [`AlgorithmConfig`] (the same JSON/serde format the core's
//! `replay` uses), written as TOML tables, so the appendix runs exactly what a user can replay.

use crate::error::Error;
pub use crate::grid::GridDim;
use ilopt::algo::AlgorithmConfig;
pub use ilopt::task::cartpole::CartPoleExpertChoice;
use ilopt::task::{AfterEnd, Horizon};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A whole profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// A short name (`"quick"`, `"full"`); recorded in the provenance.
    pub name: String,
    /// Report seeds per configuration (≥ 2 for a confidence interval; the committed profiles use ≥ 10).
    pub seeds: u32,
    /// Tuning seeds per grid point of the pre-registered tuning protocol ([`crate::protocol`]);
    /// their RNG seeds come from a key namespace of their own, disjoint from the report seeds'.
    pub tuning_seeds: u32,
    /// Which size of the theorem-check suite to run: `"quick"`, `"full"` or `"none"` (skip it).
    pub theory_profile: TheorySize,
    /// The tuning protocol's successive halving and edge extension ([`crate::protocol`]).
    #[serde(default)]
    pub tuning: TuningProtocol,
    /// Fig. 4.2.
    pub gradient_error: GradientError,
    /// Figs. 4.3–4.6, Tables 4.1/4.2.
    pub obstacle: TaskExperiment,
    /// Figs. 4.8–4.10, Tables 4.3/4.4.
    pub cartpole: TaskExperiment,
}

pub use crate::gradient_error::GradientError;

/// The size at which the theorem-check table runs (`ilopt-theory`'s profiles), or not at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum TheorySize {
    /// `ilopt-theory`'s quick table.
    Quick,
    /// `ilopt-theory --full`.
    Full,
    /// No theorem table.
    None,
}

impl TheorySize {
    /// The name a profile and `--theory` use.
    pub fn name(self) -> &'static str {
        match self {
            TheorySize::Quick => "quick",
            TheorySize::Full => "full",
            TheorySize::None => "none",
        }
    }
}

impl std::fmt::Display for TheorySize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The profile's successive-halving schedule and edge-extension limit (`[tuning]`), which the
/// tuning protocol ([`crate::protocol`]) reads and checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TuningProtocol {
    /// The rungs' budgets as fractions of the task's budget, increasing, the last 1; each is
    /// rounded up to a whole number of checkpoint intervals ([`TuningProtocol::rung_budgets`]).
    /// Default `[1]`: every point runs to the whole budget (exhaustive tuning).
    #[serde(default = "default_rungs")]
    pub rungs: Vec<f64>,
    /// At each rung the best ⌈n / `halving`⌉ points go on (default 3; at least 2).
    #[serde(default = "default_halving")]
    pub halving: u32,
    /// How many rounds of edge extension a row may take (default 0).
    #[serde(default)]
    pub extensions: u32,
    /// A grid of fewer points than this runs every point to the whole budget (successive
    /// halving saves little on a small grid, and its early rungs can drop a slow starter);
    /// default 0: every grid is halved.
    #[serde(default)]
    pub exhaustive_below: u32,
}

fn default_rungs() -> Vec<f64> {
    vec![1.0]
}

fn default_halving() -> u32 {
    3
}

impl Default for TuningProtocol {
    fn default() -> Self {
        TuningProtocol {
            rungs: default_rungs(),
            halving: default_halving(),
            extensions: 0,
            exhaustive_below: 0,
        }
    }
}

/// One task's experiment: the learner, the evaluation, the convergence criterion, the algorithms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskExperiment {
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
    /// The objective the oracle methods descend: `{ kind = "fixed", steps,
    /// after_end = "reset" | "absorb" }` (the thesis's fixed horizon; the default: CartPole 500
    /// decisions with resets, the obstacle task 200 with an absorbing end) or
    /// `{ kind = "episodic" }` (one Gymnasium episode per trajectory). An algorithm may override
    /// it (the appendix's labelled control rows).
    #[serde(default)]
    pub horizon: Option<Horizon>,
    /// Every run's budget in gradient calls (per-state gradient evaluations, [`ilopt::problem::Cost`]),
    /// the same for every method of the task. A run stops at the first step that reaches it.
    pub budget: u64,
    /// Checkpoints at the fixed call counts 0, `checkpoint_every`, 2·`checkpoint_every`, …,
    /// `budget` (each evaluated at the first iterate whose cumulative calls reach it).
    pub checkpoint_every: u64,
    /// Sustained convergence: the score ≥ `converge_score` at this many consecutive checkpoints
    /// (default 3).
    #[serde(default = "default_sustain")]
    pub sustain: usize,
    /// A run whose ‖θ‖₂ exceeds this bound (or whose θ is not finite) is *diverged*.
    pub norm_bound: f64,
    /// θ₁, the initial parameter of every run: `{ law = "zero" }` (default) or
    /// `{ law = "normal", std }` (independent N(0, std²) entries drawn from the run's own seed).
    #[serde(default)]
    pub theta1: Theta1,
    /// Deterministic evaluation episodes per checkpoint.
    pub eval_episodes: u32,
    /// Learner trajectories for the checkpoint gradient estimate (Fig. 4.5; 0 = skip).
    #[serde(default)]
    pub grad_trajectories: u32,
    /// Fig. 4.9 (CartPole): at each checkpoint, episodes are reset after every crash until one
    /// full T-step episode is completed; at most this many resets are counted (the cap).
    #[serde(default = "default_full_episode_cap")]
    pub full_episode_cap: u32,
    /// The convergence threshold on the evaluation score (success rate for the obstacle task,
    /// mean episode reward / 500 for CartPole), in [0, 1].
    pub converge_score: f64,
    /// The algorithms, in table order.
    pub algorithms: Vec<AlgorithmEntry>,
}

fn default_sustain() -> usize {
    3
}

fn default_full_episode_cap() -> u32 {
    100
}

/// θ₁, the runs' initial parameter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Theta1 {
    /// θ₁ = 0.
    #[default]
    Zero,
    /// Independent N(0, std²) entries from the run's seed (key `"<run key>|theta1"`).
    Normal {
        /// Standard deviation (finite, > 0).
        std: f64,
    },
}

impl Theta1 {
    /// How the appendix states it.
    pub fn describe(&self) -> String {
        match self {
            Theta1::Zero => "θ₁ = 0".into(),
            Theta1::Normal { std } => {
                format!("θ₁ with independent N(0, {std}²) entries, seeded per run")
            }
        }
    }
}

/// The two tasks of chapter 4.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskKind {
    /// §4.1, linear-Gaussian learner, velocity-obstacle expert.
    Obstacle,
    /// §4.2, softmax learner, PPO or LQR expert.
    Cartpole,
}

impl TaskKind {
    /// `"obstacle"` / `"cartpole"`.
    pub fn name(self) -> &'static str {
        match self {
            TaskKind::Obstacle => "obstacle",
            TaskKind::Cartpole => "cartpole",
        }
    }
}

/// The default objective of a task: CartPole 500 decisions with resets (the thesis's Fig. 4.9
/// protocol), the obstacle task 200 decisions with an absorbing end.
pub fn default_horizon(task: TaskKind) -> Horizon {
    match task {
        TaskKind::Cartpole => Horizon::fixed(500, AfterEnd::Reset),
        TaskKind::Obstacle => Horizon::fixed(200, AfterEnd::Absorb),
    }
}

/// What an algorithm's row is in the appendix.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    /// A row the thesis printed for this task.
    #[default]
    Thesis,
    /// An algorithm or variant the thesis did not run on this task (labelled as extra).
    Extra,
    /// A control row (e.g. the episodic objective), not a thesis claim.
    Control,
}

/// What determines CartPole's expert's labels, for the reuse key: the choice and, for PPO, a
/// hash of the expert file's bytes (a retrained expert invalidates the cached results).
pub fn expert_identity(choice: CartPoleExpertChoice) -> String {
    match choice {
        CartPoleExpertChoice::Lqr => "lqr".into(),
        CartPoleExpertChoice::Ppo => {
            format!(
                "ppo:{:016x}",
                crate::stats::fnv1a(ilopt::expert::ppo::COMMITTED_CARTPOLE_EXPERT)
            )
        }
    }
}

/// One algorithm of a task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlgorithmEntry {
    /// The label in tables and figures (`"STORM"`, `"IS-STORM"`, …).
    pub label: String,
    /// Thesis row, extra row or control row.
    #[serde(default)]
    pub role: Role,
    /// What the row is, printed under the table (e.g. "E10: the unweighted old-point term, as
    /// the thesis printed it").
    #[serde(default)]
    pub note: Option<String>,
    /// Overrides the task's objective (control rows).
    #[serde(default)]
    pub horizon: Option<Horizon>,
    /// Trajectories per gradient m of the oracle methods (default 1; a grid may tune it).
    #[serde(default)]
    pub m: Option<usize>,
    /// A baseline (control variate, [`ilopt::baseline::Baseline`]) subtracted from every
    /// decision's loss-to-go in the oracle methods' estimates (absent: none, eq. 3.15 as it is;
    /// a grid may tune it with the path `"baseline"`).
    #[serde(default)]
    pub baseline: Option<ilopt::baseline::Baseline>,
    /// The algorithm and its hyper-parameters (ilopt's [`AlgorithmConfig`]): the grid's base.
    pub config: AlgorithmConfig,
    /// The pre-registered tuning grid (the Cartesian product of the dimensions, the first
    /// dimension varying slowest); empty: the config is used as it is.
    #[serde(default)]
    pub grid: Vec<GridDim>,
    /// A grid made of several products (sub-grids), tried together: e.g. a constant step
    /// schedule over (η, a) beside an adaptive one over its own constants. Exclusive with
    /// `grid`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grids: Vec<Vec<GridDim>>,
    /// Take the hyper-parameters (config and m) selected for the row of this label instead of
    /// tuning (control rows: the same method under another objective).
    #[serde(default)]
    pub hyper_parameters_of: Option<String>,
}

impl AlgorithmEntry {
    /// The objective of this row's runs.
    pub fn horizon(&self, task: &TaskExperiment, kind: TaskKind) -> Horizon {
        self.horizon
            .or(task.horizon)
            .unwrap_or_else(|| default_horizon(kind))
    }

    /// The row's grid as sub-grids: `grids`, or `grid` as the one product (none without a
    /// grid).
    pub fn subgrids(&self) -> Vec<Vec<GridDim>> {
        if !self.grids.is_empty() {
            self.grids.clone()
        } else if self.grid.is_empty() {
            Vec::new()
        } else {
            vec![self.grid.clone()]
        }
    }

    /// Whether the row has a grid to tune.
    pub fn has_grid(&self) -> bool {
        !(self.grid.is_empty() && self.grids.is_empty())
    }

    /// The row's grid points in grid order ([`crate::grid::points`]).
    ///
    /// # Errors
    /// As [`crate::grid::points`].
    pub fn grid_points(&self) -> Result<Vec<crate::grid::GridPoint>, String> {
        self.points_of(&self.subgrids())
    }

    /// The points of `subgrids` (this row's grid, possibly extended) around the row's config.
    ///
    /// # Errors
    /// As [`crate::grid::points`].
    pub fn points_of(
        &self,
        subgrids: &[Vec<GridDim>],
    ) -> Result<Vec<crate::grid::GridPoint>, String> {
        crate::grid::points(&self.config, self.m, self.baseline.as_ref(), subgrids)
    }

    /// Whether the algorithm draws its gradients from the oracle (m applies), rather than
    /// training on a dataset (BC, DAgger).
    pub fn is_oracle_method(&self) -> bool {
        !matches!(
            self.config,
            AlgorithmConfig::Bc(_)
                | AlgorithmConfig::Dagger(_)
                | AlgorithmConfig::Rrm(_)
                | AlgorithmConfig::Smile(_)
                | AlgorithmConfig::ForwardTraining(_)
        )
    }
}

fn field(file: &Path, name: &str, reason: impl Into<String>) -> Error {
    Error::Config {
        file: file.display().to_string(),
        message: format!("field `{name}`: {}", reason.into()),
    }
}

/// The committed profiles' TOML texts by name (`"quick"`, `"full"`), embedded so that an
/// installed binary runs from any directory; `None` for any other name.
pub fn committed_text(name: &str) -> Option<&'static str> {
    match name {
        "quick" => Some(include_str!("../configs/quick.toml")),
        "full" => Some(include_str!("../configs/full.toml")),
        _ => None,
    }
}

/// The `theory_profile` a committed profile (`"quick"`, `"full"`) sets; `None` for any other
/// name.
pub fn committed_theory_profile(name: &str) -> Option<TheorySize> {
    let text = committed_text(name)?;
    let p = Profile::from_toml(text, Path::new(name)).expect("a committed profile is valid");
    Some(p.theory_profile)
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
        if self.tuning_seeds == 0 {
            return Err(field(file, "tuning_seeds", "must be at least 1"));
        }
        self.tuning
            .validate()
            .map_err(|(name, reason)| field(file, &format!("tuning.{name}"), reason))?;
        self.gradient_error
            .validate()
            .map_err(|(name, reason)| field(file, &name, reason))?;
        for (kind, t) in [
            (TaskKind::Obstacle, &self.obstacle),
            (TaskKind::Cartpole, &self.cartpole),
        ] {
            let name = kind.name();
            if kind == TaskKind::Obstacle && !t.sigma.is_some_and(|s| s.is_finite() && s > 0.0) {
                return Err(field(file, "obstacle.sigma", "must be set, finite and > 0"));
            }
            if kind == TaskKind::Obstacle && t.expert.is_some() {
                return Err(field(
                    file,
                    "obstacle.expert",
                    "the obstacle task's expert is the velocity-obstacle expert; remove the field",
                ));
            }
            if kind == TaskKind::Cartpole && t.features.is_some() {
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
            if kind == TaskKind::Cartpole && t.sigma.is_some() {
                return Err(field(
                    file,
                    "cartpole.sigma",
                    "CartPole's learner is a softmax (no σ); remove the field",
                ));
            }
            if t.budget == 0 {
                return Err(field(file, &format!("{name}.budget"), "must be ≥ 1"));
            }
            if t.checkpoint_every == 0 || t.checkpoint_every > t.budget {
                return Err(field(
                    file,
                    &format!("{name}.checkpoint_every"),
                    "must lie in 1..=budget",
                ));
            }
            if t.sustain == 0 {
                return Err(field(file, &format!("{name}.sustain"), "must be ≥ 1"));
            }
            if !(t.norm_bound.is_finite() && t.norm_bound > 0.0) {
                return Err(field(
                    file,
                    &format!("{name}.norm_bound"),
                    "must be finite and > 0",
                ));
            }
            if matches!(t.theta1, Theta1::Normal { std } if !(std.is_finite() && std > 0.0)) {
                return Err(field(
                    file,
                    &format!("{name}.theta1.std"),
                    "must be finite and > 0",
                ));
            }
            if t.full_episode_cap == 0 {
                return Err(field(
                    file,
                    &format!("{name}.full_episode_cap"),
                    "must be ≥ 1",
                ));
            }
            if let Some(Horizon::Fixed { steps: 0, .. }) = t.horizon {
                return Err(field(file, &format!("{name}.horizon"), "needs steps ≥ 1"));
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
            // Each row's results live in a file named after its label's slug: two labels with
            // one slug would share (and overwrite) one file.
            let mut slugs = std::collections::BTreeMap::new();
            for (i, a) in t.algorithms.iter().enumerate() {
                let here = format!("{name}.algorithms[{i}] ({})", a.label);
                if !labels.insert(a.label.clone()) {
                    return Err(field(file, &format!("{here}.label"), "duplicate label"));
                }
                let slug = crate::naming::slug(&a.label);
                if let Some(other) = slugs.insert(slug.clone(), a.label.clone()) {
                    return Err(field(
                        file,
                        &format!("{here}.label"),
                        format!(
                            "its file name `{name}-{slug}.json` is also that of label \"{other}\" \
                             (labels must differ in more than case and punctuation)"
                        ),
                    ));
                }
                if a.m == Some(0) {
                    return Err(field(file, &format!("{here}.m"), "must be ≥ 1"));
                }
                if a.m.is_some_and(|m| m > 1) && !a.is_oracle_method() {
                    return Err(field(
                        file,
                        &format!("{here}.m"),
                        "applies to the oracle methods only",
                    ));
                }
                if let Some(Horizon::Fixed { steps: 0, .. }) = a.horizon {
                    return Err(field(file, &format!("{here}.horizon"), "needs steps ≥ 1"));
                }
                if let Some(of) = &a.hyper_parameters_of {
                    let source = t.algorithms.iter().find(|b| &b.label == of);
                    if source.is_none_or(|b| b.hyper_parameters_of.is_some()) {
                        return Err(field(
                            file,
                            &format!("{here}.hyper_parameters_of"),
                            format!(
                                "`{of}` must be another row of the task that is not itself borrowed"
                            ),
                        ));
                    }
                    if a.has_grid() {
                        return Err(field(
                            file,
                            &format!("{here}.grid"),
                            "a row that borrows its hyper-parameters has no grid",
                        ));
                    }
                }
                // The algorithm's own validation (names the hyper-parameter), at every grid point.
                if !a.grid.is_empty() && !a.grids.is_empty() {
                    return Err(field(
                        file,
                        &format!("{here}.grids"),
                        "give either `grid` (one product) or `grids` (several), not both",
                    ));
                }
                let points = a
                    .grid_points()
                    .map_err(|e| field(file, &format!("{here}.grid"), e))?;
                for p in &points {
                    if p.m > 1 && !a.is_oracle_method() {
                        return Err(field(
                            file,
                            &format!("{here}.grid"),
                            "m applies to the oracle methods only",
                        ));
                    }
                    if p.baseline != ilopt::baseline::Baseline::None {
                        let where_ = if a.subgrids().iter().flatten().any(|d| d.path == "baseline")
                        {
                            format!("{here}.grid")
                        } else {
                            format!("{here}.baseline")
                        };
                        if !a.is_oracle_method() {
                            return Err(field(
                                file,
                                &where_,
                                "a baseline applies to the oracle methods only",
                            ));
                        }
                        // The oracle's own checks (values, decay, leave-one-out's m ≥ 2).
                        ilopt::baseline::Baselined::<(), f64>::new((), p.m, &p.baseline).map_err(
                            |e| field(file, &where_, format!("{e} (grid point {})", p.describe())),
                        )?;
                    }
                    type Obs = ilopt::task::TaskProblem<
                        ilopt::task::obstacle::ObstacleTask,
                        ilopt::policy::LinearGaussian<f64>,
                    >;
                    p.config.build::<f64, Obs>().map_err(|e| {
                        field(
                            file,
                            &format!("{here}.config"),
                            format!("{e} (grid point {})", p.describe()),
                        )
                    })?;
                }
            }
        }
        Ok(())
    }
}
