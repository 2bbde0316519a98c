//! The qualitative claims of chapter 4, each judged by a stated rule on intervals
//! ([`crate::verdict`]): numbers with their CIs and n, failed runs counted, and one of
//! reproduced / inconclusive / not reproduced.
//!
//! Only rows whose role is `thesis` enter a claim (the thesis's algorithms on each task); extra
//! and control rows are reported in the tables, never in a thesis claim.

use super::aggregate::num;
use crate::experiment::{Checkpoint, RunStatus, SeedRun};
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
}

/// Confidence level of every interval of a claim.
const LEVEL: f64 = 0.95;

/// A run's outcome for the verdict rules.
pub(crate) fn outcome(r: &SeedRun) -> Outcome {
    match &r.status {
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
            if r.status.is_diverged() {
                diverged
            } else {
                r.checkpoints.last().and_then(&f)
            }
        })
        .collect();
    Summary::of(&xs)
}

fn ci_text(s: &Summary) -> String {
    interval_text(s, num)
}

/// A success rate (a fraction) as [`ci_text`] in percent, the unit of the rules and tables.
fn percent_text(s: &Summary) -> String {
    interval_text(s, |x| format!("{}%", num(100.0 * x)))
}

/// `mean [lo, hi] (n = …)`, each number written by `show` (the mean alone without a finite
/// interval).
fn interval_text(s: &Summary, show: impl Fn(f64) -> String) -> String {
    if s.half_width.is_finite() {
        format!(
            "{} [{}, {}] (n = {})",
            show(s.mean),
            show(s.lo()),
            show(s.hi()),
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

/// A claim with its verdict.
fn claim(id: &str, source: &str, claim: &str, rule: &str, evidence: String, v: Verdict) -> Claim {
    Claim {
        id: id.into(),
        source: source.into(),
        claim: claim.into(),
        rule: rule.into(),
        evidence,
        verdict: v,
    }
}

/// The deterministic claims (runtime claims: [`timing_claims`]), in the order of the chapter:
/// Fig. 4.2's rate, the obstacle task's success rates, extremes and gradient calls, then
/// CartPole's.
///
/// `reset_cap` is the cap of Fig. 4.9's count (resets before one full episode): a run at the cap
/// never completed an episode, so its count is censored and says nothing about a variance.
pub fn claims(r: &Results, reset_cap: u32) -> Vec<Claim> {
    let mut out = vec![gradient_error_claim(r)];
    out.extend(obstacle_success_claims(&r.obstacle));
    out.extend(obstacle_extreme_claims(&r.obstacle));
    out.extend(obstacle_calls_claims(&r.obstacle));
    out.extend(cartpole_claims(&r.cartpole, reset_cap));
    out
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
    let success = |c: &ConfigResult| last_value(c, |k| Some(k.score), Some(0.0));
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
        claim(id, "§4.1.3, Fig. 4.3", text, &rule, ev, v)
    };
    // BC ≈ 70 %, and constant: the per-seed change from the second checkpoint to the last.
    if let Some(bc) = thesis(o, "BC") {
        let s = success(bc);
        let change: Vec<f64> = bc
            .runs
            .iter()
            .filter_map(|r| Some(r.checkpoints.last()?.score - r.checkpoints.get(1)?.score))
            .collect();
        let d = Summary::of(&change);
        out.push(claim(
            "O2",
            "§4.1.3, Fig. 4.3",
            "BC's success rate is ≈ 70% and stays constant as expert trajectories increase",
            "the final success's 95% t-interval lies in [60%, 80%], and the interval of the \
             per-seed change from the second checkpoint to the last lies in [−10, +10] pp \
             (both inside: reproduced; either disjoint: not reproduced)",
            format!(
                "{}; change {} pp",
                evidence([(bc, percent_text(&s))]),
                ci_text(&Summary {
                    n: d.n,
                    mean: 100.0 * d.mean,
                    half_width: 100.0 * d.half_width
                })
            ),
            Verdict::all(&[within(&s, 0.6, 0.8), within(&d, -0.1, 0.1)]),
        ));
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
    let trio: Vec<&ConfigResult> = ["STORM", "DAgger", "Adam"]
        .iter()
        .filter_map(|l| thesis(o, l))
        .collect();
    out.push(claim(
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
    ));
    out
}

/// O6–O8: the obstacle task's extremes: BC's crashes, STORM's gradient norm, DAgger's loss
/// (Figs. 4.4–4.6).
fn obstacle_extreme_claims(o: &[ConfigWithTiming]) -> Vec<Claim> {
    let mut out = Vec::new();
    let optimisers = |labels: &[&str]| -> Vec<&ConfigResult> {
        labels.iter().filter_map(|l| thesis(o, l)).collect()
    };
    let all_obstacle: Vec<&ConfigResult> = o
        .iter()
        .map(|r| &r.0)
        .filter(|c| c.entry.role == crate::config::Role::Thesis)
        .collect();
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
    let crashes = |c: &ConfigResult| last_value(c, |k| Some(f64::from(k.crashes)), None);
    let (ev, v) = extreme_claim("BC", &all_obstacle, &crashes, true);
    out.push(claim(
        "O6",
        "§4.1.3, Fig. 4.4",
        "BC has the most crashes",
        "BC's final crashes (of the evaluation episodes; diverged runs left out) have a 95% \
         t-interval wholly above every other thesis row's: reproduced; some other's wholly above \
         BC's: not reproduced; else inconclusive",
        ev,
        v,
    ));
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
    ));
    let loss = |c: &ConfigResult| last_value(c, |k| Some(k.loss), None);
    let (ev, v) = extreme_claim("DAgger", &all_obstacle, &loss, false);
    out.push(claim(
        "O8",
        "§4.1.3, Fig. 4.6",
        "DAgger's loss is very low at every iteration",
        "DAgger's final evaluation loss has a 95% t-interval wholly below every other thesis \
         row's (diverged runs left out, and a DAgger divergence caps the verdict)",
        ev,
        v,
    ));
    out
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
            "{MEDIAN_RULE}; DAgger's lower end at or above every other's finite upper end (a \
             lower end of +∞, DAgger never converging in most runs, counts): reproduced; DAgger's \
             upper end below another's lower end: not reproduced; else inconclusive"
        ),
        calls_evidence(set),
        verdict,
    )
}

/// O9–O10: STORM needs the fewest gradient calls, DAgger the most (Table 4.1).
fn obstacle_calls_claims(o: &[ConfigWithTiming]) -> Vec<Claim> {
    let mut out = Vec::new();
    let t41 = in_order(o, &["STORM", "SGD", "RMSProp", "DAgger", "Adam"]);
    if let Some(storm) = t41.iter().find(|c| c.label == "STORM") {
        let others: Vec<MedianCi> = t41
            .iter()
            .filter(|c| c.label != "STORM")
            .map(|c| calls(c))
            .collect();
        let v = least(&calls(storm), &others.iter().collect::<Vec<_>>());
        out.push(claim(
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
        ));
    }
    out.push(dagger_most_calls("O10", "Table 4.1", &t41));
    out
}

/// C1–C4: CartPole's gradient calls (Table 4.3), rewards (Fig. 4.10) and the variance of the
/// crashes (Fig. 4.9).
fn cartpole_claims(c: &[ConfigWithTiming], reset_cap: u32) -> Vec<Claim> {
    let mut out = Vec::new();
    let t43 = in_order(c, &["STORM", "RMSProp", "DAgger", "Adam"]);
    out.push(dagger_most_calls("C1", "Table 4.3", &t43));
    if let (Some(st), Some(ad), Some(rm)) =
        (thesis(c, "STORM"), thesis(c, "Adam"), thesis(c, "RMSProp"))
    {
        out.push(claim(
            "C2",
            "§4.2.2, Fig. 4.8, Table 4.3",
            "STORM takes more gradient calls to converge than Adam and RMSProp",
            &format!(
                "{MEDIAN_RULE}; Adam's and RMSProp's intervals each wholly below STORM's: \
                 reproduced; either's median +∞ or STORM's wholly below: not reproduced; \
                 divergences of Adam or RMSProp cap the verdict"
            ),
            calls_evidence(&[st, ad, rm]),
            cap_for_failures(
                Verdict::all(&[less(&calls(ad), &calls(st)), less(&calls(rm), &calls(st))]),
                &[tally(ad), tally(rm)],
            ),
        ));
    }
    let rewards: Vec<&ConfigResult> = c
        .iter()
        .map(|r| &r.0)
        .filter(|x| x.entry.role == crate::config::Role::Thesis)
        .collect();
    let reward = |x: &ConfigResult| last_value(x, |k| Some(k.reward), Some(0.0));
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
    ));
    let resets = |x: &ConfigResult| -> Vec<f64> {
        x.runs
            .iter()
            .filter(|r| !r.status.is_diverged())
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
        out.push(claim(
            "C4",
            "§4.2.2, Fig. 4.9",
            "among STORM, Adam and RMSProp the variance of STORM's crashes is the lowest",
            "crashes = resets of the final policy before one full 500-step episode (capped); \
             STORM's sample variance below Adam's and RMSProp's by a two-sided F test at 95% \
             (each way): reproduced; above: not reproduced; else inconclusive; a STORM \
             divergence, or a STORM run at the cap (censored: no episode completed), caps the \
             verdict at inconclusive, and all STORM runs at the cap make it not reproduced",
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
            censored(
                cap_for_failures(
                    Verdict::all(&[
                        lower_variance(&ss, &sa, &xs, &xa),
                        lower_variance(&ss, &sr, &xs, &xr),
                    ]),
                    &[tally(st)],
                ),
                &xs,
                f64::from(reset_cap),
            ),
        ));
    }
    out
}

/// Runtime claims (wall time; appendix.md only): DAgger's training time per run is the largest.
pub fn timing_claims(r: &Results) -> Vec<Claim> {
    let mut out = Vec::new();
    for (id, table, set, labels) in [
        (
            "T1",
            "Table 4.2",
            &r.obstacle,
            &["STORM", "SGD", "RMSProp", "DAgger", "Adam"][..],
        ),
        (
            "T2",
            "Table 4.4",
            &r.cartpole,
            &["STORM", "RMSProp", "DAgger", "Adam"][..],
        ),
    ] {
        let times: Vec<(String, Summary, usize)> = labels
            .iter()
            .filter_map(|l| {
                let (c, t) = set
                    .iter()
                    .find(|x| x.0.label == *l && x.0.entry.role == crate::config::Role::Thesis)?;
                let (xs, diverged) = completed_times(c, t.as_ref()?);
                Some(((*l).to_string(), Summary::of(&xs), diverged))
            })
            .collect();
        let verdict = match times.iter().find(|t| t.0 == "DAgger") {
            Some((_, d, _)) => extreme(
                d,
                &times
                    .iter()
                    .filter(|t| t.0 != "DAgger")
                    .map(|t| &t.1)
                    .collect::<Vec<_>>(),
                true,
            ),
            None => Verdict::Inconclusive,
        };
        out.push(Claim {
            id: id.into(),
            source: table.into(),
            claim: "DAgger's runtime is much higher than the other algorithms'".into(),
            rule: format!(
                "DAgger's training wall time per run (the same gradient-call budget) has a 95% \
                 t-interval wholly above that of every other row of the thesis's {table} ({}); \
                 diverged runs are left out (they stop at their first non-finite or out-of-bound \
                 parameter), and a row with fewer than two other runs makes its comparison \
                 inconclusive",
                labels
                    .iter()
                    .filter(|l| **l != "DAgger")
                    .copied()
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            evidence: times
                .iter()
                .map(|(l, s, diverged)| runtime_text(l, s, *diverged))
                .collect::<Vec<_>>()
                .join("; "),
            verdict,
        });
    }
    out
}

/// The training times (from `t`) of the runs of `c` that did not diverge, and how many diverged
/// (a diverged run stops at its first non-finite or out-of-bound parameter, so its time says
/// nothing about the method's cost).
fn completed_times(c: &ConfigResult, t: &ConfigTiming) -> (Vec<f64>, usize) {
    let diverged: Vec<u32> = c
        .runs
        .iter()
        .filter(|r| r.status.is_diverged())
        .map(|r| r.seed_index)
        .collect();
    let kept = t
        .runs
        .iter()
        .filter(|r| !diverged.contains(&r.seed_index))
        .map(|r| r.train_seconds)
        .collect();
    (kept, diverged.len())
}

/// `label mean [lo, hi] (n = k) s`, saying how many diverged runs were left out, or `label —`
/// when no run completed.
fn runtime_text(label: &str, s: &Summary, diverged: usize) -> String {
    let left_out = match diverged {
        0 => String::new(),
        1 => "; 1 diverged run left out".to_string(),
        d => format!("; {d} diverged runs left out"),
    };
    if s.n == 0 {
        format!("{label} — (all {diverged} runs diverged)")
    } else {
        format!("{label} {} s{left_out}", ci_text(s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timed(statuses: &[RunStatus]) -> (ConfigResult, ConfigTiming) {
        let runs = statuses.iter().enumerate().map(|(i, status)| SeedRun {
            seed_index: i as u32,
            seed: i as u64,
            termination: String::new(),
            theta: vec![],
            checkpoints: vec![],
            converged: None,
            status: status.clone(),
            hyper_parameters: Default::default(),
        });
        let timing = (0..statuses.len()).map(|i| crate::experiment::SeedTiming {
            seed_index: i as u32,
            train_seconds: 1.0 + i as f64,
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

    #[test]
    fn runtimes_leave_diverged_runs_out_and_say_so() {
        let diverged = RunStatus::Diverged {
            reason: "non-finite θ".into(),
            gradient_evaluations: 3,
        };
        let (c, t) = timed(&[
            RunStatus::NotConverged,
            diverged.clone(),
            RunStatus::NotConverged,
        ]);
        let (xs, d) = completed_times(&c, &t);
        assert_eq!((xs, d), (vec![1.0, 3.0], 1));
        let text = runtime_text("STORM", &Summary::of(&[1.0, 3.0]), 1);
        assert!(text.contains("n = 2") && text.contains("1 diverged run left out"));
        let (c, t) = timed(&[diverged.clone(), diverged]);
        let (xs, d) = completed_times(&c, &t);
        assert!(xs.is_empty());
        let all = Summary::of(&xs);
        assert_eq!(
            runtime_text("STORM", &all, d),
            "STORM — (all 2 runs diverged)"
        );
        // A row without runs cannot lose to DAgger: the comparison is inconclusive.
        let dagger = Summary::of(&[10.0, 11.0, 12.0]);
        assert_eq!(extreme(&dagger, &[&all], true), Verdict::Inconclusive);
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
    }
}
