//! Resolving a parsed config: every default filled in, the paths made absolute against the
//! config file's directory, every range checked (the integer keys' own ranges before, in
//! `integer_keys`), each failure naming its key.

use super::config::{
    CartPoleExpertChoice, DEFAULT_EPISODES, DEFAULT_SIGMA, HorizonKind, MAX_SEEDS, PolicyKind,
    RunFile, TaskName, Theta0,
};
use super::error::{RunError, invalid};
use ilopt::task::AfterEnd;
use ilopt::task::obstacle::ObstacleFeatures;
use std::path::Path;

impl RunFile {
    /// Fill the defaults, make the paths absolute and check every range.
    pub(super) fn resolve(&mut self, dir: &Path, path: &Path) -> Result<(), RunError> {
        let bad = |key: &str, m: &dyn std::fmt::Display| invalid(path, key, m);
        // The first key of `keys` that is set, refused with `why`.
        let refuse = |keys: &[(&str, bool)], why: &str| match keys.iter().find(|(_, set)| *set) {
            Some((key, _)) => Err(bad(key, &why)),
            None => Ok(()),
        };
        let t = &mut self.task;
        let p = &mut self.policy;
        // The keys of a task built from `[task]` and `[policy]` (all but `task.mdp`), and which
        // of them the config sets.
        let not_toy = [
            ("task.expert", t.expert.is_some()),
            ("task.expert_file", t.expert_file.is_some()),
            ("task.horizon", t.horizon.is_some()),
            ("task.steps", t.steps.is_some()),
            ("task.after_end", t.after_end.is_some()),
            ("policy.kind", p.kind.is_some()),
            ("policy.sigma", p.sigma.is_some()),
            ("policy.features", p.features.is_some()),
        ];
        let not_for = |key: &str, set: bool| -> Result<(), RunError> {
            if set {
                Err(bad(
                    key,
                    &format!("not a key of the {} task", t.name.name()),
                ))
            } else {
                Ok(())
            }
        };
        match t.name {
            TaskName::Cartpole => {
                not_for("task.mdp", t.mdp.is_some())?;
                not_for("policy.sigma", p.sigma.is_some())?;
                not_for("policy.features", p.features.is_some())?;
                let expert = *t.expert.get_or_insert(CartPoleExpertChoice::Ppo);
                if expert == CartPoleExpertChoice::Lqr && t.expert_file.is_some() {
                    return Err(bad("task.expert_file", &"only with expert = \"ppo\""));
                }
                p.kind.get_or_insert(PolicyKind::Softmax);
            }
            TaskName::Obstacle => {
                not_for("task.expert", t.expert.is_some())?;
                not_for("task.expert_file", t.expert_file.is_some())?;
                not_for("task.mdp", t.mdp.is_some())?;
                not_for("policy.kind", p.kind.is_some())?;
                let sigma = *p.sigma.get_or_insert(DEFAULT_SIGMA);
                if !(sigma.is_finite() && sigma > 0.0) {
                    return Err(bad(
                        "policy.sigma",
                        &format!("must be finite and > 0, got {sigma}"),
                    ));
                }
                let features = p.features.get_or_insert_with(ObstacleFeatures::default);
                features
                    .validate()
                    .map_err(|e| bad("policy.features", &e))?;
            }
            TaskName::Toy => {
                refuse(
                    &not_toy,
                    "not a key of the toy task (the MDP file fixes the horizon, the expert and the policy)",
                )?;
                if t.mdp.is_none() {
                    return Err(bad("task.mdp", &"required for the toy task"));
                }
            }
            TaskName::Custom => refuse(
                &[[("task.mdp", t.mdp.is_some())].as_slice(), &not_toy].concat(),
                "not a key of a plug-in task (the task passed with the config brings its expert, policy and horizon)",
            )?,
        }
        if !matches!(t.name, TaskName::Toy | TaskName::Custom) {
            match *t.horizon.get_or_insert(HorizonKind::Fixed) {
                HorizonKind::Fixed => {
                    let (steps, after) = match t.name {
                        TaskName::Cartpole => (500, AfterEnd::Reset),
                        _ => (200, AfterEnd::Absorb),
                    };
                    t.steps.get_or_insert(steps);
                    t.after_end.get_or_insert(after);
                }
                HorizonKind::Episodic => {
                    not_for("task.steps", t.steps.is_some())?;
                    not_for("task.after_end", t.after_end.is_some())?;
                }
            }
        }
        for file in [&mut t.expert_file, &mut t.mdp].into_iter().flatten() {
            let joined = if file.is_relative() {
                dir.join(&*file)
            } else {
                file.clone()
            };
            // Canonical when the file exists (no `..` left); else absolute, and the error
            // reading it names that path.
            *file = std::fs::canonicalize(&joined)
                .or_else(|_| std::path::absolute(&joined))
                .unwrap_or(joined);
        }
        let r = &self.run;
        if r.trajectories_per_gradient > 1 && self.is_dataset_learner() {
            return Err(bad(
                "run.trajectories_per_gradient",
                &"must be 1 for a dataset learner (set the algorithm's trajectories_per_iteration)",
            ));
        }
        if r.baseline.is_some() && self.is_dataset_learner() {
            return Err(bad(
                "run.baseline",
                &"a dataset learner takes no baseline (baselines apply to the oracle methods' eq. 3.15)",
            ));
        }
        if r.seeds.is_empty() {
            return Err(bad("run.seeds", &"give at least one seed"));
        }
        if r.seeds.len() > MAX_SEEDS {
            return Err(bad("run.seeds", &format!("at most {MAX_SEEDS} seeds")));
        }
        let mut sorted = r.seeds.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(bad("run.seeds", &format!("seed {} is repeated", w[0])));
        }
        if let Theta0::Values(v) = &r.theta0
            && let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite())
        {
            return Err(bad(
                "run.theta0",
                &format!("entry {i} (0-based) is not finite: {x}"),
            ));
        }
        if !(r.norm_bound.is_finite() && r.norm_bound > 0.0) {
            return Err(bad(
                "run.norm_bound",
                &format!(
                    "must be finite and > 0, got {}",
                    toml::Value::Float(r.norm_bound)
                ),
            ));
        }
        let budget = r.budget_calls;
        let e = &mut self.evaluation;
        let every = *e.every_calls.get_or_insert((budget / 10).max(1));
        if every > budget {
            return Err(bad(
                "evaluation.every_calls",
                &format!("must lie in 1..=run.budget_calls = {budget}, got {every}"),
            ));
        }
        e.episodes.get_or_insert(DEFAULT_EPISODES);
        Ok(())
    }
}
