//! The CartPole + logistic oracle, generic against hand-specialised (the target: the f64
//! instantiation of the generic oracle within 10% of a hand-specialised f64 version), timed
//! for shared machines, where criterion's means swing with the neighbours' load.
//!
//! The modes are interleaved episode by episode (every mode runs seed 0, then every mode seed 1,
//! …), and each episode is timed on its own. The report gives, per mode, the time per step of its
//! seeds' *fastest episodes*: the same seed gives the same episode every time and interference only
//! ever slows an episode down, so over many rounds each seed's minimum converges to its undisturbed
//! time — the most repeatable figure on a shared machine. Per generic/specialised pair it gives the
//! ratio of those, and the median and quartiles of per-round ratios (both sides measured in the
//! same round, microseconds apart).
//!
//! `cargo bench --bench oracle_probe -- generic,spec,rollout,specroll,estimate,specest 1 300`
//! (modes, repetitions of the 16 seeds per round, rounds; these are the defaults). Mode `softmax`:
//! the same roll-out and causal estimate with the two-action softmax policy (rows `(−θ/2, θ/2)`,
//! the same `π(1|s)`), compared with `spec`; mode `ppo`: the same with the committed PPO expert
//! as the labeller (the chapter-4 experiments' CartPole set-up), compared with `softmax`. Mode `specfresh`: the specialised roll-out into
//! freshly reserved storage, as the generic roll-out returns (it reuses one buffer otherwise).
//! Modes `pairs` and `loo`: the causal estimate alone over a pair of the generic trajectories
//! (seeds s and s + 1), the plain mean of the pair against the leave-one-out baseline
//! (`Baselined`, m = 2), compared with each other. Modes `single`, `constant` and `estimated`: the
//! causal estimate alone of one trajectory through `Baselined` with m = 1, without a baseline, with
//! the constant b = 50 and with the variance-minimising per-decision constants estimated from the
//! earlier estimates (decay 0.99), the last two compared with the first; mode `state`: the same
//! with the state-dependent baseline (the features, the decision index and 1; weights fitted on
//! every probe trajectory before the timing; every estimate sums its statistics), compared with
//! `single`. Modes `oracle` and
//! `oracle-estimated`: a whole oracle call through `Baselined` with m = 1 (roll-out of the
//! learner, then its causal estimate), without a baseline and with the estimated per-decision
//! constants (their statistics committed at each roll-out, as in training), compared; mode
//! `oracle-state` the same with the state-dependent baseline (the statistics of the default share
//! of trajectories, `DEFAULT_FIT_EVERY`), `oracle-state-all` with those of every trajectory. Modes
//! `weighted`, `weighted-estimated`, `weighted-pairs` and `weighted-loo`: the per-decision
//! importance-weighted old-point estimate of math.md §4 (IS-STORM's, θ_old = θ + 0.01 per entry)
//! on one trajectory without a baseline and with the estimated constants (committed from every
//! probe trajectory's statistics before the timing), and on the pairs
//! without a baseline and with leave-one-out, each baselined one compared with its plain one.
//! Modes `softmax-single`, `softmax-constant`, `softmax-pairs` and `softmax-loo`: modes `single`,
//! `constant`, `pairs` and `loo` with the softmax policy of mode `softmax` on its own roll-outs
//! (a policy on the kernel's default records, ∇l_t and ψ_t per decision), compared likewise.

#[path = "support/specialised.rs"]
mod specialised;
#[path = "support/state_baseline.rs"]
mod state_baseline;

use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined};
use ilopt::expert::lqr::LqrExpert;
use ilopt::policy::{Logistic, Softmax};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::task::TaskProblem;
use ilopt::task::cartpole::{self, CartPoleTask};
use nalgebra::DVector;
use rand::SeedableRng;
use specialised::{D, Specialised, Trajectory};
use state_baseline::fitted_state;
use std::collections::BTreeMap;
use std::hint::black_box;
use std::time::Instant;

const SEEDS: u64 = 16;
const THETA: [f64; D] = [0.3, 1.0, 8.0, 2.0, 0.1];

/// One roll-out of the learner θ and its causal estimate: the steps taken and the gradient's first
/// entry (so that nothing is optimised away).
fn oracle_once<P: IlProblem<f64>>(
    p: &mut P,
    theta: &DVector<f64>,
    rng: &mut KitRng,
    cost: &mut Cost,
) -> (u64, f64) {
    let before = cost.env_steps;
    let tr = p
        .rollout(&Behaviour::Learner(theta), rng, cost)
        .expect("roll-out");
    let steps = cost.env_steps - before;
    let g = p
        .estimate(theta, &tr, EstimatorForm::Causal, cost)
        .expect("estimate");
    (steps, black_box(g)[0])
}

/// Every mode the probe knows.
const MODES: [&str; 27] = [
    "generic",
    "spec",
    "rollout",
    "specroll",
    "estimate",
    "specest",
    "softmax",
    "ppo",
    "specfresh",
    "pairs",
    "loo",
    "single",
    "constant",
    "estimated",
    "state",
    "oracle",
    "oracle-estimated",
    "oracle-state",
    "oracle-state-all",
    "weighted",
    "weighted-estimated",
    "weighted-pairs",
    "weighted-loo",
    "softmax-single",
    "softmax-constant",
    "softmax-pairs",
    "softmax-loo",
];

/// Report a bad argument and exit with status 2.
fn fail(message: &str) -> ! {
    eprintln!("oracle_probe: {message}");
    std::process::exit(2)
}

fn main() {
    // `cargo bench` passes `--bench` (and criterion-style flags) to every bench binary.
    let mut args = std::env::args().skip(1).filter(|a| !a.starts_with("--"));
    let modes = args
        .next()
        .unwrap_or_else(|| "generic,spec,rollout,specroll,estimate,specest".into());
    let count = |arg: Option<String>, default: u64, what: &str| match arg {
        None => default,
        Some(x) => match x.parse::<u64>() {
            Ok(n) if n > 0 => n,
            _ => fail(&format!("{what} must be a positive integer, got {x:?}")),
        },
    };
    let reps = count(args.next(), 1, "repetitions (2nd argument)");
    let rounds = count(args.next(), 300, "rounds (3rd argument)");
    if let Some(bad) = modes.split(',').find(|m| !MODES.contains(m)) {
        fail(&format!(
            "unknown mode {bad:?} (1st argument); modes: {}",
            MODES.join(",")
        ));
    }

    let mut p = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().expect("LQR design"),
        policy: Logistic::new(cartpole::FEATURES).expect("policy"),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let theta = DVector::from_column_slice(&THETA);
    let theta_old = theta.map(|x| x + 0.01);
    let mut soft = TaskProblem {
        task: CartPoleTask::<f64>::with_lqr().expect("LQR design"),
        policy: Softmax::new(2, cartpole::FEATURES).expect("policy"),
        horizon: ilopt::task::Horizon::Episodic,
    };
    // The chapter-4 experiments' CartPole labeller: the committed PPO expert's greedy action.
    let mut soft_ppo = TaskProblem {
        task: CartPoleTask::<f64>::with_ppo(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json"),
        )
        .expect("the committed PPO expert"),
        policy: Softmax::new(2, cartpole::FEATURES).expect("policy"),
        horizon: ilopt::task::Horizon::Episodic,
    };
    let soft_theta: DVector<f64> = DVector::from_iterator(
        2 * D,
        THETA
            .iter()
            .map(|x| -x / 2.0)
            .chain(THETA.iter().map(|x| x / 2.0)),
    );
    // The softmax policy's own roll-outs, one per seed, through `Baselined` as the logistic
    // policy's: alone (m = 1) without a baseline and with b = 50, and in pairs without a baseline
    // and with leave-one-out.
    let soft_singles: Vec<Vec<_>> = (0..SEEDS)
        .map(|seed| {
            let mut rng = KitRng::seed_from_u64(seed);
            let t = soft
                .rollout(
                    &Behaviour::Learner(&soft_theta),
                    &mut rng,
                    &mut Cost::default(),
                )
                .expect("roll-out");
            vec![t]
        })
        .collect();
    let soft_pairs: Vec<Vec<_>> = (0..SEEDS as usize)
        .map(|s| {
            let next = (s + 1) % SEEDS as usize;
            vec![soft_singles[s][0].clone(), soft_singles[next][0].clone()]
        })
        .collect();
    let soft_baselined = |m, baseline: &Baseline| {
        Baselined::new(soft.clone(), m, baseline).expect("softmax baselined")
    };
    let b50 = Baseline::Constant {
        value: ConfigNumber::ratio(50, 1),
    };
    let mut soft_single = soft_baselined(1, &Baseline::None);
    let mut soft_constant = soft_baselined(1, &b50);
    let mut soft_plain_pairs = soft_baselined(2, &Baseline::None);
    let mut soft_loo = soft_baselined(2, &Baseline::LeaveOneOut);
    let gain = *LqrExpert::cartpole().expect("LQR design").gain();
    let fast = Specialised {
        k: std::array::from_fn(|i| gain[i]),
        max_steps: ilopt::env::cartpole::MAX_EPISODE_STEPS,
    };
    let generic_trajectories: Vec<_> = (0..SEEDS)
        .map(|seed| {
            let mut rng = KitRng::seed_from_u64(seed);
            p.rollout(&Behaviour::Learner(&theta), &mut rng, &mut Cost::default())
                .expect("roll-out")
        })
        .collect();
    let fast_trajectories: Vec<_> = (0..SEEDS)
        .map(|seed| {
            let mut t = Trajectory::default();
            fast.rollout(&THETA, &mut KitRng::seed_from_u64(seed), &mut t);
            t
        })
        .collect();

    let mut plain_pairs = Baselined::new(p.clone(), 2, &Baseline::None).expect("pairs");
    let mut loo_pairs = Baselined::new(p.clone(), 2, &Baseline::LeaveOneOut).expect("pairs");
    let pair_of = |seed: u64| {
        let next = (seed + 1) % SEEDS;
        vec![
            generic_trajectories[seed as usize].clone(),
            generic_trajectories[next as usize].clone(),
        ]
    };
    let pairs: Vec<_> = (0..SEEDS).map(pair_of).collect();
    let singles: Vec<_> = generic_trajectories
        .iter()
        .map(|t| vec![t.clone()])
        .collect();
    let mut single = Baselined::new(p.clone(), 1, &Baseline::None).expect("single");
    let mut constant = Baselined::new(
        p.clone(),
        1,
        &Baseline::Constant {
            value: ConfigNumber::ratio(50, 1),
        },
    )
    .expect("constant");
    let mut estimated = Baselined::new(
        p.clone(),
        1,
        &Baseline::Estimated {
            time_indexed: true,
            decay: Some(ConfigNumber::ratio(99, 100)),
        },
    )
    .expect("estimated");
    // The state-dependent baseline with the decision index, its weights fitted before the
    // timing on the probe trajectories (each estimated, then committed by a roll-out) that its
    // `fit_every` takes: every one for mode `state` (whose estimates then sum the statistics of
    // every trajectory), the default share for mode `oracle-state` and every one for
    // `oracle-state-all`.
    let fit = |fit_every| fitted_state(&p, &theta, &singles, fit_every, SEEDS);
    let (mut state, mut oracle_state, mut oracle_state_all) =
        (fit(Some(1)), fit(None), fit(Some(1)));
    let mut oracle_estimated = estimated.clone();
    // The weighted estimates use the committed baselines: statistics from every probe trajectory,
    // committed by one roll-out, as in training.
    let mut weighted_estimated = estimated.clone();
    let mut warm = Cost::default();
    for one in &singles {
        weighted_estimated
            .estimate(&theta, one, EstimatorForm::Causal, &mut warm)
            .expect("estimate");
    }
    let mut rng = KitRng::seed_from_u64(SEEDS);
    weighted_estimated
        .rollout(&Behaviour::Learner(&theta), &mut rng, &mut warm)
        .expect("roll-out");

    let mut t = Trajectory::default();
    let modes: Vec<&str> = modes.split(',').collect();
    // Per round, each mode's time: ratios within a round are immune to the machine's slow phases.
    let mut per_round: Vec<BTreeMap<&str, f64>> = Vec::new();
    // Per (mode, seed): the episode's steps and its fastest time over all rounds. The same seed
    // gives the same episode every time, and interference only ever slows an episode down, so
    // the minimum converges to the undisturbed time.
    let mut fastest: BTreeMap<(&str, u64), (u64, f64)> = BTreeMap::new();
    let mut acc = 0.0;
    for _ in 0..rounds {
        let mut this_round: BTreeMap<&str, (u64, f64)> = BTreeMap::new();
        for _ in 0..reps {
            for seed in 0..SEEDS {
                // The modes interleaved episode by episode, each on the same seed.
                for &mode in &modes {
                    let mut rng = KitRng::seed_from_u64(seed);
                    let mut cost = Cost::default();
                    let th = black_box(&theta);
                    let start = Instant::now();
                    let steps = match mode {
                        "generic" => {
                            let (n, x) = oracle_once(&mut p, th, &mut rng, &mut cost);
                            acc += x;
                            n
                        }
                        "softmax" => {
                            let th = black_box(&soft_theta);
                            let (n, x) = oracle_once(&mut soft, th, &mut rng, &mut cost);
                            acc += x;
                            n
                        }
                        "ppo" => {
                            let th = black_box(&soft_theta);
                            let (n, x) = oracle_once(&mut soft_ppo, th, &mut rng, &mut cost);
                            acc += x;
                            n
                        }
                        "rollout" => p
                            .rollout(&Behaviour::Learner(th), &mut rng, &mut cost)
                            .expect("roll-out")
                            .len() as u64,
                        "estimate" => {
                            let tr = &generic_trajectories[seed as usize];
                            acc += black_box(
                                p.estimate(th, tr, EstimatorForm::Causal, &mut cost)
                                    .expect("estimate"),
                            )[0];
                            tr.len() as u64
                        }
                        "pairs" | "loo" => {
                            let pair = &pairs[seed as usize];
                            let o = if mode == "loo" {
                                &mut loo_pairs
                            } else {
                                &mut plain_pairs
                            };
                            acc += black_box(
                                o.estimate(th, pair, EstimatorForm::Causal, &mut cost)
                                    .expect("estimate"),
                            )[0];
                            pair.iter().map(|tr| tr.len() as u64).sum()
                        }
                        "oracle" => {
                            let (n, x) = oracle_once(&mut single, th, &mut rng, &mut cost);
                            acc += x;
                            n
                        }
                        "oracle-estimated" => {
                            let (n, x) =
                                oracle_once(&mut oracle_estimated, th, &mut rng, &mut cost);
                            acc += x;
                            n
                        }
                        "oracle-state" | "oracle-state-all" => {
                            let o = if mode == "oracle-state" {
                                &mut oracle_state
                            } else {
                                &mut oracle_state_all
                            };
                            let (n, x) = oracle_once(o, th, &mut rng, &mut cost);
                            acc += x;
                            n
                        }
                        "weighted" | "weighted-estimated" | "weighted-pairs" | "weighted-loo" => {
                            let (o, batch) = match mode {
                                "weighted" => (&mut single, &singles[seed as usize]),
                                "weighted-estimated" => {
                                    (&mut weighted_estimated, &singles[seed as usize])
                                }
                                "weighted-pairs" => (&mut plain_pairs, &pairs[seed as usize]),
                                _ => (&mut loo_pairs, &pairs[seed as usize]),
                            };
                            let old = black_box(&theta_old);
                            let w = Weighting::PerDecision;
                            acc += black_box(
                                o.weighted_estimate(old, th, batch, w, &mut cost)
                                    .expect("weighted estimate"),
                            )[0];
                            batch.iter().map(|tr| tr.len() as u64).sum()
                        }
                        "single" | "constant" | "estimated" | "state" => {
                            let one = &singles[seed as usize];
                            let o = match mode {
                                "constant" => &mut constant,
                                "estimated" => &mut estimated,
                                "state" => &mut state,
                                _ => &mut single,
                            };
                            acc += black_box(
                                o.estimate(th, one, EstimatorForm::Causal, &mut cost)
                                    .expect("estimate"),
                            )[0];
                            one[0].len() as u64
                        }
                        "softmax-single" | "softmax-constant" | "softmax-pairs" | "softmax-loo" => {
                            let s = seed as usize;
                            let (o, batch) = match mode {
                                "softmax-single" => (&mut soft_single, &soft_singles[s]),
                                "softmax-constant" => (&mut soft_constant, &soft_singles[s]),
                                "softmax-pairs" => (&mut soft_plain_pairs, &soft_pairs[s]),
                                _ => (&mut soft_loo, &soft_pairs[s]),
                            };
                            let th = black_box(&soft_theta);
                            acc += black_box(
                                o.estimate(th, batch, EstimatorForm::Causal, &mut cost)
                                    .expect("estimate"),
                            )[0];
                            batch.iter().map(|tr| tr.len() as u64).sum()
                        }
                        "spec" => {
                            fast.rollout(black_box(&THETA), &mut rng, &mut t);
                            acc += black_box(Specialised::estimate(black_box(&THETA), &t))[0];
                            t.actions.len() as u64
                        }
                        "specfresh" => {
                            // The hand-specialised roll-out into fresh storage, reserved as the
                            // generic roll-out reserves it (the generic API returns an owned
                            // trajectory).
                            let max = fast.max_steps;
                            let mut fresh = Trajectory {
                                features: Vec::with_capacity(max),
                                actions: Vec::with_capacity(max),
                                labels: Vec::with_capacity(max),
                            };
                            fast.rollout(black_box(&THETA), &mut rng, &mut fresh);
                            fresh.actions.len() as u64
                        }
                        "specroll" => {
                            fast.rollout(black_box(&THETA), &mut rng, &mut t);
                            t.actions.len() as u64
                        }
                        "specest" => {
                            let tr = &fast_trajectories[seed as usize];
                            acc += black_box(Specialised::estimate(black_box(&THETA), tr))[0];
                            tr.actions.len() as u64
                        }
                        other => unreachable!("mode {other} was checked"),
                    };
                    let ns = start.elapsed().as_secs_f64() * 1e9;
                    let r = this_round.entry(mode).or_default();
                    r.0 += steps;
                    r.1 += ns;
                    let f = fastest
                        .entry((mode, seed))
                        .or_insert((steps, f64::INFINITY));
                    f.1 = f.1.min(ns);
                }
            }
        }
        per_round.push(
            this_round
                .into_iter()
                .map(|(mode, (steps, ns))| (mode, ns / steps as f64))
                .collect(),
        );
    }
    black_box(acc);
    // Each mode's time per step from its seeds' fastest episodes.
    let mut best: BTreeMap<&str, f64> = BTreeMap::new();
    for &mode in &modes {
        let (steps, ns) = (0..SEEDS)
            .map(|seed| fastest[&(mode, seed)])
            .fold((0, 0.0), |(s, t), (n, ns)| (s + n, t + ns));
        best.insert(mode, ns / steps as f64);
    }
    for (mode, ns) in &best {
        println!(
            "{mode:>16}: {ns:6.1} ns/step = {:5.2} M trajectory-steps/s",
            1e3 / ns
        );
    }
    for (a, b) in [
        ("generic", "spec"),
        ("rollout", "specroll"),
        ("estimate", "specest"),
        ("softmax", "spec"),
        ("ppo", "softmax"),
        ("loo", "pairs"),
        ("constant", "single"),
        ("estimated", "single"),
        ("state", "single"),
        ("oracle-estimated", "oracle"),
        ("oracle-state", "oracle"),
        ("oracle-state-all", "oracle"),
        ("weighted-estimated", "weighted"),
        ("weighted-loo", "weighted-pairs"),
        ("softmax-constant", "softmax-single"),
        ("softmax-loo", "softmax-pairs"),
    ] {
        let mut ratios: Vec<f64> = per_round
            .iter()
            .filter_map(|r| Some(r.get(a)? / r.get(b)?))
            .collect();
        if ratios.is_empty() {
            continue;
        }
        ratios.sort_by(f64::total_cmp);
        let q = |f: f64| ratios[((ratios.len() - 1) as f64 * f).round() as usize];
        println!(
            "{a:>16} / {b}: fastest episodes {:.3}; median of per-round ratios {:.3} (quartiles \
             {:.3}–{:.3})",
            best[a] / best[b],
            q(0.5),
            q(0.25),
            q(0.75)
        );
    }
}
