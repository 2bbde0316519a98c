//! Unit tests of the PPO trainer, network and file format.

use super::trainer::{Sample, softmax_and_log};
use super::*;
use crate::policy::{log_softmax, softmax_probs};

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
    assert!(
        approx::abs_diff_eq!(r, 1.0, epsilon = 0.2),
        "ratio {r} must be unclipped here"
    );
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
            approx::abs_diff_eq!(analytic, numeric, epsilon = 1e-8),
            "logit {b}: {analytic} vs {numeric}"
        );
    }
}

#[test]
fn adam_steps_by_the_learning_rate_for_a_constant_gradient() {
    // With bias correction, the first step is lr · g/(|g| + ε) per coordinate.
    let config = PpoConfig::default();
    let mut adam = adam(&config).unwrap();
    let g = [3.0, -0.5];
    let mut p = [1.0, -1.0];
    adam_step(&mut adam, &mut p, &g, 0.1, 1).unwrap();
    for i in 0..2 {
        let expected = [1.0, -1.0][i] - 0.1 * g[i] / (g[i].abs() + config.adam_epsilon);
        assert!(
            approx::abs_diff_eq!(p[i], expected, epsilon = 1e-15),
            "{p:?}"
        );
    }
    // A second step with the same gradient moves by the same amount (m̂ = g, v̂ = g²).
    let before = p;
    adam_step(&mut adam, &mut p, &g, 0.1, 2).unwrap();
    for i in 0..2 {
        let expected = before[i] - 0.1 * g[i] / (g[i].abs() + config.adam_epsilon);
        assert!(
            approx::abs_diff_eq!(p[i], expected, epsilon = 1e-14),
            "{p:?}"
        );
    }
}

/// The stored expert was trained with this update, written out on `f64` slices: the kit's Adam
/// must repeat it bit for bit (it does the same operations in the same order, `βᵗ` by `powi`).
#[test]
fn the_kits_adam_repeats_the_update_the_stored_expert_was_trained_with() {
    use rand::{Rng, SeedableRng};
    let config = PpoConfig::default();
    let (b1, b2, eps) = (config.adam_beta1, config.adam_beta2, config.adam_epsilon);
    let mut rng = KitRng::seed_from_u64(5);
    let dim = 7;
    let mut kit = adam(&config).unwrap();
    let mut p_kit: Vec<f64> = (0..dim).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut p_ref = p_kit.clone();
    let (mut m, mut v) = (vec![0.0; dim], vec![0.0; dim]);
    for t in 1..=2000 {
        let g: Vec<f64> = (0..dim).map(|_| rng.random_range(-3.0..3.0)).collect();
        let lr = 1e-3 * (1.0 - f64::from(t) / 4000.0);
        let (bc1, bc2) = (1.0 - b1.powi(t), 1.0 - b2.powi(t));
        for i in 0..dim {
            m[i] = b1 * m[i] + (1.0 - b1) * g[i];
            v[i] = b2 * v[i] + (1.0 - b2) * g[i] * g[i];
            p_ref[i] -= lr * (m[i] / bc1) / ((v[i] / bc2).sqrt() + eps);
        }
        adam_step(&mut kit, &mut p_kit, &g, lr, 1).unwrap();
        let bits = |w: &[f64]| w.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&p_kit), bits(&p_ref), "step {t}");
        assert_eq!(bits(kit.moments().1), bits(&v), "step {t}");
    }
}

#[test]
fn global_norm_clipping() {
    let mut g = [3.0, 4.0];
    clip_global_norm(&mut g, Some(1.0));
    approx::assert_abs_diff_eq!(g[0], 0.6, epsilon = 1e-15);
    approx::assert_abs_diff_eq!(g[1], 0.8, epsilon = 1e-15);
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

/// The mini-batch update written with the generic [`Mlp`] passes, one sample at a time (a
/// reference for [`PpoTrainer::update`], which must give the same weights bit for bit).
fn reference_update(
    t: &mut PpoTrainer,
    iteration: usize,
    schedule: f64,
    batch: &[Sample],
    chunk: &[usize],
) -> Result<[f64; 5], PpoError> {
    let net_err = |source| PpoError::Network { iteration, source };
    let non_finite = |what| PpoError::NonFinite { iteration, what };
    let n = chunk.len() as f64;
    let (mean, std) = if t.config.normalize_advantages {
        let mean = chunk.iter().map(|&i| batch[i].advantage).sum::<f64>() / n;
        let var = chunk
            .iter()
            .map(|&i| (batch[i].advantage - mean).powi(2))
            .sum::<f64>()
            / n;
        (mean, var.sqrt() + 1e-8)
    } else {
        (0.0, 1.0)
    };
    let eps = t.config.clip_epsilon * schedule;
    let c_h = t.config.entropy_coefficient;
    let mut actor_grad = vec![0.0; t.actor.len()];
    let mut critic_grad = vec![0.0; t.critic.len()];
    let mut sums = [0.0; 5];
    for &i in chunk {
        let s = &batch[i];
        let adv = (s.advantage - mean) / std;
        // Actor.
        let f = t
            .actor_net
            .net()
            .forward(&t.actor, &s.obs)
            .map_err(net_err)?;
        let probs = softmax_probs(&f.output).map_err(net_err)?;
        let log_probs: Vec<f64> = (0..ACTIONS)
            .map(|b| log_softmax(&f.output, b))
            .collect::<Result<_, _>>()
            .map_err(net_err)?;
        let log_ratio = log_probs[s.action] - s.log_prob;
        let ratio = log_ratio.exp();
        let unclipped = ratio * adv;
        let clipped = ratio.clamp(1.0 - eps, 1.0 + eps) * adv;
        let entropy = -probs
            .iter()
            .zip(&log_probs)
            .map(|(p, l)| p * l)
            .sum::<f64>();
        let mut dz = [0.0; ACTIONS];
        if unclipped <= clipped {
            for b in 0..ACTIONS {
                let e = if b == s.action { 1.0 } else { 0.0 };
                dz[b] = -adv * ratio * (e - probs[b]) / n;
            }
        }
        if c_h > 0.0 {
            for b in 0..ACTIONS {
                dz[b] += c_h * probs[b] * (log_probs[b] + entropy) / n;
            }
        }
        let g = t
            .actor_net
            .net()
            .backward(&t.actor, &s.obs, &f, &dz)
            .map_err(net_err)?;
        actor_grad.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
        // Critic.
        let f = t.critic_net.forward(&t.critic, &s.obs).map_err(net_err)?;
        let err = f.output[0] - s.target;
        let g = t
            .critic_net
            .backward(&t.critic, &s.obs, &f, &[err / n])
            .map_err(net_err)?;
        critic_grad.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
        sums[0] += unclipped.min(clipped);
        sums[1] += 0.5 * err * err;
        sums[2] += entropy;
        sums[3] += (ratio - 1.0) - log_ratio;
        sums[4] += f64::from(u8::from((ratio - 1.0).abs() > eps));
    }
    if !sums.iter().all(|x| x.is_finite()) {
        return Err(non_finite("loss"));
    }
    if !actor_grad.iter().all(|x| x.is_finite()) {
        return Err(non_finite("actor gradient"));
    }
    if !critic_grad.iter().all(|x| x.is_finite()) {
        return Err(non_finite("critic gradient"));
    }
    clip_global_norm(&mut actor_grad, t.config.max_grad_norm);
    clip_global_norm(&mut critic_grad, t.config.max_grad_norm);
    adam_step(
        &mut t.actor_adam,
        &mut t.actor,
        &actor_grad,
        t.config.actor_learning_rate * schedule,
        iteration,
    )?;
    adam_step(
        &mut t.critic_adam,
        &mut t.critic,
        &critic_grad,
        t.config.critic_learning_rate * schedule,
        iteration,
    )?;
    if !t.actor.iter().all(|x| x.is_finite()) {
        return Err(non_finite("actor weights"));
    }
    if !t.critic.iter().all(|x| x.is_finite()) {
        return Err(non_finite("critic weights"));
    }
    Ok(sums)
}

/// Random weights with non-zero biases, for the pass comparisons.
fn random_weights(net: &Mlp, rng: &mut KitRng) -> Vec<f64> {
    let mut w: Vec<f64> = net.init(rng);
    for x in w.iter_mut().filter(|x| **x == 0.0) {
        *x = rng.random::<f64>() - 0.5;
    }
    w
}

/// [`BatchMlp`]'s outputs and batch gradient equal the generic network's per-sample forward
/// passes and in-order sum of back-propagated gradients, bit for bit (both tanh branches, batch
/// sizes that are and are not multiples of four, and a zero input).
#[test]
fn batch_passes_match_the_generic_network_bit_for_bit() {
    fn check<const K: usize>(hidden: usize, samples: usize, rng: &mut KitRng) {
        let net = Mlp::new(OBSERVATION_DIM, hidden, K).unwrap();
        let theta = random_weights(&net, rng);
        let mut obs: Vec<[f64; 4]> = (0..samples)
            .map(|_| std::array::from_fn(|_| 6.0 * (rng.random::<f64>() - 0.5)))
            .collect();
        obs[0] = [0.0; 4];
        let delta: Vec<[f64; K]> = (0..samples)
            .map(|_| std::array::from_fn(|_| rng.random::<f64>() - 0.5))
            .collect();
        let mut pass = BatchMlp::<K>::new(hidden);
        pass.load(&theta).unwrap();
        pass.forward(&obs).unwrap();
        let mut grad = vec![f64::NAN; theta.len()];
        pass.backward(&obs, &delta, &mut grad);
        let mut expected = vec![0.0; theta.len()];
        for (s, (phi, d)) in obs.iter().zip(&delta).enumerate() {
            let f = net.forward(&theta, phi).unwrap();
            let got = pass.outputs()[s];
            assert_eq!(
                f.output.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "output of sample {s}"
            );
            let g = net.backward(&theta, phi, &f, d).unwrap();
            expected.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
        }
        for (i, (a, b)) in grad.iter().zip(&expected).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "gradient entry {i}: {a} vs {b}");
        }
    }
    let mut rng = KitRng::seed_from_u64(17);
    for samples in [1, 4, 7, 256] {
        check::<2>(64, samples, &mut rng);
        check::<1>(64, samples, &mut rng);
        check::<3>(5, samples, &mut rng);
    }
}

/// [`softmax_and_log`] equals [`softmax_probs`] and [`log_softmax`] bit for bit.
#[test]
fn softmax_and_log_match_the_generic_functions() {
    for z in [[0.3, -0.4], [-700.0, 30.0], [0.0, 0.0], [1e-300, -1e-300]] {
        let (p, lp) = softmax_and_log(&z).unwrap();
        let expected = softmax_probs(&z).unwrap();
        for b in 0..ACTIONS {
            assert_eq!(p[b].to_bits(), expected[b].to_bits(), "{z:?}");
            assert_eq!(
                lp[b].to_bits(),
                log_softmax(&z, b).unwrap().to_bits(),
                "{z:?}"
            );
        }
    }
    assert!(softmax_and_log(&[f64::NAN, 0.0]).is_err());
}

/// [`PpoTrainer::update`] gives the reference update's weights, optimiser state and sums bit for
/// bit, with and without the entropy bonus and advantage normalisation, on mini-batches of the
/// rollout's size and smaller.
#[test]
fn update_matches_the_reference_update_bit_for_bit() {
    for config in [
        PpoConfig {
            total_steps: 2048,
            ..PpoConfig::default()
        },
        PpoConfig {
            hidden: 7,
            envs: 3,
            steps_per_env: 10,
            total_steps: 300,
            minibatch_size: 7,
            entropy_coefficient: 0.05,
            normalize_advantages: false,
            max_grad_norm: None,
            ..PpoConfig::default()
        },
    ] {
        let mut fast = PpoTrainer::new(&config, 5).unwrap();
        let mut reference = fast.clone();
        for iteration in 1..=3 {
            let mut batch: Vec<Sample> = Vec::new();
            fast.rollout(iteration, &mut batch).unwrap();
            let mut batch_ref: Vec<Sample> = Vec::new();
            reference.rollout(iteration, &mut batch_ref).unwrap();
            let order: Vec<usize> = (0..batch.len()).rev().collect();
            for chunk in order.chunks(config.minibatch_size) {
                let a = fast.update(iteration, 0.9, &batch, chunk).unwrap();
                let b =
                    reference_update(&mut reference, iteration, 0.9, &batch_ref, chunk).unwrap();
                assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
            }
            let bits = |w: &[f64]| w.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast.actor), bits(&reference.actor));
            assert_eq!(bits(&fast.critic), bits(&reference.critic));
            assert_eq!(
                bits(fast.actor_adam.moments().0),
                bits(reference.actor_adam.moments().0)
            );
            assert_eq!(
                bits(fast.critic_adam.moments().1),
                bits(reference.critic_adam.moments().1)
            );
        }
    }
}
