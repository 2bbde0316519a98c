//! The states (θ_k, d_k) the proof-step rows are checked at: the iterates of the kit's IS-STORM
//! with schedule (3.43) on M1, seeded as the runs of row 2c, with the step sizes and momenta
//! each step actually used.
//!
//! The rows run the kit's `Storm` step by step (the runner's RNG and context, so seed r gives
//! the path of row 2c's run r) and read (η_k, a_{k+1}) from the algorithm itself after each
//! step: they are the run's `f64` values, which the rows convert exactly into ℚ.

use ilopt::algo::storm::{Correction, Storm, StormConfig, StormSchedule};
use ilopt::algo::{Algorithm, ConfigNumber, StepContext};
use ilopt::problem::{Cost, EstimatorForm, KitRng, Weighting};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;
use rand::SeedableRng;

/// One visited state of a run and the schedule around it.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// The run's importance weights.
    pub weighting: Weighting,
    /// The run's seed.
    pub seed: u64,
    /// k (1-based): the state is (θ_k, d_k) before step k.
    pub k: u64,
    /// θ_k.
    pub theta: Vec<f64>,
    /// d_k.
    pub d: Vec<f64>,
    /// η_k, the step size of step k.
    pub eta: f64,
    /// a_{k+1}, the momentum of step k.
    pub a_next: f64,
    /// η_{k−1} (for k = 1 the proof's virtual η₀ = 1/(4L), the schedule at k = 0).
    pub eta_prev: f64,
    /// a_k (for k = 1 the schedule's a₁ = 16L²η₀² = 1).
    pub a: f64,
}

impl State {
    /// The state as the rows name it.
    pub fn label(&self) -> String {
        format!(
            "{} weights, seed {}, k = {}",
            weighting_name(self.weighting),
            self.seed,
            self.k
        )
    }
}

/// The weighting as the rows name it.
pub fn weighting_name(w: Weighting) -> &'static str {
    match w {
        Weighting::Trajectory => "trajectory",
        Weighting::PerDecision => "per-decision",
    }
}

/// The schedule one run used: (η_k, a_{k+1}) for k = 1..K, and the virtual η₀.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSchedule {
    /// The run's importance weights.
    pub weighting: Weighting,
    /// The L the schedule was built with.
    pub l: f64,
    /// η₀ = 1/(4L).
    pub eta0: f64,
    /// (η_k, a_{k+1}), k = 1..K.
    pub steps: Vec<(f64, f64)>,
}

/// Which states of a run are kept: every k ≤ `dense`, and `sparse` values of k spread
/// geometrically over (dense, k_max].
pub fn kept(dense: u64, sparse: usize, k_max: u64) -> Vec<u64> {
    let mut ks: Vec<u64> = (1..=dense.min(k_max)).collect();
    if k_max > dense && sparse > 0 {
        let (lo, hi) = ((dense.max(1)) as f64, k_max as f64);
        for i in 1..=sparse {
            let k = (lo * (hi / lo).powf(i as f64 / sparse as f64)).round() as u64;
            ks.push(k.clamp(dense + 1, k_max));
        }
    }
    ks.sort_unstable();
    ks.dedup();
    ks
}

/// One seeded run of IS-STORM (schedule (3.43) for `l`, the given weights, θ₁ = `theta1`) for
/// `k_max` steps: the states at the steps `ks` and the whole schedule.
///
/// # Errors
/// A message naming the run and the step if the algorithm fails.
pub fn run(
    mdp: &ToyMdp,
    weighting: Weighting,
    l: f64,
    theta1: f64,
    seed: u64,
    k_max: u64,
    ks: &[u64],
) -> Result<(Vec<State>, RunSchedule), String> {
    let where_ = |e: &dyn std::fmt::Display| {
        format!(
            "IS-STORM ({} weights, seed {seed}): {e}",
            weighting_name(weighting)
        )
    };
    let mut problem = ToyProblem::<f64>::new(mdp);
    let mut storm = Storm::<f64>::new(&StormConfig {
        schedule: StormSchedule::Thesis {
            l: ConfigNumber::Float(l),
        },
        correction: match weighting {
            Weighting::Trajectory => Correction::Trajectory,
            Weighting::PerDecision => Correction::PerDecision,
        },
        form: EstimatorForm::Causal,
    })
    .map_err(|e| where_(&e))?;
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    let dim = mdp.policy.dim();
    Algorithm::<f64, ToyProblem<f64>>::init(
        &mut storm,
        &mut problem,
        DVector::from_element(dim, theta1),
        &mut StepContext {
            rng: &mut rng,
            cost: &mut cost,
        },
    )
    .map_err(|e| where_(&e))?;
    // The schedule at k = 0, as the kit computes it: (1/(4L))·∛1 and a₁ = ∛1² = 1.
    let eta0 = 1.0 / (4.0 * l);
    let mut prev = (eta0, 1.0);
    let mut states = Vec::with_capacity(ks.len());
    let mut steps = Vec::with_capacity(k_max as usize);
    let mut next_kept = ks.iter().peekable();
    for k in 1..=k_max {
        let theta = storm.theta().as_slice().to_vec();
        let d = storm
            .direction()
            .ok_or_else(|| where_(&"no direction after init"))?
            .as_slice()
            .to_vec();
        Algorithm::<f64, ToyProblem<f64>>::step(
            &mut storm,
            &mut problem,
            &mut StepContext {
                rng: &mut rng,
                cost: &mut cost,
            },
        )
        .map_err(|e| where_(&format!("step {k}: {e}")))?;
        let &(eta, a_next) = storm
            .last_schedule()
            .ok_or_else(|| where_(&format!("step {k} reported no schedule")))?;
        if next_kept.peek() == Some(&&k) {
            next_kept.next();
            states.push(State {
                weighting,
                seed,
                k,
                theta,
                d,
                eta,
                a_next,
                eta_prev: prev.0,
                a: prev.1,
            });
        }
        steps.push((eta, a_next));
        prev = (eta, a_next);
    }
    Ok((
        states,
        RunSchedule {
            weighting,
            l,
            eta0,
            steps,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::m1_tied;

    #[test]
    fn kept_steps_are_dense_then_geometric() {
        assert_eq!(kept(3, 0, 100), vec![1, 2, 3]);
        let ks = kept(10, 5, 10_000);
        assert_eq!(&ks[..10], &(1..=10).collect::<Vec<_>>()[..]);
        assert_eq!(*ks.last().unwrap(), 10_000);
        assert!(ks.len() <= 15 && ks.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(kept(5, 3, 4), vec![1, 2, 3, 4]);
    }

    /// The states are the iterates of the runner's run with the same seed (row 2c's path), and
    /// consecutive states satisfy θ_{k+1} = fl(θ_k − η_k d_k) with the recorded η_k.
    #[test]
    fn states_are_the_runners_iterates() {
        use ilopt::algo::{AlgorithmConfig, IterationMetrics, RunConfig, Runner, StoppingRule};
        let m1 = m1_tied();
        let l = 3.0;
        let (states, sched) = run(
            &m1,
            Weighting::Trajectory,
            l,
            0.0,
            7,
            6,
            &[1, 2, 3, 4, 5, 6],
        )
        .expect("a run");
        assert_eq!(sched.steps.len(), 6);
        assert_eq!(states[0].eta_prev, 1.0 / 12.0);
        assert_eq!(states[0].a, 1.0);
        let cfg = RunConfig {
            algorithm: AlgorithmConfig::Storm(StormConfig {
                schedule: StormSchedule::Thesis {
                    l: ConfigNumber::Float(l),
                },
                correction: Correction::Trajectory,
                form: EstimatorForm::Causal,
            }),
            theta0: vec![ConfigNumber::Float(0.0)],
            seed: 7,
            stop: StoppingRule::iterations(6),
        };
        let seen = std::cell::RefCell::new(vec![]);
        let observer = |m: &IterationMetrics<f64>| seen.borrow_mut().push(m.theta[0]);
        Runner::new(cfg.stop.clone())
            .unwrap()
            .keep_history(false)
            .with_observer(observer)
            .run_config(&cfg, &mut ToyProblem::<f64>::new(&m1))
            .unwrap();
        let seen = seen.into_inner();
        for (s, t) in states.iter().zip(&seen) {
            assert_eq!(s.theta[0], *t, "k = {}", s.k);
        }
        for w in states.windows(2) {
            assert_eq!(w[1].theta[0], w[0].theta[0] - w[0].eta * w[0].d[0]);
            assert_eq!((w[1].eta_prev, w[1].a), (w[0].eta, w[0].a_next));
        }
    }
}
