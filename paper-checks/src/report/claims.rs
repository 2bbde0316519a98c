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
mod tests {
    use super::*;

    fn timed(statuses: &[RunStatus]) -> (ConfigResult, ConfigTiming) {
        let runs = statuses.iter().enumerate().map(|(i, status)| SeedRun {
            seed: i as u64,
            seed_index: Some(i as u32),
            algorithm: "storm".into(),
            termination: ilopt::algo::RecordedTermination::GradientBudget,
            iterations: 0,
            cost: ilopt::problem::Cost::default(),
            theta: vec![],
            checkpoints: vec![],
            status: Some(status.clone()),
            hyper_parameters: None,
        });
        let timing = (0..statuses.len()).map(|i| crate::experiment::SeedTiming {
            seed: i as u64,
            seed_index: Some(i as u32),
            train_seconds: 1.0 + i as f64,
            evaluation_seconds: 0.0,
            checkpoint_seconds: vec![],
            converge_seconds: None,
        });
        (
            crate::results::storm_config_for_tests(runs.collect()),
            ConfigTiming {
                task: crate::experiment::TaskKind::Obstacle,
                label: "STORM".into(),
                runs: timing.collect(),
                wall_seconds: 0.0,
            },
        )
    }

    /// One run's evaluation at a checkpoint: success rate, crashes, loss, ‖x-row of ∇‖.
    type At = (f64, u32, f64, f64);

    /// An obstacle thesis row `label` with one run per entry of `runs`: its status and its
    /// checkpoints' evaluations.
    fn row(label: &str, runs: &[(RunStatus, Vec<At>)]) -> ConfigWithTiming {
        let runs = runs
            .iter()
            .enumerate()
            .map(|(i, (status, points))| SeedRun {
                seed: i as u64,
                seed_index: Some(i as u32),
                algorithm: "adam".into(),
                termination: ilopt::algo::RecordedTermination::GradientBudget,
                iterations: 0,
                cost: ilopt::problem::Cost::default(),
                theta: vec![],
                checkpoints: points
                    .iter()
                    .enumerate()
                    .map(|(k, &(score, crashes, loss, grad_x))| {
                        serde_json::from_value(serde_json::json!({
                            "at_calls": 1000 * k, "iteration": k, "gradient_evaluations": 1000 * k,
                            "trajectories": k, "env_steps": k, "expert_queries": k,
                            "score": score, "crashes": crashes, "eval_loss": loss,
                            "grad_x": grad_x
                        }))
                        .expect("a checkpoint")
                    })
                    .collect(),
                status: Some(status.clone()),
                hyper_parameters: None,
            })
            .collect();
        let mut c = crate::results::storm_config_for_tests(runs);
        c.label = label.into();
        (c, None)
    }

    fn diverged() -> RunStatus {
        RunStatus::Diverged {
            reason: "‖θ‖ > 1e4".into(),
            gradient_evaluations: 1,
        }
    }

    /// `n` runs that did not converge, each with the same checkpoints.
    fn same(n: usize, points: &[At]) -> Vec<(RunStatus, Vec<At>)> {
        vec![(RunStatus::NotConverged, points.to_vec()); n]
    }

    fn verdict_of(claims: &[Claim], id: &str) -> Verdict {
        claims
            .iter()
            .find(|c| c.id == id)
            .expect("the claim")
            .verdict
    }

    /// O2: BC's final success inside [60 %, 80 %] and its change from the second checkpoint to
    /// the last inside [−10, +10] pp; a BC that keeps improving is not "constant".
    #[test]
    fn bc_is_constant_when_its_change_after_the_second_checkpoint_is_small() {
        let runs = |late: [f64; 4]| -> Vec<(RunStatus, Vec<At>)> {
            [
                (0.65, late[0]),
                (0.7, late[1]),
                (0.75, late[2]),
                (0.7, late[3]),
            ]
            .iter()
            .map(|&(second, last)| {
                let p = vec![
                    (0.0, 5, 1.0, 1.0),
                    (second, 5, 1.0, 1.0),
                    (last, 5, 1.0, 1.0),
                ];
                (RunStatus::NotConverged, p)
            })
            .collect()
        };
        let flat = [row("BC", &runs([0.7, 0.7, 0.7, 0.72]))];
        assert_eq!(
            verdict_of(&obstacle_success_claims(&flat), "O2"),
            Verdict::Reproduced
        );
        let mut rising = runs([0.7, 0.7, 0.7, 0.72]);
        for (r, first) in rising.iter_mut().zip([0.1, 0.2, 0.1, 0.2]) {
            r.1[1].0 = first;
        }
        assert_eq!(
            verdict_of(&obstacle_success_claims(&[row("BC", &rising)]), "O2"),
            Verdict::NotReproduced
        );
    }

    /// The six rows the thesis compared on the obstacle task, BC's runs given, every other row
    /// with 4 runs of 1–2 crashes.
    fn with_bc(bc: &[(RunStatus, Vec<At>)]) -> Vec<ConfigWithTiming> {
        let mut rows = vec![row("BC", bc)];
        for label in ["DAgger", "SGD", "Adam", "RMSProp", "STORM"] {
            let mut runs = same(2, &[(0.0, 1, 1.0, 1.0)]);
            runs.extend(same(2, &[(0.0, 2, 1.0, 1.0)]));
            rows.push(row(label, &runs));
        }
        rows
    }

    /// O6 compares BC's crashes (diverged runs left out) with every other row's; a diverged BC run
    /// does not cap a "most crashes" verdict, a majority of diverged runs makes it not
    /// reproduced (exactly half is no majority).
    #[test]
    fn bc_has_the_most_crashes_against_every_other_row_and_not_with_most_runs_diverged() {
        let high = |n: usize| same(n, &[(0.0, 9, 1.0, 1.0)]);
        let o6 = |bc: Vec<(RunStatus, Vec<At>)>| {
            verdict_of(&obstacle_extreme_claims(&with_bc(&bc)), "O6")
        };
        assert_eq!(o6(high(4)), Verdict::Reproduced);
        let mut one = high(4);
        one.push((diverged(), vec![]));
        assert_eq!(o6(one), Verdict::Reproduced);
        let mut half = high(2);
        half.extend([(diverged(), vec![]), (diverged(), vec![])]);
        assert_eq!(o6(half), Verdict::Reproduced);
        let mut most = high(2);
        most.extend([
            (diverged(), vec![]),
            (diverged(), vec![]),
            (diverged(), vec![]),
        ]);
        assert_eq!(o6(most), Verdict::NotReproduced);
        // Fewer crashes than the others: some other's interval lies wholly above BC's.
        assert_eq!(o6(same(4, &[(0.0, 0, 1.0, 1.0)])), Verdict::NotReproduced);
    }

    /// O7: STORM's lowest gradient norm is capped at inconclusive by one diverged STORM run.
    #[test]
    fn a_diverged_storm_run_caps_its_lowest_gradient_norm() {
        let mut rows: Vec<ConfigWithTiming> = ["SGD", "Adam", "RMSProp"]
            .iter()
            .map(|l| row(l, &same(4, &[(0.0, 1, 1.0, 5.0)])))
            .collect();
        let low = same(4, &[(0.0, 1, 1.0, 0.1)]);
        rows.push(row("STORM", &low));
        assert_eq!(
            verdict_of(&obstacle_extreme_claims(&rows), "O7"),
            Verdict::Reproduced
        );
        let mut capped = low;
        capped.push((diverged(), vec![]));
        rows.pop();
        rows.push(row("STORM", &capped));
        assert_eq!(
            verdict_of(&obstacle_extreme_claims(&rows), "O7"),
            Verdict::Inconclusive
        );
    }

    /// O8 reads DAgger's loss (runs that did not diverge) at every checkpoint after θ₁ against
    /// every other row's, and names the first checkpoint where DAgger is not the lowest.
    #[test]
    fn dagger_s_loss_is_compared_at_every_checkpoint_and_the_first_exception_is_named() {
        let others = |rows: &mut Vec<ConfigWithTiming>| {
            for label in ["BC", "SGD", "Adam", "RMSProp", "STORM"] {
                let mut runs = same(
                    2,
                    &[(0.0, 1, 5.0, 1.0), (0.0, 1, 5.0, 1.0), (0.0, 1, 3.0, 1.0)],
                );
                runs.extend(same(
                    2,
                    &[(0.0, 1, 6.0, 1.0), (0.0, 1, 6.0, 1.0), (0.0, 1, 4.0, 1.0)],
                ));
                rows.push(row(label, &runs));
            }
        };
        let o8 = |dagger: [f64; 3], failed: bool| {
            let points: Vec<At> = dagger.iter().map(|&l| (0.0, 1, l, 1.0)).collect();
            let mut runs = same(3, &points);
            if failed {
                runs.push((diverged(), vec![(0.0, 1, 100.0, 1.0); 3]));
            }
            let mut rows = vec![row("DAgger", &runs)];
            others(&mut rows);
            let set: Vec<&ConfigResult> = rows.iter().map(|r| &r.0).collect();
            dagger_loss_claim(&set)
        };
        let below = o8([5.0, 1.0, 1.0], false);
        assert_eq!(below.verdict, Verdict::Reproduced);
        assert!(
            below.evidence.contains(
                "2 checkpoints after θ₁; DAgger below every other at 2 of them; at the last"
            ),
            "{}",
            below.evidence
        );
        // A diverged run caps the verdict; its loss is left out of DAgger's.
        let capped = o8([5.0, 1.0, 1.0], true);
        assert_eq!(capped.verdict, Verdict::Inconclusive);
        assert!(
            capped.evidence.contains("at 2 of them;"),
            "{}",
            capped.evidence
        );
        let later = o8([5.0, 1.0, 3.5], false);
        assert_eq!(later.verdict, Verdict::Inconclusive);
        assert!(
            later
                .evidence
                .contains("at 1 of them (first exception: checkpoint 2, DAgger 3.5"),
            "{}",
            later.evidence
        );
        let above = o8([5.0, 9.0, 1.0], false);
        assert_eq!(above.verdict, Verdict::NotReproduced);
        assert!(above.evidence.contains("(first exception: checkpoint 1,"));
    }

    /// A row `label` whose runs end as the statuses given, each with one checkpoint of that mean
    /// reward and resets before a full episode (CartPole's quantities).
    fn cartpole_row(label: &str, runs: &[(RunStatus, f64, u32)]) -> ConfigWithTiming {
        let mut r = row(label, &[]);
        r.0.runs = runs
            .iter()
            .enumerate()
            .map(|(i, (status, reward, resets))| {
                let mut run = row(label, &[(status.clone(), vec![(0.0, 0, 0.0, 0.0)])])
                    .0
                    .runs
                    .remove(0);
                run.seed = i as u64;
                let k = &mut run.checkpoints[0];
                k.reward = Some(*reward);
                k.resets_to_full_episode = Some(*resets);
                run
            })
            .collect();
        r
    }

    fn converged_at(calls: u64) -> RunStatus {
        RunStatus::Converged {
            checkpoint: 1,
            gradient_evaluations: calls,
        }
    }

    /// O9, O10 and C1 compare the medians of the named rows: STORM's against every other row's,
    /// DAgger's against every other row's.
    #[test]
    fn the_call_claims_compare_one_row_with_every_other_row() {
        let rows = |storm: u64, dagger: u64| -> Vec<ConfigWithTiming> {
            [
                ("STORM", storm),
                ("SGD", 1000),
                ("RMSProp", 1000),
                ("DAgger", dagger),
                ("Adam", 1000),
            ]
            .iter()
            .map(|&(l, calls)| cartpole_row(l, &vec![(converged_at(calls), 500.0, 0); 10]))
            .collect()
        };
        let verdicts = |rows: &[ConfigWithTiming]| {
            let o = obstacle_calls_claims(rows);
            let c = cartpole_claims(rows, 100);
            (
                verdict_of(&o, "O9"),
                verdict_of(&o, "O10"),
                verdict_of(&c, "C1"),
            )
        };
        let r = Verdict::Reproduced;
        let n = Verdict::NotReproduced;
        assert_eq!(verdicts(&rows(100, 10_000)), (r, r, r));
        let o9 = obstacle_calls_claims(&rows(100, 10_000)).remove(0);
        assert!(
            o9.evidence.starts_with("STORM median calls 100")
                && o9.evidence.contains("SGD median calls 1000"),
            "{}",
            o9.evidence
        );
        assert_eq!(verdicts(&rows(5000, 10)), (n, n, n));
    }

    /// C3 reads every thesis row's final reward, and only the thesis rows'.
    #[test]
    fn rewards_reach_500_on_every_thesis_row_and_extra_rows_do_not_count() {
        let mut rows: Vec<ConfigWithTiming> = ["DAgger", "Adam", "RMSProp", "STORM"]
            .iter()
            .map(|l| cartpole_row(l, &vec![(RunStatus::NotConverged, 500.0, 0); 10]))
            .collect();
        let mut extra = cartpole_row("SGD", &vec![(RunStatus::NotConverged, 20.0, 0); 10]);
        extra.0.entry.role = crate::config::Role::Extra;
        rows.push(extra);
        assert_eq!(
            verdict_of(&cartpole_claims(&rows, 100), "C3"),
            Verdict::Reproduced
        );
        rows[1] = cartpole_row("Adam", &vec![(RunStatus::NotConverged, 20.0, 0); 10]);
        assert_eq!(
            verdict_of(&cartpole_claims(&rows, 100), "C3"),
            Verdict::NotReproduced
        );
    }

    /// C4 compares the resets of the runs that did not diverge (a diverged run's value at the
    /// cap is left out, not read as censoring); a row with fewer than 2 such runs prints no sd.
    #[test]
    fn the_crash_variance_reads_the_runs_that_did_not_diverge() {
        let spread = |label: &str, failed: bool| {
            let mut runs: Vec<(RunStatus, f64, u32)> = [1, 10, 20, 5, 30, 2, 15, 25, 8, 12]
                .iter()
                .map(|&k| (RunStatus::NotConverged, 100.0, k))
                .collect();
            if failed {
                runs.push((diverged(), 0.0, 100));
            }
            cartpole_row(label, &runs)
        };
        let storm = cartpole_row(
            "STORM",
            &[3, 3, 3, 3, 4, 4, 4, 4, 3, 4].map(|k| (RunStatus::NotConverged, 100.0, k)),
        );
        let rows = vec![
            storm.clone(),
            spread("Adam", true),
            spread("RMSProp", false),
        ];
        let c4 = cartpole_claims(&rows, 100)
            .into_iter()
            .find(|c| c.id == "C4")
            .expect("C4");
        assert_eq!(c4.verdict, Verdict::Reproduced);
        // STORM: mean 3.5, sample variance 10 · 0.25 / 9; two values 0 and 2: sd √2.
        assert!(
            c4.evidence
                .starts_with("STORM sd 0.5270 (mean 3.500, n = 10)"),
            "{}",
            c4.evidence
        );
        let two = cartpole_row(
            "STORM",
            &[0, 2].map(|k| (RunStatus::NotConverged, 100.0, k)),
        );
        let c4 = cartpole_claims(&[two, spread("Adam", false), spread("RMSProp", false)], 100)
            .into_iter()
            .find(|c| c.id == "C4")
            .expect("C4");
        assert!(
            c4.evidence
                .starts_with("STORM sd 1.414 (mean 1.000, n = 2)"),
            "{}",
            c4.evidence
        );
        let lone = cartpole_row("RMSProp", &[(diverged(), 0.0, 100)]);
        let rows = vec![storm, spread("Adam", false), lone];
        let c4 = cartpole_claims(&rows, 100)
            .into_iter()
            .find(|c| c.id == "C4")
            .expect("C4");
        assert!(
            c4.evidence.contains("RMSProp sd — (mean"),
            "{}",
            c4.evidence
        );
    }

    /// T1/T2 compare DAgger's median time to converge (its thesis row's, not an extra row of the
    /// same label) with every other thesis row's.
    #[test]
    fn dagger_s_runtime_is_compared_with_every_other_thesis_row() {
        let timed_row = |label: &str, seconds: f64, role: crate::config::Role| {
            let (mut c, _) = cartpole_row(label, &vec![(converged_at(10), 500.0, 0); 10]);
            c.entry.role = role;
            let runs = c
                .runs
                .iter()
                .map(|r| crate::experiment::SeedTiming {
                    seed: r.seed,
                    seed_index: r.seed_index,
                    train_seconds: 2.0 * seconds,
                    evaluation_seconds: 0.0,
                    checkpoint_seconds: vec![],
                    converge_seconds: Some(seconds),
                })
                .collect();
            let t = ConfigTiming {
                task: TaskKind::Cartpole,
                label: label.into(),
                runs,
                wall_seconds: 0.0,
            };
            (c, Some(t))
        };
        use crate::config::Role::{Extra, Thesis};
        let set = |dagger: f64| {
            vec![
                timed_row("STORM", 1.0, Thesis),
                timed_row("DAgger", 0.5, Extra),
                timed_row("DAgger", dagger, Thesis),
                timed_row("Adam", 1.0, Thesis),
                timed_row("RMSProp", 2.0, Thesis),
            ]
        };
        let t2 =
            |dagger: f64| runtime_claim("T2", "Table 4.4", TaskKind::Cartpole, &set(dagger), &T43);
        let slow = t2(100.0);
        assert_eq!(slow.verdict, Verdict::Reproduced);
        assert!(
            slow.evidence.contains("DAgger median 100"),
            "{}",
            slow.evidence
        );
        assert_eq!(t2(0.1).verdict, Verdict::NotReproduced);
    }

    #[test]
    fn time_to_converge_counts_unconverged_and_diverged_runs_as_infinite() {
        let diverged = RunStatus::Diverged {
            reason: "non-finite θ".into(),
            gradient_evaluations: 3,
        };
        let conv = RunStatus::Converged {
            checkpoint: 1,
            gradient_evaluations: 10,
        };
        let (c, mut t) = timed(&[conv.clone(), diverged, RunStatus::NotConverged, conv]);
        for (i, r) in t.runs.iter_mut().enumerate() {
            r.converge_seconds = Some(10.0 * i as f64 + 1.0);
        }
        let xs = time_to_converge(&c, &t);
        assert_eq!(xs[0], 1.0);
        assert!(xs[1].is_infinite() && xs[2].is_infinite());
        assert_eq!(xs[3], 31.0);
    }

    #[test]
    fn a_not_reproduced_on_weak_tuning_or_a_short_budget_becomes_inconclusive_with_its_reason() {
        use crate::protocol::{PointResult, Round, TuningResult};
        let never = timed(&[RunStatus::NotConverged, RunStatus::NotConverged]).0;
        let converged = RunStatus::Converged {
            checkpoint: 1,
            gradient_evaluations: 10,
        };
        let all = timed(&[converged.clone(), converged]).0;
        let base = || {
            claim(
                "O9",
                "Table 4.1",
                "a claim",
                "a rule",
                "numbers".into(),
                Verdict::NotReproduced,
            )
            .on(TaskKind::Obstacle, &["STORM"])
        };
        let tuned = |weak: bool| TuningResult {
            task: TaskKind::Obstacle,
            label: "STORM".into(),
            key_hash: String::new(),
            dims: vec![],
            points: vec![PointResult {
                point: crate::grid::points(&all.entry.config, None, None, &[])
                    .unwrap()
                    .remove(0),
                runs: vec![],
                score: None,
                rung: 0,
            }],
            selected: 0,
            budget: 1,
            rounds: vec![Round {
                points: 1,
                rungs: vec![],
                pick: String::new(),
                extended: vec![],
            }],
            on_edge: if weak {
                vec!["x (upper end)".into()]
            } else {
                vec![]
            },
            tied_with: vec![],
            tuning_seeds: 3,
        };
        // The thesis's STORM figure on this task is 2764 calls: a budget of 10 000 is enough.
        let q = qualify_with(base(), &[&never], &[tuned(false)], 10_000);
        assert_eq!((q.verdict, q.caveat), (Verdict::NotReproduced, None));
        // Only the compared row's own tuning counts: a weak pick of another row of the task, or
        // of the same label on the other task, listed first, leaves the verdict alone.
        let other_row = TuningResult {
            label: "SGD".into(),
            ..tuned(true)
        };
        let other_task = TuningResult {
            task: TaskKind::Cartpole,
            ..tuned(true)
        };
        let q = qualify_with(
            base(),
            &[&never],
            &[other_row, other_task, tuned(false)],
            10_000,
        );
        assert_eq!((q.verdict, q.caveat), (Verdict::NotReproduced, None));
        let q = qualify_with(base(), &[&never], &[tuned(true)], 10_000);
        assert_eq!(q.verdict, Verdict::Inconclusive);
        assert_eq!(q.verdict_short(), "inconclusive (tuning)");
        assert!(
            q.caveat
                .unwrap()
                .contains("STORM: its pick lies on an edge of x")
        );
        // A budget below twice the thesis's figure matters only when a run did not converge.
        let q = qualify_with(base(), &[&never], &[tuned(false)], 5_000);
        assert_eq!(q.verdict_short(), "inconclusive (budget)");
        assert!(q.caveat.unwrap().contains("STORM 2/2"));
        let q = qualify_with(base(), &[&all], &[tuned(false)], 5_000);
        assert_eq!(q.verdict, Verdict::NotReproduced);
        // Exactly twice the thesis's figure is enough ("at least twice").
        let q = qualify_with(base(), &[&never], &[tuned(false)], 2 * 2764);
        assert_eq!((q.verdict, q.caveat), (Verdict::NotReproduced, None));
        let q = qualify_with(base(), &[&never], &[tuned(false)], 2 * 2764 - 1);
        assert_eq!(q.verdict_short(), "inconclusive (budget)");
        let q = qualify_with(base(), &[&never], &[tuned(true)], 5_000);
        assert_eq!(q.verdict_short(), "inconclusive (tuning, budget)");
        // Other verdicts, and claims comparing no rows, stand.
        let mut r = base();
        r.verdict = Verdict::Reproduced;
        assert_eq!(
            qualify_with(r, &[&never], &[tuned(true)], 5_000).verdict,
            Verdict::Reproduced
        );
        let mut none = base();
        none.task = None;
        assert_eq!(
            qualify_with(none, &[&never], &[tuned(true)], 5_000).verdict,
            Verdict::NotReproduced
        );
    }

    /// A claim reads the row of its label that the thesis printed, not an extra or control row of
    /// the same label; a label with no thesis row is skipped.
    #[test]
    fn thesis_rows_are_found_by_label_among_the_thesis_rows() {
        let storm = timed(&[RunStatus::NotConverged]).0;
        let mut extra = timed(&[
            RunStatus::NotConverged,
            RunStatus::NotConverged,
            RunStatus::NotConverged,
        ])
        .0;
        extra.entry.role = crate::config::Role::Extra;
        let rows = vec![(extra, None), (storm, None)];
        let found = thesis(&rows, "STORM").expect("the thesis row");
        assert_eq!(found.entry.role, crate::config::Role::Thesis);
        assert_eq!(found.runs.len(), 1);
        assert!(thesis(&rows, "Adam").is_none());
        let ordered = in_order(&rows, &["Adam", "STORM"]);
        assert_eq!(ordered.len(), 1);
        assert_eq!(ordered[0].runs.len(), 1);
    }

    /// Interval ends inside the quantity's range are printed as they are (an end exactly at the
    /// range's end too); ends beyond it at the range's end, marked †; without a finite interval,
    /// the mean alone.
    #[test]
    fn interval_text_clamps_only_the_ends_beyond_the_range() {
        let s = |mean, half_width| Summary {
            n: 4,
            mean,
            half_width,
        };
        assert_eq!(ci_text(&s(2.0, 1.0)), "2.000 [1.000, 3.000] (n = 4)");
        assert_eq!(ci_text(&s(1.0, 1.0)), "1.000 [0, 2.000] (n = 4)");
        assert_eq!(ci_text(&s(1.0, 2.0)), "1.000 [0†, 3.000] (n = 4)");
        assert_eq!(signed_text(&s(1.0, 2.0)), "1.000 [-1.000, 3.000] (n = 4)");
        assert_eq!(percent_text(&s(0.5, 0.5)), "50.00% [0%, 100.0%] (n = 4)");
        assert_eq!(
            percent_text(&s(0.9, 0.2)),
            "90.00% [70.00%, 100.0%†] (n = 4)"
        );
        let one = Summary {
            n: 1,
            mean: 5.0,
            half_width: f64::NAN,
        };
        assert_eq!(ci_text(&one), "5.000 (n = 1)");
    }

    /// A claim's evidence names each row, its value and how its runs ended.
    #[test]
    fn evidence_names_each_row_with_its_tally() {
        let conv = RunStatus::Converged {
            checkpoint: 1,
            gradient_evaluations: 10,
        };
        let storm = timed(&[conv, RunStatus::NotConverged]).0;
        assert_eq!(
            evidence([(&storm, "12 calls".to_string())]),
            "STORM 12 calls — converged 1/2, 1 never"
        );
    }

    /// The F test divides each sum of squares by its own n − 1: with 3 against 21 values, a
    /// variance ratio of 2 lies between the 2.5 % and 97.5 % points of F(20, 2) and F(2, 20)
    /// (≈ 39.4 and ≈ 4.46), so nothing is decided; a ratio of 100 is decided.
    #[test]
    fn the_variance_test_uses_each_sample_s_own_degrees_of_freedom() {
        let xa = [0.0, 1.0, 2.0];
        let c = 2f64.sqrt();
        let xb: Vec<f64> = (0..21)
            .map(|i| {
                if i == 20 {
                    0.0
                } else if i % 2 == 0 {
                    c
                } else {
                    -c
                }
            })
            .collect();
        let (a, b) = (Summary::of(&xa), Summary::of(&xb));
        assert_eq!(lower_variance(&a, &b, &xa, &xb), Verdict::Inconclusive);
        // Ratio 38, just below F(20, 2)'s 97.5 % point (≈ 39.45): still undecided.
        let near: Vec<f64> = xb.iter().map(|x| x * 19f64.sqrt()).collect();
        let n = Summary::of(&near);
        assert_eq!(lower_variance(&a, &n, &xa, &near), Verdict::Inconclusive);
        let wide: Vec<f64> = xb.iter().map(|x| 10.0 * x).collect();
        let w = Summary::of(&wide);
        assert_eq!(lower_variance(&a, &w, &xa, &wide), Verdict::Reproduced);
        assert_eq!(lower_variance(&w, &a, &wide, &xa), Verdict::NotReproduced);
        // Two values are enough for a variance (F(20, 1)'s 97.5 % point is ≈ 993).
        let two = [0.0, 1.0];
        let huge: Vec<f64> = xb.iter().map(|x| 100.0 * x).collect();
        let (t, h) = (Summary::of(&two), Summary::of(&huge));
        assert_eq!(lower_variance(&t, &h, &two, &huge), Verdict::Reproduced);
        assert_eq!(lower_variance(&h, &t, &huge, &two), Verdict::NotReproduced);
    }

    /// A claim's budget is its task's, as the profile states it.
    #[test]
    fn a_claim_s_budget_is_its_task_s() {
        let text = crate::config::committed_text("quick").expect("the quick profile");
        let p = Profile::from_toml(text, std::path::Path::new("quick.toml")).expect("valid");
        assert_eq!(budget_of(&p, TaskKind::Obstacle), p.obstacle.budget);
        assert_eq!(budget_of(&p, TaskKind::Cartpole), p.cartpole.budget);
        assert_ne!(p.obstacle.budget, p.cartpole.budget);
    }

    /// The figures are Tables 4.1 and 4.3's gradient calls, found by task and label together.
    #[test]
    fn thesis_calls_are_looked_up_by_task_and_label() {
        assert_eq!(thesis_calls(TaskKind::Obstacle, "Adam"), Some(10785.0));
        assert_eq!(thesis_calls(TaskKind::Cartpole, "Adam"), Some(2467044.0));
        assert_eq!(thesis_calls(TaskKind::Cartpole, "DAgger"), Some(31905600.0));
        // SGD is in Table 4.1 only; BC in neither.
        assert_eq!(thesis_calls(TaskKind::Obstacle, "SGD"), Some(9450.0));
        assert_eq!(thesis_calls(TaskKind::Cartpole, "SGD"), None);
        assert_eq!(thesis_calls(TaskKind::Obstacle, "BC"), None);
    }

    #[test]
    fn storm_slower_needs_a_storm_that_converges() {
        let fast = MedianCi::of(&[10.0; 10], LEVEL);
        let slow = MedianCi::of(&[1000.0; 10], LEVEL);
        let never = MedianCi::of(&[f64::INFINITY; 10], LEVEL);
        let ok = Tally::of(&[Outcome::Converged(1.0)]);
        assert_eq!(
            storm_slower(&slow, &fast, &fast, std::slice::from_ref(&ok)),
            Verdict::Reproduced
        );
        // A STORM that never converges does not "take more calls to converge".
        assert_eq!(
            storm_slower(&never, &fast, &fast, std::slice::from_ref(&ok)),
            Verdict::NotReproduced
        );
        assert_eq!(
            storm_slower(&fast, &slow, &fast, &[ok]),
            Verdict::NotReproduced
        );
    }

    #[test]
    fn censoring_in_any_compared_row_caps_a_decided_variance_verdict() {
        let cap = 100.0;
        let (xs, clean, hit) = ([3.0, 4.0, 5.0], [3.0, 9.0], [3.0, 100.0]);
        assert_eq!(
            censored_any(Verdict::Reproduced, &xs, &[&clean, &clean], cap),
            Verdict::Reproduced
        );
        assert_eq!(
            censored_any(Verdict::Reproduced, &xs, &[&clean, &hit], cap),
            Verdict::Inconclusive
        );
        assert_eq!(
            censored_any(Verdict::NotReproduced, &xs, &[&hit, &clean], cap),
            Verdict::Inconclusive
        );
        // Every STORM run at the cap stays not reproduced.
        assert_eq!(
            censored_any(Verdict::Inconclusive, &[cap, cap], &[&hit], cap),
            Verdict::NotReproduced
        );
    }

    /// The F test compares the ratio of the variances with F(n_b − 1, n_a − 1)'s 97.5 % point:
    /// 3 values against 21 read F(2, 20), ≈ 4.46 (F(3, 20) ≈ 3.86, F(4, 20) ≈ 3.51). Variances
    /// 10 and 42 (ratio 4.2) are undecided although they differ by far more than the quantile;
    /// 10 and 50 (ratio 5) are decided.
    #[test]
    fn the_variance_test_compares_a_ratio_with_the_quantile_of_the_right_degrees() {
        let c = 10f64.sqrt();
        let xa: Vec<f64> = (0..21)
            .map(|i| match i {
                20 => 0.0,
                _ if i % 2 == 0 => c,
                _ => -c,
            })
            .collect();
        let spread = |v: f64| [-v.sqrt(), 0.0, v.sqrt()];
        let a = Summary::of(&xa);
        let undecided = spread(42.0);
        let b = Summary::of(&undecided);
        assert_eq!(
            lower_variance(&a, &b, &xa, &undecided),
            Verdict::Inconclusive
        );
        assert_eq!(
            lower_variance(&b, &a, &undecided, &xa),
            Verdict::Inconclusive
        );
        let decided = spread(50.0);
        let d = Summary::of(&decided);
        assert_eq!(lower_variance(&a, &d, &xa, &decided), Verdict::Reproduced);
        assert_eq!(
            lower_variance(&d, &a, &decided, &xa),
            Verdict::NotReproduced
        );
    }

    /// A spread sample against one of equal values: the constant one has the lower variance,
    /// whichever side it is on; a sample of fewer than 2 values (none or one) decides nothing.
    #[test]
    fn a_zero_variance_is_lower_and_a_sample_too_small_decides_nothing() {
        let (spread, flat) = ([1.0, 4.0, 9.0], [5.0, 5.0, 5.0]);
        let (s, f) = (Summary::of(&spread), Summary::of(&flat));
        assert_eq!(lower_variance(&f, &s, &flat, &spread), Verdict::Reproduced);
        assert_eq!(
            lower_variance(&s, &f, &spread, &flat),
            Verdict::NotReproduced
        );
        for small in [&[][..], &[2.0][..]] {
            let m = Summary::of(small);
            assert_eq!(
                lower_variance(&m, &s, small, &spread),
                Verdict::Inconclusive
            );
            assert_eq!(
                lower_variance(&s, &m, &spread, small),
                Verdict::Inconclusive
            );
        }
    }

    #[test]
    fn a_variance_of_censored_counts_is_never_a_lower_variance() {
        let (a, b) = ([100.0; 5], [10.0, 90.0, 40.0, 60.0, 100.0]);
        let (sa, sb) = (Summary::of(&a), Summary::of(&b));
        // Zero spread beats any spread by the F test, but every value is at the cap.
        assert_eq!(lower_variance(&sa, &sb, &a, &b), Verdict::Reproduced);
        assert_eq!(
            censored(lower_variance(&sa, &sb, &a, &b), &a, 100.0),
            Verdict::NotReproduced
        );
        let c = [3.0, 3.0, 3.0, 100.0, 3.0];
        assert_eq!(
            censored(Verdict::Reproduced, &c, 100.0),
            Verdict::Inconclusive
        );
        assert_eq!(
            censored(Verdict::Reproduced, &[3.0, 4.0], 100.0),
            Verdict::Reproduced
        );
    }

    #[test]
    fn success_rates_are_printed_in_the_rules_unit() {
        // The rules state success in percent; the evidence must not print the fraction.
        let s = Summary::of(&[0.5, 0.6, 0.7]);
        let text = percent_text(&s);
        assert!(text.starts_with("60.00% ["), "{text}");
        assert_eq!(text.matches('%').count(), 3, "{text}");
        assert!(text.ends_with("(n = 3)"), "{text}");
        assert_eq!(percent_text(&Summary::of(&[0.25])), "25.00% (n = 1)");
        // An interval leaving [0, 1] is printed at the end it left, marked.
        let low = percent_text(&Summary::of(&[0.0, 0.0, 0.5]));
        assert!(low.starts_with("16.67% [0%†, "), "{low}");
        let high = percent_text(&Summary::of(&[1.0, 1.0, 0.5]));
        assert!(high.contains(", 100.0%†]"), "{high}");
        assert!(signed_text(&Summary::of(&[-1.0, 1.0])).contains("[-"));
    }

    #[test]
    fn the_slope_rule_needs_minus_a_half_inside_and_zero_outside() {
        let s = |lo, hi| SlopeCi {
            estimate: 0.5 * (lo + hi),
            lo,
            hi,
            n: 100,
        };
        assert_eq!(slope_verdict(&s(-0.55, -0.45)), Verdict::Reproduced);
        assert_eq!(slope_verdict(&s(-0.3, -0.1)), Verdict::NotReproduced);
        assert_eq!(slope_verdict(&s(-0.7, 0.1)), Verdict::Inconclusive);
        // An interval wholly below −1/2 excludes it too.
        assert_eq!(slope_verdict(&s(-0.9, -0.6)), Verdict::NotReproduced);
        // −1/2 on the interval's end is inside it; with 0 inside too, nothing is decided.
        assert_eq!(slope_verdict(&s(-0.5, 0.1)), Verdict::Inconclusive);
        assert_eq!(slope_verdict(&s(-0.5, -0.1)), Verdict::Reproduced);
        // A bootstrap that failed at either end decides nothing.
        assert_eq!(
            slope_verdict(&s(-0.6, f64::INFINITY)),
            Verdict::Inconclusive
        );
        assert_eq!(slope_verdict(&s(f64::NAN, -0.1)), Verdict::Inconclusive);
        assert_eq!(
            slope_verdict(&s(f64::NEG_INFINITY, -0.1)),
            Verdict::Inconclusive
        );
    }
}
