//! The fixed-horizon objective on MDPs that terminate (math.md §8), exactly:
//!
//! * on two hand-built MDPs (the example files, reset and absorbing) F and F′ from closed forms
//!   derived by hand equal X1 enumeration, X2 forward DP, X3 backward DP, ∇(p·L) in dual numbers,
//!   E\[g\] and E\[g_full\], and a route of this file that enumerates the environment's own events
//!   (a crash followed by a reset draw, an absorbing tail) without the augmented kernel P′;
//! * on random MDPs with terminal states the environment route agrees with X2;
//! * mutations are caught: an estimator that forgets the scores before each reset, and one that
//!   drops the absorbing tail from the loss-to-go, are biased by exactly −(1 − θ)² and −3/4;
//! * the sampler follows the same law (prefix frequencies, the estimator's mean), takes no
//!   decision at absorbing states and charges them nothing, and follows one path per seed in
//!   f64, rationals and intervals;
//! * terminal flags that are all false change nothing.

use crate::common::{example, q, terminating_mdp_and_two_thetas};
use approx::abs_diff_eq;
use ilopt::exact::backward::backward;
use ilopt::exact::enumerate::{for_each_prefix, gradient_by_duals, moments};
use ilopt::exact::forward::forward;
use ilopt::exact::rrm::rrm_map;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError};
use ilopt::scalar::{BigRational, Dual, Interval, Scalar, interval_contains_rational};
use ilopt::toy::estimator::causal;
use ilopt::toy::{PolicyTable, Termination, ToyMdp, ToyProblem, ToyTrajectory};
use nalgebra::DVector;
use proptest::prelude::*;
use rand::SeedableRng;
use std::collections::HashMap;

type Q = BigRational;

/// One path of the environment's own process: the states the learner occupies (s_1..s_{T−1}),
/// the actions (a_1..a_{T−2}; 0 at absorbing steps), whether s_t was reached through a terminal
/// state and a reset draw, and the path's probability.
struct Path<S> {
    states: Vec<usize>,
    actions: Vec<usize>,
    reset: Vec<bool>,
    prob: S,
}

/// Every positive-probability path, enumerated from the file's kernel P: a transition into a
/// terminal state is followed, under a reset, by a separate draw from the reset law; under
/// absorption the terminal state repeats with no decision. This route does not use the
/// augmented kernel P′ of the library.
fn environment_paths<S: Scalar>(mdp: &ToyMdp, table: &PolicyTable<S>) -> Vec<Path<S>> {
    let cast = |x: &Q| S::from_rational(x);
    let (law, absorbing): (Vec<S>, Vec<bool>) = match &mdp.termination {
        Termination::Reset { law, .. } => (law.iter().map(cast).collect(), vec![false; mdp.states]),
        Termination::Absorb { loss } => (vec![], loss.iter().map(Option::is_some).collect()),
        _ => (vec![], vec![false; mdp.states]),
    };
    let len = mdp.horizon - 1;
    let mut out = Vec::new();
    let mut stack: Vec<Path<S>> = mdp
        .initial
        .iter()
        .enumerate()
        .filter(|(_, m)| !m.is_certainly_zero())
        .map(|(s, m)| Path {
            states: vec![s],
            actions: vec![],
            reset: vec![false],
            prob: cast(m),
        })
        .collect();
    while let Some(p) = stack.pop() {
        if p.states.len() == len {
            out.push(p);
            continue;
        }
        let s = *p.states.last().unwrap();
        let mut extend = |next: usize, a: usize, reset: bool, prob: S| {
            let mut q = Path {
                states: p.states.clone(),
                actions: p.actions.clone(),
                reset: p.reset.clone(),
                prob,
            };
            q.states.push(next);
            q.actions.push(a);
            q.reset.push(reset);
            stack.push(q);
        };
        if absorbing[s] {
            extend(s, 0, false, p.prob.clone());
            continue;
        }
        for a in 0..mdp.actions {
            for (next, pt) in mdp.transition[s][a].iter().enumerate() {
                if pt.is_certainly_zero() {
                    continue;
                }
                let w = p.prob.clone() * table.prob(s, a) * cast(pt);
                if mdp.termination.is_terminal(next) && !law.is_empty() {
                    for (landing, m) in law.iter().enumerate() {
                        if !m.is_certainly_zero() {
                            extend(landing, a, true, w.clone() * m);
                        }
                    }
                } else {
                    extend(next, a, false, w);
                }
            }
        }
    }
    out
}

/// eq. 3.15 written forwards, `Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`, over the decisions of a path. With
/// `forget_at_resets` it is the mutant: the score sum restarts at every reset, so the scores of
/// decisions before a reset no longer multiply the losses after it.
fn forward_causal<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    path: &Path<S>,
    forget_at_resets: bool,
) -> Vec<S> {
    let actions = problem.scored_actions(&path.states, &path.actions);
    let mut g = vec![S::zero(); table.dim];
    let mut scores = vec![S::zero(); table.dim];
    for (t, &s) in path.states.iter().enumerate() {
        if forget_at_resets && path.reset[t] {
            scores = vec![S::zero(); table.dim];
        }
        table.add_block_unscaled(&mut g, s, &table.loss_grad[s]);
        for (x, y) in g.iter_mut().zip(&scores) {
            *x += table.loss[s].clone() * y;
        }
        if t < actions.len() {
            table.add_block_unscaled(&mut scores, s, table.score(s, actions[t]));
        }
    }
    g
}

/// The mutant that drops the absorbing tail from the loss-to-go: eq. 3.15 on the decisions only,
/// as if the episode ended at absorption.
fn without_absorbing_tail<S: Scalar>(
    problem: &ToyProblem<S>,
    table: &PolicyTable<S>,
    path: &Path<S>,
) -> Vec<S> {
    let n = problem.decision_count(&path.states);
    causal(
        table,
        &path.states[..n],
        problem.scored_actions(&path.states, &path.actions),
    )
}

/// (F, E[estimator]) over the environment's paths.
fn environment_moments<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    estimator: impl Fn(&PolicyTable<S>, &Path<S>) -> Vec<S>,
) -> (S, Vec<S>) {
    let table = problem.table(theta).unwrap();
    let mut f = S::zero();
    let mut eg = vec![S::zero(); table.dim];
    let mut total = S::zero();
    for path in environment_paths(problem.mdp(), &table) {
        total += &path.prob;
        let loss = path
            .states
            .iter()
            .fold(S::zero(), |acc, &s| acc + &table.loss[s]);
        f += path.prob.clone() * &loss;
        for (e, x) in eg.iter_mut().zip(estimator(&table, &path)) {
            *e += path.prob.clone() * &x;
        }
    }
    assert_eq!(total, S::one(), "the paths' probabilities sum to 1");
    (f, eg)
}

fn with_horizon(name: &str, horizon: usize) -> ToyMdp {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/toy")
        .join(name);
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["horizon"] = horizon.into();
    ToyMdp::from_json(&doc).unwrap()
}

/// The hand-derived objectives of the example files, θ = π(0|·), q = θ/2, l(run) = 2θ²,
/// l(start) = 2(1 − θ)². Reset (a crash lands in `start`): T = 3: F = 2θ²(2 − q) + 2(1 − θ)² q
/// = θ + 2θ²; T = 4: F = 2θ²(2 + (1 − q)²) + 2(1 − θ)² q(2 − q). Absorb (crash 3/2 per step,
/// goal 0), r = P(still running after one step) = 3/4 − θ/4: T = 3: F = 2θ²(1 + r) + (3/2)q;
/// T = 4: F = 2θ²(1 + r + r²) + (3/2) q (2 + r).
fn closed_form<T: Scalar>(reset: bool, horizon: usize, theta: &T) -> T {
    let c = |n: i64, d: i64| T::from_ratio(n, d);
    let th = theta.clone();
    let l_run = c(2, 1) * &th * &th;
    let one_minus = c(1, 1) - &th;
    let l_start = c(2, 1) * &one_minus * &one_minus;
    let qq = th.clone() * c(1, 2);
    let r = c(3, 4) - th.clone() * c(1, 4);
    match (reset, horizon) {
        (true, 3) => l_run * (c(2, 1) - &qq) + l_start * &qq,
        (true, 4) => {
            let stay = c(1, 1) - &qq;
            l_run * (c(2, 1) + stay.square()) + l_start * &qq * (c(2, 1) - &qq)
        }
        (false, 3) => l_run * (c(1, 1) + &r) + c(3, 2) * &qq,
        (false, 4) => l_run * (c(1, 1) + r.clone() + r.square()) + c(3, 2) * &qq * (c(2, 1) + &r),
        _ => unreachable!("closed forms for T = 3, 4"),
    }
}

fn thetas() -> Vec<Q> {
    ["1/2", "1/3", "1/7", "5/6", "99/100", "1/1000"]
        .iter()
        .map(|x| q(x))
        .collect()
}

/// Every route computes the hand-derived F and F′ exactly, for both semantics and T = 3, 4.
fn closed_forms_by_every_route<S: Scalar>() {
    for (file, reset) in [
        ("terminal-reset.json", true),
        ("terminal-absorb.json", false),
    ] {
        for horizon in [3, 4] {
            let mdp = with_horizon(file, horizon);
            let p = ToyProblem::<S>::new(&mdp);
            for theta in thetas() {
                let th = [S::from_rational(&theta)];
                let (f, df) =
                    closed_form(reset, horizon, &Dual::variable(th[0].clone(), 0, 1)).into_parts(1);
                let at = format!("{file}, T = {horizon}, θ = {theta}");
                let x1 = moments(&p, &th).unwrap();
                let x2 = forward(&p, &th).unwrap();
                let x3 = backward(&p, &th).unwrap();
                let duals = gradient_by_duals(&p, &th).unwrap();
                let env = environment_moments(&p, &th, |t, path| {
                    causal(
                        t,
                        &path.states,
                        p.scored_actions(&path.states, &path.actions),
                    )
                });
                for (route, value) in [
                    ("X1", &x1.objective),
                    ("X2", &x2.objective),
                    ("X3", &x3.0),
                    ("Σ p·L in duals", &duals.0),
                    ("environment paths", &env.0),
                ] {
                    assert_eq!(value, &f, "F by {route}, {at}");
                }
                for (route, value) in [
                    ("X2", &x2.gradient),
                    ("X3", &x3.1),
                    ("∇(Σ p·L) in duals", &duals.1),
                    ("E[g] (X1)", &x1.expected_estimate),
                    ("E[g_full] (X1)", &x1.expected_full),
                    ("E[g] over environment paths", &env.1),
                ] {
                    assert_eq!(value, &df, "F′ by {route}, {at}");
                }
            }
        }
    }
}

/// The two mutants are biased by exactly the terms they drop (T = 3, derived by hand):
/// forgetting the scores before a reset loses E[ψ_1 l_2 1{reset}] = θ · ½ · (1/θ) · 2(1 − θ)²,
/// dropping the absorbing tail loses E[ψ_1 · 3/2 · 1{crash}] = θ · ½ · (1/θ) · 3/2. At T = 4 they
/// are biased too (checked ≠, in ℚ).
fn mutants_are_biased<S: Scalar>() {
    for theta in thetas() {
        let th = [S::from_rational(&theta)];
        for horizon in [3, 4] {
            let reset = ToyProblem::<S>::new(&with_horizon("terminal-reset.json", horizon));
            let grad = forward(&reset, &th).unwrap().gradient;
            let (_, honest) = environment_moments(&reset, &th, |t, path| {
                forward_causal(&reset, t, path, false)
            });
            assert_eq!(honest, grad, "the unmutated forward form is unbiased");
            let (_, mutant) =
                environment_moments(&reset, &th, |t, path| forward_causal(&reset, t, path, true));
            assert_ne!(mutant, grad, "reset mutant, T = {horizon}, θ = {theta}");
            if horizon == 3 {
                let one_minus = S::one() - th[0].clone();
                let bias = mutant[0].clone() - &grad[0];
                assert_eq!(
                    bias,
                    -one_minus.square(),
                    "reset mutant's bias at θ = {theta}"
                );
            }

            let absorb = ToyProblem::<S>::new(&with_horizon("terminal-absorb.json", horizon));
            let grad = forward(&absorb, &th).unwrap().gradient;
            let (_, mutant) = environment_moments(&absorb, &th, |t, path| {
                without_absorbing_tail(&absorb, t, path)
            });
            assert_ne!(mutant, grad, "absorb mutant, T = {horizon}, θ = {theta}");
            if horizon == 3 {
                let bias = mutant[0].clone() - &grad[0];
                assert_eq!(
                    bias,
                    S::from_ratio(-3, 4),
                    "absorb mutant's bias at θ = {theta}"
                );
            }
        }
    }
}

macro_rules! for_each_exact_scalar {
    ($body:ident: $($name:ident => $t:ty),+ $(,)?) => {
        mod $body {
            use super::*;
            $( #[test] fn $name() { $body::<$t>(); } )+
        }
    };
}

for_each_exact_scalar!(closed_forms_by_every_route:
    rational => BigRational,
    dual_rational => Dual<BigRational>,
);
for_each_exact_scalar!(mutants_are_biased:
    rational => BigRational,
    dual_rational => Dual<BigRational>,
);

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// On random MDPs with terminal states, the environment's paths (reset draws and absorbing
    /// tails spelled out) give the F and ∇F of X2 on the augmented chain, E[g] over them is ∇F,
    /// and the forward form of eq. 3.15 used by the mutant equals the library's on every path.
    #[test]
    fn environment_paths_agree_with_the_augmented_chain(
        (mdp, theta, _) in terminating_mdp_and_two_thetas()
    ) {
        let p = ToyProblem::<Q>::new(&mdp);
        let x2 = forward(&p, &theta).unwrap();
        let table = p.table(&theta).unwrap();
        for path in environment_paths(&mdp, &table) {
            let library = causal(&table, &path.states, p.scored_actions(&path.states, &path.actions));
            prop_assert_eq!(forward_causal(&p, &table, &path, false), library);
        }
        let env = environment_moments(&p, &theta, |t, path| {
            causal(t, &path.states, p.scored_actions(&path.states, &path.actions))
        });
        prop_assert_eq!(env.0, x2.objective);
        prop_assert_eq!(env.1, x2.gradient);
    }
}

fn rollouts(mdp: &ToyMdp, theta: &str, seed: u64, n: usize) -> (Vec<ToyTrajectory>, Cost) {
    let mut p = ToyProblem::<f64>::new(mdp);
    let th = DVector::from_vec(vec![q(theta).to_f64()]);
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    let taus = (0..n)
        .map(|_| {
            p.rollout(&Behaviour::Learner(&th), &mut rng, &mut cost)
                .unwrap()
        })
        .collect();
    (taus, cost)
}

/// The sampler's law is the exact chain's: each prefix's frequency lies within 5 standard
/// deviations of its exact probability, no sampled prefix is impossible, and the sample mean of
/// the estimator lies within 5 standard errors (from the exact variance) of ∇F.
#[test]
fn the_sampler_follows_the_exact_law() {
    let n = 20_000;
    for file in ["terminal-reset.json", "terminal-absorb.json"] {
        let mdp = with_horizon(file, 5);
        let exact = ToyProblem::<Q>::new(&mdp);
        let theta = [q("1/3")];
        let table = exact.table(&theta).unwrap();
        let mut law: HashMap<(Vec<usize>, Vec<usize>), f64> = HashMap::new();
        for_each_prefix(&exact, &table, |s, a, p| {
            law.insert((s.to_vec(), a.to_vec()), p.to_f64());
        })
        .unwrap();
        let (taus, _) = rollouts(&mdp, "1/3", 17, n);
        let mut counts: HashMap<(Vec<usize>, Vec<usize>), usize> = HashMap::new();
        for tau in &taus {
            let key = (tau.states[..4].to_vec(), tau.actions[..3].to_vec());
            assert!(law.contains_key(&key), "{file}: impossible prefix {key:?}");
            *counts.entry(key).or_default() += 1;
        }
        for (key, p) in &law {
            let got = counts.get(key).copied().unwrap_or(0) as f64;
            let (mean, sd) = (n as f64 * p, (n as f64 * p * (1.0 - p)).sqrt());
            assert!(
                abs_diff_eq!(got, mean, epsilon = 5.0 * sd + 1.0),
                "{file}: prefix {key:?} seen {got} times, expected {mean} ± {sd}"
            );
        }
        let mut sampled = ToyProblem::<f64>::new(&mdp);
        let th = DVector::from_vec(vec![1.0 / 3.0]);
        let mut cost = Cost::default();
        let mean = taus
            .iter()
            .map(|t| {
                sampled
                    .estimate(&th, t, EstimatorForm::Causal, &mut cost)
                    .unwrap()[0]
            })
            .sum::<f64>()
            / n as f64;
        let m = moments(&exact, &theta).unwrap();
        let (grad, se) = (
            m.expected_estimate[0].to_f64(),
            (m.variance.to_f64() / n as f64).sqrt(),
        );
        assert!(
            abs_diff_eq!(mean, grad, epsilon = 5.0 * se),
            "{file}: sample mean {mean}, ∇F = {grad} ± {se}"
        );
    }
}

/// Reset trajectories never occupy a terminal state; absorbing ones repeat the terminal state
/// with the placeholder action 0, take no decision there (no expert query, no environment step,
/// no gradient evaluation) and offer no supervised example there.
#[test]
fn trajectories_and_costs_under_termination() {
    let reset = with_horizon("terminal-reset.json", 6);
    let (taus, cost) = rollouts(&reset, "1/2", 3, 500);
    assert!(taus.iter().all(|t| t.states.iter().all(|&s| s != 2)));
    assert!(
        taus.iter().any(|t| t.states[1..].contains(&1)),
        "some stream was reset to `start`"
    );
    assert_eq!(cost.env_steps, 500 * 5);
    assert_eq!(cost.expert_queries, 500 * 5);

    let absorb = with_horizon("terminal-absorb.json", 6);
    let mut p = ToyProblem::<f64>::new(&absorb);
    let (taus, cost) = rollouts(&absorb, "1/2", 3, 500);
    let mut decisions = 0u64;
    let mut absorbed = 0;
    for t in &taus {
        let n = t
            .states
            .iter()
            .position(|&s| s != 0)
            .unwrap_or(t.states.len());
        assert!(t.states[n..].iter().all(|&s| s == t.states[n]), "{t:?}");
        assert!(
            t.actions[n.min(t.actions.len())..].iter().all(|&a| a == 0),
            "{t:?}"
        );
        decisions += n.min(5) as u64;
        absorbed += usize::from(n < 5);
        assert_eq!(p.labelled_states(t).len(), n.min(5));
    }
    assert!(absorbed > 100, "the sample absorbs often ({absorbed})");
    assert_eq!(cost.env_steps, decisions);
    assert_eq!(cost.expert_queries, decisions);

    // One trajectory by hand: run, run, crash, crash, crash, crash (T = 6).
    let tau = ToyTrajectory {
        states: vec![0, 0, 1, 1, 1, 1],
        actions: vec![1, 0, 0, 0, 0],
        labels: vec![1, 1, 0, 0, 0],
    };
    let th = DVector::from_vec(vec![0.5]);
    let mut cost = Cost::default();
    p.estimate(&th, &tau, EstimatorForm::Causal, &mut cost)
        .unwrap();
    assert_eq!(
        cost.gradient_evaluations, 2,
        "two decisions, three absorbing steps"
    );
    let loss = p.trajectory_loss(&th, &tau).unwrap();
    assert_eq!(
        loss,
        2.0 * 0.25 * 2.0 + 3.0 * 1.5,
        "l(run) = 2θ² twice, 3/2 three times"
    );
}

/// A trajectory that contradicts the semantics is rejected with a clear error.
#[test]
fn foreign_trajectories_are_rejected() {
    let th = DVector::from_vec(vec![q("1/2")]);
    let mut cost = Cost::default();
    let mut reset = ToyProblem::<Q>::new(&example("terminal-reset.json"));
    let tau = ToyTrajectory {
        states: vec![0, 2, 1],
        actions: vec![0, 0],
        labels: vec![1, 0],
    };
    let e = reset
        .estimate(&th, &tau, EstimatorForm::Causal, &mut cost)
        .unwrap_err();
    assert!(
        matches!(&e, OracleError::Trajectory(m) if m.contains("states[1] = 2 is terminal")),
        "{e}"
    );
    let absorb = ToyProblem::<Q>::new(&example("terminal-absorb.json"));
    let tau = ToyTrajectory {
        states: vec![1, 0, 0],
        actions: vec![0, 0],
        labels: vec![0, 1],
    };
    let e = absorb.trajectory_loss(&th, &tau).unwrap_err();
    assert!(
        matches!(&e, OracleError::Trajectory(m) if m.contains("states[1] = 0 follows the absorbing state 1")),
        "{e}"
    );
}

/// Flags that mark no state terminal leave every exact value and every sampled trajectory as
/// they are without the extension.
#[test]
fn no_terminal_state_changes_nothing() {
    let plain = example("three-state.json");
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/toy/three-state.json");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["terminal"] = serde_json::json!([false, false, false]);
    for rule in [
        serde_json::json!({"kind": "reset"}),
        serde_json::json!({"kind": "absorb", "loss": "5"}),
    ] {
        doc["on_terminal"] = rule;
        let flagged = ToyMdp::from_json(&doc).unwrap();
        let theta: Vec<Q> = ["1/2", "-1", "0.1", "3", "2/3", "-5/4"]
            .iter()
            .map(|x| q(x))
            .collect();
        let (a, b) = (ToyProblem::<Q>::new(&plain), ToyProblem::<Q>::new(&flagged));
        assert_eq!(moments(&a, &theta).unwrap(), moments(&b, &theta).unwrap());
        assert_eq!(forward(&a, &theta).unwrap(), forward(&b, &theta).unwrap());
        let th: DVector<f64> = DVector::from_iterator(6, theta.iter().map(Scalar::to_f64));
        let (mut fa, mut fb) = (
            ToyProblem::<f64>::new(&plain),
            ToyProblem::<f64>::new(&flagged),
        );
        let (mut ra, mut rb) = (KitRng::seed_from_u64(9), KitRng::seed_from_u64(9));
        let mut cost = Cost::default();
        for _ in 0..200 {
            let ta = fa
                .rollout(&Behaviour::Learner(&th), &mut ra, &mut cost)
                .unwrap();
            let tb = fb
                .rollout(&Behaviour::Learner(&th), &mut rb, &mut cost)
                .unwrap();
            assert_eq!(ta, tb);
        }
    }
}

/// The RRM map (eq. 3.29) fits the expert's labels where decisions are taken: absorbing states,
/// whose loss does not depend on the policy, carry no label mass. In the absorbing example every
/// decision is taken in `run`, whose label is action 1, so G(θ) = π(0|·) = 0 whatever θ.
#[test]
fn rrm_map_ignores_absorbing_states() {
    let p = ToyProblem::<Q>::new(&with_horizon("terminal-absorb.json", 5));
    for theta in thetas() {
        assert_eq!(rrm_map(&p, &[theta]).unwrap(), vec![q("0")]);
    }
}

fn seeded_rollouts<S: Scalar>(
    mdp: &ToyMdp,
    theta: &[Q],
    seed: u64,
) -> Result<Vec<ToyTrajectory>, OracleError> {
    let mut p = ToyProblem::<S>::new(mdp);
    let th = DVector::from_iterator(theta.len(), theta.iter().map(S::from_rational));
    let mut rng = KitRng::seed_from_u64(seed);
    let mut cost = Cost::default();
    (0..20)
        .map(|_| p.rollout(&Behaviour::Learner(&th), &mut rng, &mut cost))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// With resets and absorption the sampler still follows the same path in f64, rationals and
    /// intervals for one seed (intervals may only decline, as undecidable), and the interval
    /// estimates on those paths enclose the exact ones.
    #[test]
    fn same_seed_same_paths_in_every_scalar(
        (mdp, theta, _) in terminating_mdp_and_two_thetas(),
        seed in 0u64..1000,
    ) {
        let exact = seeded_rollouts::<Q>(&mdp, &theta, seed).unwrap();
        prop_assert_eq!(&seeded_rollouts::<f64>(&mdp, &theta, seed).unwrap(), &exact);
        match seeded_rollouts::<Interval>(&mdp, &theta, seed) {
            Ok(paths) => prop_assert_eq!(&paths, &exact),
            Err(e) => prop_assert!(matches!(e, OracleError::Undecidable(_)), "{}", e),
        }
        let (mut pq, mut pi) = (ToyProblem::<Q>::new(&mdp), ToyProblem::<Interval>::new(&mdp));
        let tq = DVector::from_vec(theta.clone());
        let ti = DVector::from_iterator(theta.len(), theta.iter().map(Interval::from_rational));
        let mut cost = Cost::default();
        for tau in &exact {
            let gq = pq.estimate(&tq, tau, EstimatorForm::Causal, &mut cost).unwrap();
            let gi = pi.estimate(&ti, tau, EstimatorForm::Causal, &mut cost).unwrap();
            prop_assert!((0..gq.len()).all(|j| interval_contains_rational(gi[j], &gq[j])));
        }
    }
}
