//! The appendix document: the chapter-4 tables beside the thesis's, the claims, the tuning, the
//! theorem checks and the errata, with the figures in their sections, as [`Block`]s rendered
//! to `appendix.md` and `appendix.tex`.

use super::aggregate::{
    ConvergenceRow, FRACTION, ci, last, num, out_of, percent, reward_range, runtime,
};
use super::blocks::{self, Block, Table};
use super::claims::Claim;
use super::figures::NamedFigure;
use super::thesis::{ERRATA, THESIS_T41, THESIS_T42, THESIS_T43, THESIS_T44};
use super::{protocol_section, speedup, theory};
use crate::config::Profile;
use crate::error::Error;
use crate::experiment::Evaluated;
use crate::experiment::{Checkpoint, SeedRun, TaskKind};
use crate::results::{ConfigResult, ConfigWithTiming, Results};
use crate::stats::{Interval, Range};
use crate::storage::write_atomic;
use std::path::Path;

/// The final-checkpoint table's rows of a task's baselines (evaluated on every seed's episodes).
fn baseline_rows(r: &Results, task: TaskKind) -> Vec<Vec<String>> {
    r.baselines
        .iter()
        .filter(|b| b.task == task)
        .map(|b| {
            let s = |what: &str, range: Range, f: &dyn Fn(&Checkpoint) -> f64| {
                let key = format!("{}/{}/{what}", task.name(), b.label);
                Interval::of(&b.runs.iter().map(f).collect::<Vec<_>>(), range, &key)
            };
            let episodes = b
                .runs
                .iter()
                .map(|k| f64::from(k.successes() + k.crashes() + k.timeouts()))
                .fold(0.0, f64::max);
            vec![
                format!("*{}* (reference, no training)", b.label),
                if task == TaskKind::Obstacle {
                    ci(&percent(&s("score", FRACTION, &|c| c.score())))
                } else {
                    ci(&s("reward", reward_range(task), &|c| c.reward()))
                },
                ci(&s("crashes", out_of(episodes), &|c| f64::from(c.crashes()))),
                ci(&s("loss", Range::NonNegative, &|c| c.loss())),
                "—".into(),
            ]
        })
        .collect()
}

/// Both tasks' speed-up rows (Table 4.2's, then Table 4.4's, each with its total).
fn speedup_all_cells(r: &Results) -> Vec<Vec<String>> {
    let mut rows = speedup::speedup_cells("4.2", &speedup::speedup_rows(&r.obstacle, &THESIS_T42));
    rows.extend(speedup::speedup_cells(
        "4.4",
        &speedup::speedup_rows(&r.cartpole, &THESIS_T44),
    ));
    rows
}

/// Kit-vs-thesis rows of a gradient-call table.
fn calls_table(rows: &[ConvergenceRow], thesis: &[(&str, f64, f64)]) -> Vec<[String; 5]> {
    let mut out = Vec::new();
    for row in rows {
        if row.label == "BC" {
            continue;
        }
        let th = thesis
            .iter()
            .find(|t| t.0 == row.label)
            .map_or("—".into(), |t| format!("{} ± {}", num(t.1), num(t.2)));
        out.push([
            row.label.clone(),
            ci(&row.gradient_calls),
            format!("{}/{}", row.converged, row.seeds),
            ci(&row.total_gradient_calls),
            th,
        ]);
    }
    out
}

fn runtime_table(set: &[ConfigWithTiming], thesis: &[(&str, f64)]) -> Vec<[String; 4]> {
    set.iter()
        .filter(|c| c.0.label != "BC")
        .map(|(c, t)| {
            let (conv, total) = runtime(t.as_ref());
            [
                c.label.clone(),
                ci(&conv),
                ci(&total),
                thesis
                    .iter()
                    .find(|x| x.0 == c.label)
                    .map_or("—".into(), |x| num(x.1)),
            ]
        })
        .collect()
}

fn final_rows(rows: &[ConvergenceRow], obstacle: bool) -> Vec<Vec<String>> {
    rows.iter()
        .map(|r| {
            vec![
                r.label.clone(),
                if obstacle {
                    ci(&percent(&r.final_score))
                } else {
                    ci(&r.final_reward)
                },
                ci(&r.final_crashes),
                ci(&r.final_loss),
                format!("{}", r.failed_runs),
            ]
        })
        .collect()
}

/// A task's two cost tables (gradient calls to converge; runtime), kit next to thesis.
fn cost_tables(
    (calls_no, runtime_no): (&str, &str),
    rows: &[ConvergenceRow],
    configs: &[ConfigWithTiming],
    thesis_calls: &[(&str, f64, f64)],
    thesis_runtime: &[(&str, f64)],
) -> [Block; 2] {
    [
        Block::Table(Table {
            caption: Some(format!(
                "**Table {calls_no}: gradient calls to converge** (kit vs thesis; a diverged \
                 run's whole run ends where it diverged):"
            )),
            label: format!("tab:pc-{}", calls_no.replace('.', "-")),
            header: strings(&[
                "algorithm",
                "kit: gradient calls to converge",
                "kit: converged",
                "kit: gradient calls of the whole run",
                "thesis",
            ]),
            rows: calls_table(rows, thesis_calls)
                .into_iter()
                .map(|a| a.to_vec())
                .collect(),
            spec: "lrrrr".into(),
        }),
        Block::Table(Table {
            caption: Some(format!(
                "**Table {runtime_no}: runtime in seconds** (kit vs thesis; machine-dependent):"
            )),
            label: format!("tab:pc-{}", runtime_no.replace('.', "-")),
            header: strings(&["algorithm", "kit: to converge", "kit: whole run", "thesis"]),
            rows: runtime_table(configs, thesis_runtime)
                .into_iter()
                .map(|a| a.to_vec())
                .collect(),
            spec: "lrrr".into(),
        }),
    ]
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| (*s).to_string()).collect()
}

/// What the objective does with episodes that end early, with CartPole's numbers: the loss at
/// θ₀ and at the last checkpoint, and the final reward, of every algorithm that descends F
/// directly (all but BC and DAgger).
fn episode_length_note(r: &Results) -> String {
    let mean_at =
        |c: &ConfigResult, pick: fn(&SeedRun) -> Option<&Checkpoint>, f: fn(&Checkpoint) -> f64| {
            let xs: Vec<f64> = c.runs.iter().filter_map(pick).map(f).collect();
            xs.iter().sum::<f64>() / xs.len().max(1) as f64
        };
    let rows: Vec<String> = r
        .cartpole
        .iter()
        .filter(|(c, _)| !c.label.starts_with("DAgger"))
        .map(|(c, _)| {
            format!(
                "{}: loss {} → {}, reward {} → {}",
                c.label,
                num(mean_at(c, |s| s.checkpoints.first(), |k| k.loss())),
                num(mean_at(c, last, |k| k.loss())),
                num(mean_at(c, |s| s.checkpoints.first(), |k| k.reward())),
                num(mean_at(c, last, |k| k.reward())),
            )
        })
        .collect();
    format!(
        "**Objective.** Every oracle row (SGD, Adam, RMSProp, the STORM variants) but the controls \
         minimises the thesis's F (eqs. 3.1–3.16), and BC and DAgger, which fit the expert's labels \
         by supervised learning, roll out on the same horizon: a fixed \
         horizon of T decisions (CartPole T = 500: after a crash the environment resets and the \
         stream goes on, the thesis's protocol; obstacle task T = 200: after the episode ends the \
         remaining steps cost 0 after success and (2·v_max)² after a crash). The rows marked \
         *control* minimise the episodic objective instead (the loss summed over each episode's own \
         length), under which a short episode is cheap; comparing a control with its row shows \
         what the choice of objective does. CartPole, mean evaluation loss and reward at θ₀ → at \
         the last checkpoint (deterministic policy): {}.",
        if rows.is_empty() {
            "no such algorithm in this profile".to_string()
        } else {
            rows.join("; ")
        }
    )
}

/// The flags after `cargo run --release -p paper-checks` that run `profile`: `--full` for the
/// full profile, and `--theory SIZE` when a committed profile's theorem table was run at a size
/// other than the one its file sets (`quick` for both committed profiles).
fn command_flags(profile: &Profile) -> String {
    let mut flags = Vec::new();
    if profile.name == "full" {
        flags.push("--full".to_string());
    }
    if let Some(own) = crate::config::committed_theory_profile(&profile.name)
        && profile.theory_profile != own
    {
        flags.push(format!("--theory {}", profile.theory_profile));
    }
    if flags.is_empty() {
        String::new()
    } else {
        format!(" -- {}", flags.join(" "))
    }
}

/// The obstacle section's description of the learner (from the profile).
fn obstacle_learner_text(profile: &Profile) -> String {
    use ilopt::task::obstacle::ObstacleFeatures;
    let features = match profile.obstacle.features.unwrap_or_default() {
        ObstacleFeatures::Basic => {
            "the 9 basic features (goal − agent, obstacle − agent, obstacle \
             velocity, agent velocity, 1)"
                .to_string()
        }
        f @ ObstacleFeatures::Rbf {
            per_axis,
            width,
            x_range,
            y_range,
        } => format!(
            "{} features: the 9 basic ones (goal − agent, obstacle − agent, obstacle velocity, agent \
             velocity, 1), the unit vector to the goal, and for each of {per_axis} × {per_axis} centres c \
             over the obstacle's relative position r (x in [{}, {}], y in [{}, {}]) the bump \
             exp(−‖r − c‖²/(2·{width}²)) and its products with the obstacle's velocity \
             (`ObstacleFeatures::Rbf`)",
            f.dim(),
            x_range[0],
            x_range[1],
            y_range[0],
            y_range[1]
        ),
    };
    format!(
        "The learner (the thesis does not state one) is linear-Gaussian (P3, σ_π = {}) over {features}; \
         its loss is that of the executed velocity, ‖clip(Wφ) − π*(s)‖², bounded by (v_max + ‖π*‖)² \
         (`SpeedLimitedGaussian`). The expert is the velocity-obstacle expert of eq. 4.1.",
        profile.obstacle.sigma.unwrap_or(0.02)
    )
}

/// A column of the verdict summary: its header and the cell of a claim. A field added to
/// [`Claim`] (a caveat, say) is one more line here.
type ClaimColumn = (&'static str, fn(&Claim) -> String);

/// The verdict summary's columns, in order (where in the thesis each claim stands is in the
/// claims section, so that the statement reads in one or two lines).
const SUMMARY_COLUMNS: [ClaimColumn; 3] = [
    ("#", |c| c.id.clone()),
    ("claim", |c| c.claim.clone()),
    ("verdict", |c| format!("**{}**", c.verdict_short())),
];

/// The fields of a claim listed under its statement in the claims section, after the verdict:
/// a label and the text (a new field of [`Claim`] is one more line here).
const DETAIL_FIELDS: [ClaimColumn; 2] = [
    ("Rule", |c| c.rule.clone()),
    ("Numbers", |c| c.evidence.clone()),
];

/// The verdict summary at the top: a sentence counting the verdicts, then one row per claim
/// ([`SUMMARY_COLUMNS`]).
fn verdict_summary(claims: &[Claim], timing: &[Claim]) -> Vec<Block> {
    use crate::verdict::Verdict;
    let all: Vec<&Claim> = claims.iter().chain(timing).collect();
    let count = |v: Verdict| all.iter().filter(|c| c.verdict == v).count();
    vec![
        Block::Heading {
            level: 2,
            text: "Verdicts at a glance".into(),
        },
        Block::Para(format!(
            "{} claims of chapter 4: **{} reproduced**, **{} inconclusive**, **{} not \
             reproduced**. Each is judged by a stated rule on 95% intervals; the rule and the \
             numbers of each claim are in the appendix's section *Claims of chapter 4: rules and \
             numbers*.",
            all.len(),
            count(Verdict::Reproduced),
            count(Verdict::Inconclusive),
            count(Verdict::NotReproduced),
        )),
        Block::Table(Table {
            caption: Some("The claims of chapter 4 and their verdicts".into()),
            label: "tab:pc-verdicts".into(),
            header: SUMMARY_COLUMNS.iter().map(|c| c.0.to_string()).collect(),
            rows: all
                .iter()
                .map(|c| SUMMARY_COLUMNS.iter().map(|col| (col.1)(c)).collect())
                .collect(),
            spec: "llll".into(),
        }),
    ]
}

/// `results.md`: the verdict summary without its heading — the count sentence and the table, the
/// same text as the appendix's "Verdicts at a glance" — for a front page to quote verbatim (the
/// README's results block is this file of a quick run, and CI compares the two).
pub fn results_page(claims: &[Claim], timing: &[Claim]) -> String {
    blocks::markdown(&verdict_summary(claims, timing)[1..])
}

/// A claim in the claims section: id, place, statement and verdict, then [`DETAIL_FIELDS`].
fn claim_details(c: &Claim) -> String {
    let mut o = format!(
        "**{}** ({}) {} — **{}**.",
        c.id,
        c.source,
        c.claim,
        c.verdict_text()
    );
    for (label, field) in DETAIL_FIELDS {
        let text = field(c);
        let text = text.trim_end();
        let stop = if text.ends_with(['.', '!', '?']) {
            ""
        } else {
            "."
        };
        o += &format!(" *{label}:* {text}{stop}");
    }
    o
}

/// Everything the appendix needs to say, in order.
pub struct Inputs<'a> {
    /// The profile run.
    pub profile: &'a Profile,
    /// Its results.
    pub results: &'a Results,
    /// The obstacle task's convergence rows, in table order.
    pub obstacle_rows: &'a [ConvergenceRow],
    /// CartPole's convergence rows, in table order.
    pub cartpole_rows: &'a [ConvergenceRow],
    /// The deterministic claims with their verdicts.
    pub claims: &'a [Claim],
    /// The runtime claims with their verdicts.
    pub timing_claims: &'a [Claim],
    /// Every figure, in document order.
    pub figures: &'a [NamedFigure],
    /// Whether PNG files were written beside the SVGs.
    pub png: bool,
    /// The machine the run's wall times were measured on.
    pub machine: &'a crate::provenance::Machine,
}

/// The appendix as blocks, rendered by [`blocks::markdown`] and [`blocks::latex`].
pub fn document(x: &Inputs<'_>) -> Vec<Block> {
    let (profile, r) = (x.profile, x.results);
    let mut d = Vec::new();
    let h = |text: &str| Block::Heading {
        level: 2,
        text: text.into(),
    };
    let figures = |d: &mut Vec<Block>, which: &[&str]| {
        let ext = if x.png { "png" } else { "svg" };
        for (name, fig, f) in x.figures {
            if which.contains(fig) {
                d.push(Block::Figure {
                    path: format!("figures/{name}.{ext}"),
                    caption: f.title.clone(),
                });
            }
        }
    };
    d.push(Block::Heading {
        level: 1,
        text: "Appendix: thesis chapter 4, regenerated".into(),
    });
    d.extend(verdict_summary(x.claims, x.timing_claims));
    d.push(h("How this appendix was made"));
    d.push(Block::Para(format!(
        "Generated by `cargo run --release -p paper-checks{}` (profile `{}`, {} seeds per configuration). \
         Every number below is computed from the per-seed data in this directory (`checkpoints.csv`, \
         `runs/*.json`, `gradient_error.csv`); configurations and seeds are in `provenance.json`, wall \
         times in `timings.json` / `timings.csv`.",
        command_flags(profile),
        profile.name,
        profile.seeds
    )));
    d.push(h("Definitions (applied to every algorithm alike)"));
    d.push(Block::List(vec![
        format!(
            "**Evaluation.** At each checkpoint (fixed gradient-call counts, below) the learned \
             policy acts deterministically — the linear-Gaussian mean `Wφ(s)` as the environment executes it \
             (clipped to the maximum speed) (obstacle), the most probable action of the softmax (CartPole) — \
             on {} (obstacle) / {} (CartPole) seeded episodes, the same episodes for every algorithm, \
             checkpoint and reference policy of a seed. Crash (obstacle) = the discs overlap; crash \
             (CartPole) = the episode terminates before 500 steps. Loss = mean per-decision supervised loss on \
             the states the deterministic policy visits (obstacle: squared error of the executed velocity \
             against the velocity-obstacle expert's, split into x and y; CartPole: Brier loss against the \
             {} expert's action).",
            profile.obstacle.eval_episodes,
            profile.cartpole.eval_episodes,
            profile.cartpole.expert.unwrap_or_default().name(),
        ),
        "**Reference policies** (no training; rows in *italics*, dashed lines in the figures): the \
         task's expert, and on the obstacle task *straight to goal* — full speed at the goal, ignoring \
         the obstacle. They are evaluated on the same episodes as the learners: the expert is the \
         ceiling imitation aims at, straight to goal what a controller that ignores the obstacle \
         achieves (some learners end below it)."
            .into(),
        format!(
            "**Converge.** A run converges at the first checkpoint of the first window of `sustain` consecutive checkpoints whose score is ≥ the task's threshold (sustained convergence; a diverged run never converges): \
             score = success rate (obstacle, threshold {}) or mean episode reward / 500 (CartPole, threshold \
             {}). *Gradient calls to converge* = cumulative per-state gradient evaluations (`Cost::gradient_evaluations`, \
             the same unit for the oracle methods and the dataset learners' inner updates) at that checkpoint; \
             *runtime* = training wall time up to it (evaluation excluded). The tables' means of gradient calls are \
             over the seeds that converged (their number is given); the claims compare medians over \
             all seeds, a run that did not converge or diverged counting +∞.",
            profile.obstacle.converge_score, profile.cartpole.converge_score,
        ),
        format!(
            "**Confidence intervals.** Tables print `mean [low, high]`, a 95% interval over seeds \
             that stays inside the quantity's range; figures shade the same interval at each \
             checkpoint. *Success rates, crashes (out of the evaluation episodes), CartPole \
             rewards (0–500) and resets (0 to the cap)* — bounded on both sides — use the \
             percentile bootstrap of the mean over seeds ({} resamples of the seeds with \
             replacement, the 2.5% and 97.5% percentiles of their means; the generator is seeded \
             from the task, algorithm and quantity, so the numbers are the same on every run). \
             The seed is the unit: a seed's episodes share one policy, so they are not \
             independent trials and a binomial (e.g. Wilson) interval on the pooled episodes \
             would be too narrow. With few seeds the bootstrap interval is somewhat too narrow \
             (it never leaves the range of the seeds' values). *Gradient calls, runtimes and \
             losses* — non-negative, no upper bound — use the Student-t interval \
             `mean ± t(0.975, n−1)·s/√n` with its lower end raised to 0 where it falls below, \
             marked † (clamped). One seed: the mean alone. The claims' evidence keeps the \
             t intervals its rules are stated on, and its medians use distribution-free order \
             statistics. The thesis's ± values are its own (their meaning is not stated). \
             Claims are judged by the rule beside each (C4 by an F test of two variances): \
             reproduced, not reproduced, or inconclusive when the intervals overlap.",
            crate::stats::BOOTSTRAP_RESAMPLES
        ),
        "**Hyper-parameters** are selected by the pre-registered tuning protocol below (see `provenance.json`)."
            .into(),
        episode_length_note(r),
    ]));
    d.extend(protocol_section::blocks(profile, r));

    d.push(h(
        "Fig. 4.2: gradient-estimate error vs number of trajectories",
    ));
    d.push(Block::Para(crate::gradient_error::description(
        &profile.gradient_error,
        &r.gradient_error,
    )));
    figures(&mut d, &["Fig. 4.2"]);
    for (route, label, head) in [
        (
            &r.gradient_error.toy,
            "tab:pc-fig-4-2a",
            &["N", "RMSE [95% CI]", "σ/√N", "RMSE / (σ/√N)"][..],
        ),
        (
            &r.gradient_error.obstacle,
            "tab:pc-fig-4-2b",
            &[
                "N",
                "RMSE vs reference [95% CI]",
                "ref. variance removed [95% CI]",
                "σ̂/√N",
                "ratio",
            ][..],
        ),
    ] {
        d.push(Block::Table(Table {
            caption: Some(if route.reference_trajectories.is_some() {
                "RMSE by N on the obstacle task (the data of thesis Fig. 4.2 (b))".into()
            } else {
                "RMSE by N on the toy MDP against the exact ∇F (the data of thesis Fig. 4.2 (a))"
                    .into()
            }),
            label: label.into(),
            header: strings(head),
            rows: crate::gradient_error::table_rows(route),
            spec: "r".repeat(head.len()),
        }));
    }

    for (heading, para, figs, task, head1, obstacle, rows, configs, nos, tc, tr) in [
        (
            "Obstacle avoidance (§4.1): Figs. 4.3–4.6, Tables 4.1–4.2",
            Some(obstacle_learner_text(profile)),
            &["Fig. 4.3", "Fig. 4.4", "Fig. 4.5", "Fig. 4.6"][..],
            "obstacle",
            "success rate (%)",
            true,
            x.obstacle_rows,
            &r.obstacle,
            ("4.1", "4.2"),
            &THESIS_T41[..],
            &THESIS_T42[..],
        ),
        (
            "CartPole (§4.2): Figs. 4.8–4.10, Tables 4.3–4.4",
            Some(match profile.cartpole.expert.unwrap_or_default() {
                crate::config::CartPoleExpertChoice::Ppo => "The expert is the committed PPO policy \
                    (`experts/cartpole-ppo.json`, acting greedily), as in the thesis; the learner is a \
                    linear softmax over the state and a bias."
                    .to_string(),
                crate::config::CartPoleExpertChoice::Lqr => "The expert is the kit's LQR controller \
                    (the thesis uses PPO); the learner is a linear softmax over the state and a bias."
                    .to_string(),
            }),
            &["Fig. 4.8", "Fig. 4.9", "Fig. 4.10"][..],
            "cartpole",
            "mean reward",
            false,
            x.cartpole_rows,
            &r.cartpole,
            ("4.3", "4.4"),
            &THESIS_T43[..],
            &THESIS_T44[..],
        ),
    ] {
        d.push(h(heading));
        if let Some(p) = para {
            d.push(Block::Para(p));
        }
        figures(&mut d, figs);
        d.push(Block::Table(Table {
            caption: Some(format!(
                "**Final checkpoint** (mean [95% interval] over the runs that did not diverge: a \
                 diverged run has no final policy and counts only under failed runs; crashes = the \
                 evaluation episodes (of {}) {}):",
                if obstacle {
                    profile.obstacle.eval_episodes
                } else {
                    profile.cartpole.eval_episodes
                },
                if obstacle {
                    "in which the discs overlapped"
                } else {
                    "that ended before 500 steps"
                }
            )),
            label: format!("tab:pc-final-{task}"),
            header: strings(&["algorithm", head1, "crashes", "loss", "failed runs"]),
            rows: final_rows(rows, obstacle)
                .into_iter()
                .chain(baseline_rows(
                    r,
                    if obstacle {
                        TaskKind::Obstacle
                    } else {
                        TaskKind::Cartpole
                    },
                ))
                .collect(),
            spec: "lrrrr".into(),
        }));
        d.extend(cost_tables(nos, rows, configs, tc, tr));
    }

    d.extend(super::beyond::blocks(r, x.obstacle_rows, x.cartpole_rows));

    d.push(h("Kit time vs thesis (Tables 4.2 and 4.4)"));
    d.push(Block::Para(speedup::speedup_intro(x.machine)));
    d.push(Block::Table(Table {
        caption: None,
        label: "tab:pc-speedup".into(),
        header: strings(&speedup::SPEEDUP_HEAD),
        rows: speedup_all_cells(r),
        spec: "llrlrr".into(),
    }));

    d.push(h("Claims of chapter 4: rules and numbers"));
    d.push(Block::Para(
        "Each verdict is computed from the numbers by the stated rule (the verdicts are \
         summarised at the top)."
            .into(),
    ));
    d.push(Block::List(
        x.claims
            .iter()
            .chain(x.timing_claims)
            .map(claim_details)
            .collect(),
    ));

    d.push(h("Theorem checks (`ilopt-theory`)"));
    d.extend(theory::blocks(
        &r.theory,
        profile.theory_profile,
        "tab:pc-theory",
    ));
    d.push(h("Errata (math.md §0)"));
    let by = theory::checks_by_erratum(r.theory.checks());
    d.push(Block::Table(Table {
        caption: None,
        label: "tab:pc-errata".into(),
        header: strings(&["#", "thesis statement", "problem", "correction", "check"]),
        rows: ERRATA
            .iter()
            .map(|(id, w, p, c)| {
                vec![
                    (*id).into(),
                    (*w).into(),
                    (*p).into(),
                    (*c).into(),
                    by.get(*id)
                        .map_or("— (no numerical check)".into(), |v| v.join(", ")),
                ]
            })
            .collect(),
        spec: "llp{4.5cm}p{4.5cm}l".into(),
    }));
    d
}

/// The LaTeX fragment's opening comment.
const LATEX_PREAMBLE: &str = "% Generated by paper-checks. \\input{} into a document whose preamble loads\n\
     % amsmath, amssymb, booktabs, longtable, array, graphicx and pdflscape\n\
     % (appendix-standalone.tex does). Tables are laid out for a text block about 17 cm wide (A4\n\
     % with 2 cm margins, as the standalone document sets with geometry); a narrower one wraps\n\
     % their cells more. A float whose caption leads with a thesis number carries that number\n\
     % (\\thefigure/\\thetable set inside the float). Figures float ([htbp]); a \\FloatBarrier before each heading\n\
     % keeps them in their section (placeins' if loaded, else a kernel-only one defined below).\n\
     % Figures are referenced relative to this file's directory.\n";

/// The complete LaTeX document around `appendix.tex` (`pdflatex appendix-standalone.tex` in the
/// output directory builds the PDF).
pub fn latex_standalone() -> String {
    format!(
        "% Generated by paper-checks: the appendix as a complete document.\n\
         % Build: pdflatex -interaction=nonstopmode -halt-on-error appendix-standalone.tex (twice, for the\n\
         % longtables' column widths).\n\
         \\documentclass[10pt,a4paper]{{article}}\n\
         \\usepackage[a4paper,margin=2cm]{{geometry}}\n\
         {}\
         % The appendix's own tables and figures (those without a thesis number) are A.1, A.2, ….\n\
         \\renewcommand{{\\thetable}}{{A.\\arabic{{table}}}}\n\
         \\renewcommand{{\\thefigure}}{{A.\\arabic{{figure}}}}\n\
         \\setlength{{\\emergencystretch}}{{3em}}\n\
         % Floats may fill more of a text page, and a page of floats need not be nearly full,\n\
         % so figures sit close to their text rather than wait for a float page.\n\
         \\renewcommand{{\\topfraction}}{{0.9}}\n\
         \\renewcommand{{\\bottomfraction}}{{0.8}}\n\
         \\renewcommand{{\\textfraction}}{{0.07}}\n\
         \\renewcommand{{\\floatpagefraction}}{{0.7}}\n\
         \\begin{{document}}\n\
         \\input{{appendix}}\n\
         \\end{{document}}\n",
        blocks::LATEX_PACKAGES
    )
}

/// Write `appendix.md`, `appendix.tex` (a fragment to `\\input`) and
/// `appendix-standalone.tex` (the complete document around it) into `out`.
///
/// # Errors
/// [`Error::Io`].
pub fn write_documents(blocks: &[Block], out: &Path) -> Result<(), Error> {
    write_atomic(
        &out.join("appendix.md"),
        blocks::markdown(blocks).as_bytes(),
    )?;
    write_atomic(
        &out.join("appendix.tex"),
        blocks::latex(blocks, LATEX_PREAMBLE).as_bytes(),
    )?;
    write_atomic(
        &out.join("appendix-standalone.tex"),
        latex_standalone().as_bytes(),
    )
}

#[cfg(test)]
mod tests {
    use super::{Block, Claim, blocks, command_flags, results_page, verdict_summary};
    use crate::config::Profile;
    use crate::verdict::Verdict;
    use std::path::Path;

    fn committed(name: &str) -> Profile {
        let text = crate::config::committed_text(name).expect("a committed profile");
        Profile::from_toml(text, Path::new(name)).expect("valid")
    }

    /// The "Generated by" command names `--theory` exactly when a committed profile's table was
    /// run at another size than its own.
    #[test]
    fn the_command_names_a_theory_size_other_than_the_profiles() {
        let mut quick = committed("quick");
        assert_eq!(command_flags(&quick), "");
        quick.theory_profile = crate::config::TheorySize::None;
        assert_eq!(command_flags(&quick), " -- --theory none");
        let mut full = committed("full");
        assert_eq!(command_flags(&full), " -- --full");
        full.theory_profile = crate::config::TheorySize::Full;
        assert_eq!(command_flags(&full), " -- --full --theory full");
    }

    fn claim(id: &str, verdict: Verdict) -> Claim {
        Claim {
            id: id.into(),
            source: "§4.1".into(),
            claim: format!("claim {id}"),
            rule: "a rule".into(),
            evidence: "the numbers".into(),
            verdict,
            caveat: None,
            task: None,
            compared: Vec::new(),
        }
    }

    /// `results.md` is the appendix's verdict summary, word for word, without its heading.
    #[test]
    fn the_results_page_is_the_appendixs_summary_without_its_heading() {
        let claims = [
            claim("O1", Verdict::Reproduced),
            claim("C2", Verdict::NotReproduced),
        ];
        let timing = [claim("T1", Verdict::Inconclusive)];
        let page = results_page(&claims, &timing);
        let appendix = blocks::markdown(&verdict_summary(&claims, &timing));
        assert!(!page.contains("Verdicts at a glance"), "{page}");
        assert!(appendix.contains("Verdicts at a glance"));
        assert!(
            appendix.trim_end().ends_with(page.trim_end()),
            "{page}\n---\n{appendix}"
        );
        assert!(
            page.contains("| C2 | claim C2 | **not reproduced** |"),
            "{page}"
        );
    }

    /// The summary counts the verdicts and has a row per claim, in both renderings.
    #[test]
    fn the_verdict_summary_lists_every_claim_with_its_verdict() {
        let blocks = verdict_summary(
            &[
                claim("C1", Verdict::Reproduced),
                claim("C2", Verdict::NotReproduced),
            ],
            &[claim("T1", Verdict::Inconclusive)],
        );
        let Block::Table(t) = &blocks[2] else {
            panic!("no table: {blocks:?}")
        };
        assert_eq!(t.header, ["#", "claim", "verdict"]);
        assert_eq!(t.rows.len(), 3);
        assert_eq!(t.rows[1], ["C2", "claim C2", "**not reproduced**"]);
        let md = blocks::markdown(&blocks);
        assert!(
            md.contains(
                "3 claims of chapter 4: **1 reproduced**, **1 inconclusive**, **1 not reproduced**"
            ),
            "{md}"
        );
        assert!(md.contains("| T1 | claim T1 | **inconclusive** |"), "{md}");
        let tex = blocks::latex(&blocks, "");
        assert!(
            tex.contains("T1 & claim T1 & \\textbf{inconclusive} \\\\"),
            "{tex}"
        );
        assert_eq!(
            super::claim_details(&claim("C1", Verdict::Reproduced)),
            "**C1** (§4.1) claim C1 — **reproduced**. *Rule:* a rule. *Numbers:* the numbers."
        );
        // A qualified verdict names its reason's kind in the summary, in full in the details.
        let mut q = claim("O3", Verdict::Inconclusive);
        q.caveat = Some("inconclusive (tuning): SGD: no tuning run of its pick converged".into());
        let b = verdict_summary(std::slice::from_ref(&q), &[]);
        let Block::Table(t) = &b[2] else {
            panic!("no table")
        };
        assert_eq!(t.rows[0][2], "**inconclusive (tuning)**");
        assert!(super::claim_details(&q).contains("— **inconclusive (tuning): SGD: no tuning run"));
    }
}
