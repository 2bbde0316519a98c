//! The PPO expert for CartPole-v1: the committed weights, file validation,
//! reproducible training, and the comparison with the LQR expert on the same seeded episodes.

use approx::assert_abs_diff_eq;
use ilopt::env::Env;
use ilopt::env::cartpole::{CartPole, MAX_EPISODE_STEPS};
use ilopt::expert::lqr::LqrExpert;
use ilopt::expert::ppo::{
    EVAL_EPISODES, EVAL_FIRST_SEED, PpoConfig, PpoError, PpoExpert, PpoExpertFile, PpoTrainer,
    evaluate_cartpole, train,
};
use ilopt::policy::{Mlp, MlpSoftmax};
use ilopt::problem::KitRng;
use ilopt::scalar::Dual;
use rand::SeedableRng;
use std::path::PathBuf;

/// The threshold: mean return ≥ 495 over 100 seeded episodes.
const REQUIRED_MEAN_RETURN: f64 = 495.0;

fn committed_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json")
}

fn committed_text() -> String {
    std::fs::read_to_string(committed_path()).expect("experts/cartpole-ppo.json is committed")
}

/// The copy built into the kit (what `ilopt run` and paper-checks use) is the committed file, and
/// it validates.
#[test]
fn the_embedded_expert_is_the_committed_file_and_validates() {
    assert_eq!(
        ilopt::expert::ppo::COMMITTED_CARTPOLE_EXPERT,
        committed_text()
    );
    PpoExpertFile::committed_cartpole()
        .and_then(|f| f.expert())
        .unwrap();
}

#[test]
fn committed_expert_reaches_495_on_100_seeded_episodes() {
    let expert = PpoExpert::load(committed_path()).unwrap();
    let evaluation = evaluate_cartpole(|s| expert.action(s), 0, 100).unwrap();
    assert_eq!(evaluation.returns.len(), 100);
    eprintln!(
        "PPO expert: mean return {} over 100 episodes, min {}",
        evaluation.mean_return, evaluation.min_return
    );
    assert!(
        evaluation.mean_return >= REQUIRED_MEAN_RETURN,
        "mean return {}",
        evaluation.mean_return
    );
    // The evaluation stored in the file is what the weights actually do.
    let file = PpoExpertFile::read(committed_path()).unwrap();
    assert_eq!(file.evaluation, evaluation);
    assert_eq!(file.evaluation, expert.evaluate().unwrap());
    assert_eq!((EVAL_FIRST_SEED, EVAL_EPISODES), (0, 100));
    // The file's weights are the expert's, and the expert is greedy over its own probabilities.
    assert_eq!(expert.actor_weights(), &file.actor[..]);
    assert_eq!(expert.critic_weights(), &file.critic[..]);
    assert_eq!(expert.hidden(), file.config.hidden);
    for s in [
        [0.0, 0.0, 0.05, 0.0],
        [0.0, 0.0, -0.05, 0.0],
        [0.1, -0.2, 0.01, 0.3],
    ] {
        let [p0, p1] = expert.probabilities(&s).unwrap();
        assert_abs_diff_eq!(p0 + p1, 1.0, epsilon = 1e-12);
        assert_eq!(expert.action(&s).unwrap(), usize::from(p1 > p0));
        assert!(expert.value(&s).unwrap().is_finite());
    }
    // The generic greedy action agrees with the f64 one, in f64 and in dual numbers, on the
    // states of the first evaluation episode.
    let mut env = CartPole::<f64>::new();
    let mut obs = env.reset(&mut KitRng::seed_from_u64(0));
    for _ in 0..MAX_EPISODE_STEPS {
        let a = expert.action(&obs).unwrap();
        assert_eq!(expert.action_in(&obs).unwrap(), a);
        let dual: [Dual<f64>; 4] = std::array::from_fn(|i| Dual::variable(obs[i], i, 4));
        assert_eq!(expert.action_in(&dual).unwrap(), a);
        let step = env.step(a).unwrap();
        if step.done() {
            break;
        }
        obs = step.observation;
    }
    assert!(expert.action_in(&[f64::NAN, 0.0, 0.0, 0.0]).is_err());
    // Pushing right when the pole leans right keeps it up (as for the LQR expert).
    assert_eq!(expert.action(&[0.0, 0.0, 0.05, 0.0]).unwrap(), 1);
    assert_eq!(expert.action(&[0.0, 0.0, -0.05, 0.0]).unwrap(), 0);
}

/// Both experts on the same 100 seeded episodes (the table in `ilopt::expert::ppo`'s docs).
#[test]
fn lqr_and_ppo_on_the_same_100_seeded_episodes() {
    let ppo = PpoExpert::load(committed_path()).unwrap();
    let lqr = LqrExpert::cartpole().unwrap();
    let ppo_eval = evaluate_cartpole(|s| ppo.action(s), 0, 100).unwrap();
    let lqr_eval = evaluate_cartpole(|s| lqr.action(s), 0, 100).unwrap();
    eprintln!("| expert | mean return | min return |");
    eprintln!("|---|---|---|");
    for (name, e) in [("LQR", &lqr_eval), ("PPO (greedy)", &ppo_eval)] {
        eprintln!("| {name} | {} | {} |", e.mean_return, e.min_return);
    }
    assert_eq!(ppo_eval.first_seed, lqr_eval.first_seed);
    assert!(lqr_eval.mean_return >= REQUIRED_MEAN_RETURN);
    assert!(ppo_eval.mean_return >= REQUIRED_MEAN_RETURN);
    // Episodes are capped at 500 steps (reward 1 per step).
    assert!(
        ppo_eval
            .returns
            .iter()
            .chain(&lqr_eval.returns)
            .all(|&r| (1.0..=500.0).contains(&r))
    );
}

/// Rewrites the committed file's JSON with `edit` and parses it.
fn parse_edited(edit: impl FnOnce(&mut serde_json::Value)) -> Result<PpoExpertFile, PpoError> {
    let mut v: serde_json::Value = serde_json::from_str(&committed_text()).unwrap();
    edit(&mut v);
    PpoExpertFile::parse(&v.to_string(), "edited.json")
}

fn invalid_field(r: Result<PpoExpertFile, PpoError>) -> (String, String) {
    match r {
        Err(PpoError::InvalidFile { field, reason, .. }) => (field, reason),
        other => panic!("expected InvalidFile, got {other:?}"),
    }
}

#[test]
fn corrupted_files_give_errors_naming_the_field() {
    // Unedited text parses, and the expert loads from it.
    parse_edited(|_| {}).unwrap().expert().unwrap();

    let (field, reason) = invalid_field(parse_edited(|v| v["actor"][3] = serde_json::Value::Null));
    assert_eq!(field, "actor[3]");
    assert!(reason.contains("finite number"), "{reason}");
    let (field, _) = invalid_field(parse_edited(|v| v["critic"][0] = "NaN".into()));
    assert_eq!(field, "critic[0]");

    // Shape mismatches: a weight missing, or a hidden width that does not fit the weights.
    // One hidden layer of `hidden` units: 4·h + h + 2·h + 2 actor and 4·h + h + h + 1 critic weights.
    let hidden = PpoExpertFile::read(committed_path()).unwrap().config.hidden;
    let actor_dim = MlpSoftmax::new(4, hidden, 2).unwrap().net().param_dim();
    let critic_dim = Mlp::new(4, hidden, 1).unwrap().param_dim();
    assert_eq!((actor_dim, critic_dim), (7 * hidden + 2, 6 * hidden + 1));
    let (field, reason) = invalid_field(parse_edited(|v| {
        v["actor"].as_array_mut().unwrap().pop();
    }));
    assert_eq!(field, "actor");
    assert!(
        reason.contains(&format!("expected {actor_dim} weights")),
        "{reason}"
    );
    let (field, _) = invalid_field(parse_edited(|v| v["config"]["hidden"] = 32.into()));
    assert_eq!(field, "actor");
    let (field, _) = invalid_field(parse_edited(|v| {
        v["critic"].as_array_mut().unwrap().push(0.5.into());
    }));
    assert_eq!(field, "critic");

    // An invalid configuration, a wrong format or version.
    let (field, _) = invalid_field(parse_edited(|v| v["config"]["gamma"] = 1.5.into()));
    assert_eq!(field, "config.gamma");
    let (field, _) = invalid_field(parse_edited(|v| v["config"]["hidden"] = 0.into()));
    assert_eq!(field, "config.hidden");
    let (field, _) = invalid_field(parse_edited(|v| v["format"] = "something-else".into()));
    assert_eq!(field, "format");
    let (field, _) = invalid_field(parse_edited(|v| v["version"] = 2.into()));
    assert_eq!(field, "version");

    // Missing or unknown fields, non-JSON, an overflowing number, a missing file.
    let json_error = |r: Result<PpoExpertFile, PpoError>| match r {
        Err(e @ PpoError::Json { .. }) => e.to_string(),
        other => panic!("expected a JSON error, got {other:?}"),
    };
    let msg = json_error(parse_edited(|v| {
        v.as_object_mut().unwrap().remove("critic");
    }));
    assert!(msg.contains("critic"), "{msg}");
    let msg = json_error(parse_edited(|v| v["extra"] = 1.into()));
    assert!(msg.contains("extra"), "{msg}");
    let msg = json_error(parse_edited(|v| v["config"]["epochz"] = 1.into()));
    assert!(msg.contains("epochz"), "{msg}");
    json_error(PpoExpertFile::parse("not json", "x.json"));
    let overflowing =
        committed_text().replacen("\"actor\": [\n    ", "\"actor\": [\n    1e999, ", 1);
    assert_ne!(overflowing, committed_text());
    json_error(PpoExpertFile::parse(&overflowing, "x.json"));
    let missing = PpoExpert::load("/nonexistent/cartpole-ppo.json");
    assert!(matches!(missing, Err(PpoError::Io { .. })), "{missing:?}");

    // In-memory construction validates too.
    let (a, c) = (actor_dim, critic_dim);
    assert!(PpoExpert::new(hidden, vec![0.0; a], vec![0.0; c]).is_ok());
    assert!(PpoExpert::new(hidden, vec![0.0; a - 1], vec![0.0; c]).is_err());
    assert!(PpoExpert::new(hidden, vec![0.0; a], vec![0.0; c + 1]).is_err());
    assert!(PpoExpert::new(hidden, vec![f64::NAN; a], vec![0.0; c]).is_err());
    assert!(PpoExpert::new(0, vec![], vec![]).is_err());
}

#[test]
fn the_expert_rejects_non_finite_states() {
    let expert = PpoExpert::load(committed_path()).unwrap();
    assert!(matches!(
        expert.action(&[f64::NAN, 0.0, 0.0, 0.0]),
        Err(PpoError::Act(_))
    ));
    assert!(expert.value(&[0.0, f64::INFINITY, 0.0, 0.0]).is_err());
    // A failing controller is an evaluation error naming the episode's seed and the step.
    assert!(evaluate_cartpole(|s| expert.action(s), 0, 0).is_err());
    let err = evaluate_cartpole(|_| Ok::<usize, String>(2), 40, 3).unwrap_err();
    assert!(
        matches!(
            err,
            PpoError::Evaluation {
                seed: 40,
                step: 1,
                ..
            }
        ),
        "{err:?}"
    );
    let mut calls = 0;
    let err = evaluate_cartpole(
        |s| {
            calls += 1;
            if calls == 3 {
                Err("refused".to_string())
            } else {
                expert.action(s).map_err(|e| e.to_string())
            }
        },
        7,
        2,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            PpoError::Evaluation {
                seed: 7,
                step: 3,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("refused"), "{err}");
}

/// A short run: 16 iterations of 256 steps.
fn short_config() -> PpoConfig {
    PpoConfig {
        total_steps: 4096,
        ..PpoConfig::default()
    }
}

/// Same seed ⇒ bit-identical weights; another seed ⇒ other weights; and 4 096 steps of training
/// raise the greedy actor's mean return over seeds 0..100 strictly above that of the same actor
/// before training (its initial weights, drawn from the same seed).
#[test]
fn short_training_is_reproducible_and_improves_on_the_untrained_actor() {
    let config = short_config();
    let bits = |w: &[f64]| w.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    let mut iterations = 0;
    let (a, summary) = train(&config, 7, |s| {
        iterations += 1;
        assert_eq!(s.iteration, iterations);
    })
    .unwrap();
    assert_eq!(iterations, 16);
    assert_eq!(summary.iterations, 16);
    assert_eq!(summary.env_steps, 4096);
    let (b, summary_b) = train(&config, 7, |_| {}).unwrap();
    assert_eq!(bits(a.actor_weights()), bits(b.actor_weights()));
    assert_eq!(bits(a.critic_weights()), bits(b.critic_weights()));
    assert_eq!(summary, summary_b);
    let (c, _) = train(&config, 8, |_| {}).unwrap();
    assert_ne!(bits(a.actor_weights()), bits(c.actor_weights()));

    let untrained = PpoTrainer::new(&config, 7).unwrap().expert();
    let before = untrained.evaluate().unwrap().mean_return;
    let after = a.evaluate().unwrap().mean_return;
    eprintln!("greedy mean return over seeds 0..100: untrained {before}, after 4096 steps {after}");
    assert!(after > before, "untrained {before}, trained {after}");
}

#[test]
fn invalid_configurations_are_rejected_naming_the_field() {
    let field_of = |c: PpoConfig| match PpoTrainer::new(&c, 0) {
        Err(PpoError::InvalidConfig { field, .. }) => field,
        other => panic!("expected InvalidConfig, got {other:?}"),
    };
    let d = PpoConfig::default;
    assert!(d().validate().is_ok());
    assert_eq!(field_of(PpoConfig { hidden: 0, ..d() }), "hidden");
    assert_eq!(field_of(PpoConfig { envs: 0, ..d() }), "envs");
    assert_eq!(field_of(PpoConfig { epochs: 0, ..d() }), "epochs");
    assert_eq!(
        field_of(PpoConfig {
            minibatch_size: 257,
            ..d()
        }),
        "minibatch_size"
    );
    assert_eq!(
        field_of(PpoConfig {
            gamma: f64::NAN,
            ..d()
        }),
        "gamma"
    );
    assert_eq!(
        field_of(PpoConfig {
            gae_lambda: -0.1,
            ..d()
        }),
        "gae_lambda"
    );
    assert_eq!(
        field_of(PpoConfig {
            clip_epsilon: 0.0,
            ..d()
        }),
        "clip_epsilon"
    );
    assert_eq!(
        field_of(PpoConfig {
            actor_learning_rate: f64::INFINITY,
            ..d()
        }),
        "actor_learning_rate"
    );
    assert_eq!(
        field_of(PpoConfig {
            max_grad_norm: Some(-1.0),
            ..d()
        }),
        "max_grad_norm"
    );
    assert_eq!(
        field_of(PpoConfig {
            adam_beta2: 1.0,
            ..d()
        }),
        "adam_beta2"
    );
}

/// A step size of 10³⁰⁰ sends the weights out of range within the first iteration: the error
/// names iteration 1 instead of training on NaNs.
#[test]
fn divergence_is_an_error_naming_the_iteration() {
    let config = PpoConfig {
        actor_learning_rate: 1e300,
        critic_learning_rate: 1e300,
        max_grad_norm: None,
        ..short_config()
    };
    let err = train(&config, 1, |_| {}).unwrap_err();
    assert!(
        matches!(
            err,
            PpoError::NonFinite { iteration: 1, .. } | PpoError::Network { iteration: 1, .. }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("iteration 1"), "{err}");
}

/// The recorded command retrains the committed expert bit for bit (same platform), and full
/// training reaches the target.
#[test]
#[ignore = "trains PPO for 100 096 steps to ≥ 495 (run it in release)"]
fn retraining_reproduces_the_committed_expert() {
    let file = PpoExpertFile::read(committed_path()).unwrap();
    let (expert, summary) = train(&file.config, file.seed, |_| {}).unwrap();
    let evaluation = expert.evaluate().unwrap();
    assert!(evaluation.mean_return >= REQUIRED_MEAN_RETURN);
    assert_eq!(evaluation, file.evaluation);
    assert_eq!(summary, file.training);
    let bits = |w: &[f64]| w.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert_eq!(bits(expert.actor_weights()), bits(&file.actor));
    assert_eq!(bits(expert.critic_weights()), bits(&file.critic));
}

/// `act_stochastic` samples from `π(·|s)`: over 20 000 seeded draws at a state where the actor is
/// unsure, the frequency of action 0 is within 5 standard errors of `π(0|s)` (a fixed seed, so the
/// test is deterministic; for a random seed it would fail with probability < 10⁻⁶).
#[test]
fn stochastic_actions_follow_the_probabilities() {
    let expert = PpoExpert::load(committed_path()).unwrap();
    // Search along θ for a state with 0.2 ≤ π(0|s) ≤ 0.8 (the greedy action flips across θ = 0).
    let state = (-100..=100)
        .map(|i| [0.0, 0.0, f64::from(i) * 1e-3, 0.0])
        .find(|s| {
            let p0 = expert.probabilities(s).unwrap()[0];
            (0.2..=0.8).contains(&p0)
        })
        .expect("an undecided state near upright");
    let p0 = expert.probabilities(&state).unwrap()[0];
    let n = 20_000;
    let mut rng = KitRng::seed_from_u64(11);
    let zeros = (0..n)
        .filter(|_| expert.act_stochastic(&state, &mut rng).unwrap() == 0)
        .count();
    let freq = zeros as f64 / n as f64;
    let se = (p0 * (1.0 - p0) / n as f64).sqrt();
    assert_abs_diff_eq!(freq, p0, epsilon = 5.0 * se);
}
