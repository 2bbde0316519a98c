//! The appendix's protocol section: the objective, budgets and checkpoints, the
//! convergence and divergence rules, θ₁, the selected hyper-parameters of every row, the run
//! statuses, and the whole tuning grid's results (the sensitivity table).

use super::aggregate::num;
use super::doc::{Block, Table};
use crate::config::{Profile, Role, TaskSection};
use crate::experiment::{RunStatus, TaskKind};
use crate::results::Results;
use crate::tuning::TuningResult;

fn strings(xs: &[&str]) -> Vec<String> {
    xs.iter().map(|s| (*s).to_string()).collect()
}

fn role(r: Role) -> &'static str {
    match r {
        Role::Thesis => "thesis row",
        Role::Extra => "extra row",
        Role::Control => "control row",
    }
}

fn section(profile: &Profile, kind: TaskKind) -> &TaskSection {
    match kind {
        TaskKind::Obstacle => &profile.obstacle,
        TaskKind::Cartpole => &profile.cartpole,
    }
}

/// A selection statistic as text: calls, or "2 × budget" when the median tuning run did not
/// converge (or diverged).
pub fn score_text(score: f64, budget: u64) -> String {
    if !score.is_finite() {
        "—".into()
    } else if score >= 2.0 * budget as f64 {
        "2 × budget (median run not converged)".into()
    } else {
        num(score)
    }
}

fn counts(statuses: &[&RunStatus]) -> String {
    let c = statuses.iter().filter(|s| s.is_converged()).count();
    let d = statuses.iter().filter(|s| s.is_diverged()).count();
    let n = statuses.len() - c - d;
    format!("{c} / {n} / {d}")
}

/// The selected hyper-parameters of every row, one line each (also used by the provenance).
pub fn selected_lines(r: &Results) -> Vec<(TaskKind, String, String)> {
    r.tuning
        .iter()
        .map(|t| (t.task, t.label.clone(), t.chosen().describe()))
        .collect()
}

fn protocol_list(profile: &Profile) -> Vec<String> {
    let mut out = Vec::new();
    for kind in [TaskKind::Obstacle, TaskKind::Cartpole] {
        let t = section(profile, kind);
        let overrides: Vec<String> = t
            .algorithms
            .iter()
            .filter(|e| e.horizon.is_some())
            .map(|e| format!("{} → `{}`", e.label, e.horizon(t, kind.name()).label()))
            .collect();
        out.push(format!(
            "**{}.** Objective `{}`{}; budget {} gradient calls per run for every method (a run \
             stops after the step that reaches it, whose calls count in full: DAgger's last round \
             of retraining overshoots the most); \
             checkpoints every {} calls (and at the budget); sustained convergence = score ≥ {} at \
             {} consecutive checkpoints; diverged = ‖θ‖₂ > {} or a non-finite θ or a failed step; {}.{}",
            kind.name(),
            t.horizon
                .unwrap_or_else(|| crate::config::default_horizon(kind.name()))
                .label(),
            if overrides.is_empty() {
                String::new()
            } else {
                format!(" (control rows: {})", overrides.join(", "))
            },
            t.budget,
            t.checkpoint_every,
            t.converge_score,
            t.sustain,
            t.norm_bound,
            t.theta1.describe(),
            if kind == TaskKind::Cartpole {
                format!(
                    " Fig. 4.9: at each checkpoint the deterministic policy plays seeded episodes, \
                     reset after each crash, until one completes 500 steps; plotted = crashes before \
                     it, capped at {} (the cap = none completed).",
                    t.full_episode_cap
                )
            } else {
                String::new()
            }
        ));
    }
    out.push(format!(
        "**Tuning (pre-registered in the committed profile).** Each row's grid is run on {} tuning \
         seeds whose RNG seeds and evaluation episodes come from their own key namespace (checked \
         disjoint from the {} report seeds before any report run). Rule: the median over tuning seeds \
         of the gradient calls at sustained convergence, a run that did not converge or diverged \
         counting 2 × budget; the smallest median wins, ties to the first point in grid order. The \
         thesis's numbers never enter (when every point scores 2 × budget the rule selects the first \
         point in grid order). Tuning runs stop at sustained convergence or divergence. \
         Rows borrowing another row's selection say so.",
        profile.tuning_seeds, profile.seeds
    ));
    out
}

fn selected_table(profile: &Profile, r: &Results) -> Table {
    let mut rows = Vec::new();
    for t in &r.tuning {
        let sec = section(profile, t.task);
        let entry = sec.algorithms.iter().find(|e| e.label == t.label);
        let runs: Vec<&RunStatus> = r
            .obstacle
            .iter()
            .chain(&r.cartpole)
            .filter(|(c, _)| c.task == t.task && c.label == t.label)
            .flat_map(|(c, _)| c.runs.iter().map(|s| &s.status))
            .collect();
        let how = match entry.and_then(|e| e.hyper_parameters_of.clone()) {
            Some(of) => format!("as selected for {of}"),
            None if t.dims.is_empty() => "as configured (no grid)".into(),
            None => format!(
                "tuned over {} points: median {}",
                t.points.len(),
                score_text(t.points[t.selected].score, t.budget)
            ),
        };
        rows.push(vec![
            t.task.name().to_string(),
            t.label.clone(),
            entry.map_or("", |e| role(e.role)).to_string(),
            entry.and_then(|e| e.note.clone()).unwrap_or_default(),
            format!("`{}`", t.chosen().describe()),
            how,
            counts(&runs),
        ]);
    }
    Table {
        caption: Some(
            "Selected hyper-parameters of every row (recorded in `provenance.json`), and how the \
             report runs ended:"
                .into(),
        ),
        label: "tab:pc-selected".into(),
        header: strings(&[
            "task",
            "row",
            "role",
            "what it is",
            "selected hyper-parameters",
            "selection",
            "report runs: converged / not / diverged",
        ]),
        rows,
        spec: "llp{1.5cm}p{4cm}p{3cm}p{2.5cm}l".into(),
    }
}

fn sensitivity_table(tuning: &[TuningResult]) -> Table {
    let mut rows = Vec::new();
    for t in tuning.iter().filter(|t| !t.dims.is_empty()) {
        for (i, p) in t.points.iter().enumerate() {
            let st: Vec<&RunStatus> = p.runs.iter().map(|r| &r.status).collect();
            rows.push(vec![
                t.task.name().to_string(),
                t.label.clone(),
                format!("`{}`", p.point.describe()),
                score_text(p.score, t.budget),
                counts(&st),
                if i == t.selected {
                    "**selected**".into()
                } else {
                    String::new()
                },
            ]);
        }
    }
    Table {
        caption: Some(
            "Sensitivity: every grid point's tuning result (the whole pre-registered grid, in grid \
             order). STORM rows tune the schedule as a grid dimension: `kind=constant` (η, a) and \
             `kind=adaptive` (Algorithm 4's schedule with E9 corrected, k' = w = 0.1, c as listed):"
                .into(),
        ),
        label: "tab:pc-sensitivity".into(),
        header: strings(&[
            "task",
            "row",
            "grid point",
            "median calls to sustained convergence",
            "tuning runs: converged / not / diverged",
            "",
        ]),
        rows,
        spec: "llp{5cm}rll".into(),
    }
}

/// The protocol section's blocks.
pub fn blocks(profile: &Profile, r: &Results) -> Vec<Block> {
    vec![
        Block::Heading {
            level: 2,
            text: "Protocol: objective, budgets, convergence, tuning".into(),
        },
        Block::List(protocol_list(profile)),
        Block::Table(selected_table(profile, r)),
        Block::Table(sensitivity_table(&r.tuning)),
    ]
}
