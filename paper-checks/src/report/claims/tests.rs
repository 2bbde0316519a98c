//! Tests of the claim rules: each rule against runs built to sit on either side of it.

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
    let o6 =
        |bc: Vec<(RunStatus, Vec<At>)>| verdict_of(&obstacle_extreme_claims(&with_bc(&bc)), "O6");
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
        below
            .evidence
            .contains("2 checkpoints after θ₁; DAgger below every other at 2 of them; at the last"),
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
    let t2 = |dagger: f64| runtime_claim("T2", "Table 4.4", TaskKind::Cartpole, &set(dagger), &T43);
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
