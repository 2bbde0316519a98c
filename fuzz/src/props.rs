//! The properties checked by the fuzz targets, shared word for word with the proptest suites
//! (`tests/inputs/hostile_input.rs`) and the regression tests (`tests/inputs/fuzz_regressions.rs`), which include
//! this file with `#[path = "../fuzz/src/props.rs"] mod props;`.
//!
//! Every `check_*` function panics (a fuzzer "crash") exactly when a property is violated; a clean
//! error from the library is never a violation. The inputs are plain structs so that the fuzz crate
//! can implement `arbitrary::Arbitrary` for them and the proptest suites can build them from
//! strategies; they only need `ilopt`'s own dependencies.
#![allow(dead_code)]

use ilopt::algo::RunConfig;
use ilopt::env::cartpole::CartPoleDynamics;
use ilopt::expert::vo::{VoError, objective, vo_expert};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::scalar::{BigRational, Interval, Scalar, interval_contains_rational};
use ilopt::toy::{
    MAX_ACTIONS, MAX_HORIZON, MAX_STATES, PolicyKind, Termination, ToyMdp, ToyProblem,
    ToyTrajectory,
};
use nalgebra::DVector;
use num_bigint::BigInt;
use num_traits::{One, Signed, Zero};
use rand::SeedableRng;

// ---------------------------------------------------------------------------------------------
// 1. The toy-MDP parser.
// ---------------------------------------------------------------------------------------------

/// Arbitrary bytes → [`ToyMdp::from_json_str`]: never a panic; an error has a message; an accepted
/// MDP satisfies every invariant of `docs/formats/toy-mdp.md`.
pub fn check_toy_parser(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match ToyMdp::from_json_str(text) {
        Ok(mdp) => check_mdp_invariants(&mdp),
        Err(e) => assert!(!e.to_string().is_empty(), "empty error message"),
    }
}

/// The invariants of an accepted toy MDP (exact: rows sum to exactly 1).
pub fn check_mdp_invariants(m: &ToyMdp) {
    let (s, a) = (m.states, m.actions);
    assert!((1..=MAX_STATES).contains(&s), "states = {s}");
    assert!((2..=MAX_ACTIONS).contains(&a), "actions = {a}");
    assert!(
        (2..=MAX_HORIZON).contains(&m.horizon),
        "horizon = {}",
        m.horizon
    );
    let dist = |row: &[BigRational], what: &str| {
        assert_eq!(row.len(), s, "{what}: length");
        assert!(
            row.iter().all(|p| !p.is_negative()),
            "{what}: negative entry"
        );
        let sum = row
            .iter()
            .fold(<BigRational as Zero>::zero(), |acc, p| acc + p);
        assert!(sum.is_one(), "{what} sums to {sum}");
    };
    dist(&m.initial, "initial");
    assert_eq!(m.transition.len(), s);
    for (i, row) in m.transition.iter().enumerate() {
        assert_eq!(row.len(), a, "transition[{i}]: length");
        for (j, d) in row.iter().enumerate() {
            dist(d, &format!("transition[{i}][{j}]"));
        }
    }
    assert_eq!(m.expert.len(), s);
    assert!(
        m.expert.iter().all(|&e| e < a),
        "expert action out of range"
    );
    let p = &m.policy;
    assert_eq!(p.actions(), a);
    assert_eq!(p.groups.len(), s);
    let g = p.group_count();
    assert!(g >= 1 && g <= s, "group count {g}");
    assert!((0..g).all(|o| p.groups.contains(&o)), "a group is unused");
    assert!(p.groups.iter().all(|&o| o < g));
    match p.kind {
        PolicyKind::Direct => assert!(p.c.is_none(), "direct with c"),
        PolicyKind::RationalSoftmax | PolicyKind::TiedSoftmax => {
            assert!(p.c.as_ref().is_some_and(Signed::is_positive), "c not > 0")
        }
    }
    if p.kind == PolicyKind::TiedSoftmax {
        assert_eq!(a, 2, "tied-softmax with {a} actions");
    }
    assert_eq!(p.dim(), g * p.block());
    match &m.termination {
        Termination::Reset { terminal, law } => {
            assert_eq!(terminal.len(), s, "terminal: length");
            dist(law, "on_terminal.law");
            for (z, _) in terminal.iter().enumerate().filter(|(_, t)| **t) {
                assert!(law[z].is_zero(), "reset law has mass on terminal state {z}");
                assert!(
                    m.initial[z].is_zero(),
                    "initial law has mass on terminal state {z}"
                );
            }
        }
        Termination::Absorb { loss } => {
            assert_eq!(loss.len(), s, "on_terminal.loss: length");
            assert!(
                loss.iter().flatten().all(|c| !c.is_negative()),
                "negative absorbing loss"
            );
        }
        _ => {}
    }
    // The augmented chain (math.md §8) is a Markov kernel.
    for (i, row) in m.chain_transition().iter().enumerate() {
        for (j, d) in row.iter().enumerate() {
            dist(d, &format!("chain_transition[{i}][{j}]"));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 2./3. The oracle on small MDPs, and the differential check f64 / Interval / BigRational.
// ---------------------------------------------------------------------------------------------

/// A fraction of small integers (`den = 0` is written as such and must be rejected).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frac {
    /// Numerator.
    pub num: i16,
    /// Denominator.
    pub den: u8,
}

/// A small MDP described loosely; [`MdpSpec::to_json`] writes it in the toy-MDP format, where it
/// is either valid or rejected by the parser.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MdpSpec {
    /// S = `states % 4` (0 is rejected).
    pub states: u8,
    /// A = `actions % 4` (0 and 1 are rejected).
    pub actions: u8,
    /// T = `horizon % 5` (0 and 1 are rejected).
    pub horizon: u8,
    /// Entries of μ and P, used cyclically.
    pub probs: Vec<Frac>,
    /// Write every distribution as weights `|num| % 4` normalised to sum 1 (else raw `num/den`).
    pub normalize: bool,
    /// π*(s) = `expert[s] % (A + 1)` (A is rejected), cyclically.
    pub expert: Vec<u8>,
    /// 0 rational-softmax, 1 direct, 2 tied-softmax, 3 an unknown kind.
    pub kind: u8,
    /// The policy parameter c.
    pub c: Frac,
    /// Optional observation map (`groups[s] % (S + 1)`).
    pub groups: Option<Vec<u8>>,
}

impl MdpSpec {
    /// S, A, T as written to the file.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (
            usize::from(self.states % 4),
            usize::from(self.actions % 4),
            usize::from(self.horizon % 5),
        )
    }

    /// The toy-MDP JSON text.
    pub fn to_json(&self) -> String {
        let (s, a, t) = self.sizes();
        let fallback = [Frac { num: 1, den: 1 }];
        let probs: &[Frac] = if self.probs.is_empty() {
            &fallback
        } else {
            &self.probs
        };
        let mut next = 0usize;
        let mut row = |len: usize| -> serde_json::Value {
            let fr: Vec<Frac> = (0..len)
                .map(|_| {
                    let f = probs[next % probs.len()];
                    next += 1;
                    f
                })
                .collect();
            if self.normalize {
                let mut w: Vec<u32> = fr
                    .iter()
                    .map(|f| u32::from(f.num.unsigned_abs() % 4))
                    .collect();
                if w.iter().all(|&x| x == 0)
                    && let Some(first) = w.first_mut()
                {
                    *first = 1;
                }
                let sum: u32 = w.iter().sum();
                serde_json::Value::Array(w.iter().map(|x| format!("{x}/{sum}").into()).collect())
            } else {
                serde_json::Value::Array(
                    fr.iter()
                        .map(|f| format!("{}/{}", f.num, f.den).into())
                        .collect(),
                )
            }
        };
        let initial = row(s);
        let transition: Vec<serde_json::Value> = (0..s)
            .map(|_| serde_json::Value::Array((0..a).map(|_| row(s)).collect()))
            .collect();
        let expert: Vec<u64> = (0..s)
            .map(|i| {
                let e = self
                    .expert
                    .get(i % self.expert.len().max(1))
                    .copied()
                    .unwrap_or(0);
                u64::from(e) % (a as u64 + 1)
            })
            .collect();
        let mut policy = serde_json::json!({
            "kind": match self.kind % 4 {
                0 => "rational-softmax",
                1 => "direct",
                2 => "tied-softmax",
                _ => "softmax",
            }
        });
        if self.kind % 4 != 1 {
            policy["c"] = format!("{}/{}", self.c.num, self.c.den).into();
        }
        if let Some(g) = &self.groups {
            let g: Vec<u64> = (0..s)
                .map(|i| u64::from(g.get(i).copied().unwrap_or(0)) % (s as u64 + 1))
                .collect();
            policy["groups"] = g.into();
        }
        serde_json::json!({
            "states": s,
            "actions": a,
            "horizon": t,
            "initial": initial,
            "transition": transition,
            "expert": expert,
            "policy": policy,
        })
        .to_string()
    }
}

/// A trajectory given loosely: `conform` fits it to the MDP (lengths and ranges), otherwise it is
/// used as given (and should be rejected as foreign when it does not fit).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TrajSpec {
    /// States.
    pub states: Vec<u8>,
    /// Actions.
    pub actions: Vec<u8>,
    /// Expert labels.
    pub labels: Vec<u8>,
    /// Fit to the MDP.
    pub conform: bool,
}

impl TrajSpec {
    /// The trajectory for an MDP of S states, A actions, horizon T.
    pub fn build(&self, s: usize, a: usize, t: usize) -> ToyTrajectory {
        let cyc = |v: &[u8], i: usize| v.get(i % v.len().max(1)).copied().unwrap_or(0) as usize;
        if self.conform {
            ToyTrajectory {
                states: (0..t).map(|i| cyc(&self.states, i) % s).collect(),
                actions: (0..t - 1).map(|i| cyc(&self.actions, i) % a).collect(),
                labels: (0..t - 1).map(|i| cyc(&self.labels, i) % a).collect(),
            }
        } else {
            let raw = |v: &[u8]| v.iter().take(8).map(|&x| usize::from(x)).collect();
            ToyTrajectory {
                states: raw(&self.states),
                actions: raw(&self.actions),
                labels: raw(&self.labels),
            }
        }
    }
}

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
    let p = ToyProblem::<S>::new(mdp);
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
        .map(|ex| p.supervised(&th, ex, &mut cost))
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

/// Errors that depend only on the *shape* of the input, never on the arithmetic: every scalar
/// must agree on them.
fn structural(e: &OracleError) -> Option<&'static str> {
    match e {
        OracleError::Dimension { .. } => Some("dimension"),
        OracleError::Trajectory(_) => Some("trajectory"),
        OracleError::Behaviour(_) => Some("behaviour"),
        _ => None,
    }
}

fn same_structure<A, B>(x: &Result<A, OracleError>, y: &Result<B, OracleError>, what: &str) {
    let kx = x.as_ref().err().and_then(structural);
    let ky = y.as_ref().err().and_then(structural);
    if kx.is_some() || ky.is_some() {
        assert_eq!(kx, ky, "{what}: structural errors differ");
    }
}

/// The kit's tolerance policy on one value: the exact value in the enclosure, the `f64` value in
/// the enclosure (src/tolerance.rs).
fn agree(q: &BigRational, i: &Interval, f: Option<&f64>, what: &str) {
    assert!(
        interval_contains_rational(*i, q),
        "{what}: exact {q} not in the interval {i:?}"
    );
    if let Some(f) = f {
        assert!(
            f.is_finite() && i.contains(*f),
            "{what}: f64 {f:e} not in the interval {i:?} (exact {q})"
        );
    }
}

fn agree_vec(
    q: &Result<DVector<BigRational>, OracleError>,
    i: &Result<DVector<Interval>, OracleError>,
    f: &Result<DVector<f64>, OracleError>,
    what: &str,
) {
    same_structure(q, i, what);
    same_structure(q, f, what);
    if let (Ok(q), Ok(i)) = (q, i) {
        assert_eq!(q.len(), i.len());
        for k in 0..q.len() {
            let fk = f.as_ref().ok().map(|f| &f[k]);
            agree(&q[k], &i[k], fk, &format!("{what}[{k}]"));
        }
    }
}

/// Target `differential`: the same oracle input in `f64`, [`Interval`] and [`BigRational`]. Where
/// the exact and the interval computation both succeed, the exact value lies in the enclosure and
/// so does the `f64` value (when it succeeds too); errors caused by the input's shape are the same
/// in every arithmetic; an interval roll-out that succeeds is the exact roll-out.
pub fn check_differential(input: &OracleInput) {
    let Some(mdp) = input.parse() else { return };
    let (th, th_new) = input.thetas(&mdp);
    let traj = input.traj.build(mdp.states, mdp.actions, mdp.horizon);
    let (seed, w) = (input.seed, input.expert_weight);
    let f = run_oracle::<f64>(&mdp, &th, &th_new, &traj, seed, w);
    let i = run_oracle::<Interval>(&mdp, &th, &th_new, &traj, seed, w);
    let q = run_oracle::<BigRational>(&mdp, &th, &th_new, &traj, seed, w);
    check_oracle_outputs(&mdp, &f);
    check_oracle_outputs(&mdp, &q);
    for k in 0..2 {
        agree_vec(
            &q.estimates[k],
            &i.estimates[k],
            &f.estimates[k],
            &format!("estimate {k}"),
        );
        agree_vec(
            &q.weighted[k],
            &i.weighted[k],
            &f.weighted[k],
            &format!("weighted {k}"),
        );
    }
    same_structure(&q.loss, &i.loss, "loss");
    same_structure(&q.loss, &f.loss, "loss");
    if let (Ok(ql), Ok(il)) = (&q.loss, &i.loss) {
        agree(ql, il, f.loss.as_ref().ok(), "trajectory_loss");
    }
    for (k, ((qs, is), fs)) in q
        .supervised
        .iter()
        .zip(&i.supervised)
        .zip(&f.supervised)
        .enumerate()
    {
        same_structure(qs, is, "supervised");
        same_structure(qs, fs, "supervised");
        if let (Ok((ql, qg)), Ok((il, ig))) = (qs, is) {
            let fv = fs.as_ref().ok();
            agree(ql, il, fv.map(|x| &x.0), &format!("supervised {k} loss"));
            agree_vec(
                &Ok(qg.clone()),
                &Ok(ig.clone()),
                &fv.map(|x| x.1.clone()).ok_or(OracleError::NonFinite("f64")),
                &format!("supervised {k} gradient"),
            );
        }
    }
    for k in 0..3 {
        same_structure(&q.rollouts[k], &i.rollouts[k], "rollout");
        same_structure(&q.rollouts[k], &f.rollouts[k], "rollout");
        if let (Ok(qt), Ok(it)) = (&q.rollouts[k], &i.rollouts[k]) {
            assert_eq!(qt, it, "rollout {k}: the interval run decided differently");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 4. The velocity-obstacle expert.
// ---------------------------------------------------------------------------------------------

/// One geometry for [`vo_expert`] (any bit patterns: NaN, ±∞, subnormals, huge values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoInput {
    /// Obstacle centre minus agent centre.
    pub r: [f64; 2],
    /// Obstacle velocity.
    pub v_o: [f64; 2],
    /// Agent velocity.
    pub v_r: [f64; 2],
    /// Desired velocity.
    pub v_des: [f64; 2],
    /// λ.
    pub lam: f64,
    /// R.
    pub big_r: f64,
    /// Offsets along the perpendicular of `r` for extra feasible candidate points.
    pub probes: [f64; 2],
}

const EPS: f64 = f64::EPSILON;

fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

/// Exact test of the constraint of eq. 4.1 at a float point `u`, with a slack relative to the
/// scale of `c`: `(rᵀv)² − (‖r‖² − R²)‖v‖² ≤ rel·(‖r‖² + R²)‖v‖²`, `v = v_o − v_r − u` (all in
/// rationals), i.e. `c(u) ≤ rel·(‖r‖² + R²)` for `v ≠ 0`; `v = 0` is feasible by the module's
/// convention.
/// The finite float `x` times 2¹⁰⁷⁵, an exact integer (`integer_decode` reports subnormals with
/// exponent −1075).
fn z(x: f64) -> BigInt {
    let (m, e, sign) = num_traits::Float::integer_decode(x);
    let n = BigInt::from(m) << usize::try_from(i32::from(e) + 1075).expect("e ≥ −1075");
    if sign < 0 { -n } else { n }
}

fn constraint_exact_le(inp: &VoInput, u: [f64; 2], rel: f64) -> bool {
    if !rel.is_finite() {
        return true; // the tolerance itself overflowed (∞ or ∞/∞): no information
    }
    // Every float is an integer multiple of 2⁻¹⁰⁷⁵ (`integer_decode` reports subnormals with exponent −1075): compute with the integers x·2¹⁰⁷⁵ (exact, and
    // much faster than rationals, which reduce by a gcd after every operation). Both sides of
    // the inequality are homogeneous of degree 2 in (r, R) and in v, so the scale cancels; `rel`
    // is scaled too, so the left side is multiplied by 2¹⁰⁷⁵ once more.
    let v: Vec<BigInt> = (0..2)
        .map(|k| z(inp.v_o[k]) - z(inp.v_r[k]) - z(u[k]))
        .collect();
    let r: Vec<BigInt> = inp.r.iter().map(|&x| z(x)).collect();
    let vv = &v[0] * &v[0] + &v[1] * &v[1];
    if vv.is_zero() {
        return true;
    }
    let rv = &r[0] * &v[0] + &r[1] * &v[1];
    let rr = &r[0] * &r[0] + &r[1] * &r[1];
    let rr2 = z(inp.big_r) * z(inp.big_r);
    ((&rv * &rv - (&rr - &rr2) * &vv) << 1075usize) <= z(rel) * (rr + rr2) * vv
}

/// The documented rounding tolerance of the feasibility check (fuzz/README.md), relative to the
/// scale `‖r‖² + R²` of `c`: with `M = ‖v_o‖ + ‖v_r‖ + ‖v_des‖ + ‖u‖`,
/// `c(u*) ≤ 64·(‖r‖² + R²)·(ε + (εM + η)/‖v‖)`, `η = 2⁻¹⁰⁷⁴` (the subnormal spacing). The
/// returned `u*` is the rounded image of a point on the cone's boundary; an error
/// `e ≲ 8(εM + η)` in its position turns the line's direction by `e/‖v‖`,
/// which moves `c` by at most `‖r‖²·e/‖v‖`; computing the boundary direction `d±` (one square
/// root of `‖r‖² − R²`) costs another few `ε(‖r‖² + R²)`. Both are invariant under rescaling r
/// and R, so the bound is stated relative to `‖r‖² + R²`.
pub fn vo_feasibility_slack(inp: &VoInput, u: [f64; 2]) -> f64 {
    let v = [
        inp.v_o[0] - inp.v_r[0] - u[0],
        inp.v_o[1] - inp.v_r[1] - u[1],
    ];
    let m = norm(inp.v_o) + norm(inp.v_r) + norm(inp.v_des) + norm(u);
    let nv = norm(v);
    // Position error of u*: a few ulps of M, but never less than the spacing of subnormals
    // (2⁻¹⁰⁷⁴): a u* in the subnormal range has only a few significant bits.
    let e = EPS * m + f64::from_bits(1);
    let ratio = if nv > 0.0 { e / nv } else { f64::INFINITY };
    64.0 * (EPS + ratio)
}

/// Target `vo_expert`: a finite, feasible (within [`vo_feasibility_slack`]) global optimum that is
/// no worse than a few known feasible points, or a clear error; never NaN, never a panic.
pub fn check_vo(inp: &VoInput) {
    let res = vo_expert(inp.r, inp.v_o, inp.v_r, inp.v_des, inp.lam, inp.big_r);
    let all = [
        inp.r[0],
        inp.r[1],
        inp.v_o[0],
        inp.v_o[1],
        inp.v_r[0],
        inp.v_r[1],
        inp.v_des[0],
        inp.v_des[1],
        inp.lam,
        inp.big_r,
    ];
    let sol = match res {
        Err(e) => {
            assert!(!e.to_string().is_empty());
            assert!(!e.to_string().contains("NaN"), "error prints NaN: {e}");
            if all.iter().any(|x| !x.is_finite()) {
                assert!(
                    matches!(e, VoError::NonFinite { .. }),
                    "non-finite input gave {e:?}"
                );
            }
            return;
        }
        Ok(sol) => sol,
    };
    assert!(
        all.iter().all(|x| x.is_finite()),
        "Ok for a non-finite input"
    );
    assert!(inp.lam >= 0.0 && inp.big_r > 0.0, "Ok for λ < 0 or R ≤ 0");
    // ‖r‖ > R, decided exactly (‖r‖ may exceed R by less than an ulp).
    let (r0, r1, big) = (z(inp.r[0]), z(inp.r[1]), z(inp.big_r));
    assert!(
        &r0 * &r0 + &r1 * &r1 > &big * &big,
        "Ok inside the obstacle"
    );
    let u = sol.u;
    assert!(
        u[0].is_finite() && u[1].is_finite() && sol.j.is_finite(),
        "non-finite Ok: {sol:?}"
    );
    let j_u = objective(u, inp.v_r, inp.v_des, inp.lam);
    // The scale of J's terms; everything below is relative to it.
    let m = norm(inp.v_o) + norm(inp.v_r) + norm(inp.v_des) + norm(u);
    let j_scale = (1.0 + inp.lam) * (1.0 + m) * (1.0 + m);
    if !j_scale.is_finite() || !j_u.is_finite() {
        return; // the f64 checks below would overflow; finiteness was checked above
    }
    let j_tol = 1e-9 * j_scale;
    assert!(sol.j >= -j_tol, "J* < 0: {sol:?}");
    assert!(
        (sol.j - j_u).abs() <= j_tol,
        "J* = {} but J(u*) = {j_u}",
        sol.j
    );
    let slack = vo_feasibility_slack(inp, u);
    assert!(
        constraint_exact_le(inp, u, slack),
        "u* = {u:?} infeasible beyond the slack {slack:e}"
    );
    // Known feasible points: the apex (v = 0), and points of the line through v_o perpendicular
    // to r (rᵀv = 0 there, so c = R² − ‖r‖² < 0); plus u = 0 and u₀ when exactly feasible.
    let apex = [inp.v_o[0] - inp.v_r[0], inp.v_o[1] - inp.v_r[1]];
    let nr = norm(inp.r);
    let perp = [-inp.r[1] / nr, inp.r[0] / nr];
    let mut candidates = vec![apex, [0.0, 0.0]];
    let u0 = [
        (inp.v_des[0] - inp.v_r[0]) / (1.0 + inp.lam),
        (inp.v_des[1] - inp.v_r[1]) / (1.0 + inp.lam),
    ];
    candidates.push(u0);
    for &s in &inp.probes {
        if s.is_finite() && s.abs() < 1e6 * (1.0 + m) {
            candidates.push([apex[0] + s * perp[0], apex[1] + s * perp[1]]);
        }
    }
    for c in candidates {
        if !(c[0].is_finite() && c[1].is_finite()) {
            continue;
        }
        // Only points that are feasible exactly (no slack) count.
        if !constraint_exact_le(inp, c, 0.0) {
            continue;
        }
        let j_c = objective(c, inp.v_r, inp.v_des, inp.lam);
        if !j_c.is_finite() {
            continue;
        }
        let tol = 1e-9 * (j_scale + (1.0 + inp.lam) * (norm(c) + 1.0).powi(2));
        assert!(
            sol.j <= j_c + tol,
            "J* = {} > J({c:?}) = {j_c} at a feasible point",
            sol.j
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 5. CartPole replay.
// ---------------------------------------------------------------------------------------------

/// An initial state and actions (any `u8`: only 0 and 1 are valid), plus text for the CLI's
/// argument parsers.
#[derive(Debug, Clone, PartialEq)]
pub struct CartpoleInput {
    /// x, ẋ, θ, θ̇ (any bit patterns).
    pub init: [f64; 4],
    /// Actions.
    pub actions: Vec<u8>,
    /// Text given to `parse_init` and `parse_actions` of `ilopt replay cartpole`.
    pub text: String,
}

/// Target `cartpole_replay`: no panic; every step's termination flag is Gymnasium's test on the
/// returned state; a non-finite state is an error; an invalid action is an error.
pub fn check_cartpole(inp: &CartpoleInput) {
    let dynamics = CartPoleDynamics::<f64>::new();
    let x_max = 2.4f64;
    let theta_max = 12.0 * 2.0 * std::f64::consts::PI / 360.0;
    let mut state = inp.init;
    for &a in inp.actions.iter().take(600) {
        let res = dynamics.step(&state, usize::from(a));
        if !state.iter().all(|x| x.is_finite()) {
            assert!(
                res.is_err(),
                "non-finite state {state:?} stepped to {res:?}"
            );
        }
        if a > 1 {
            assert!(res.is_err(), "action {a} accepted");
        }
        match res {
            Ok((next, term)) => {
                assert!(next.iter().all(|x| x.is_finite()), "non-finite Ok {next:?}");
                let expect = next[0] < -x_max
                    || next[0] > x_max
                    || next[2] < -theta_max
                    || next[2] > theta_max;
                assert_eq!(term, expect, "termination flag of {next:?}");
                state = next;
            }
            Err(e) => {
                assert!(!e.to_string().is_empty());
                if a > 1 {
                    continue; // an invalid action leaves the state as it was
                }
                break;
            }
        }
    }
    // The CLI's parsers of the same inputs.
    match ilopt::cli::replay::parse_init(&inp.text) {
        Ok(s) => assert!(s.iter().all(|x| x.is_finite())),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
    match ilopt::cli::replay::parse_actions(&inp.text) {
        Ok(a) => assert!(!a.0.is_empty() && a.0.iter().all(|&x| x <= 1)),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

// ---------------------------------------------------------------------------------------------
// 6. Configuration files.
// ---------------------------------------------------------------------------------------------

/// Target `config`: arbitrary bytes as a run configuration ([`RunConfig::from_json`]) and as a
/// toy-MDP file: never a panic. An accepted run configuration builds its algorithm (or returns a
/// clear error), converts θ₀, and survives a JSON round trip unchanged.
pub fn check_config(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    if let Ok(m) = ToyMdp::from_json_str(text) {
        check_mdp_invariants(&m);
    }
    let cfg = match RunConfig::from_json(text) {
        Ok(c) => c,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    let _ = cfg.theta0::<f64>();
    let _ = cfg.theta0::<BigRational>();
    let _ = cfg.theta0::<Interval>();
    if let Err(e) = cfg.algorithm.build::<f64, ToyProblem<f64>>() {
        assert!(!e.to_string().is_empty());
    }
    if let Err(e) = cfg
        .algorithm
        .build::<BigRational, ToyProblem<BigRational>>()
    {
        assert!(!e.to_string().is_empty());
    }
    let json = cfg.to_json().expect("an accepted config serialises");
    let back = RunConfig::from_json(&json)
        .unwrap_or_else(|e| panic!("the config's own JSON is rejected: {e}\n{json}"));
    assert_eq!(
        back.to_json().expect("serialises"),
        json,
        "JSON round trip changed the config"
    );
}
