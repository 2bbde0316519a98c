//! The qualitative claims of chapter 4, each judged by a stated rule on intervals
//! ([`crate::verdict`]): numbers with their CIs and n, failed runs counted, and one of
//! reproduced / inconclusive / not reproduced.
//!
//! Only rows whose role is `thesis` enter a claim (the thesis's algorithms on each task); extra
//! and control rows are reported in the tables, never in a thesis claim.

use super::aggregate::num;
use crate::config::Profile;
use crate::experiment::{AppendixRun, Evaluated};
use crate::experiment::{Checkpoint, RunStatus, SeedRun, TaskKind};
use crate::gradient_error::SlopeCi;
use crate::results::{ConfigResult, ConfigTiming, ConfigWithTiming, Results};
use crate::stats::Summary;
use crate::verdict::{
    MedianCi, Outcome, Tally, Verdict, cap_for_failures, extreme, least, less, most, within,
};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

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
    /// Why a "not reproduced" became "inconclusive": `inconclusive (tuning): …` or
    /// `inconclusive (budget): …` (absent when the verdict stands as its rule gave it).
    pub caveat: Option<String>,
    /// The task of the rows the claim compares (absent for O1, which compares none).
    pub task: Option<TaskKind>,
    /// The rows the claim compares (labels).
    pub compared: Vec<String>,
}

impl Claim {
    /// The claim as comparing the rows `labels` of `task`.
    fn on(mut self, task: TaskKind, labels: &[&str]) -> Self {
        self.task = Some(task);
        self.compared = labels.iter().map(|l| (*l).to_string()).collect();
        self
    }

    /// The verdict with its reason in full, as the claims section prints it.
    pub fn verdict_text(&self) -> String {
        match &self.caveat {
            Some(c) => c.clone(),
            None => self.verdict.text().to_string(),
        }
    }

    /// The verdict with the kind of its reason only (`inconclusive (tuning)`,
    /// `inconclusive (budget)`, `inconclusive (tuning, budget)`), as the summary prints it.
    pub fn verdict_short(&self) -> String {
        let Some(c) = &self.caveat else {
            return self.verdict.text().to_string();
        };
        let kinds: Vec<&str> = ["tuning", "budget"]
            .into_iter()
            .filter(|k| c.contains(&format!("({k})")))
            .collect();
        format!("{} ({})", self.verdict.text(), kinds.join(", "))
    }
}

/// The thesis's gradient calls to converge (Tables 4.1 and 4.3) by task and row.
const THESIS_CALLS: &[(TaskKind, &str, f64)] = &[
    (TaskKind::Obstacle, "STORM", 2764.0),
    (TaskKind::Obstacle, "SGD", 9450.0),
    (TaskKind::Obstacle, "RMSProp", 6411.0),
    (TaskKind::Obstacle, "DAgger", 53704.0),
    (TaskKind::Obstacle, "Adam", 10785.0),
    (TaskKind::Cartpole, "STORM", 4472049.0),
    (TaskKind::Cartpole, "RMSProp", 1903548.0),
    (TaskKind::Cartpole, "DAgger", 31905600.0),
    (TaskKind::Cartpole, "Adam", 2467044.0),
];

/// The thesis's figure for a row, if it printed one.
pub fn thesis_calls(task: TaskKind, label: &str) -> Option<f64> {
    THESIS_CALLS
        .iter()
        .find(|(t, l, _)| *t == task && *l == label)
        .map(|x| x.2)
}

/// A "not reproduced" that its evidence cannot carry becomes "inconclusive", with the reason:
/// * **tuning**: a compared row's pick had no converging tuning run, still lies on an edge of
///   its grid after extension, or was tuned on fewer than 3 seeds
///   ([`TuningResult::weakness`]);
/// * **budget**: the task's budget is below twice the largest thesis figure among the compared
///   rows ([`thesis_calls`]), and some run of a compared row did not converge within it.
fn qualify(c: Claim, r: &Results, budget_of: impl Fn(TaskKind) -> u64) -> Claim {
    let Some(task) = c.task else {
        return c;
    };
    let rows: Vec<&ConfigResult> = match task {
        TaskKind::Obstacle => &r.obstacle,
        TaskKind::Cartpole => &r.cartpole,
    }
    .iter()
    .map(|x| &x.0)
    .filter(|x| c.compared.contains(&x.label))
    .collect();
    qualify_with(c, &rows, &r.tuning, budget_of(task))
}

/// [`qualify`] on the compared `rows` of the claim's task, their `tuning` and the task's
/// `budget`.
fn qualify_with(
    mut c: Claim,
    rows: &[&ConfigResult],
    tuning: &[crate::protocol::TuningResult],
    budget: u64,
) -> Claim {
    let Some(task) = c.task else {
        return c;
    };
    if c.verdict != Verdict::NotReproduced {
        return c;
    }
    let tuning: Vec<String> = rows
        .iter()
        .filter_map(|row| {
            let t = tuning
                .iter()
                .find(|t| t.task == task && t.label == row.label)?;
            t.weakness().map(|w| format!("{}: {w}", row.label))
        })
        .collect();
    let largest = c
        .compared
        .iter()
        .filter_map(|l| thesis_calls(task, l))
        .fold(0.0, f64::max);
    let censored: Vec<String> = rows
        .iter()
        .filter_map(|row| {
            let n = row
                .runs
                .iter()
                .filter(|x| !x.status().is_converged())
                .count();
            (n > 0).then(|| format!("{} {n}/{}", row.label, row.runs.len()))
        })
        .collect();
    let mut why = Vec::new();
    if !tuning.is_empty() {
        why.push(format!("inconclusive (tuning): {}", tuning.join("; ")));
    }
    if (budget as f64) < 2.0 * largest && !censored.is_empty() {
        why.push(format!(
            "inconclusive (budget): {} calls, below twice the thesis's {} and runs did not \
             converge ({})",
            num(budget as f64),
            num(largest),
            censored.join(", ")
        ));
    }
    if !why.is_empty() {
        c.verdict = Verdict::Inconclusive;
        c.caveat = Some(why.join(" — "));
    }
    c
}

/// Confidence level of every interval of a claim.
const LEVEL: f64 = 0.95;

/// A run's outcome for the verdict rules.
pub(crate) fn outcome(r: &SeedRun) -> Outcome {
    match r.status() {
        RunStatus::Converged {
            gradient_evaluations,
            ..
        } => Outcome::Converged(*gradient_evaluations as f64),
        RunStatus::NotConverged => Outcome::NotConverged,
        RunStatus::Diverged { .. } => Outcome::Diverged,
    }
}

/// A thesis row of a task by label.
fn thesis<'a>(rows: &'a [ConfigWithTiming], label: &str) -> Option<&'a ConfigResult> {
    rows.iter()
        .map(|r| &r.0)
        .find(|c| c.label == label && c.entry.role == crate::config::Role::Thesis)
}

/// The thesis rows of `labels`, in that order (missing ones skipped).
fn in_order<'a>(rows: &'a [ConfigWithTiming], labels: &[&str]) -> Vec<&'a ConfigResult> {
    labels.iter().filter_map(|l| thesis(rows, l)).collect()
}

fn tally(c: &ConfigResult) -> Tally {
    Tally::of(&c.runs.iter().map(outcome).collect::<Vec<_>>())
}

/// Calls to sustained convergence, +∞ for runs that did not converge.
pub(crate) fn calls(c: &ConfigResult) -> MedianCi {
    let xs: Vec<f64> = c.runs.iter().map(|r| outcome(r).cost()).collect();
    MedianCi::of(&xs, LEVEL)
}

/// A quantity of each run's last checkpoint; `diverged` gives a diverged run's value (`None`:
/// left out).
fn last_value(
    c: &ConfigResult,
    f: impl Fn(&Checkpoint) -> Option<f64>,
    diverged: Option<f64>,
) -> Summary {
    let xs: Vec<f64> = c
        .runs
        .iter()
        .filter_map(|r| {
            if r.status().is_diverged() {
                diverged
            } else {
                r.checkpoints.last().and_then(&f)
            }
        })
        .collect();
    Summary::of(&xs)
}

/// A non-negative quantity (crashes, rewards, losses, norms, calls, seconds) as
/// [`interval_text`] with the interval's lower end clamped at 0.
fn ci_text(s: &Summary) -> String {
    interval_text(s, num, (0.0, f64::INFINITY))
}

/// A signed quantity as [`interval_text`], unclamped.
fn signed_text(s: &Summary) -> String {
    interval_text(s, num, (f64::NEG_INFINITY, f64::INFINITY))
}

/// A success rate (a fraction) as [`ci_text`] in percent, the unit of the rules and tables,
/// its interval clamped to [0 %, 100 %].
fn percent_text(s: &Summary) -> String {
    interval_text(s, |x| format!("{}%", num(100.0 * x)), (0.0, 1.0))
}

/// `mean [lo, hi] (n = …)`, each number written by `show` (the mean alone without a finite
/// interval); an end of the Student-t interval beyond the quantity's `range` is printed at the
/// range's end and marked † (clamping decides no rule: the rules compare intervals with bands
/// and with each other inside the range).
fn interval_text(s: &Summary, show: impl Fn(f64) -> String, range: (f64, f64)) -> String {
    if s.half_width.is_finite() {
        let end = |x: f64| {
            if x < range.0 {
                format!("{}†", show(range.0))
            } else if x > range.1 {
                format!("{}†", show(range.1))
            } else {
                show(x)
            }
        };
        format!(
            "{} [{}, {}] (n = {})",
            show(s.mean),
            end(s.lo()),
            end(s.hi()),
            s.n
        )
    } else {
        format!("{} (n = {})", show(s.mean), s.n)
    }
}

/// `label: value; tally` for each row.
fn evidence<'a>(rows: impl IntoIterator<Item = (&'a ConfigResult, String)>) -> String {
    rows.into_iter()
        .map(|(c, v)| format!("{} {v} — {}", c.label, tally(c).text()))
        .collect::<Vec<_>>()
        .join("; ")
}

/// O1's rule for one route: reproduced if the slope's CI contains −1/2 and lies below 0, not
/// reproduced if it excludes −1/2, inconclusive otherwise (it contains −1/2 and 0).
fn slope_verdict(s: &SlopeCi) -> Verdict {
    if !(s.lo.is_finite() && s.hi.is_finite()) {
        Verdict::Inconclusive
    } else if s.consistent_with_inverse_sqrt() {
        Verdict::Reproduced
    } else if s.lo > -0.5 || s.hi < -0.5 {
        Verdict::NotReproduced
    } else {
        Verdict::Inconclusive
    }
}

/// "`a`'s variance is lower than `b`'s": the one-sided F test at level 0.975 each way.
fn lower_variance(a: &Summary, b: &Summary, xa: &[f64], xb: &[f64]) -> Verdict {
    let var =
        |x: &[f64], m: f64| x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0);
    if xa.len() < 2 || xb.len() < 2 {
        return Verdict::Inconclusive;
    }
    let (va, vb) = (var(xa, a.mean), var(xb, b.mean));
    let quantile = |d1: usize, d2: usize| {
        FisherSnedecor::new((d1 - 1) as f64, (d2 - 1) as f64)
            .map(|f| f.inverse_cdf(LEVEL + (1.0 - LEVEL) / 2.0))
            .unwrap_or(f64::INFINITY)
    };
    if va == 0.0 && vb == 0.0 {
        Verdict::Inconclusive
    } else if vb > va * quantile(xb.len(), xa.len()) {
        Verdict::Reproduced
    } else if va > vb * quantile(xa.len(), xb.len()) {
        Verdict::NotReproduced
    } else {
        Verdict::Inconclusive
    }
}

/// A lower variance of `xs` cannot be shown when its values are censored at `cap`: any at the
/// cap caps `v` at inconclusive; all at the cap (no run ever completed an episode) make it not
/// reproduced.
fn censored(v: Verdict, xs: &[f64], cap: f64) -> Verdict {
    if !xs.is_empty() && xs.iter().all(|x| *x >= cap) {
        Verdict::NotReproduced
    } else if v == Verdict::Reproduced && xs.iter().any(|x| *x >= cap) {
        Verdict::Inconclusive
    } else {
        v
    }
}

/// [`censored`] on the target's values `xs`, and a run at the cap among the `others` also caps
/// a decided verdict at inconclusive (a censored sample's variance is unknown either way).
fn censored_any(v: Verdict, xs: &[f64], others: &[&[f64]], cap: f64) -> Verdict {
    let v = censored(v, xs, cap);
    if v != Verdict::Inconclusive
        && !(v == Verdict::NotReproduced && !xs.is_empty() && xs.iter().all(|x| *x >= cap))
        && others.iter().any(|o| o.iter().any(|x| *x >= cap))
    {
        Verdict::Inconclusive
    } else {
        v
    }
}

/// A claim with its verdict.
fn claim(id: &str, source: &str, claim: &str, rule: &str, evidence: String, v: Verdict) -> Claim {
    Claim {
        id: id.into(),
        source: source.into(),
        claim: claim.into(),
        rule: rule.into(),
        evidence,
        verdict: v,
        caveat: None,
        task: None,
        compared: Vec::new(),
    }
}

/// The deterministic claims (runtime claims: [`timing_claims`]), in the order of the chapter:
/// Fig. 4.2's rate, the obstacle task's success rates, extremes and gradient calls, then
/// CartPole's.
///
/// The cap of Fig. 4.9's count (resets before one full episode, the profile's
/// `full_episode_cap`): a run at the cap never completed an episode, so its count is censored
/// and says nothing about a variance. Every "not reproduced" is then qualified: a compared row's weak tuning or a short budget with
/// unconverged runs makes it "inconclusive (tuning)" or "inconclusive (budget)".
pub fn claims(r: &Results, profile: &Profile) -> Vec<Claim> {
    let mut out = vec![gradient_error_claim(r)];
    out.extend(obstacle_success_claims(&r.obstacle));
    out.extend(obstacle_extreme_claims(&r.obstacle));
    out.extend(obstacle_calls_claims(&r.obstacle));
    out.extend(cartpole_claims(
        &r.cartpole,
        profile.cartpole.full_episode_cap,
    ));
    out.into_iter()
        .map(|c| qualify(c, r, |t| budget_of(profile, t)))
        .collect()
}

fn budget_of(profile: &Profile, t: TaskKind) -> u64 {
    match t {
        TaskKind::Obstacle => profile.obstacle.budget,
        TaskKind::Cartpole => profile.cartpole.budget,
    }
}

/// O1: the gradient-estimate error decays at ≈ 1/√N (Fig. 4.2), by the slope of each route.
fn gradient_error_claim(r: &Results) -> Claim {
    let (toy, obst) = (&r.gradient_error.toy, &r.gradient_error.obstacle);
    claim(
        "O1",
        "§4.1.3, Fig. 4.2",
        "the gradient-estimate error decays at ≈ 1/√N",
        "for each route, the 95% bootstrap CI of the least-squares slope of log RMSE vs log N: \
         reproduced if it contains −1/2 and lies below 0, not reproduced if it excludes −1/2",
        format!(
            "toy MDP vs exact ∇F: slope {}; obstacle task vs an M = {} reference (SE {}): slope {}",
            crate::gradient_error::slope_text(toy),
            obst.reference_trajectories.unwrap_or(0),
            num(obst.reference_variance.sqrt()),
            crate::gradient_error::slope_text(obst)
        ),
        Verdict::all(&[slope_verdict(&toy.slope), slope_verdict(&obst.slope)]),
    )
}

/// O2–O5: the obstacle task's final success rates (Fig. 4.3).
fn obstacle_success_claims(o: &[ConfigWithTiming]) -> Vec<Claim> {
    let mut out = Vec::new();
    let success = |c: &ConfigResult| last_value(c, |k| Some(k.score()), Some(0.0));
    // A thesis row's final success rate lies in [lo, hi].
    let level = |id: &str, label: &str, text: &str, lo: f64, hi: f64| {
        let rule = format!(
            "the 95% t-interval of the final success rate (diverged runs count as 0) lies in \
             [{}%, {}%]: reproduced; disjoint from it: not reproduced; else inconclusive",
            num(100.0 * lo),
            num(100.0 * hi)
        );
        let (ev, v) = match thesis(o, label) {
            Some(c) => {
                let s = success(c);
                (evidence([(c, percent_text(&s))]), within(&s, lo, hi))
            }
            None => (format!("no thesis row {label}"), Verdict::Inconclusive),
        };
        claim(id, "§4.1.3, Fig. 4.3", text, &rule, ev, v).on(TaskKind::Obstacle, &[label])
    };
    // BC ≈ 70 %, and constant: the per-seed change from the second checkpoint to the last.
    if let Some(bc) = thesis(o, "BC") {
        let s = success(bc);
        let change: Vec<f64> = bc
            .runs
            .iter()
            .filter_map(|r| Some(r.checkpoints.last()?.score() - r.checkpoints.get(1)?.score()))
            .collect();
        let d = Summary::of(&change);
        out.push(
            claim(
                "O2",
                "§4.1.3, Fig. 4.3",
                "BC's success rate is ≈ 70% and stays constant as expert trajectories increase",
                "the final success's 95% t-interval lies in [60%, 80%], and the interval of the \
             per-seed change from the second checkpoint to the last lies in [−10, +10] pp \
             (both inside: reproduced; either disjoint: not reproduced)",
                format!(
                    "{}; change {} pp",
                    evidence([(bc, percent_text(&s))]),
                    signed_text(&Summary {
                        n: d.n,
                        mean: 100.0 * d.mean,
                        half_width: 100.0 * d.half_width
                    })
                ),
                Verdict::all(&[within(&s, 0.6, 0.8), within(&d, -0.1, 0.1)]),
            )
            .on(TaskKind::Obstacle, &["BC"]),
        );
    }
    for (id, label, text, lo, hi) in [
        ("O3", "SGD", "SGD's success rate is ≈ 82.5%", 0.725, 0.925),
        (
            "O4",
            "RMSProp",
            "RMSProp's success rate lies between 72% and 85%",
            0.67,
            0.90,
        ),
    ] {
        out.push(level(id, label, text, lo, hi));
    }
    let trio_labels = ["STORM", "DAgger", "Adam"];
    let trio: Vec<&ConfigResult> = trio_labels.iter().filter_map(|l| thesis(o, l)).collect();
    out.push(
        claim(
            "O5",
            "§4.1.3, Fig. 4.3",
            "STORM, DAgger and Adam reach ≈ 90% success for many expert trajectories",
            "each final success's 95% t-interval (diverged runs count as 0) lies in [80%, 100%]; \
         any disjoint from it: not reproduced",
            evidence(trio.iter().map(|c| (*c, percent_text(&success(c))))),
            Verdict::all(
                &trio
                    .iter()
                    .map(|c| within(&success(c), 0.8, 1.0))
                    .collect::<Vec<_>>(),
            ),
        )
        .on(TaskKind::Obstacle, &trio_labels),
    );
    out
}

/// O6–O8: the obstacle task's extremes: BC's crashes, STORM's gradient norm, DAgger's loss
/// (Figs. 4.4–4.6).
fn obstacle_extreme_claims(o: &[ConfigWithTiming]) -> Vec<Claim> {
    let mut out = Vec::new();
    let optimisers = |labels: &[&str]| -> Vec<&ConfigResult> {
        labels.iter().filter_map(|l| thesis(o, l)).collect()
    };
    let printed: Vec<&ConfigResult> = optimisers(&PRINTED_OBSTACLE);
    let extreme_claim = |target: &str,
                         set: &[&ConfigResult],
                         f: &dyn Fn(&ConfigResult) -> Summary,
                         largest: bool|
     -> (String, Verdict) {
        let Some(t) = set.iter().find(|c| c.label == target) else {
            return (format!("no thesis row {target}"), Verdict::Inconclusive);
        };
        let ts = f(t);
        let others: Vec<Summary> = set
            .iter()
            .filter(|c| c.label != target)
            .map(|c| f(c))
            .collect();
        let refs: Vec<&Summary> = others.iter().collect();
        let mut v = extreme(&ts, &refs, largest);
        if !largest {
            v = cap_for_failures(v, &[tally(t)]);
        }
        if tally(t).diverged * 2 > tally(t).runs() {
            v = Verdict::NotReproduced;
        }
        (evidence(set.iter().map(|c| (*c, ci_text(&f(c))))), v)
    };
    let crashes = |c: &ConfigResult| last_value(c, |k| Some(f64::from(k.crashes())), None);
    let (ev, v) = extreme_claim("BC", &printed, &crashes, true);
    out.push(
        claim(
            "O6",
            "§4.1.3, Fig. 4.4",
            "BC has the most crashes",
            "BC's final crashes (of the evaluation episodes; diverged runs left out) have a 95% \
         t-interval wholly above that of every other algorithm the thesis compared on this task \
         (DAgger, SGD, Adam, RMSProp, STORM): reproduced; some other's wholly above BC's: not \
         reproduced; else inconclusive",
            ev,
            v,
        )
        .on(TaskKind::Obstacle, &PRINTED_OBSTACLE),
    );
    let opt = optimisers(&["SGD", "Adam", "RMSProp", "STORM"]);
    let grad_x = |c: &ConfigResult| last_value(c, |k| k.grad_x, None);
    let (ev, v) = extreme_claim("STORM", &opt, &grad_x, false);
    out.push(claim(
        "O7",
        "§4.1.3, Fig. 4.5",
        "in the x direction STORM converges faster than the other optimisers (lowest gradient norm)",
        "STORM's final ‖x-row of the gradient estimate‖ (runs that did not diverge) has a 95% \
         t-interval wholly below SGD's, Adam's and RMSProp's; a STORM run that diverged caps the \
         verdict at inconclusive, a majority of diverged runs makes it not reproduced",
        ev,
        v,
    )
    .on(TaskKind::Obstacle, &["SGD", "Adam", "RMSProp", "STORM"]));
    out.push(dagger_loss_claim(&printed));
    out
}

/// The algorithms the thesis compared on the obstacle task (§4.1.3).
const PRINTED_OBSTACLE: [&str; 6] = ["BC", "DAgger", "SGD", "Adam", "RMSProp", "STORM"];

/// The mean evaluation loss of `c`'s runs that did not diverge at checkpoint `k`.
fn loss_at(c: &ConfigResult, k: usize) -> Summary {
    let xs: Vec<f64> = c
        .runs
        .iter()
        .filter(|r| !r.status().is_diverged())
        .filter_map(|r| r.checkpoints.get(k).map(|x| x.loss()))
        .collect();
    Summary::of(&xs)
}

/// O8: "DAgger's loss is very low at every iteration" (Fig. 4.6): at every checkpoint after
/// θ₁, DAgger's loss below every other compared row's.
fn dagger_loss_claim(set: &[&ConfigResult]) -> Claim {
    let labels: Vec<&str> = set.iter().map(|c| c.label.as_str()).collect();
    let rule = "at every checkpoint after θ₁ (diverged runs left out), DAgger's mean evaluation \
                loss has a 95% t-interval wholly below that of every other algorithm the thesis \
                compared on this task: reproduced; at some checkpoint some other's wholly below \
                DAgger's: not reproduced; else inconclusive; a DAgger divergence caps the verdict";
    let Some(d) = set.iter().find(|c| c.label == "DAgger") else {
        return claim(
            "O8",
            "§4.1.3, Fig. 4.6",
            "DAgger's loss is very low at every iteration",
            rule,
            "no thesis row DAgger".into(),
            Verdict::Inconclusive,
        );
    };
    let checkpoints = d
        .runs
        .iter()
        .map(|r| r.checkpoints.len())
        .max()
        .unwrap_or(0);
    let mut parts = Vec::new();
    let mut worst: Option<(usize, String)> = None;
    for k in 1..checkpoints {
        let dk = loss_at(d, k);
        let others: Vec<Summary> = set
            .iter()
            .filter(|c| c.label != "DAgger")
            .map(|c| loss_at(c, k))
            .collect();
        let v = extreme(&dk, &others.iter().collect::<Vec<_>>(), false);
        if v != Verdict::Reproduced && worst.is_none() {
            worst = Some((k, ci_text(&dk)));
        }
        parts.push(v);
    }
    let last = checkpoints.saturating_sub(1);
    let evidence = format!(
        "{} checkpoints after θ₁; DAgger below every other at {} of them{}; at the last: {}",
        parts.len(),
        parts.iter().filter(|v| **v == Verdict::Reproduced).count(),
        worst.map_or(String::new(), |(k, t)| format!(
            " (first exception: checkpoint {k}, DAgger {t})"
        )),
        evidence(set.iter().map(|c| (*c, ci_text(&loss_at(c, last)))))
    );
    claim(
        "O8",
        "§4.1.3, Fig. 4.6",
        "DAgger's loss is very low at every iteration",
        rule,
        evidence,
        cap_for_failures(Verdict::all(&parts), &[tally(d)]),
    )
    .on(TaskKind::Obstacle, &labels)
}

/// The rule of the gradient-call claims (Tables 4.1 and 4.3).
const MEDIAN_RULE: &str = "medians of the gradient calls to sustained convergence with \
     distribution-free 95% intervals (order statistics); runs that never converged or diverged \
     count as +∞";

/// The gradient-call medians of `set`, as evidence.
fn calls_evidence(set: &[&ConfigResult]) -> String {
    evidence(
        set.iter()
            .map(|c| (*c, format!("median calls {}", calls(c).text(num)))),
    )
}

/// "DAgger needs the most gradient calls to converge" on the rows `set` (O10, C1).
fn dagger_most_calls(id: &str, source: &str, set: &[&ConfigResult]) -> Claim {
    let verdict = match set.iter().find(|c| c.label == "DAgger") {
        None => Verdict::Inconclusive,
        Some(d) => {
            let others: Vec<MedianCi> = set
                .iter()
                .filter(|c| c.label != "DAgger")
                .map(|c| calls(c))
                .collect();
            most(&calls(d), &others.iter().collect::<Vec<_>>())
        }
    };
    claim(
        id,
        source,
        "DAgger needs the most gradient calls to converge",
        &format!(
            "{MEDIAN_RULE}; DAgger's lower end above every other's finite upper end (a \
             lower end of +∞, DAgger never converging in most runs, counts): reproduced; DAgger's \
             upper end below another's lower end: not reproduced; else inconclusive"
        ),
        calls_evidence(set),
        verdict,
    )
}

/// The rows of Table 4.1.
const T41: [&str; 5] = ["STORM", "SGD", "RMSProp", "DAgger", "Adam"];
/// The rows of Table 4.3.
const T43: [&str; 4] = ["STORM", "RMSProp", "DAgger", "Adam"];

/// O9–O10: STORM needs the fewest gradient calls, DAgger the most (Table 4.1).
fn obstacle_calls_claims(o: &[ConfigWithTiming]) -> Vec<Claim> {
    let mut out = Vec::new();
    let t41 = in_order(o, &T41);
    if let Some(storm) = t41.iter().find(|c| c.label == "STORM") {
        let others: Vec<MedianCi> = t41
            .iter()
            .filter(|c| c.label != "STORM")
            .map(|c| calls(c))
            .collect();
        let v = least(&calls(storm), &others.iter().collect::<Vec<_>>());
        out.push(
            claim(
                "O9",
                "Table 4.1",
                "STORM needs the fewest gradient calls to converge",
                &format!(
                    "{MEDIAN_RULE}; STORM's interval wholly below every other's: reproduced; some \
                 wholly below STORM's, or STORM's median +∞: not reproduced; a STORM divergence \
                 caps the verdict"
                ),
                calls_evidence(&t41),
                cap_for_failures(v, &[tally(storm)]),
            )
            .on(TaskKind::Obstacle, &T41),
        );
    }
    out.push(dagger_most_calls("O10", "Table 4.1", &t41).on(TaskKind::Obstacle, &T41));
    out
}

/// C2's rule: STORM converges (finite median) and each of Adam's and RMSProp's intervals lies
/// wholly below STORM's; a STORM that does not converge refutes it (the thesis's STORM converges).
fn storm_slower(st: &MedianCi, ad: &MedianCi, rm: &MedianCi, favoured: &[Tally]) -> Verdict {
    if !st.median.is_finite() {
        return Verdict::NotReproduced;
    }
    cap_for_failures(Verdict::all(&[less(ad, st), less(rm, st)]), favoured)
}

/// C1–C4: CartPole's gradient calls (Table 4.3), rewards (Fig. 4.10) and the variance of the
/// crashes (Fig. 4.9).
fn cartpole_claims(c: &[ConfigWithTiming], reset_cap: u32) -> Vec<Claim> {
    let mut out = Vec::new();
    let t43 = in_order(c, &T43);
    out.push(dagger_most_calls("C1", "Table 4.3", &t43).on(TaskKind::Cartpole, &T43));
    if let (Some(st), Some(ad), Some(rm)) =
        (thesis(c, "STORM"), thesis(c, "Adam"), thesis(c, "RMSProp"))
    {
        out.push(claim(
            "C2",
            "§4.2.2, Fig. 4.8, Table 4.3",
            "STORM takes more gradient calls to converge than Adam and RMSProp",
            &format!(
                "{MEDIAN_RULE}; STORM converges (its median finite: the thesis's STORM converges, \
                 after more calls) and Adam's and RMSProp's intervals each lie wholly below \
                 STORM's: reproduced; STORM's median +∞, either's median +∞, or STORM's \
                 interval wholly below either's: not reproduced; divergences of Adam or RMSProp \
                 cap the verdict"
            ),
            calls_evidence(&[st, ad, rm]),
            storm_slower(&calls(st), &calls(ad), &calls(rm), &[tally(ad), tally(rm)]),
        )
        .on(TaskKind::Cartpole, &["STORM", "Adam", "RMSProp"]));
    }
    let rewards: Vec<&ConfigResult> = c
        .iter()
        .map(|r| &r.0)
        .filter(|x| x.entry.role == crate::config::Role::Thesis)
        .collect();
    let reward = |x: &ConfigResult| last_value(x, |k| Some(k.reward()), Some(0.0));
    out.push(claim(
        "C3",
        "§4.2.2, Fig. 4.10",
        "rewards increase to the maximum episode reward of 500",
        "for every thesis row, the final mean reward's 95% t-interval (diverged runs count as 0) \
         lies in [475, 500] (CartPole-v1's solved threshold): reproduced; any disjoint: not \
         reproduced",
        evidence(rewards.iter().map(|x| (*x, ci_text(&reward(x))))),
        Verdict::all(
            &rewards
                .iter()
                .map(|x| within(&reward(x), 475.0, 500.0))
                .collect::<Vec<_>>(),
        ),
    )
    .on(
        TaskKind::Cartpole,
        &rewards.iter().map(|x| x.label.as_str()).collect::<Vec<_>>(),
    ));
    let resets = |x: &ConfigResult| -> Vec<f64> {
        x.runs
            .iter()
            .filter(|r| !r.status().is_diverged())
            .filter_map(|r| r.checkpoints.last()?.resets_to_full_episode.map(f64::from))
            .collect()
    };
    if let (Some(st), Some(ad), Some(rm)) =
        (thesis(c, "STORM"), thesis(c, "Adam"), thesis(c, "RMSProp"))
    {
        let (xs, xa, xr) = (resets(st), resets(ad), resets(rm));
        let (ss, sa, sr) = (Summary::of(&xs), Summary::of(&xa), Summary::of(&xr));
        let sd = |x: &[f64], s: &Summary| {
            if x.len() < 2 {
                "—".to_string()
            } else {
                num(
                    (x.iter().map(|v| (v - s.mean).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0))
                        .sqrt(),
                )
            }
        };
        out.push(
            claim(
                "C4",
                "§4.2.2, Fig. 4.9",
                "among STORM, Adam and RMSProp the variance of STORM's crashes is the lowest",
                "crashes = resets of the final policy before one full 500-step episode (capped); \
             STORM's sample variance below Adam's and RMSProp's by a two-sided F test at 95% \
             (each way): reproduced; above: not reproduced; else inconclusive; a STORM \
             divergence, or a run of any of the three at the cap (censored: no episode \
             completed, so its variance is unknown), caps the verdict at inconclusive, and all \
             STORM runs at the cap make it not reproduced",
                [(st, &xs, &ss), (ad, &xa, &sa), (rm, &xr, &sr)]
                    .iter()
                    .map(|(x, v, s)| {
                        format!(
                            "{} sd {} (mean {}, n = {}) — {}",
                            x.label,
                            sd(v, s),
                            num(s.mean),
                            v.len(),
                            tally(x).text()
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
                censored_any(
                    cap_for_failures(
                        Verdict::all(&[
                            lower_variance(&ss, &sa, &xs, &xa),
                            lower_variance(&ss, &sr, &xs, &xr),
                        ]),
                        &[tally(st)],
                    ),
                    &xs,
                    &[&xa, &xr],
                    f64::from(reset_cap),
                ),
            )
            .on(TaskKind::Cartpole, &["STORM", "Adam", "RMSProp"]),
        );
    }
    out
}

/// Runtime claims (wall time; appendix.md only): DAgger's time to converge is the largest.
///
/// The thesis blames DAgger's runtime on its growing dataset (each round retrains on everything
/// aggregated so far), so the claims compare the training wall time **to sustained
/// convergence**, where that cost accrues, not the time of equal call budgets.
pub fn timing_claims(r: &Results, profile: &Profile) -> Vec<Claim> {
    [
        ("T1", "Table 4.2", TaskKind::Obstacle, &r.obstacle, &T41[..]),
        ("T2", "Table 4.4", TaskKind::Cartpole, &r.cartpole, &T43[..]),
    ]
    .into_iter()
    .map(|(id, table, kind, set, labels)| {
        qualify(runtime_claim(id, table, kind, set, labels), r, |t| {
            budget_of(profile, t)
        })
    })
    .collect()
}

/// One runtime claim on the thesis rows `labels` of `set` (the table `table` of task `kind`),
/// before [`qualify`]: DAgger's median time to converge against every other row's.
fn runtime_claim(
    id: &str,
    table: &str,
    kind: TaskKind,
    set: &[ConfigWithTiming],
    labels: &[&str],
) -> Claim {
    let times: Vec<(String, MedianCi)> = labels
        .iter()
        .filter_map(|l| {
            let (c, t) = set
                .iter()
                .find(|x| x.0.label == *l && x.0.entry.role == crate::config::Role::Thesis)?;
            Some((
                (*l).to_string(),
                MedianCi::of(&time_to_converge(c, t.as_ref()?), LEVEL),
            ))
        })
        .collect();
    let verdict = match times.iter().find(|t| t.0 == "DAgger") {
        Some((_, d)) => most(
            d,
            &times
                .iter()
                .filter(|t| t.0 != "DAgger")
                .map(|t| &t.1)
                .collect::<Vec<_>>(),
        ),
        None => Verdict::Inconclusive,
    };
    Claim {
        id: id.into(),
        source: table.into(),
        claim: "DAgger's runtime is much higher than the other algorithms'".into(),
        rule: format!(
            "the median training wall time to sustained convergence (seconds; +∞ for a run \
             that did not converge or diverged) with its distribution-free 95% interval: \
             DAgger's wholly above that of every other row of the thesis's {table} ({}): \
             reproduced; another's wholly above DAgger's: not reproduced; else inconclusive",
            labels
                .iter()
                .filter(|l| **l != "DAgger")
                .copied()
                .collect::<Vec<_>>()
                .join(", ")
        ),
        evidence: times
            .iter()
            .map(|(l, m)| format!("{l} median {} s", m.text(num)))
            .collect::<Vec<_>>()
            .join("; "),
        verdict,
        caveat: None,
        task: None,
        compared: Vec::new(),
    }
    .on(kind, labels)
}

/// Each run's training wall time to sustained convergence, +∞ for a run that did not converge
/// (or diverged).
fn time_to_converge(c: &ConfigResult, t: &ConfigTiming) -> Vec<f64> {
    c.runs
        .iter()
        .map(|r| {
            t.runs
                .iter()
                .find(|x| x.seed_index == r.seed_index)
                .and_then(|x| x.converge_seconds)
                .filter(|_| r.status().is_converged())
                .unwrap_or(f64::INFINITY)
        })
        .collect()
}

#[cfg(test)]
mod tests;
