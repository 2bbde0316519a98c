//! Baselines for eq. 3.15 (math.md §9), exactly on toy MDPs: `E[g_b] = ∇F` in rationals for the
//! constant, time-indexed, estimated and leave-one-out kinds (∇F by the forward DP X2, an
//! independent route), a baseline that peeks at a_i caught as biased, the second-moment identity
//! and the optimality of b*, the importance-weighted baselined old-point estimate (I3 with a
//! baseline), and the `f64` oracle against the exact one on the same trajectories.

use crate::common::{example, mdp_and_two_thetas, q, qs, terminating_mdp_and_two_thetas};
use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined, PerDecisionTerms, baselined_estimate};
use ilopt::exact::baseline::{
    baselined_moments, baselined_moments_by, optimal_baselines, optimal_state_baseline,
    prefix_trajectory,
};
use ilopt::exact::enumerate::{for_each_prefix, moments};
use ilopt::exact::forward::forward;
use ilopt::oracle::DecisionTerms;
use ilopt::oracle::EstimatorKernel;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::scalar::{BigRational, Interval, Scalar, dot, norm_sq};
use ilopt::tolerance::all_agree;
use ilopt::toy::estimator::{causal, decision_terms};
use ilopt::toy::{ToyMdp, ToyProblem, ToyTrajectory};
use nalgebra::DVector;
use proptest::prelude::*;
use rand::SeedableRng;

type Q = BigRational;

/// Every positive-probability prefix at θ as a trajectory of the problem, with its probability.
fn trajectories(p: &ToyProblem<Q>, theta: &[Q]) -> Vec<(ToyTrajectory, Q)> {
    let table = p.table(theta).unwrap();
    let mut out = Vec::new();
    for_each_prefix(p, &table, |states, actions, prob| {
        out.push((prefix_trajectory(p, states, actions), prob.clone()));
    })
    .unwrap();
    out
}

/// `Σ_τ p(τ) f(τ)` over vectors.
fn expectation(all: &[(ToyTrajectory, Q)], mut f: impl FnMut(&ToyTrajectory) -> Vec<Q>) -> Vec<Q> {
    let mut acc: Option<Vec<Q>> = None;
    for (t, p) in all {
        let g = f(t);
        let acc = acc.get_or_insert_with(|| vec![Q::zero(); g.len()]);
        for (a, x) in acc.iter_mut().zip(g) {
            *a += p.clone() * x;
        }
    }
    acc.unwrap_or_default()
}

/// Baselines from small integers: (constant, time-indexed of length T − 2).
fn baselines(mdp: &ToyMdp, seed: &[(i64, i64)]) -> (Q, Vec<Q>) {
    let r = |(n, d): (i64, i64)| BigRational::new(n.into(), d.into());
    let k = mdp.horizon - 2;
    let b: Vec<Q> = (0..k).map(|i| r(seed[(i + 1) % seed.len()])).collect();
    (r(seed[0]), b)
}

fn nums(xs: &[Q]) -> Vec<ConfigNumber> {
    xs.iter().cloned().map(ConfigNumber::from).collect()
}

/// Every exact claim at θ (with θ′ for the weighted estimate); the first that fails.
fn check(mdp: &ToyMdp, theta: &[Q], theta_prime: &[Q], seed: &[(i64, i64)]) -> Result<(), String> {
    let p = ToyProblem::<Q>::new(mdp);
    let grad = forward(&p, theta).map_err(|e| e.to_string())?.gradient;
    let plain = moments(&p, theta).map_err(|e| e.to_string())?;
    let opt = optimal_baselines(&p, theta).map_err(|e| e.to_string())?;
    let (b0, bs) = baselines(mdp, seed);
    let k = mdp.horizon - 2;
    let mut constants = vec![vec![b0.clone()], vec![opt.constant.clone()]];
    if k > 0 {
        constants.push(bs.clone());
        constants.push(opt.time_indexed.clone());
    }
    for b in &constants {
        let m = baselined_moments(&p, theta, b).map_err(|e| e.to_string())?;
        if m.expected_estimate != grad {
            return Err(format!(
                "E[g_b] with b = {b:?}: {:?} ≠ ∇F = {grad:?}",
                m.expected_estimate
            ));
        }
        // E‖g_b‖² = E‖g‖² − 2 Σ b_i E[g·ψ_i] + Σ b_i² E‖ψ_i‖².
        let pick = |i: usize| {
            if b.len() == 1 {
                b[0].clone()
            } else {
                b[i].clone()
            }
        };
        let mut identity = plain.second_moment.clone();
        for i in 0..k {
            identity -= Q::from_i64(2) * pick(i) * &opt.cross[i];
            identity += pick(i).square() * &opt.score_moment[i];
        }
        if identity != m.second_moment {
            return Err(format!(
                "second-moment identity with b = {b:?}: {identity} ≠ {}",
                m.second_moment
            ));
        }
        // The optima beat every other choice of their kind.
        if m.second_moment < opt.second_moment_time_indexed
            || (b.len() == 1 && m.second_moment < opt.second_moment_constant)
        {
            return Err(format!("b = {b:?} beats the optimum: {}", m.second_moment));
        }
    }
    if opt.second_moment_time_indexed > opt.second_moment_constant
        || opt.second_moment_constant > plain.second_moment
    {
        return Err("the optima are ordered E‖g_{b*}‖² ≤ E‖g_{b*const}‖² ≤ E‖g‖²".into());
    }
    check_state_dependent(&p, theta, theta_prime, seed, &grad)?;
    // The oracle itself, with the constant / time-indexed baseline, plain and importance-weighted.
    let all_at = trajectories(&p, theta);
    let all_at_prime = trajectories(&p, theta_prime);
    let th = DVector::from_column_slice(theta);
    let th_prime = DVector::from_column_slice(theta_prime);
    let mut kinds = vec![Baseline::Constant {
        value: ConfigNumber::from(b0.clone()),
    }];
    if k > 0 {
        kinds.push(Baseline::TimeIndexed { values: nums(&bs) });
    }
    for kind in &kinds {
        let mut oracle = Baselined::<_, Q>::new(p.clone(), 1, kind).map_err(|e| e.to_string())?;
        oracle_is_unbiased(
            &mut oracle,
            (&th, &all_at),
            (&th_prime, &all_at_prime),
            &grad,
            &format!("{kind:?}"),
        )?;
    }
    Ok(())
}

/// The oracle's estimates are exactly unbiased at θ: `Σ_τ p(τ; θ) g_b(θ, τ) = ∇F(θ)` over
/// `all_at` (the prefixes at θ), and `Σ_τ p(τ; θ′) w g_b(θ, τ) = ∇F(θ)` over `all_at_prime` with
/// both weightings. The oracle is not rolled out in between, so its baselines stay fixed.
fn oracle_is_unbiased(
    oracle: &mut Baselined<ToyProblem<Q>, Q>,
    (th, all_at): (&DVector<Q>, &[(ToyTrajectory, Q)]),
    (th_prime, all_at_prime): (&DVector<Q>, &[(ToyTrajectory, Q)]),
    grad: &[Q],
    what: &str,
) -> Result<(), String> {
    let mut cost = Cost::default();
    let mean = expectation(all_at, |t| {
        let g = oracle.estimate(th, &vec![t.clone()], EstimatorForm::Causal, &mut cost);
        g.unwrap().as_slice().to_vec()
    });
    if mean != grad {
        return Err(format!("oracle E[g_b] ({what}) = {mean:?} ≠ ∇F = {grad:?}"));
    }
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        let mean = expectation(all_at_prime, |t| {
            let g = oracle.weighted_estimate(th, th_prime, &vec![t.clone()], w, &mut cost);
            g.unwrap().as_slice().to_vec()
        });
        if mean != grad {
            return Err(format!(
                "E_θ′[w g_b(θ)] ({what}, {w:?}) = {mean:?} ≠ ∇F(θ) = {grad:?}"
            ));
        }
    }
    Ok(())
}

/// The state-dependent baseline `b_i = w_{s_i}` (one-hot state features): `E[g_b] = ∇F` for a
/// given w and for the optimum; `E‖g_b‖² = E‖g‖² − 2 Σ_s w_s c_s + Σ_s w_s² A_ss` against the
/// enumeration; the optimum's closed form against its enumeration, and no w beats it; then the
/// oracle: after one earlier trajectory is observed and committed, its weights are that
/// trajectory's `c_s/A_ss` and its estimates (plain, and importance-weighted both ways) have mean
/// ∇F exactly.
fn check_state_dependent(
    p: &ToyProblem<Q>,
    theta: &[Q],
    theta_prime: &[Q],
    seed: &[(i64, i64)],
    grad: &[Q],
) -> Result<(), String> {
    let mdp = p.mdp().clone();
    let r = |(n, d): (i64, i64)| BigRational::new(n.into(), d.into());
    let w: Vec<Q> = (0..mdp.states).map(|s| r(seed[s % seed.len()])).collect();
    let opt = optimal_state_baseline(p, theta).map_err(|e| e.to_string())?;
    let given = baselined_moments_by(p, theta, |states, i| Some(w[states[i]].clone()))
        .map_err(|e| e.to_string())?;
    if given.expected_estimate != grad {
        return Err(format!("state baseline w = {w:?}: E[g_b] ≠ ∇F"));
    }
    let mut identity = opt.second_moment.clone();
    for ((ws, c), a) in w.iter().zip(&opt.cross).zip(&opt.score_moment) {
        identity -= Q::from_i64(2) * ws * c;
        identity += ws.square() * a;
    }
    if identity != given.second_moment {
        return Err(format!(
            "state second-moment identity: {identity} ≠ {}",
            given.second_moment
        ));
    }
    if opt.second_moment_optimal != opt.second_moment_closed_form {
        return Err(format!(
            "the state optimum: enumeration {} ≠ closed form {}",
            opt.second_moment_optimal, opt.second_moment_closed_form
        ));
    }
    if given.second_moment < opt.second_moment_optimal
        || opt.second_moment_optimal > opt.second_moment
    {
        return Err("the state optimum is beaten".into());
    }
    // The oracle, with the weights of one earlier trajectory (the last prefix at θ).
    for time in [false, true] {
        check_state_oracle(&mut p.clone(), theta, theta_prime, grad, time)?;
    }
    Ok(())
}

/// The state-dependent oracle (with the decision index and 1 appended when `time`) after one
/// earlier trajectory is observed and committed: without `time` its weights are that
/// trajectory's `c_s/A_ss`; either way its estimates (plain, and importance-weighted both ways)
/// have mean ∇F exactly.
fn check_state_oracle(
    p: &mut ToyProblem<Q>,
    theta: &[Q],
    theta_prime: &[Q],
    grad: &[Q],
    time: bool,
) -> Result<(), String> {
    let mdp = p.mdp().clone();
    let all_at = trajectories(p, theta);
    let all_at_prime = trajectories(p, theta_prime);
    let th = DVector::from_column_slice(theta);
    let th_prime = DVector::from_column_slice(theta_prime);
    let kind = Baseline::StateDependent {
        features: None,
        time,
        decay: None,
        ridge: None,
        fit_every: None,
    };
    let mut oracle = Baselined::<_, Q>::new(p.clone(), 1, &kind).map_err(|e| e.to_string())?;
    let mut cost = Cost::default();
    let (earlier, _) = all_at.last().ok_or("no prefix")?;
    let first = oracle
        .estimate(
            &th,
            &vec![earlier.clone()],
            EstimatorForm::Causal,
            &mut cost,
        )
        .map_err(|e| e.to_string())?;
    let plain = p
        .estimate(&th, earlier, EstimatorForm::Causal, &mut cost)
        .map_err(|e| e.to_string())?;
    if first != plain {
        return Err("no earlier trajectory: the state baseline must be 0".into());
    }
    let mut rng = KitRng::seed_from_u64(1);
    oracle
        .rollout(&Behaviour::Learner(&th), &mut rng, &mut cost)
        .map_err(|e| e.to_string())?;
    // That trajectory's c_s / A_ss, by the toy's independent per-decision terms.
    let table = p.table(theta).map_err(|e| e.to_string())?;
    let h = mdp.horizon;
    let states = &earlier.states[..h - 1];
    let scored = p.scored_actions(states, &earlier.actions[..h - 2]);
    let mut terms = DecisionTerms::new();
    decision_terms(&table, states, scored, None, false, &mut terms);
    let (mut c, mut a) = (vec![Q::zero(); mdp.states], vec![Q::zero(); mdp.states]);
    for i in 0..terms.decisions() {
        c[states[i]] += dot(plain.as_slice(), terms.score(i));
        a[states[i]] += norm_sq(terms.score(i));
    }
    let want: Vec<Q> = c
        .iter()
        .zip(&a)
        .map(|(c, a)| {
            if a.is_certainly_zero() {
                Q::zero()
            } else {
                c / a
            }
        })
        .collect();
    if !time && oracle.state_weights() != Some(want.clone()) {
        return Err(format!(
            "committed weights {:?} ≠ {want:?}",
            oracle.state_weights()
        ));
    }
    oracle_is_unbiased(
        &mut oracle,
        (&th, &all_at),
        (&th_prime, &all_at_prime),
        grad,
        &format!("state, time = {time}"),
    )
}

/// Most prefixes for which every pair is enumerated (the square of it is the work).
const PAIR_PREFIXES: usize = 25;

/// Leave-one-out with m = 2: `Σ_{τ1, τ2} p(τ1) p(τ2) g_LOO(θ; τ1, τ2) = ∇F` over every pair. An
/// MDP with more than [`PAIR_PREFIXES`] prefixes at θ or θ′ is checked with a shorter horizon.
fn check_leave_one_out(mdp: &ToyMdp, theta: &[Q], theta_prime: &[Q]) -> Result<(), String> {
    let mut mdp = mdp.clone();
    while mdp.horizon > 2 {
        let p = ToyProblem::<Q>::new(&mdp);
        if trajectories(&p, theta)
            .len()
            .max(trajectories(&p, theta_prime).len())
            <= PAIR_PREFIXES
        {
            break;
        }
        mdp.horizon -= 1;
    }
    let mdp = &mdp;
    let p = ToyProblem::<Q>::new(mdp);
    let grad = forward(&p, theta).map_err(|e| e.to_string())?.gradient;
    let mut oracle =
        Baselined::<_, Q>::new(p.clone(), 2, &Baseline::LeaveOneOut).map_err(|e| e.to_string())?;
    let th = DVector::from_column_slice(theta);
    let th_prime = DVector::from_column_slice(theta_prime);
    let mut cost = Cost::default();
    let all = trajectories(&p, theta);
    let pairs: Vec<_> = all
        .iter()
        .flat_map(|(a, pa)| {
            all.iter()
                .map(move |(b, pb)| (vec![a.clone(), b.clone()], pa.clone() * pb))
        })
        .collect();
    let mut mean = vec![Q::zero(); grad.len()];
    for (batch, prob) in &pairs {
        let g = oracle
            .estimate(&th, batch, EstimatorForm::Causal, &mut cost)
            .map_err(|e| e.to_string())?;
        for (m, x) in mean.iter_mut().zip(g.iter()) {
            *m += prob.clone() * x;
        }
    }
    if mean != grad {
        return Err(format!("leave-one-out E[g] = {mean:?} ≠ ∇F = {grad:?}"));
    }
    // Weighted (per-decision), pairs sampled at θ′.
    let all = trajectories(&p, theta_prime);
    let mut mean = vec![Q::zero(); grad.len()];
    for (a, pa) in &all {
        for (b, pb) in &all {
            let batch = vec![a.clone(), b.clone()];
            let g = oracle
                .weighted_estimate(&th, &th_prime, &batch, Weighting::PerDecision, &mut cost)
                .map_err(|e| e.to_string())?;
            for (m, x) in mean.iter_mut().zip(g.iter()) {
                *m += pa.clone() * pb * x;
            }
        }
    }
    if mean != grad {
        return Err(format!(
            "weighted leave-one-out E = {mean:?} ≠ ∇F = {grad:?}"
        ));
    }
    Ok(())
}

fn baseline_seed() -> impl Strategy<Value = Vec<(i64, i64)>> {
    prop::collection::vec((-6i64..=6, 1i64..=4), 3)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("regressions"),
        )),
        ..ProptestConfig::default()
    })]

    /// Constant and time-indexed baselines (given and optimal) on random MDPs without termination.
    #[test]
    fn baselines_are_exactly_unbiased((mdp, theta, theta_prime) in mdp_and_two_thetas(), seed in baseline_seed()) {
        prop_assert_eq!(check(&mdp, &theta, &theta_prime, &seed), Ok(()));
    }

    /// The same on random MDPs with terminal states (reset or absorbing).
    #[test]
    fn baselines_are_exactly_unbiased_under_termination((mdp, theta, theta_prime) in terminating_mdp_and_two_thetas(), seed in baseline_seed()) {
        prop_assert_eq!(check(&mdp, &theta, &theta_prime, &seed), Ok(()));
    }

    /// Leave-one-out over every pair of prefixes.
    #[test]
    fn leave_one_out_is_exactly_unbiased((mdp, theta, theta_prime) in mdp_and_two_thetas()) {
        prop_assert_eq!(check_leave_one_out(&mdp, &theta, &theta_prime), Ok(()));
    }

    /// Leave-one-out under termination.
    #[test]
    fn leave_one_out_is_exactly_unbiased_under_termination((mdp, theta, theta_prime) in terminating_mdp_and_two_thetas()) {
        prop_assert_eq!(check_leave_one_out(&mdp, &theta, &theta_prime), Ok(()));
    }
}

/// `E[g_b]` when `b_i = 1[a_i = 0]` (it looks at the action it multiplies), by enumeration.
fn peeking_mean(p: &ToyProblem<Q>, theta: &[Q]) -> Vec<Q> {
    let table = p.table(theta).unwrap();
    let mut terms = DecisionTerms::new();
    let mut g = vec![Q::zero(); table.dim];
    let mut acc = vec![Q::zero(); table.dim];
    for_each_prefix(p, &table, |states, actions, prob| {
        let actions = p.scored_actions(states, actions);
        decision_terms(&table, states, actions, None, false, &mut terms);
        terms.estimate_into(
            |i| Some(if actions[i] == 0 { Q::one() } else { Q::zero() }),
            &mut g,
        );
        for (a, x) in acc.iter_mut().zip(&g) {
            *a += prob.clone() * x;
        }
    })
    .unwrap();
    acc
}

#[test]
fn a_baseline_that_peeks_at_the_action_is_biased() {
    // M1 (tied softmax, T = 3) at θ = 0: E[1[a_1 = 0] ψ_1] = E[∇π(0|s_1)] = −p′(0) = −1/4.
    let p = ToyProblem::<Q>::new(&example("m1-tied.json"));
    let grad = forward(&p, &qs(&["0"])).unwrap().gradient;
    let mean = peeking_mean(&p, &qs(&["0"]));
    assert_eq!(
        mean[0].clone() - &grad[0],
        q("1/4"),
        "E[g_b] − ∇F = −E[b_1 ψ_1] = 1/4"
    );
    // And on every example MDP at a generic θ the difference is nonzero.
    for (name, theta) in [
        ("three-state.json", "-1/2,3,1/4,-7/2,1/3,1"),
        ("terminal-absorb.json", "1/3"),
        ("terminal-reset.json", "1/3"),
    ] {
        let mdp = example(name);
        let p = ToyProblem::<Q>::new(&mdp);
        let theta = ilopt::scalar::parse_exact_list(theta).unwrap();
        if theta.len() != mdp.policy.dim() {
            continue;
        }
        let grad = forward(&p, &theta).unwrap().gradient;
        assert_ne!(
            peeking_mean(&p, &theta),
            grad,
            "{name}: the mutation must be caught"
        );
    }
}

/// A "state" baseline that reads the *next* state, `b_i = w_{s_{i+1}}` (s_{i+1} depends on
/// a_i), is caught as biased on every example MDP whose transitions depend on the action, while
/// the same w on the decision's own state is exact.
#[test]
fn a_state_baseline_that_reads_the_next_state_is_biased() {
    let mut caught = 0;
    for (name, theta) in [
        ("m1-tied.json", "0"),
        ("three-state.json", "-1/2,3,1/4,-7/2,1/3,1"),
        ("terminal-absorb.json", "1/3"),
        ("terminal-reset.json", "1/3"),
    ] {
        let mdp = example(name);
        let theta = ilopt::scalar::parse_exact_list(theta).unwrap();
        if theta.len() != mdp.policy.dim() {
            continue;
        }
        let p = ToyProblem::<Q>::new(&mdp);
        let grad = forward(&p, &theta).unwrap().gradient;
        let w: Vec<Q> = (0..mdp.states)
            .map(|s| Q::from_i64(2 * s as i64 + 1))
            .collect();
        let own = baselined_moments_by(&p, &theta, |states, i| Some(w[states[i]].clone())).unwrap();
        assert_eq!(
            own.expected_estimate, grad,
            "{name}: the own state is exact"
        );
        let next =
            baselined_moments_by(&p, &theta, |states, i| Some(w[states[i + 1]].clone())).unwrap();
        if next.expected_estimate != grad {
            caught += 1;
        }
    }
    assert!(
        caught >= 2,
        "the next-state mutation was caught on {caught} MDPs"
    );
}

/// The baselined oracle on a toy MDP in the scalar `S`.
type ToyOracle<S> = Baselined<ToyProblem<S>, S>;

/// The same batch estimated by the `f64`, exact and interval oracles: the `f64` estimate lies
/// inside the interval run of the same code and the exact value inside both (the kit's tolerance
/// policy); the exact estimate is returned.
fn estimates_agree(
    (of, ox, oi): (
        &mut ToyOracle<f64>,
        &mut ToyOracle<Q>,
        &mut ToyOracle<Interval>,
    ),
    (theta_f, theta_x, theta_i): (&DVector<f64>, &DVector<Q>, &DVector<Interval>),
    batch: &Vec<ToyTrajectory>,
    what: &str,
) -> DVector<Q> {
    let mut cost = Cost::default();
    let f = of
        .estimate(theta_f, batch, EstimatorForm::Causal, &mut cost)
        .unwrap();
    let x = ox
        .estimate(theta_x, batch, EstimatorForm::Causal, &mut cost)
        .unwrap();
    let i = oi
        .estimate(theta_i, batch, EstimatorForm::Causal, &mut cost)
        .unwrap();
    assert!(
        all_agree(f.as_slice(), x.as_slice(), i.as_slice()),
        "{what}: {f:?} vs {x:?}"
    );
    x
}

/// The state-dependent oracle in `f64` against the exact one on the same trajectories, estimate
/// after estimate with a roll-out (commit) between them: inside the interval run of the same
/// code; from the second trajectory on the baseline changes the estimate.
#[test]
fn f64_state_dependent_oracle_agrees_with_the_exact_one() {
    let mdp = example("three-state.json");
    let theta_q = ilopt::scalar::parse_exact_list("-1/2,3,1/4,-7/2,1/3,1").unwrap();
    let theta_f: DVector<f64> = DVector::from_iterator(6, theta_q.iter().map(Scalar::to_f64));
    let theta_x: DVector<Q> = DVector::from_vec(theta_q.clone());
    let theta_i: DVector<Interval> =
        DVector::from_iterator(6, theta_q.iter().map(<Interval as Scalar>::from_rational));
    let kind = Baseline::StateDependent {
        features: None,
        time: true,
        decay: Some(ConfigNumber::ratio(9, 10)),
        ridge: Some(ConfigNumber::ratio(1, 100)),
        fit_every: None,
    };
    let pf = ToyProblem::<f64>::new(&mdp);
    let mut px = ToyProblem::<Q>::new(&mdp);
    let mut of = Baselined::<_, f64>::new(pf.clone(), 1, &kind).unwrap();
    let mut ox = Baselined::<_, Q>::new(px.clone(), 1, &kind).unwrap();
    let mut oi =
        Baselined::<_, Interval>::new(ToyProblem::<Interval>::new(&mdp), 1, &kind).unwrap();
    let mut rng = KitRng::seed_from_u64(3);
    let mut cost = Cost::default();
    let mut changed = 0;
    for _ in 0..8 {
        let batch = of
            .rollout(&Behaviour::Learner(&theta_f), &mut rng, &mut cost)
            .unwrap();
        let mut r2 = KitRng::seed_from_u64(0);
        ox.rollout(&Behaviour::Learner(&theta_x), &mut r2, &mut cost)
            .unwrap();
        oi.rollout(&Behaviour::Learner(&theta_i), &mut r2, &mut cost)
            .unwrap();
        let x = estimates_agree(
            (&mut of, &mut ox, &mut oi),
            (&theta_f, &theta_x, &theta_i),
            &batch,
            "state-dependent",
        );
        let plain = px
            .estimate(&theta_x, &batch[0], EstimatorForm::Causal, &mut cost)
            .unwrap();
        changed += usize::from(plain != x);
    }
    assert!(
        changed >= 6,
        "the baseline changed only {changed} of 8 estimates"
    );
}

/// Bad settings of the state-dependent baseline are clear errors naming the setting.
#[test]
fn invalid_state_baselines_are_clear_errors() {
    let p = ToyProblem::<f64>::new(&example("m1-tied.json"));
    let make_every = |features, decay, ridge, fit_every| {
        Baselined::<_, f64>::new(
            p.clone(),
            1,
            &Baseline::StateDependent {
                features,
                time: false,
                decay,
                ridge,
                fit_every,
            },
        )
    };
    let make = |features, decay, ridge| make_every(features, decay, ridge, None);
    let e = make_every(None, None, None, Some(0)).unwrap_err();
    assert!(e.to_string().contains("fit_every = 0"), "{e}");
    let e = make(Some(0), None, None).unwrap_err();
    assert!(e.to_string().contains("features = 0"), "{e}");
    let e = make(None, Some(ConfigNumber::ratio(-1, 2)), None).unwrap_err();
    assert!(e.to_string().contains("decay"), "{e}");
    let e = make(None, None, Some(ConfigNumber::ratio(-1, 2))).unwrap_err();
    assert!(e.to_string().contains("ridge"), "{e}");
    // More features than the problem has: refused at the first estimate.
    let mut o = make(Some(7), None, None).unwrap();
    let theta = DVector::from_vec(vec![0.0]);
    let mut rng = KitRng::seed_from_u64(1);
    let mut cost = Cost::default();
    let t = o
        .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
        .unwrap();
    let e = o
        .estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
        .unwrap_err();
    assert!(e.to_string().contains("7 state features"), "{e}");
}

#[test]
fn the_reference_values_on_m1() {
    // math.md §1.4, M1 at θ = 0 from its prefix table: ψ(1) = 1, ψ(0) = −1/3 (P(a = 1) = 1/4),
    // E‖ψ‖² = 3/4·1/9 + 1/4 = 1/3, E[g ψ] = 5/24, so b* = 5/8 and
    // E‖g_b‖² = 185/192 − 2b·5/24 + b²/3.
    let p = ToyProblem::<Q>::new(&example("m1-tied.json"));
    let o = optimal_baselines(&p, &qs(&["0"])).unwrap();
    assert_eq!(o.cross, qs(&["5/24"]));
    assert_eq!(o.score_moment, qs(&["1/3"]));
    assert_eq!(o.constant, q("5/8"));
    assert_eq!(o.time_indexed, qs(&["5/8"]));
    assert_eq!(o.second_moment_constant, q("185/192") - q("25/192"));
    assert_eq!(o.reduction_constant(), Some(q("185/160")));
    let m = baselined_moments(&p, &qs(&["0"]), &qs(&["1"])).unwrap();
    assert_eq!(m.second_moment, q("169/192"));
    assert_eq!(m.expected_estimate, qs(&["-1/2"]));
}

/// The estimated optimum: the first trajectory is estimated without a baseline, the next with
/// the b_i of the first one only (committed at the next roll-out), and with those fixed the
/// estimate is exactly unbiased.
#[test]
fn the_estimated_baseline_uses_earlier_trajectories_only() {
    let mdp = example("three-state.json");
    let mut p = ToyProblem::<Q>::new(&mdp);
    let theta =
        DVector::from_vec(ilopt::scalar::parse_exact_list("-1/2,3,1/4,-7/2,1/3,1").unwrap());
    let grad = forward(&p, theta.as_slice()).unwrap().gradient;
    for time_indexed in [true, false] {
        let mut oracle = Baselined::<_, Q>::new(
            p.clone(),
            1,
            &Baseline::Estimated {
                time_indexed,
                decay: None,
            },
        )
        .unwrap();
        let mut rng = KitRng::seed_from_u64(7);
        let mut cost = Cost::default();
        let first = oracle
            .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
            .unwrap();
        let g1 = oracle
            .estimate(&theta, &first, EstimatorForm::Causal, &mut cost)
            .unwrap();
        let plain = p
            .estimate(&theta, &first[0], EstimatorForm::Causal, &mut cost)
            .unwrap();
        assert_eq!(g1, plain, "no earlier trajectory: no baseline");
        // The next roll-out commits the first trajectory's statistics: b_i = g·ψ_i/‖ψ_i‖².
        let _ = oracle
            .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
            .unwrap();
        let table = p.table(theta.as_slice()).unwrap();
        let t = &first[0];
        let h = mdp.horizon;
        let scored = p.scored_actions(&t.states[..h - 1], &t.actions[..h - 2]);
        let full = |s: usize, a: usize| {
            let mut v = vec![Q::zero(); table.dim];
            table.add_block_unscaled(&mut v, s, table.score(s, a));
            v
        };
        let psi: Vec<Vec<Q>> = scored
            .iter()
            .enumerate()
            .map(|(i, &a)| full(t.states[i], a))
            .collect();
        let running = oracle.running().unwrap();
        let (mut num, mut den) = (Q::zero(), Q::zero());
        for (i, s) in psi.iter().enumerate() {
            let (c, m) = (dot(plain.as_slice(), s), norm_sq(s));
            num += &c;
            den += &m;
            if !m.is_certainly_zero() {
                assert_eq!(running.time_indexed(i), Some(c / m));
            }
        }
        if !den.is_certainly_zero() {
            assert_eq!(running.constant(), Some(num / den));
        }
        // With these fixed (no roll-out in between), the estimate is exactly unbiased.
        let all = trajectories(&p, theta.as_slice());
        let mean = expectation(&all, |t| {
            oracle
                .estimate(&theta, &vec![t.clone()], EstimatorForm::Causal, &mut cost)
                .unwrap()
                .as_slice()
                .to_vec()
        });
        assert_eq!(mean, grad, "time_indexed = {time_indexed}");
    }
}

/// The `f64` oracle with a baseline against the exact one on the same trajectories: inside the
/// interval run of the same code (the kit's tolerance policy), for every kind.
#[test]
fn f64_baselined_oracle_agrees_with_the_exact_one() {
    let mdp = example("three-state.json");
    let theta_q = ilopt::scalar::parse_exact_list("-1/2,3,1/4,-7/2,1/3,1").unwrap();
    let theta_f: DVector<f64> = DVector::from_iterator(6, theta_q.iter().map(Scalar::to_f64));
    let theta_x: DVector<Q> = DVector::from_vec(theta_q.clone());
    let theta_i: DVector<Interval> =
        DVector::from_iterator(6, theta_q.iter().map(<Interval as Scalar>::from_rational));
    let mut pf = ToyProblem::<f64>::new(&mdp);
    let mut rng = KitRng::seed_from_u64(3);
    let mut cost = Cost::default();
    let batch: Vec<ToyTrajectory> = (0..4)
        .map(|_| {
            pf.rollout(&Behaviour::Learner(&theta_f), &mut rng, &mut cost)
                .unwrap()
        })
        .collect();
    let k = mdp.horizon - 2;
    let kinds = [
        (
            1,
            Baseline::Constant {
                value: ConfigNumber::ratio(1, 3),
            },
        ),
        (
            1,
            Baseline::TimeIndexed {
                values: (0..k)
                    .map(|i| ConfigNumber::ratio(i as i64 - 1, 2))
                    .collect(),
            },
        ),
        (4, Baseline::LeaveOneOut),
    ];
    for (m, kind) in kinds {
        let mut of = Baselined::<_, f64>::new(pf.clone(), m, &kind).unwrap();
        let mut ox = Baselined::<_, Q>::new(ToyProblem::<Q>::new(&mdp), m, &kind).unwrap();
        let mut oi =
            Baselined::<_, Interval>::new(ToyProblem::<Interval>::new(&mdp), m, &kind).unwrap();
        for chunk in batch.chunks(m) {
            let chunk = chunk.to_vec();
            let x = estimates_agree(
                (&mut of, &mut ox, &mut oi),
                (&theta_f, &theta_x, &theta_i),
                &chunk,
                &format!("{kind:?}"),
            );
            // The baselined estimate differs from the plain one by Σ b_i ψ_i, computed here by
            // the independent causal code of the toy oracle.
            if m == 1 {
                let plain = causal(
                    &ToyProblem::<Q>::new(&mdp).table(&theta_q).unwrap(),
                    &chunk[0].states[..mdp.horizon - 1],
                    ToyProblem::<Q>::new(&mdp).scored_actions(
                        &chunk[0].states[..mdp.horizon - 1],
                        &chunk[0].actions[..k],
                    ),
                );
                assert_ne!(
                    x.as_slice(),
                    plain.as_slice(),
                    "{kind:?}: the baseline changes the estimate"
                );
            }
        }
    }
}

#[test]
fn invalid_baselines_are_clear_errors() {
    let p = ToyProblem::<f64>::new(&example("m1-tied.json"));
    let e = Baselined::<_, f64>::new(p.clone(), 1, &Baseline::LeaveOneOut).unwrap_err();
    assert!(
        matches!(e, OracleError::Baseline(ref m) if m.contains("at least 2")),
        "{e}"
    );
    let e = Baselined::<_, f64>::new(
        p.clone(),
        1,
        &Baseline::Estimated {
            time_indexed: true,
            decay: Some(ConfigNumber::ratio(3, 2)),
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("decay"), "{e}");
    let mut o = Baselined::<_, f64>::new(
        p.clone(),
        1,
        &Baseline::Constant {
            value: ConfigNumber::ratio(1, 2),
        },
    )
    .unwrap();
    let theta = DVector::from_vec(vec![0.0]);
    let mut rng = KitRng::seed_from_u64(1);
    let mut cost = Cost::default();
    let t = o
        .rollout(&Behaviour::Learner(&theta), &mut rng, &mut cost)
        .unwrap();
    assert!(matches!(
        o.estimate(&theta, &t, EstimatorForm::Full, &mut cost),
        Err(OracleError::Baseline(_))
    ));
    let mut short =
        Baselined::<_, f64>::new(p, 1, &Baseline::TimeIndexed { values: vec![] }).unwrap();
    let e = short
        .estimate(&theta, &t, EstimatorForm::Causal, &mut cost)
        .unwrap_err();
    assert!(e.to_string().contains("time-indexed"), "{e}");
}

#[test]
fn no_baseline_is_bit_identical_to_the_plain_minibatch() {
    let p = ToyProblem::<f64>::new(&example("three-state.json"));
    let theta = DVector::from_vec(vec![-0.5, 3.0, 0.25, -3.5, 0.1, 1.0]);
    let mut plain = ilopt::batched::Batched::new(p.clone(), 3).unwrap();
    let mut none = Baselined::<_, f64>::new(p, 3, &Baseline::None).unwrap();
    let (mut r1, mut r2) = (KitRng::seed_from_u64(9), KitRng::seed_from_u64(9));
    let (mut c1, mut c2) = (Cost::default(), Cost::default());
    for _ in 0..5 {
        let t1 = plain
            .rollout(&Behaviour::Learner(&theta), &mut r1, &mut c1)
            .unwrap();
        let t2 = none
            .rollout(&Behaviour::Learner(&theta), &mut r2, &mut c2)
            .unwrap();
        assert_eq!(t1, t2);
        let g1 = plain
            .estimate(&theta, &t1, EstimatorForm::Causal, &mut c1)
            .unwrap();
        let g2 = none
            .estimate(&theta, &t2, EstimatorForm::Causal, &mut c2)
            .unwrap();
        assert_eq!(
            g1.as_slice()
                .iter()
                .map(|x| x.to_bits())
                .collect::<Vec<_>>(),
            g2.as_slice()
                .iter()
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        );
    }
    assert_eq!(c1, c2);
}

#[test]
fn the_configuration_round_trips_through_json() {
    for b in [
        Baseline::None,
        Baseline::Constant {
            value: ConfigNumber::ratio(1, 3),
        },
        Baseline::TimeIndexed {
            values: vec![ConfigNumber::ratio(1, 2), ConfigNumber::from(0.25)],
        },
        Baseline::Estimated {
            time_indexed: false,
            decay: Some(ConfigNumber::ratio(9, 10)),
        },
        Baseline::LeaveOneOut,
        Baseline::StateDependent {
            features: Some(4),
            time: true,
            decay: Some(ConfigNumber::ratio(99, 100)),
            ridge: None,
            fit_every: None,
        },
        Baseline::StateDependent {
            features: None,
            time: false,
            decay: None,
            ridge: Some(ConfigNumber::from(0.5)),
            fit_every: Some(3),
        },
    ] {
        let text = serde_json::to_string(&b).unwrap();
        let back: Baseline = serde_json::from_str(&text).unwrap();
        assert_eq!(back, b, "{text}");
    }
    let b: Baseline = serde_json::from_str(r#"{"kind": "leave-one-out"}"#).unwrap();
    assert_eq!(b, Baseline::LeaveOneOut);
    let b: Baseline = serde_json::from_str(r#"{"kind": "state-dependent"}"#).unwrap();
    assert_eq!(
        b,
        Baseline::StateDependent {
            features: None,
            time: false,
            decay: None,
            ridge: None,
            fit_every: None,
        }
    );
}

/// A given baseline enters the real tasks' recorded decisions as loss shifts
/// `δ_t = b_t − b_{t−1}` (summation by parts, `ilopt::baseline::baselined_estimate`); that sum
/// agrees with the baselined estimate
/// assembled term by term from the stored scores, for the logistic policy (its own fixed-
/// dimension loop) and the softmax policy (the default records), and with b = 0 it is the plain
/// estimate bit for bit.
#[test]
fn the_records_route_agrees_with_the_term_by_term_one() {
    use ilopt::oracle::Given;
    use ilopt::policy::{Logistic, Softmax};
    use ilopt::task::cartpole::{self, CartPoleTask};
    use ilopt::task::{AfterEnd, TaskProblem};
    use ilopt::tolerance::derivative_f64_agrees;

    fn check<P>(p: &mut TaskProblem<CartPoleTask<f64>, P>, theta: &DVector<f64>)
    where
        P: ilopt::policy::LikelihoodRatio<f64, Action = usize, Label = usize>
            + EstimatorKernel<f64>,
    {
        let mut rng = KitRng::seed_from_u64(21);
        let mut cost = Cost::default();
        for _ in 0..6 {
            let t = p
                .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .unwrap();
            let n = t.len();
            let zero = 0.0;
            let recorded =
                baselined_estimate(p, theta, &t, Given::Constant(&zero), &mut cost).unwrap();
            let plain = p
                .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap();
            assert_eq!(
                recorded.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                plain.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "b = 0 is the plain estimate"
            );
            let ramp: Vec<f64> = (0..n).map(|i| 3.0 - i as f64 / 50.0).collect();
            let constant = 2.5;
            for given in [Given::Constant(&constant), Given::TimeIndexed(&ramp)] {
                let recorded = baselined_estimate(p, theta, &t, given, &mut cost).unwrap();
                let mut terms = DecisionTerms::new();
                p.decision_terms(theta, &t, None, &mut terms, &mut cost)
                    .unwrap();
                terms.finish();
                let mut direct = vec![0.0; theta.len()];
                terms.estimate_into(|i| given.at(i).copied(), &mut direct);
                assert!(
                    derivative_f64_agrees(recorded.as_slice(), &direct),
                    "{given:?}: {recorded:?} vs {direct:?}"
                );
            }
        }
    }
    let mut logistic = TaskProblem::fixed(
        CartPoleTask::<f64>::with_lqr().unwrap(),
        Logistic::new(cartpole::FEATURES).unwrap(),
        120,
        AfterEnd::Reset,
    )
    .unwrap();
    check(
        &mut logistic,
        &DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1]),
    );
    let mut softmax = TaskProblem::fixed(
        CartPoleTask::<f64>::with_lqr().unwrap(),
        Softmax::new(2, cartpole::FEATURES).unwrap(),
        120,
        AfterEnd::Reset,
    )
    .unwrap();
    check(
        &mut softmax,
        &DVector::from_vec(vec![0.1, -0.2, 0.3, 0.5, 0.0, 0.2, 0.1, -0.4, 0.3, 0.1]),
    );
}

/// The real tasks' per-decision terms with no baseline reproduce the task's own estimators (an
/// independent pass): the plain causal estimate and both importance-weighted old-point estimates,
/// on CartPole (fixed horizon with resets) and on the obstacle task (fixed horizon with an
/// absorbing tail), to the kit's f64 derivative tolerance.
#[test]
fn task_decision_terms_reproduce_the_task_estimators() {
    use ilopt::policy::Logistic;
    use ilopt::task::cartpole::{self, CartPoleTask};
    use ilopt::task::{AfterEnd, TaskProblem};
    use ilopt::tolerance::derivative_f64_agrees;

    fn check<P: PerDecisionTerms<f64>>(
        p: &mut P,
        theta: &DVector<f64>,
        theta_new: &DVector<f64>,
        what: &str,
    ) {
        let mut rng = KitRng::seed_from_u64(4);
        let mut cost = Cost::default();
        let mut terms = DecisionTerms::new();
        for _ in 0..5 {
            let t = p
                .rollout(&Behaviour::Learner(theta_new), &mut rng, &mut cost)
                .unwrap();
            let mut g = vec![0.0; theta.len()];
            p.decision_terms(theta, &t, None, &mut terms, &mut cost)
                .unwrap();
            terms.finish();
            terms.estimate_into(|_| None, &mut g);
            let plain = p
                .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap();
            assert!(
                derivative_f64_agrees(&g, plain.as_slice()),
                "{what}: {g:?} vs {plain:?}"
            );
            for w in [Weighting::Trajectory, Weighting::PerDecision] {
                p.decision_terms(theta, &t, Some((theta_new, w)), &mut terms, &mut cost)
                    .unwrap();
                terms.finish();
                terms.estimate_into(|_| None, &mut g);
                let direct = p
                    .weighted_estimate(theta, theta_new, &t, w, &mut cost)
                    .unwrap();
                assert!(
                    derivative_f64_agrees(&g, direct.as_slice()),
                    "{what}, {w:?}: {g:?} vs {direct:?}"
                );
            }
        }
    }
    let mut cartpole = TaskProblem::fixed(
        CartPoleTask::<f64>::with_lqr().unwrap(),
        Logistic::new(cartpole::FEATURES).unwrap(),
        150,
        AfterEnd::Reset,
    )
    .unwrap();
    check(
        &mut cartpole,
        &DVector::from_vec(vec![0.3, 1.0, 8.0, 2.0, 0.1]),
        &DVector::from_vec(vec![0.25, 1.1, 7.5, 2.0, 0.15]),
        "cartpole",
    );
    let (mut obstacle, w) = crate::common::absorbing_obstacle_problem();
    let mut w_new = w.clone();
    w_new[1] = 0.05;
    check(&mut obstacle, &w, &w_new, "obstacle");
    // The same roll-outs (same seed) include absorbing tails.
    let mut rng = KitRng::seed_from_u64(4);
    let absorbed = (0..5)
        .filter(|_| {
            obstacle
                .rollout(&Behaviour::Learner(&w_new), &mut rng, &mut Cost::default())
                .unwrap()
                .absorbed
                .is_some()
        })
        .count();
    assert!(
        absorbed > 0,
        "no absorbing tail among the checked trajectories"
    );
}

/// `fit_every`: with e = 3 the state-dependent oracle takes the statistics of trajectories 0, 3,
/// 6, … only, so its weights equal, bit for bit, those of an oracle that takes every trajectory
/// and is shown only those; a trajectory whose statistics are not taken gets the same estimate,
/// bit for bit, as from an oracle with the same weights that takes its statistics (features by
/// columns). On CartPole (resets; the logistic policy's products pass forms each `w·φ_i` off
/// the stored feature rows, `Baselines::Linear`) and the obstacle task (an absorbing tail; the
/// Gaussian policy's default products pass, `ScoreProducts::add_rows`, forms the baselines off
/// the stored rows first and makes the correction alone). Fails if
/// the selection depended on anything but the count, if a row route summed `w·φ_i` in another
/// order or corrected a decision that is not scored, or if the correction stopped with the
/// statistics.
#[test]
fn fit_every_takes_every_eth_trajectory_and_leaves_the_estimates_unchanged() {
    use ilopt::policy::{LikelihoodRatio, Logistic};
    use ilopt::task::cartpole::{self, CartPoleTask};
    use ilopt::task::{AfterEnd, Horizon, Task, TaskProblem};
    use std::borrow::Borrow;

    fn check<T, P>(p: &TaskProblem<T, P>, theta: &DVector<f64>, k: usize)
    where
        T: Task<f64> + Clone,
        P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64> + Clone,
        T::Label: Borrow<P::Label>,
    {
        let make = |fit_every| {
            Baselined::<_, f64>::new(
                p.clone(),
                1,
                &Baseline::StateDependent {
                    features: None,
                    time: true,
                    decay: None,
                    ridge: None,
                    fit_every: Some(fit_every),
                },
            )
            .unwrap()
        };
        // `every1` is shown trajectories 0, 3, 6, … only; its clones estimate every trajectory
        // with its weights and are dropped with their statistics.
        let (mut every3, mut every1) = (make(3), make(1));
        let mut rng = KitRng::seed_from_u64(17);
        let mut other = KitRng::seed_from_u64(0);
        let mut cost = Cost::default();
        for j in 0..10 {
            let t = every3
                .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .unwrap();
            every1
                .rollout(&Behaviour::Learner(theta), &mut other, &mut cost)
                .unwrap();
            assert_eq!(every3.state_weights(), every1.state_weights(), "before {j}");
            let g3 = every3
                .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap();
            let g1 = every1
                .clone()
                .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                .unwrap();
            assert_eq!(g3, g1, "trajectory {j}");
            if j % 3 == 0 {
                every1
                    .estimate(theta, &t, EstimatorForm::Causal, &mut cost)
                    .unwrap();
            }
        }
        for o in [&mut every3, &mut every1] {
            o.rollout(&Behaviour::Learner(theta), &mut other, &mut cost)
                .unwrap();
        }
        let w = every3.state_weights().unwrap();
        assert!(w.len() == k + 2 && w.iter().any(|x| *x != 0.0), "{w:?}");
        assert_eq!(Some(w), every1.state_weights());
    }
    let cartpole = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().unwrap(),
        policy: Logistic::new(cartpole::FEATURES).unwrap(),
        horizon: Horizon::fixed(200, AfterEnd::Reset),
    };
    let theta = DVector::from_vec(vec![0.1, 0.5, 3.0, 1.0, 0.05]);
    check(&cartpole, &theta, cartpole::FEATURES);
    let (obstacle, w) = crate::common::absorbing_obstacle_problem();
    check(&obstacle, &w, ilopt::task::obstacle::FEATURES);
}
