//! The appendix: aggregated tables (kit vs thesis), claim verdicts, figures, CSV/JSON data, the
//! theorem-check and errata tables, Markdown and LaTeX.
//!
//! Confidence intervals are Student-t 95% intervals over seeds ([`Summary`]). Verdicts are
//! computed from the numbers by the rules stated next to each claim; nothing is tuned.

use crate::config::Profile;
use crate::error::Error;
use crate::experiment::{Checkpoint, SeedRun, TaskKind};
use crate::pipeline::{ConfigResult, ConfigTiming, Results, to_json, write_atomic};
use crate::plots::{Figure, Series};
use crate::stats::Summary;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

pub mod claims;
pub mod doc;
pub mod speedup;
pub mod tex;
pub mod theory;
pub mod tuning;

use doc::{Block, Table};

/// The thesis's Table 4.1 (gradient calls, mean ± spread) and 4.2 (runtime, s).
pub const THESIS_T41: [(&str, f64, f64); 5] = [
    ("STORM", 2764.0, 1300.0),
    ("SGD", 9450.0, 2886.0),
    ("RMSProp", 6411.0, 1880.0),
    ("DAgger", 53704.0, 4233.0),
    ("Adam", 10785.0, 3460.0),
];
/// Table 4.2 (runtime in seconds).
pub const THESIS_T42: [(&str, f64); 5] = [
    ("STORM", 561.37),
    ("SGD", 786.64),
    ("RMSProp", 594.49),
    ("DAgger", 1064.589),
    ("Adam", 1734.45),
];
/// Table 4.3 (gradient calls, mean ± spread).
pub const THESIS_T43: [(&str, f64, f64); 4] = [
    ("STORM", 4_472_049.0, 11031.0),
    ("RMSProp", 1_903_548.0, 9866.0),
    ("DAgger", 31_905_600.0, 4263.0),
    ("Adam", 2_467_044.0, 11636.0),
];
/// Table 4.4 (runtime in seconds).
pub const THESIS_T44: [(&str, f64); 4] = [
    ("STORM", 8233.7),
    ("RMSProp", 3328.4),
    ("DAgger", 39340.1),
    ("Adam", 4717.6),
];

/// The errata of math.md §0: (id, where, problem, correction).
pub const ERRATA: [(&str, &str, &str, &str); 18] = [
    (
        "E1",
        "(3.2), (3.5)",
        "l_t must not depend on the sampled action a_t; otherwise (3.15) is biased",
        "define l_t on the policy output (math.md §1.2)",
    ),
    (
        "E2",
        "(3.41)",
        "\"f L-smooth implies F L-smooth\" is false in IL (the sampling law depends on θ); the estimator field is not a gradient field",
        "assume L_F-smoothness of F directly, plus (A4)",
    ),
    (
        "E3",
        "(3.44) Lemma 3.3",
        "the Δ_k term lacks η_k²",
        "4(1−a_{k+1})²L²η_k²Δ_k",
    ),
    ("E4", "(3.46), (3.47)", "f written for ∇f", "typo"),
    (
        "E5",
        "(3.54)–(3.56)",
        "L²/2 in the quadratic upper bound",
        "L/2",
    ),
    (
        "E6",
        "(3.58)",
        "both coefficients wrong; needs ηL ≤ 1/4, not ηL < 2",
        "−(η/2)(1−2Lη)Δ + (η/2)(1+2Lη)e ≤ −(η/4)Δ + (3η/4)e for Lη ≤ 1/4",
    ),
    (
        "E7",
        "after (3.58)/(3.59)",
        "\"these choices make the first term negative\" is false for k = 1..23; the telescoping is invalid as written",
        "a different potential; the same step sizes then work",
    ),
    (
        "E8",
        "(3.60)",
        "O(·) hides constants, mixes T and K",
        "explicit bound (3.60*)",
    ),
    (
        "E9",
        "Alg. 4",
        "d_{k+1} = ∇f(θ_{k+1}, τ_{k+1}) + (1−a_{k+1})∇f(θ_k, τ_{k+1})",
        "d_{k+1} = ∇f(θ_{k+1}, τ_{k+1}) + (1−a_{k+1})(d_k − ∇f(θ_k, τ_{k+1})), as (3.40)",
    ),
    (
        "E10",
        "Alg. 4 / Lemma 3.3 in IL",
        "∇f(θ_k, τ_{k+1}) with τ_{k+1} ∼ p(·; θ_{k+1}) is biased for ∇F(θ_k)",
        "importance weight w = p(τ; θ_k)/p(τ; θ_{k+1}) (IS-STORM)",
    ),
    (
        "E11",
        "Alg. 5",
        "τ_n ∼ p(τ; θ_n) while the gradient is taken at w_n",
        "τ_n ∼ p(τ; w_n)",
    ),
    ("E12", "(3.64), (3.67)", "F(θ_1)", "F(θ_0)"),
    (
        "E13",
        "Thm 3.8 proof",
        "u_n = u^{mod(n,T)+1}; \"dividing by KDT = KM\"; (3.69) bounds a sum of norms by √T σ",
        "u_n = u^{⌈n/T⌉}; divide by DM; bound ‖Σ_t X_t‖, not Σ_t ‖X_t‖",
    ),
    (
        "E14",
        "(3.72)",
        "+s_n Δ_{n'}",
        "−s_{n'} Δ_{n'} (bound unaffected)",
    ),
    (
        "E15",
        "Thm 3.1",
        "statement has ‖θ_i − θ'‖; convergence needs βε/γ < 1 (unstated); Lemma 3.2 garbled",
        "‖θ_i − θ'_i‖; math.md §6",
    ),
    (
        "E16",
        "§3.2.1 end",
        "\"‖θ_k − θ_PO‖ ≤ α⁻¹‖∇F‖ ≤ E‖∇F‖\": the last inequality is false",
        "only E‖θ_k − θ_PO‖ ≤ α⁻¹ E‖∇F(θ_k)‖",
    ),
    (
        "E17",
        "Alg. 3, 4",
        "return θ_K",
        "guarantees are for a random / best iterate, not θ_K",
    ),
    (
        "E18",
        "(3.29), (3.30) vs (3.1)",
        "sums to T vs T−1",
        "use T−1 throughout",
    ),
];

pub use crate::verdict::Verdict;

/// A qualitative claim of chapter 4 with its verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Claim {
    /// Identifier.
    pub id: String,
    /// Where in the thesis.
    pub source: String,
    /// The claim.
    pub claim: String,
    /// The rule applied.
    pub rule: String,
    /// The numbers.
    pub evidence: String,
    /// The verdict.
    pub verdict: Verdict,
}

/// Gradient calls (or runtime) to converge of one configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConvergenceRow {
    /// Algorithm.
    pub label: String,
    /// Seeds that converged.
    pub converged: usize,
    /// Seeds.
    pub seeds: usize,
    /// Over the converged seeds.
    pub gradient_calls: Summary,
    /// Gradient calls of the whole run (all seeds).
    pub total_gradient_calls: Summary,
    /// Final score (all seeds).
    pub final_score: Summary,
    /// Final crashes (all seeds).
    pub final_crashes: Summary,
    /// Final mean reward (all seeds).
    pub final_reward: Summary,
    /// Final evaluation loss (all seeds).
    pub final_loss: Summary,
    /// Diverged runs ([`crate::experiment::RunStatus::Diverged`]: ‖θ‖ beyond the bound, a
    /// non-finite iterate, a failed step).
    pub failed_runs: usize,
}

fn last(r: &SeedRun) -> Option<&Checkpoint> {
    r.checkpoints.last()
}

fn summarise(c: &ConfigResult, f: impl Fn(&Checkpoint) -> f64) -> Summary {
    let xs: Vec<f64> = c.runs.iter().filter_map(last).map(f).collect();
    Summary::of(&xs)
}

fn convergence_row(c: &ConfigResult) -> ConvergenceRow {
    let calls: Vec<f64> = c
        .runs
        .iter()
        .filter_map(|r| {
            r.converged
                .map(|i| r.checkpoints[i].gradient_evaluations as f64)
        })
        .collect();
    ConvergenceRow {
        label: c.label.clone(),
        converged: calls.len(),
        seeds: c.runs.len(),
        gradient_calls: Summary::of(&calls),
        total_gradient_calls: summarise(c, |k| k.gradient_evaluations as f64),
        final_score: summarise(c, |k| k.score),
        final_crashes: summarise(c, |k| f64::from(k.crashes)),
        final_reward: summarise(c, |k| k.reward),
        final_loss: summarise(c, |k| k.loss),
        failed_runs: c.runs.iter().filter(|r| r.status.is_diverged()).count(),
    }
}

fn runtime(t: Option<&ConfigTiming>) -> (Summary, Summary) {
    let Some(t) = t else {
        return (Summary::of(&[]), Summary::of(&[]));
    };
    let conv: Vec<f64> = t.runs.iter().filter_map(|r| r.converge_seconds).collect();
    let total: Vec<f64> = t.runs.iter().map(|r| r.train_seconds).collect();
    (Summary::of(&conv), Summary::of(&total))
}

/// Four significant digits.
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return "—".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.3e}")
    }
}

fn ci(s: &Summary) -> String {
    if s.n == 0 {
        "—".into()
    } else if s.half_width.is_finite() {
        format!("{} ± {}", num(s.mean), num(s.half_width))
    } else {
        num(s.mean)
    }
}

/// Per-checkpoint band of a metric across seeds: (x = mean of `xf`, summary of `yf`).
fn band(
    c: &ConfigResult,
    xf: impl Fn(&Checkpoint) -> f64,
    yf: impl Fn(&Checkpoint) -> Option<f64>,
) -> Series {
    // Checkpoints are aligned by their nominal call count, on the schedule of the longest run (a
    // diverged run stops early: its checkpoints are those it reached).
    let schedule: Vec<u64> = c
        .runs
        .iter()
        .max_by_key(|r| r.checkpoints.len())
        .map(|r| r.checkpoints.iter().map(|k| k.at_calls).collect())
        .unwrap_or_default();
    let mut s = Series::new(c.label.clone());
    s.off_schedule = c
        .runs
        .iter()
        .flat_map(|r| &r.checkpoints)
        .filter(|k| !schedule.contains(&k.at_calls))
        .count();
    for it in schedule {
        let cps: Vec<&Checkpoint> = c
            .runs
            .iter()
            .filter_map(|r| r.checkpoints.iter().find(|k| k.at_calls == it))
            .collect();
        let all: Vec<f64> = cps.iter().filter_map(|c| yf(c)).collect();
        let ys: Vec<f64> = all.iter().copied().filter(|y| y.is_finite()).collect();
        s.non_finite += all.len() - ys.len();
        if ys.is_empty() {
            continue;
        }
        let x = cps.iter().map(|c| xf(c)).sum::<f64>() / cps.len() as f64;
        let sm = Summary::of(&ys);
        s.x.push(x);
        s.mean.push(sm.mean);
        s.lo.push(if sm.half_width.is_finite() {
            sm.lo()
        } else {
            sm.mean
        });
        s.hi.push(if sm.half_width.is_finite() {
            sm.hi()
        } else {
            sm.mean
        });
    }
    s
}

/// A dashed reference line (no band: its band is the line itself).
fn reference_series(label: String, x: Vec<f64>, mean: Vec<f64>) -> Series {
    Series {
        label,
        x,
        lo: mean.clone(),
        hi: mean.clone(),
        mean,
        reference: true,
        non_finite: 0,
        off_schedule: 0,
    }
}

/// Horizontal dashed lines at the mean of `f` over each baseline of `task` (reference policies,
/// no training), across the x range of the figure's learner curves.
fn baseline_lines(
    r: &Results,
    task: TaskKind,
    f: impl Fn(&Checkpoint) -> f64,
    over: &[Series],
) -> Vec<Series> {
    let xs = || {
        over.iter()
            .flat_map(|s| s.x.iter().copied())
            .filter(|x| *x > 0.0)
    };
    let (Some(x0), Some(x1)) = (xs().reduce(f64::min), xs().reduce(f64::max)) else {
        return vec![];
    };
    r.baselines
        .iter()
        .filter(|b| b.task == task)
        .filter_map(|b| {
            let m = b.runs.iter().map(&f).sum::<f64>() / b.runs.len().max(1) as f64;
            // A reference without the quantity (no gradient estimate) is not drawn at all.
            m.is_finite()
                .then(|| reference_series(format!("{} (ref.)", b.label), vec![x0, x1], vec![m, m]))
        })
        .collect()
}

/// A success-rate summary in percent.
fn percent(s: &Summary) -> Summary {
    Summary {
        mean: 100.0 * s.mean,
        half_width: 100.0 * s.half_width,
        n: s.n,
    }
}

/// The final-checkpoint table's rows of a task's baselines (evaluated on every seed's episodes).
fn baseline_rows(r: &Results, task: TaskKind) -> Vec<Vec<String>> {
    r.baselines
        .iter()
        .filter(|b| b.task == task)
        .map(|b| {
            let s = |f: &dyn Fn(&Checkpoint) -> f64| {
                Summary::of(&b.runs.iter().map(f).collect::<Vec<_>>())
            };
            vec![
                format!("*{}* (reference, no training)", b.label),
                if task == TaskKind::Obstacle {
                    ci(&percent(&s(&|c| c.score)))
                } else {
                    ci(&s(&|c| c.reward))
                },
                ci(&s(&|c| f64::from(c.crashes))),
                ci(&s(&|c| c.loss)),
                "—".into(),
            ]
        })
        .collect()
}

/// Write everything: CSV/JSON data, figures, appendix.md and appendix.tex.
///
/// # Errors
/// I/O, serialisation or plotting failures.
pub fn write(
    profile: &Profile,
    profile_text: &str,
    r: &Results,
    out: &Path,
    png: bool,
) -> Result<(), Error> {
    let fig_dir = out.join("figures");
    std::fs::create_dir_all(&fig_dir).map_err(|e| Error::io(&fig_dir, e))?;
    // Raw data.
    let mut csv = String::from(
        "task,algorithm,seed_index,seed,iteration,trajectories,gradient_evaluations,expert_queries,score,successes,crashes,timeouts,reward,loss,loss_x,loss_y,grad_x,grad_y,converged_here,at_calls,resets_to_full_episode,run_status\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
    for (c, _) in r.obstacle.iter().chain(&r.cartpole) {
        for run in &c.runs {
            for (i, k) in run.checkpoints.iter().enumerate() {
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    c.task.name(),
                    c.label,
                    run.seed_index,
                    run.seed,
                    k.iteration,
                    k.trajectories,
                    k.gradient_evaluations,
                    k.expert_queries,
                    k.score,
                    k.successes,
                    k.crashes,
                    k.timeouts,
                    k.reward,
                    k.loss,
                    opt(k.loss_x),
                    opt(k.loss_y),
                    opt(k.grad_x),
                    opt(k.grad_y),
                    run.converged == Some(i),
                    k.at_calls,
                    k.resets_to_full_episode
                        .map_or(String::new(), |x| x.to_string()),
                    match &run.status {
                        crate::experiment::RunStatus::Converged { .. } => "converged",
                        crate::experiment::RunStatus::NotConverged => "not-converged",
                        crate::experiment::RunStatus::Diverged { .. } => "diverged",
                    }
                );
            }
        }
    }
    write_atomic(&out.join("checkpoints.csv"), csv.as_bytes())?;
    let g = crate::gradient_error::csv(&r.gradient_error);
    write_atomic(&out.join("gradient_error.csv"), g.as_bytes())?;
    let mut t = String::from("task,algorithm,seed_index,train_seconds,converge_seconds\n");
    for (c, tm) in r.obstacle.iter().chain(&r.cartpole) {
        if let Some(tm) = tm {
            for s in &tm.runs {
                let _ = writeln!(
                    t,
                    "{},{},{},{},{}",
                    c.task.name(),
                    c.label,
                    s.seed_index,
                    s.train_seconds,
                    opt(s.converge_seconds)
                );
            }
        }
    }
    write_atomic(&out.join("timings.csv"), t.as_bytes())?;

    let obs: Vec<ConvergenceRow> = r.obstacle.iter().map(|c| convergence_row(&c.0)).collect();
    let cp: Vec<ConvergenceRow> = r.cartpole.iter().map(|c| convergence_row(&c.0)).collect();
    let cl = claims::claims(r, profile.cartpole.full_episode_cap);
    let tcl = claims::timing_claims(r);
    write_atomic(
        &out.join("tables.json"),
        &to_json(
            "tables",
            &serde_json::json!({
                "confidence_interval": "95% Student-t over seeds: mean ± t(0.975, n−1)·s/√n",
                "obstacle": obs, "cartpole": cp, "claims": cl,
            }),
        )?,
    )?;

    // Figures.
    let mut figs: Vec<(&str, &str, Figure)> = Vec::new();
    for (name, f) in crate::gradient_error::figures(&r.gradient_error) {
        figs.push((name, "Fig. 4.2", f));
    }
    let it = |c: &Checkpoint| c.iteration as f64;
    let traj = |c: &Checkpoint| c.trajectories as f64;
    let gc = |c: &Checkpoint| c.gradient_evaluations as f64;
    let by_iteration: (&str, &dyn Fn(&Checkpoint) -> f64) = ("iteration (parameter updates)", &it);
    let by_trajectories: (&str, &dyn Fn(&Checkpoint) -> f64) = (
        "expert-labelled trajectories rolled out (cumulative count)",
        &traj,
    );
    let obstacle_fig = |title: &str,
                        y: &str,
                        log_y: bool,
                        f: &dyn Fn(&Checkpoint) -> Option<f64>,
                        skip_dataset: bool,
                        (x_label, xf): (&str, &dyn Fn(&Checkpoint) -> f64)| {
        let series: Vec<Series> = r
            .obstacle
            .iter()
            .filter(|c| !(skip_dataset && matches!(c.0.label.as_str(), "BC" | "DAgger")))
            .map(|c| band(&c.0, xf, f))
            .collect();
        let lines = baseline_lines(r, TaskKind::Obstacle, |c| f(c).unwrap_or(f64::NAN), &series);
        Figure {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y.into(),
            log_x: false,
            log_y,
            y_range: None,
            series: series.into_iter().chain(lines).collect(),
        }
    };
    let n_obs = f64::from(profile.obstacle.eval_episodes);
    figs.push((
        "fig4-3-success",
        "Fig. 4.3",
        obstacle_fig(
            "Fig. 4.3: obstacle task, success rate of the deterministic policy (mean over seeds, 95% CI band; dashed: reference policies)",
            "success rate (fraction of episodes)",
            false,
            &|c| Some(c.score),
            false,
            by_trajectories,
        )
        .clamped((0.0, 1.0)),
    ));
    figs.push((
        "fig4-4-crashes",
        "Fig. 4.4",
        obstacle_fig(
            &format!("Fig. 4.4: obstacle task, crashes in {n_obs} evaluation episodes (mean over seeds, 95% CI band; dashed: reference policies)"),
            &format!("crashes (episodes out of {n_obs})"),
            false,
            &|c| Some(f64::from(c.crashes)),
            false,
            by_trajectories,
        )
        .clamped((0.0, n_obs)),
    ));
    // Figs. 4.5 (gradient-estimate rows, oracle methods only) and 4.6 (loss rows), against
    // iterations on a log y axis.
    type Metric<'a> = &'a dyn Fn(&Checkpoint) -> Option<f64>;
    let rows: [(&str, &str, String, &str, Metric<'_>, bool); 4] = [
        (
            "fig4-5a-gradient-x",
            "Fig. 4.5",
            " (a): obstacle task, norm of the x-row of the gradient estimate (oracle methods; mean over seeds, 95% CI band)".into(),
            "‖gradient estimate, x-row‖ (log scale)",
            &|c| c.grad_x,
            true,
        ),
        (
            "fig4-5b-gradient-y",
            "Fig. 4.5",
            " (b): obstacle task, norm of the y-row of the gradient estimate (oracle methods; mean over seeds, 95% CI band)".into(),
            "‖gradient estimate, y-row‖ (log scale)",
            &|c| c.grad_y,
            true,
        ),
        (
            "fig4-6a-loss-x",
            "Fig. 4.6",
            " (a): obstacle task, loss of the x velocity per decision (mean over seeds, 95% CI band)".into(),
            "x-velocity squared error (log scale)",
            &|c| c.loss_x,
            false,
        ),
        (
            "fig4-6b-loss-y",
            "Fig. 4.6",
            " (b): obstacle task, loss of the y velocity per decision (mean over seeds, 95% CI band)".into(),
            "y-velocity squared error (log scale)",
            &|c| c.loss_y,
            false,
        ),
    ];
    for (name, fig, what, y, f, oracle_only) in rows {
        figs.push((
            name,
            fig,
            obstacle_fig(
                &format!("{fig}{what}"),
                y,
                true,
                f,
                oracle_only,
                by_iteration,
            )
            .clamped((0.0, f64::INFINITY)),
        ));
    }
    let cart_fig = |title: &str, y: &str, log_y: bool, f: &dyn Fn(&Checkpoint) -> Option<f64>| {
        // Checkpoints are evenly spaced in gradient calls: a linear axis in millions shows the
        // start (0 calls) of every algorithm alike.
        let series: Vec<Series> = r
            .cartpole
            .iter()
            .map(|c| band(&c.0, |k| gc(k) / 1e6, f))
            .collect();
        let lines = baseline_lines(r, TaskKind::Cartpole, |c| f(c).unwrap_or(f64::NAN), &series);
        Figure {
            title: title.into(),
            x_label: "gradient calls (millions, cumulative)".into(),
            y_label: y.into(),
            log_x: false,
            log_y,
            y_range: None,
            series: series.into_iter().chain(lines).collect(),
        }
    };
    figs.push((
        "fig4-8-loss",
        "Fig. 4.8",
        cart_fig(
            "Fig. 4.8: CartPole, Brier loss per decision against the expert's action (mean over seeds, 95% CI band; dashed: reference policy)",
            "Brier loss per decision",
            false,
            &|c| Some(c.loss),
        )
        .clamped((0.0, f64::INFINITY)),
    ));
    figs.push((
        "fig4-9-crashes",
        "Fig. 4.9",
        cart_fig(
            &format!(
                "Fig. 4.9: CartPole, resets until one full 500-step episode, capped at {} (mean over seeds, 95% CI band; dashed: reference policy)",
                profile.cartpole.full_episode_cap
            ),
            "resets before a full episode (count)",
            false,
            &|c| c.resets_to_full_episode.map(f64::from),
        )
        .clamped((0.0, f64::from(profile.cartpole.full_episode_cap))),
    ));
    figs.push((
        "fig4-10-reward",
        "Fig. 4.10",
        cart_fig(
            "Fig. 4.10: CartPole, mean episode reward of the deterministic policy (mean over seeds, 95% CI band; dashed: reference policy)",
            "episode reward (steps, max. 500)",
            false,
            &|c| Some(c.reward),
        )
        .clamped((0.0, 500.0)),
    ));
    let mut png_ok = png;
    for (name, _, f) in &figs {
        match f.write(&fig_dir.join(format!("{name}.svg")), png_ok) {
            Ok(()) => {}
            Err(e) if png_ok => {
                eprintln!("warning: PNG rendering failed ({e}); writing SVG only");
                png_ok = false;
                f.write(&fig_dir.join(format!("{name}.svg")), false)?;
            }
            Err(e) => return Err(e),
        }
    }

    let machine = crate::provenance::Machine::current();
    let blocks = document(&Inputs {
        profile,
        r,
        obs: &obs,
        cp: &cp,
        cl: &cl,
        tcl: &tcl,
        figs: &figs,
        png: png_ok,
        machine: &machine,
    });
    let _ = profile_text;
    write_atomic(&out.join("appendix.md"), doc::markdown(&blocks).as_bytes())?;
    write_atomic(
        &out.join("appendix.tex"),
        doc::latex(&blocks, LATEX_PREAMBLE).as_bytes(),
    )?;
    write_atomic(
        &out.join("appendix-standalone.tex"),
        latex_standalone().as_bytes(),
    )?;
    Ok(())
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

fn runtime_table(
    set: &[(ConfigResult, Option<ConfigTiming>)],
    thesis: &[(&str, f64)],
) -> Vec<[String; 4]> {
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
    configs: &[(ConfigResult, Option<ConfigTiming>)],
    thesis_calls: &[(&str, f64, f64)],
    thesis_runtime: &[(&str, f64)],
) -> [Block; 2] {
    [
        Block::Table(Table {
            caption: Some(format!(
                "**Table {calls_no}: gradient calls to converge** (kit vs thesis):"
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
                num(mean_at(c, |s| s.checkpoints.first(), |k| k.loss)),
                num(mean_at(c, last, |k| k.loss)),
                num(mean_at(c, |s| s.checkpoints.first(), |k| k.reward)),
                num(mean_at(c, last, |k| k.reward)),
            )
        })
        .collect();
    format!(
        "**Objective.** Every row but the controls minimises the thesis's F (eqs. 3.1–3.16): a fixed \
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

/// Everything the appendix needs to say, in order.
struct Inputs<'a> {
    profile: &'a Profile,
    r: &'a Results,
    obs: &'a [ConvergenceRow],
    cp: &'a [ConvergenceRow],
    cl: &'a [Claim],
    tcl: &'a [Claim],
    figs: &'a [(&'a str, &'a str, Figure)],
    png: bool,
    machine: &'a crate::provenance::Machine,
}

/// The appendix as blocks, rendered by [`doc::markdown`] and [`doc::latex`].
fn document(x: &Inputs<'_>) -> Vec<Block> {
    let (profile, r) = (x.profile, x.r);
    let mut d = Vec::new();
    let h = |text: &str| Block::Heading {
        level: 2,
        text: text.into(),
    };
    let figures = |d: &mut Vec<Block>, which: &[&str]| {
        let ext = if x.png { "png" } else { "svg" };
        for (name, fig, f) in x.figs {
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
    d.push(Block::Para(format!(
        "Generated by `cargo run --release -p paper-checks{}` (profile `{}`, {} seeds per configuration). \
         Every number below is computed from the per-seed data in this directory (`checkpoints.csv`, \
         `runs/*.json`, `gradient_error.csv`); configurations and seeds are in `provenance.json`, wall \
         times in `timings.json` / `timings.csv`.",
        if profile.name == "full" {
            " -- --full"
        } else {
            ""
        },
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
         the obstacle. They are evaluated on the same episodes as the learners and bracket what \
         imitation achieves."
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
        "**Confidence intervals.** Mean ± half-width of the 95% Student-t interval over seeds, \
         `t(0.975, n−1)·s/√n`, in every table; figures shade the same interval at each checkpoint. \
         The thesis's ± values are its own (their meaning is not stated). Claims are judged on \
         intervals only (rules beside each claim): reproduced, not reproduced, or inconclusive when \
         the intervals overlap."
            .into(),
        "**Hyper-parameters** are selected by the pre-registered tuning protocol below (see `provenance.json`)."
            .into(),
        episode_length_note(r),
    ]));
    d.extend(tuning::blocks(profile, r));

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
            x.obs,
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
            x.cp,
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
            caption: Some("**Final checkpoint** (all seeds):".into()),
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

    d.push(h("Kit time vs thesis (Tables 4.2 and 4.4)"));
    d.push(Block::Para(speedup::speedup_intro(x.machine)));
    d.push(Block::Table(Table {
        caption: None,
        label: "tab:pc-speedup".into(),
        header: strings(&speedup::SPEEDUP_HEAD),
        rows: speedup_all_cells(r),
        spec: "llrlrr".into(),
    }));

    d.push(h("Claims of chapter 4 and verdicts"));
    d.push(Block::Para(
        "Each verdict is computed from the numbers by the stated rule.".into(),
    ));
    d.push(Block::Table(Table {
        caption: None,
        label: "tab:pc-claims".into(),
        header: strings(&["#", "where", "claim", "rule", "numbers", "verdict"]),
        rows: x
            .cl
            .iter()
            .chain(x.tcl)
            .map(|c| {
                vec![
                    c.id.clone(),
                    c.source.clone(),
                    c.claim.clone(),
                    c.rule.clone(),
                    c.evidence.clone(),
                    format!("**{}**", c.verdict.text()),
                ]
            })
            .collect(),
        spec: "llp{3cm}p{3.5cm}p{3.5cm}l".into(),
    }));

    d.push(h("Theorem checks (`ilopt-theory`)"));
    d.extend(theory::blocks(&r.theory, "tab:pc-theory"));
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
     % amsmath, amssymb, booktabs, longtable, array, graphicx, float and pdflscape\n\
     % (appendix-standalone.tex does).\n\
     % Figures are referenced relative to this file's directory.\n";

/// The complete LaTeX document around `appendix.tex` (`pdflatex appendix-standalone.tex` in the
/// output directory builds the PDF).
pub fn latex_standalone() -> String {
    format!(
        "% Generated by paper-checks: the appendix as a complete document.\n\
         % Build: pdflatex -interaction=nonstopmode -halt-on-error appendix-standalone.tex (twice, for the\n\
         % longtables' column widths).\n\
         \\documentclass[10pt,a4paper]{{article}}\n\
         {}\
         \\setlength{{\\emergencystretch}}{{3em}}\n\
         \\begin{{document}}\n\
         \\input{{appendix}}\n\
         \\end{{document}}\n",
        doc::LATEX_PACKAGES
    )
}
