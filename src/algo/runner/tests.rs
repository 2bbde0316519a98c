//! The runner's stopping order, its observers and every [`Termination`] it can give.

use super::*;
use crate::algo::{CheckpointObserver, NormBound, Progress, Schedule, norm_of};
use crate::toy::{ToyMdp, ToyProblem};

/// What one scripted step does.
#[derive(Debug, Clone)]
enum Move {
    /// Add `delta` to θ, cost `calls` gradient calls, report `loss`.
    Go { delta: f64, calls: u64, loss: f64 },
    /// Like `Go` and report the schedule finished.
    Last { delta: f64 },
    /// Fail.
    Fail,
    /// Sleep, then add nothing and cost one call.
    Sleep(u64),
}

/// An algorithm following a script (the problem is not used); `init` costs `init_calls`.
struct Walk {
    theta: DVector<f64>,
    script: Vec<Move>,
    at: usize,
    init_calls: u64,
}

fn walk(script: Vec<Move>) -> Walk {
    Walk {
        theta: DVector::zeros(1),
        script,
        at: 0,
        init_calls: 0,
    }
}

fn go(delta: f64, calls: u64) -> Move {
    Move::Go {
        delta,
        calls,
        loss: 1.0,
    }
}

impl<P: IlProblem<f64> + ?Sized> Algorithm<f64, P> for Walk {
    fn name(&self) -> &'static str {
        "walk"
    }
    fn init(
        &mut self,
        _: &mut P,
        theta0: DVector<f64>,
        ctx: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        self.theta = theta0;
        ctx.cost.gradient_evaluations += self.init_calls;
        Ok(())
    }
    fn step(&mut self, _: &mut P, ctx: &mut StepContext<'_>) -> Result<StepReport<f64>, AlgoError> {
        let m = self.script[self.at % self.script.len()].clone();
        self.at += 1;
        match m {
            Move::Go { delta, calls, loss } => {
                self.theta[0] += delta;
                ctx.cost.gradient_evaluations += calls;
                Ok(StepReport::new(
                    Some(DVector::from_element(1, delta)),
                    Some(loss),
                ))
            }
            Move::Last { delta } => {
                self.theta[0] += delta;
                ctx.cost.gradient_evaluations += 1;
                let mut r = StepReport::new(None, None);
                r.finished = true;
                Ok(r)
            }
            Move::Fail => Err(AlgoError::State("scripted failure")),
            Move::Sleep(ms) => {
                std::thread::sleep(std::time::Duration::from_millis(ms));
                ctx.cost.gradient_evaluations += 1;
                Ok(StepReport::new(None, None))
            }
        }
    }
    fn theta(&self) -> &DVector<f64> {
        &self.theta
    }
}

fn problem() -> ToyProblem<f64> {
    let mdp = ToyMdp::from_json_str(include_str!("../../../examples/toy/m1-direct.json"));
    ToyProblem::new(&mdp.expect("the example MDP parses"))
}

fn run(stop: StoppingRule, alg: &mut Walk) -> RunRecord<f64> {
    Runner::new(stop)
        .unwrap()
        .run(alg, &mut problem(), DVector::zeros(1), 1)
        .unwrap()
}

#[test]
fn max_iterations_ends_the_run_after_that_many_steps() {
    let rec = run(StoppingRule::iterations(3), &mut walk(vec![go(1.0, 1)]));
    assert_eq!(rec.termination, Termination::MaxIterations);
    assert_eq!(
        (rec.iterations, rec.theta[0], rec.history.len()),
        (3, 3.0, 4)
    );
    assert_eq!(rec.termination.to_string(), "max-iterations");
}

#[test]
fn the_gradient_budget_is_checked_before_every_step_including_the_first() {
    let rec = run(
        StoppingRule::gradient_budget(5),
        &mut walk(vec![go(1.0, 2)]),
    );
    assert_eq!(rec.termination, Termination::GradientBudget);
    assert_eq!((rec.iterations, rec.cost.gradient_evaluations), (3, 6));
    let mut w = walk(vec![go(1.0, 2)]);
    w.init_calls = 5;
    let rec = run(StoppingRule::gradient_budget(5), &mut w);
    assert_eq!(
        (rec.termination.clone(), rec.iterations),
        (Termination::GradientBudget, 0)
    );
    assert_eq!(rec.termination.to_string(), "gradient-budget");
}

#[test]
fn the_target_loss_ends_the_run_at_the_first_step_that_reaches_it() {
    let script = [3.0, 2.0, 0.5, 0.1]
        .map(|loss| Move::Go {
            delta: 0.0,
            calls: 1,
            loss,
        })
        .to_vec();
    let stop = StoppingRule {
        target_loss: Some(ConfigNumber::ratio(1, 2)),
        ..StoppingRule::iterations(10)
    };
    let rec = run(stop, &mut walk(script));
    assert_eq!(
        (rec.termination.clone(), rec.iterations),
        (Termination::TargetLoss, 3)
    );
    assert_eq!(rec.termination.to_string(), "target-loss");
}

#[test]
fn the_time_limit_ends_the_run() {
    let stop = StoppingRule {
        time_limit_ms: Some(1),
        ..StoppingRule::default()
    };
    let rec = run(stop, &mut walk(vec![Move::Sleep(3)]));
    assert_eq!(
        (rec.termination.clone(), rec.iterations),
        (Termination::TimeOut, 1)
    );
    assert_eq!(rec.termination.to_string(), "time-out");
}

#[test]
fn an_algorithm_that_finishes_ends_the_run() {
    let rec = run(
        StoppingRule::iterations(10),
        &mut walk(vec![go(1.0, 1), Move::Last { delta: 1.0 }]),
    );
    assert_eq!(
        (rec.termination.clone(), rec.iterations),
        (Termination::Finished, 2)
    );
    assert_eq!(rec.termination.to_string(), "finished");
}

#[test]
fn a_failing_step_diverges_and_keeps_the_iterate_before_it() {
    let rec = run(
        StoppingRule::iterations(10),
        &mut walk(vec![go(1.0, 1), Move::Fail]),
    );
    assert_eq!(
        rec.termination,
        Termination::Diverged(Divergence::StepFailed(AlgoError::State("scripted failure")))
    );
    assert_eq!((rec.iterations, rec.theta[0]), (1, 1.0));
    assert_eq!(
        rec.termination.to_string(),
        "diverged: step failed: algorithm state: scripted failure"
    );
}

#[test]
fn a_non_finite_iterate_diverges_after_the_observers_saw_it() {
    let rec = run(
        StoppingRule::iterations(10),
        &mut walk(vec![go(f64::INFINITY, 1)]),
    );
    assert_eq!(
        rec.termination,
        Termination::Diverged(Divergence::NonFiniteTheta)
    );
    assert_eq!((rec.iterations, rec.history.len()), (1, 2));
    assert_eq!(rec.termination.to_string(), "diverged: non-finite θ");
}

#[test]
fn steps_without_a_gradient_call_diverge_after_the_limit() {
    let stop = StoppingRule {
        max_free_steps: Some(3),
        ..StoppingRule::gradient_budget(100)
    };
    // Calls per step 1, 0, 1, 0, …: never three free steps in a row.
    let rec = run(stop, &mut walk(vec![go(1.0, 1), go(1.0, 0)]));
    assert_eq!(rec.termination, Termination::GradientBudget);
    let stop = StoppingRule {
        max_free_steps: Some(3),
        ..StoppingRule::gradient_budget(100)
    };
    let mut w = walk(vec![go(1.0, 0)]);
    w.init_calls = 1;
    let rec = run(stop, &mut w);
    assert_eq!(
        rec.termination,
        Termination::Diverged(Divergence::NoGradientCall { steps: 3 })
    );
    assert_eq!(rec.iterations, 3);
    assert_eq!(
        rec.termination.to_string(),
        "diverged: 3 steps in a row without a gradient call"
    );
}

#[test]
fn the_norm_bound_observer_ends_the_run_once_the_norm_exceeds_it() {
    let rec = Runner::new(StoppingRule::iterations(10))
        .unwrap()
        .with_observer(NormBound { bound: 15.0 })
        .run(
            &mut walk(vec![go(10.0, 1)]),
            &mut problem(),
            DVector::zeros(1),
            1,
        )
        .unwrap();
    assert_eq!(
        rec.termination,
        Termination::Diverged(Divergence::NormBound {
            norm: 20.0,
            bound: 15.0
        })
    );
    assert_eq!(rec.iterations, 2);
    assert_eq!(
        rec.termination.to_string(),
        "diverged: ‖θ‖ = 2.000e1 > 1.5e1"
    );
    // θ₀ is judged too.
    let rec = Runner::new(StoppingRule::iterations(10))
        .unwrap()
        .with_observer(NormBound { bound: 1.0 })
        .run(
            &mut walk(vec![go(0.0, 1)]),
            &mut problem(),
            DVector::from_element(1, 2.0),
            1,
        )
        .unwrap();
    assert_eq!(rec.iterations, 0);
    assert!(matches!(
        rec.termination,
        Termination::Diverged(Divergence::NormBound { .. })
    ));
}

#[test]
fn the_norm_does_not_overflow_when_the_sum_of_squares_does() {
    let theta = DVector::from_vec(vec![3e300, 4e300]);
    assert_eq!(theta.norm(), f64::INFINITY);
    assert!((norm_of(&theta) / 5e300 - 1.0).abs() < 1e-15);
    assert_eq!(norm_of(&DVector::from_vec(vec![3.0, 4.0])), 5.0);
}

#[test]
fn closure_and_progress_observers_see_every_iterate_and_never_stop_the_run() {
    let mut seen = Vec::new();
    let rec = Runner::new(StoppingRule::iterations(4))
        .unwrap()
        .keep_history(false)
        .with_observer(Progress { every: u64::MAX })
        .with_observer(|m: &IterationMetrics<f64>| seen.push((m.iteration, m.theta[0])))
        .run(
            &mut walk(vec![go(1.0, 1)]),
            &mut problem(),
            DVector::zeros(1),
            1,
        )
        .unwrap();
    assert_eq!(rec.termination, Termination::MaxIterations);
    assert!(rec.history.is_empty());
    assert_eq!(seen, vec![(0, 0.0), (1, 1.0), (2, 2.0), (3, 3.0), (4, 4.0)]);
}

#[test]
fn the_schedule_serves_every_count_reached_once_and_in_order() {
    let mut s = Schedule::every(3, 7);
    assert_eq!(s.due(0), vec![0]);
    assert_eq!(s.due(2), Vec::<u64>::new());
    assert_eq!(s.due(7), vec![3, 6, 7]);
    assert_eq!(s.due(100), Vec::<u64>::new());
    let mut s = Schedule::every(0, 2);
    assert_eq!(s.due(5), vec![0, 1, 2]);
}

/// Records (iteration, counts) and stops at a given count, or fails at one.
struct Recorder {
    seen: Vec<(u64, Vec<u64>)>,
    stop_at: Option<u64>,
    fail_at: Option<u64>,
}

impl CheckpointObserver<f64> for Recorder {
    type Error = String;
    fn checkpoint(
        &mut self,
        m: &IterationMetrics<f64>,
        at: &[u64],
    ) -> Result<Option<Termination>, String> {
        self.seen.push((m.iteration, at.to_vec()));
        if self.fail_at.is_some_and(|f| at.contains(&f)) {
            return Err("evaluation failed".into());
        }
        Ok(self
            .stop_at
            .is_some_and(|s| at.contains(&s))
            .then_some(Termination::Stopped("sustained-convergence")))
    }
}

fn scheduled(rec: &mut Recorder, script: Vec<Move>) -> Result<RunRecord<f64>, RunFailure<String>> {
    Runner::new(StoppingRule::gradient_budget(10))
        .unwrap()
        .keep_history(false)
        .run_with_checkpoints(
            &mut walk(script),
            &mut problem(),
            DVector::zeros(1),
            1,
            Some(Schedule::every(4, 10)),
            rec,
        )
}

#[test]
fn checkpoints_are_taken_at_the_first_iterate_reaching_each_count() {
    let mut r = Recorder {
        seen: vec![],
        stop_at: None,
        fail_at: None,
    };
    let rec = scheduled(&mut r, vec![go(1.0, 3), go(1.0, 6)]).unwrap();
    // Calls after each step: 3, 9, 12.
    assert_eq!(rec.termination, Termination::GradientBudget);
    assert_eq!(r.seen, vec![(0, vec![0]), (2, vec![4, 8]), (3, vec![10])]);
    assert_eq!(rec.seconds_at_checkpoints.len(), 4);
    assert!(rec.train_seconds <= rec.wall_time);
}

#[test]
fn a_checkpoint_observer_stops_the_run_with_its_reason() {
    let mut r = Recorder {
        seen: vec![],
        stop_at: Some(4),
        fail_at: None,
    };
    let rec = scheduled(&mut r, vec![go(1.0, 2)]).unwrap();
    assert_eq!(
        rec.termination,
        Termination::Stopped("sustained-convergence")
    );
    assert_eq!(rec.iterations, 2);
    assert_eq!(rec.termination.to_string(), "sustained-convergence");
}

#[test]
fn a_failing_checkpoint_ends_the_run_with_its_error() {
    let mut r = Recorder {
        seen: vec![],
        stop_at: None,
        fail_at: Some(4),
    };
    let e = scheduled(&mut r, vec![go(1.0, 2)]).unwrap_err();
    assert_eq!(e, RunFailure::Checkpoint("evaluation failed".to_string()));
}
