//! The oracle's property: every output of eq. 3.15's estimators on a random toy MDP is finite or a
//! clean error, in every scalar.

use super::toy::{Frac, MdpSpec, TrajSpec, check_mdp_invariants};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{PolicyKind, ToyMdp, ToyProblem, ToyTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;

/// One oracle input: MDP, θ (and a second point θ_new), a trajectory, a roll-out seed and a
/// mixture weight.
#[derive(Debug, Clone, PartialEq)]
pub struct OracleInput {
    /// The MDP.
    pub mdp: MdpSpec,
    /// θ entries (`num / max(den, 1)`).
    pub theta: Vec<Frac>,
    /// θ_new entries.
    pub theta_new: Vec<Frac>,
    /// Give θ exactly the policy's dimension (cycling the entries; for the direct kind, a point of
    /// the open simplex) rather than the raw list.
    pub fit_theta: bool,
    /// The trajectory.
    pub traj: TrajSpec,
    /// Seed of the roll-outs.
    pub seed: u64,
    /// Expert weight of a mixture roll-out (arbitrary, validated by the oracle).
    pub expert_weight: f64,
}

fn frac(f: Frac) -> BigRational {
    BigRational::new(f.num.into(), i32::from(f.den.max(1)).into())
}

impl OracleInput {
    /// The parsed MDP, if the parser accepts it.
    pub fn parse(&self) -> Option<ToyMdp> {
        let m = ToyMdp::from_json_str(&self.mdp.to_json());
        if let Ok(m) = &m {
            check_mdp_invariants(m);
        }
        m.ok()
    }

    fn point(&self, raw: &[Frac], mdp: &ToyMdp) -> Vec<BigRational> {
        if !self.fit_theta {
            return raw.iter().take(12).map(|&f| frac(f)).collect();
        }
        let dim = mdp.policy.dim();
        let fallback = [Frac { num: 1, den: 2 }];
        let raw = if raw.is_empty() { &fallback[..] } else { raw };
        (0..dim)
            .map(|i| {
                let f = raw[i % raw.len()];
                if mdp.policy.kind == PolicyKind::Direct {
                    // Each entry in (0, 1/A], so the A−1 entries of a block sum to < 1.
                    BigRational::new(
                        (1 + i64::from(f.num.unsigned_abs() % 4)).into(),
                        (4 * mdp.actions as i64).into(),
                    )
                } else {
                    frac(f)
                }
            })
            .collect()
    }

    /// θ, θ_new as exact rationals for `mdp`.
    pub fn thetas(&self, mdp: &ToyMdp) -> (Vec<BigRational>, Vec<BigRational>) {
        (
            self.point(&self.theta, mdp),
            self.point(&self.theta_new, mdp),
        )
    }
}

/// Everything the oracle computes on one input, in scalar `S`.
#[derive(Debug)]
pub struct OracleOutputs<S> {
    /// `estimate` (causal, full).
    pub estimates: [Result<DVector<S>, OracleError>; 2],
    /// `weighted_estimate` (trajectory, per-decision).
    pub weighted: [Result<DVector<S>, OracleError>; 2],
    /// `trajectory_loss`.
    pub loss: Result<S, OracleError>,
    /// `supervised` at each labelled state: loss and gradient.
    pub supervised: Vec<Result<(S, DVector<S>), OracleError>>,
    /// Roll-outs: learner, expert, mixture.
    pub rollouts: [Result<ToyTrajectory, OracleError>; 3],
}

/// Run every oracle entry point in scalar `S`.
pub fn run_oracle<S: Scalar>(
    mdp: &ToyMdp,
    theta: &[BigRational],
    theta_new: &[BigRational],
    traj: &ToyTrajectory,
    seed: u64,
    expert_weight: f64,
) -> OracleOutputs<S> {
    let mut p = ToyProblem::<S>::new(mdp);
    let cast = |v: &[BigRational]| DVector::from_iterator(v.len(), v.iter().map(S::from_rational));
    let (th, th_new) = (cast(theta), cast(theta_new));
    let mut cost = Cost::default();
    let estimates = [EstimatorForm::Causal, EstimatorForm::Full]
        .map(|form| p.estimate(&th, traj, form, &mut cost));
    let weighted = [Weighting::Trajectory, Weighting::PerDecision]
        .map(|w| p.weighted_estimate(&th, &th_new, traj, w, &mut cost));
    let loss = p.trajectory_loss(&th, traj);
    let supervised = p
        .labelled_states(traj)
        .iter()
        .take(8)
        .map(|ex| {
            let mut g = vec![S::zero(); th.len()];
            p.supervised(&th, ex, &mut g, &mut cost)
                .map(|l| (l, DVector::from_vec(g)))
        })
        .collect();
    let behaviours = [
        Behaviour::Learner(&th),
        Behaviour::Expert,
        Behaviour::Mixture {
            expert_weight,
            learners: vec![(1.0 - expert_weight, &th)],
        },
    ];
    let rollouts = behaviours.map(|b| {
        let mut rng = KitRng::seed_from_u64(seed);
        p.rollout(&b, &mut rng, &mut cost)
    });
    OracleOutputs {
        estimates,
        weighted,
        loss,
        supervised,
        rollouts,
    }
}

fn error_ok(e: &OracleError) {
    assert!(!e.to_string().is_empty(), "empty error message: {e:?}");
}

fn finite_vec<S: Scalar>(r: &Result<DVector<S>, OracleError>, what: &str) {
    match r {
        Ok(v) => assert!(
            v.iter().all(Scalar::is_finite),
            "{what}: non-finite Ok {v:?}"
        ),
        Err(e) => error_ok(e),
    }
}

/// The oracle never panics, and every `Ok` is finite and well-formed (right dimension, roll-outs
/// that belong to the MDP and carry the expert's labels).
pub fn check_oracle_outputs<S: Scalar>(mdp: &ToyMdp, out: &OracleOutputs<S>) {
    let dim = mdp.policy.dim();
    for (i, r) in out.estimates.iter().chain(&out.weighted).enumerate() {
        finite_vec(r, &format!("estimate #{i}"));
        if let Ok(v) = r {
            assert_eq!(v.len(), dim);
        }
    }
    match &out.loss {
        Ok(l) => assert!(l.is_finite(), "loss not finite: {l:?}"),
        Err(e) => error_ok(e),
    }
    for r in &out.supervised {
        match r {
            Ok((l, g)) => {
                assert!(
                    l.is_finite() && g.iter().all(Scalar::is_finite),
                    "{l:?} {g:?}"
                );
                assert_eq!(g.len(), dim);
            }
            Err(e) => error_ok(e),
        }
    }
    for r in &out.rollouts {
        match r {
            Ok(t) => {
                assert_eq!(t.states.len(), mdp.horizon);
                assert_eq!(t.actions.len(), mdp.horizon - 1);
                assert_eq!(t.labels.len(), mdp.horizon - 1);
                assert!(t.states.iter().all(|&s| s < mdp.states));
                assert!(t.actions.iter().all(|&a| a < mdp.actions));
                for (s, l) in t.states.iter().zip(&t.labels) {
                    assert_eq!(mdp.expert[*s], *l, "label is not the expert's action");
                }
            }
            Err(e) => error_ok(e),
        }
    }
}

/// Target `oracle`: parse, then run the oracle in `f64` and in exact rationals.
pub fn check_oracle(input: &OracleInput) {
    let Some(mdp) = input.parse() else { return };
    let (th, th_new) = input.thetas(&mdp);
    let traj = input.traj.build(mdp.states, mdp.actions, mdp.horizon);
    let f = run_oracle::<f64>(&mdp, &th, &th_new, &traj, input.seed, input.expert_weight);
    check_oracle_outputs(&mdp, &f);
    let q = run_oracle::<BigRational>(&mdp, &th, &th_new, &traj, input.seed, input.expert_weight);
    check_oracle_outputs(&mdp, &q);
}
