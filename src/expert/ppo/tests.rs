//! Unit tests of the PPO trainer, network and file format.

use super::*;

/// The logit gradient of the surrogate and of the entropy against central differences.
#[test]
fn logit_gradients_match_finite_differences() {
    let z = [0.3, -0.4];
    let (a, old_log_prob, adv, c_h) = (1usize, -0.9, 1.7, 0.05);
    // The objective to minimise, −r Â − c_H H, with the ratio inside the clip range.
    let loss = |z: &[f64; 2]| {
        let lp: Vec<f64> = (0..2).map(|b| log_softmax(z, b).unwrap()).collect();
        let p: Vec<f64> = lp.iter().map(|l| l.exp()).collect();
        let h = -(p[0] * lp[0] + p[1] * lp[1]);
        -(lp[a] - old_log_prob).exp() * adv - c_h * h
    };
    let lp: Vec<f64> = (0..2).map(|b| log_softmax(&z, b).unwrap()).collect();
    let p: Vec<f64> = lp.iter().map(|l| l.exp()).collect();
    let r = (lp[a] - old_log_prob).exp();
    assert!((r - 1.0).abs() < 0.2, "ratio {r} must be unclipped here");
    let h = -(p[0] * lp[0] + p[1] * lp[1]);
    for b in 0..2 {
        let e = if b == a { 1.0 } else { 0.0 };
        let analytic = -adv * r * (e - p[b]) + c_h * p[b] * (lp[b] + h);
        let step = 1e-6;
        let mut zp = z;
        zp[b] += step;
        let mut zm = z;
        zm[b] -= step;
        let numeric = (loss(&zp) - loss(&zm)) / (2.0 * step);
        assert!(
            (analytic - numeric).abs() < 1e-8,
            "logit {b}: {analytic} vs {numeric}"
        );
    }
}

#[test]
fn adam_steps_by_the_learning_rate_for_a_constant_gradient() {
    // With bias correction, the first step is lr · g/(|g| + ε) per coordinate.
    let config = PpoConfig::default();
    let mut adam = Adam::new(2, &config);
    let g = [3.0, -0.5];
    let mut p = [1.0, -1.0];
    adam.step(&mut p, &g, 0.1);
    for i in 0..2 {
        let expected = [1.0, -1.0][i] - 0.1 * g[i] / (g[i].abs() + config.adam_epsilon);
        assert!((p[i] - expected).abs() < 1e-15, "{p:?}");
    }
    // A second step with the same gradient moves by the same amount (m̂ = g, v̂ = g²).
    let before = p;
    adam.step(&mut p, &g, 0.1);
    for i in 0..2 {
        let expected = before[i] - 0.1 * g[i] / (g[i].abs() + config.adam_epsilon);
        assert!((p[i] - expected).abs() < 1e-14, "{p:?}");
    }
}

#[test]
fn global_norm_clipping() {
    let mut g = [3.0, 4.0];
    clip_global_norm(&mut g, Some(1.0));
    assert!((g[0] - 0.6).abs() < 1e-15 && (g[1] - 0.8).abs() < 1e-15);
    let mut g = [0.3, 0.4];
    clip_global_norm(&mut g, Some(1.0));
    assert_eq!(g, [0.3, 0.4]);
    clip_global_norm(&mut g, None);
    assert_eq!(g, [0.3, 0.4]);
}

/// GAE at a truncation bootstraps from the critic; at a termination from 0; and the λ chain
/// stops at the end of the episode (the next episode's steps do not leak into it): the last
/// step's advantage is exactly `r + γ·(bootstrap) − V(s)`, and the one before it is
/// `δ + γλ·Â_last`.
#[test]
fn truncation_bootstraps_and_termination_does_not() {
    let config = PpoConfig {
        envs: 1,
        steps_per_env: 12,
        total_steps: 12,
        minibatch_size: 12,
        ..PpoConfig::default()
    };
    let (gamma, lambda) = (config.gamma, config.gae_lambda);
    assert!(lambda > 0.0);
    // A truncation after 5 steps from near upright; a termination after 2 steps from a state
    // where the pole falls whatever the actions.
    for (max_steps, start, len) in [
        (5, [0.01, -0.02, 0.03, 0.01], 5),
        (500, [0.0, 0.0, 0.18, 1.0], 2),
    ] {
        let mut t = PpoTrainer::new(&config, 3).unwrap();
        t.workers[0].env = CartPole::with_max_episode_steps(max_steps);
        t.workers[0].obs = t.workers[0].env.reset_to(start);
        let mut batch = Vec::new();
        t.rollout(1, &mut batch).unwrap();
        // Replay the rollout's actions to the end of the first episode.
        let mut env = CartPole::<f64>::with_max_episode_steps(max_steps);
        env.reset_to(start);
        let mut last_step = None;
        for (i, s) in batch.iter().enumerate().take(len) {
            assert_eq!(env.state(), Some(&s.obs));
            let step = env.step(s.action).unwrap();
            assert_eq!(step.done(), i + 1 == len, "max_steps {max_steps}, step {i}");
            last_step = Some(step);
        }
        let step = last_step.unwrap();
        assert_eq!(step.truncated, max_steps == 5);
        assert_eq!(step.terminated, max_steps == 500);
        let (last, before) = (&batch[len - 1], &batch[len - 2]);
        let next_value = if step.terminated {
            0.0
        } else {
            t.value(&step.observation, 1).unwrap()
        };
        let expected_last = 1.0 + gamma * next_value - last.value;
        assert_eq!(last.advantage, expected_last + gamma * lambda * 0.0);
        let delta = 1.0 + gamma * last.value - before.value;
        assert_eq!(before.advantage, delta + gamma * lambda * last.advantage);
        assert_eq!(last.target, last.advantage + last.value);
    }
}
