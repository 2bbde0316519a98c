//! The appendix's protocol section: the objective, budgets and checkpoints, the
//! convergence and divergence rules, θ₁, the selected hyper-parameters of every row, the run
//! statuses, and the whole tuning grid's results (the sensitivity table).

use super::aggregate::num;
use super::blocks::{Block, Table};
use crate::config::{Profile, Role, TaskExperiment};
use crate::experiment::AppendixRun;
use crate::experiment::{RunStatus, TaskKind};
use crate::protocol::{Score, TuningResult};
use crate::results::Results;

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

fn section(profile: &Profile, kind: TaskKind) -> &TaskExperiment {
    match kind {
        TaskKind::Obstacle => &profile.obstacle,
        TaskKind::Cartpole => &profile.cartpole,
    }
}

/// A tuning score as text: the median calls to sustained convergence (or "none converged"),
/// and the area under the learning curve.
pub fn score_text(score: Option<&Score>) -> String {
    match score {
        None => "—".into(),
        Some(s) => format!(
            "{}; area {}",
            if s.median_calls.is_finite() {
                format!("median {} calls", num(s.median_calls))
            } else {
                "median not converged".into()
            },
            num(s.auc)
        ),
    }
}

/// How a tuned row's pick was reached: the rounds (each with its rungs and extensions), where
/// the pick lies, and its ties.
pub fn selection_text(t: &TuningResult) -> String {
    let rounds: Vec<String> = t
        .rounds
        .iter()
        .enumerate()
        .map(|(k, round)| {
            let rungs: Vec<String> = round
                .rungs
                .iter()
                .map(|g| format!("{}→{} at {}", g.points, g.kept, num(g.budget as f64)))
                .collect();
            let ext = if round.extended.is_empty() {
                String::new()
            } else {
                format!("; extended {}", round.extended.join(", "))
            };
            format!("round {}: {}{ext}", k + 1, rungs.join(", "))
        })
        .collect();
    let place = if t.on_edge.is_empty() {
        "interior".to_string()
    } else {
        format!("on an edge: {}", t.on_edge.join(", "))
    };
    let ties = if t.tied_with.is_empty() {
        String::new()
    } else {
        format!(
            "; tied on calls and area with {} (broken by the smaller step, then m)",
            t.tied_with.len()
        )
    };
    format!(
        "{}; {}; {place}{ties}",
        rounds.join("; "),
        score_text(t.points[t.selected].score.as_ref())
    )
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
            .map(|e| format!("{} → `{}`", e.label, e.horizon(t, kind).label()))
            .collect();
        out.push(format!(
            "**{}.** Objective `{}`{}; budget {} gradient calls per run for every method (a run \
             stops after the step that reaches it, whose calls count in full: DAgger's last round \
             of retraining overshoots the most); \
             checkpoints every {} calls (and at the budget); sustained convergence = score ≥ {} at \
             {} consecutive checkpoints; diverged = ‖θ‖₂ > {} or a non-finite θ or a failed step; {}.{}",
            kind.name(),
            t.horizon
                .unwrap_or_else(|| crate::config::default_horizon(kind))
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
    let p = &profile.tuning;
    out.push(format!(
        "**Tuning (pre-registered in the committed profile, protocol v2).** Each row's grid is run \
         on {} tuning seeds whose RNG seeds and evaluation episodes come from their own key \
         namespace (checked disjoint from the {} report seeds before any report run). Step sizes \
         run over log ranges (…, 10⁻³, 3·10⁻³, 10⁻², … or powers of ten). **Score**, \
         lexicographic: (1) the median over tuning seeds of the gradient calls to sustained \
         convergence (a run that did not converge or diverged counts +∞); (2) among points tied \
         there, including \"nothing converged\", the larger mean area under the learning curve \
         (the mean score over the checkpoints; a diverged run scores 0 from the point it \
         diverged, a converged tuning run, which stops there, keeps its last score); (3) the \
         smaller step; (4) the fewer trajectories per gradient. Grid order never decides: a tie \
         that survives (1)–(2) is reported. **Successive halving** over the rungs {} of the \
         budget: every point runs to the first rung, the best ⌈n/{}⌉ go on to the next (with \
         every point tied with the last of them), the last rung is the whole budget; a grid of \
         fewer than {} points runs every point to the whole budget. **Edge \
         extension**: a pick on an end of a log range grows that range by its next value and the \
         selection is made again, up to {} time(s). A pick whose tuning runs never converged, \
         one still on an edge after extension, or fewer than 3 tuning seeds make every \"not \
         reproduced\" of the claims its row enters \"inconclusive (tuning)\". The thesis's \
         numbers never enter. Rows borrowing another row's selection say so.",
        profile.tuning_seeds,
        profile.seeds,
        p.rungs
            .iter()
            .map(|f| num(*f))
            .collect::<Vec<_>>()
            .join(", "),
        p.halving,
        p.exhaustive_below,
        p.extensions
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
            .flat_map(|(c, _)| c.runs.iter().map(|s| s.status()))
            .collect();
        let how = match entry.and_then(|e| e.hyper_parameters_of.clone()) {
            Some(of) => format!("as selected for {of}"),
            None if !t.is_tuned() => "as configured (no grid)".into(),
            None => format!("{} points tried; {}", t.points.len(), selection_text(t)),
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
        spec: "llp{1.5cm}p{3cm}p{3cm}p{4.5cm}l".into(),
    }
}

fn sensitivity_table(tuning: &[TuningResult]) -> Table {
    let mut rows = Vec::new();
    for t in tuning.iter().filter(|t| t.is_tuned()) {
        for (i, p) in t.points.iter().enumerate() {
            let st: Vec<&RunStatus> = p.runs.iter().map(|r| &r.status).collect();
            rows.push(vec![
                t.task.name().to_string(),
                t.label.clone(),
                format!("`{}`", p.point.describe()),
                format!(
                    "{} (rung {}, {} calls)",
                    score_text(p.score.as_ref()),
                    p.rung + 1,
                    num(p.score.as_ref().map_or(0.0, |s| s.budget as f64))
                ),
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
            "Sensitivity: every grid point tried (the pre-registered grid and its extensions, in \
             grid order), scored at the highest rung of successive halving it reached. STORM rows \
             tune the schedule: `kind=constant` (η, a) beside `kind=adaptive` (Algorithm 4's \
             schedule with E9 corrected, its constants as listed):"
                .into(),
        ),
        label: "tab:pc-sensitivity".into(),
        header: strings(&[
            "task",
            "row",
            "grid point",
            "score: median calls to sustained convergence; area under the curve",
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
