//! The PPO trainer: roll-outs of parallel CartPole copies, generalised advantage estimation,
//! and minibatch epochs of the clipped surrogate (module docs of [`super`]).

use super::*;

/// What one training iteration did (for progress reports).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationStats {
    /// The iteration (1-based).
    pub iteration: usize,
    /// Environment steps so far.
    pub env_steps: usize,
    /// Episodes that ended during this iteration's rollout.
    pub episodes: usize,
    /// Mean return of those episodes (`None` if none ended).
    pub mean_episode_return: Option<f64>,
    /// Mean clipped surrogate objective over the last epoch's samples (without the entropy term).
    pub surrogate: f64,
    /// Mean value loss `½(V − R̂)²` over the last epoch's samples.
    pub value_loss: f64,
    /// Mean policy entropy over the last epoch's samples.
    pub entropy: f64,
    /// Mean of `(r − 1) − ln r` (an estimate of KL(π_old‖π)) over the last epoch's samples.
    pub approx_kl: f64,
    /// Fraction of the last epoch's samples whose ratio left `[1 − ε, 1 + ε]`.
    pub clip_fraction: f64,
    /// The learning-rate and `ε` factor of this iteration (1 without annealing).
    pub schedule: f64,
}

/// A summary of a training run, stored with the expert.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingSummary {
    /// Iterations run.
    pub iterations: usize,
    /// Environment steps taken.
    pub env_steps: usize,
    /// Episodes completed during training.
    pub episodes: usize,
    /// Mean return of the episodes completed in the last iteration (stochastic actor), if any.
    pub last_mean_episode_return: Option<f64>,
}

/// One CartPole copy of the rollout.
#[derive(Debug, Clone)]
pub(super) struct Worker {
    pub(super) env: CartPole<f64>,
    pub(super) obs: [f64; 4],
    pub(super) episode_return: f64,
}

/// The buffers of a mini-batch update, reused from one to the next.
#[derive(Debug, Clone)]
pub(super) struct Scratch {
    /// The mini-batch's observations, in its order.
    pub(super) obs: Vec<[f64; OBSERVATION_DIM]>,
    /// Per sample, the gradient of its loss term with respect to the logits and to the value.
    pub(super) actor_delta: Vec<[f64; ACTIONS]>,
    pub(super) critic_delta: Vec<[f64; 1]>,
    /// The mini-batch's gradients ([`Mlp`] layout).
    pub(super) actor_grad: Vec<f64>,
    pub(super) critic_grad: Vec<f64>,
}

/// One step of a rollout.
#[derive(Debug, Clone, Copy)]
pub(super) struct Sample {
    pub(super) obs: [f64; 4],
    pub(super) action: usize,
    pub(super) log_prob: f64,
    pub(super) value: f64,
    pub(super) advantage: f64,
    pub(super) target: f64,
}

/// PPO as an algorithm struct: [`PpoTrainer::new`] initialises the networks and environments from
/// the seed, each [`PpoTrainer::iteration`] collects one rollout and updates both networks, and
/// [`train`] is the loop.
#[derive(Debug, Clone)]
pub struct PpoTrainer {
    pub(super) config: PpoConfig,
    pub(super) seed: u64,
    pub(super) actor_net: MlpSoftmax,
    pub(super) critic_net: Mlp,
    pub(super) actor: Vec<f64>,
    pub(super) critic: Vec<f64>,
    pub(super) actor_adam: AdamRule<f64>,
    pub(super) critic_adam: AdamRule<f64>,
    pub(super) workers: Vec<Worker>,
    pub(super) rng: KitRng,
    /// The actor's and the critic's batch passes, and the mini-batch buffers.
    pub(super) actor_pass: BatchMlp<ACTIONS>,
    pub(super) critic_pass: BatchMlp<1>,
    pub(super) scratch: Scratch,
    pub(super) iteration: usize,
    pub(super) env_steps: usize,
    pub(super) episodes: usize,
    pub(super) last_mean_episode_return: Option<f64>,
}

impl PpoTrainer {
    /// Validates `config`, then seeds one [`KitRng`] with `seed` and draws, in this order, the
    /// actor's and the critic's initial weights ([`Mlp::init`]) and the initial state of each
    /// environment copy.
    ///
    /// # Errors
    /// [`PpoError::InvalidConfig`].
    pub fn new(config: &PpoConfig, seed: u64) -> Result<Self, PpoError> {
        config.validate()?;
        let (actor_net, critic_net) = networks(config.hidden).map_err(|e| {
            invalid("hidden", e.to_string()) // unreachable after validation
        })?;
        let mut rng = KitRng::seed_from_u64(seed);
        let actor: Vec<f64> = actor_net.net().init(&mut rng);
        let critic: Vec<f64> = critic_net.init(&mut rng);
        let workers = (0..config.envs)
            .map(|_| {
                let mut env = CartPole::new();
                let obs = env.reset(&mut rng);
                Worker {
                    env,
                    obs,
                    episode_return: 0.0,
                }
            })
            .collect();
        Ok(PpoTrainer {
            actor_adam: adam(config)?,
            critic_adam: adam(config)?,
            actor_pass: BatchMlp::new(config.hidden),
            critic_pass: BatchMlp::new(config.hidden),
            scratch: Scratch {
                obs: Vec::with_capacity(config.minibatch_size),
                actor_delta: Vec::with_capacity(config.minibatch_size),
                critic_delta: Vec::with_capacity(config.minibatch_size),
                actor_grad: vec![0.0; actor.len()],
                critic_grad: vec![0.0; critic.len()],
            },
            config: config.clone(),
            seed,
            actor_net,
            critic_net,
            actor,
            critic,
            workers,
            rng,
            iteration: 0,
            env_steps: 0,
            episodes: 0,
            last_mean_episode_return: None,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PpoConfig {
        &self.config
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Iterations done.
    pub fn iterations_done(&self) -> usize {
        self.iteration
    }

    /// Whether the run has done its [`PpoConfig::iterations`].
    pub fn is_done(&self) -> bool {
        self.iteration >= self.config.iterations()
    }

    /// The current actor and critic as an expert.
    pub fn expert(&self) -> PpoExpert {
        PpoExpert {
            actor_net: self.actor_net,
            critic_net: self.critic_net,
            actor: self.actor.clone(),
            critic: self.critic.clone(),
        }
    }

    /// What the run did so far.
    pub fn summary(&self) -> TrainingSummary {
        TrainingSummary {
            iterations: self.iteration,
            env_steps: self.env_steps,
            episodes: self.episodes,
            last_mean_episode_return: self.last_mean_episode_return,
        }
    }

    pub(super) fn value(&self, obs: &[f64; 4], iteration: usize) -> Result<f64, PpoError> {
        let f = self
            .critic_net
            .forward(&self.critic, obs)
            .map_err(|source| PpoError::Network { iteration, source })?;
        Ok(f.output[0])
    }

    /// One PPO iteration: a rollout of `envs × steps_per_env` steps with the stochastic actor,
    /// GAE(λ) advantages (module docs, truncation included), then `epochs` shuffled passes of
    /// mini-batch Adam steps on the clipped surrogate (actor) and the value loss (critic).
    ///
    /// # Errors
    /// [`PpoError::NonFinite`], [`PpoError::Network`] or [`PpoError::Env`] naming the iteration;
    /// the trainer should not be used after an error.
    pub fn iteration(&mut self) -> Result<IterationStats, PpoError> {
        let iteration = self.iteration + 1;
        let schedule = if self.config.anneal {
            1.0 - (iteration - 1) as f64 / self.config.iterations() as f64
        } else {
            1.0
        };
        let mut batch = Vec::with_capacity(self.config.rollout_size());
        let (episodes, return_sum) = self.rollout(iteration, &mut batch)?;
        self.episodes += episodes;
        self.env_steps += batch.len();
        self.last_mean_episode_return = (episodes > 0).then(|| return_sum / episodes as f64);
        let mut stats = IterationStats {
            iteration,
            env_steps: self.env_steps,
            episodes,
            mean_episode_return: self.last_mean_episode_return,
            surrogate: 0.0,
            value_loss: 0.0,
            entropy: 0.0,
            approx_kl: 0.0,
            clip_fraction: 0.0,
            schedule,
        };
        let mut order: Vec<usize> = (0..batch.len()).collect();
        for epoch in 0..self.config.epochs {
            order.shuffle(&mut self.rng);
            let last = epoch + 1 == self.config.epochs;
            let mut sums = [0.0; 5];
            for chunk in order.chunks(self.config.minibatch_size) {
                let s = self.update(iteration, schedule, &batch, chunk)?;
                for (acc, v) in sums.iter_mut().zip(s) {
                    *acc += v;
                }
            }
            if last {
                let n = batch.len() as f64;
                stats.surrogate = sums[0] / n;
                stats.value_loss = sums[1] / n;
                stats.entropy = sums[2] / n;
                stats.approx_kl = sums[3] / n;
                stats.clip_fraction = sums[4] / n;
            }
        }
        self.iteration = iteration;
        Ok(stats)
    }

    /// Collects one rollout into `batch` (with advantages and value targets); returns the number
    /// of episodes that ended and the sum of their returns.
    pub(super) fn rollout(
        &mut self,
        iteration: usize,
        batch: &mut Vec<Sample>,
    ) -> Result<(usize, f64), PpoError> {
        let steps = self.config.steps_per_env;
        let (gamma, lambda) = (self.config.gamma, self.config.gae_lambda);
        let mut episodes = 0;
        let mut return_sum = 0.0;
        let net_err = |source| PpoError::Network { iteration, source };
        self.actor_pass.load(&self.actor).map_err(net_err)?;
        self.critic_pass.load(&self.critic).map_err(net_err)?;
        for w in 0..self.workers.len() {
            let start = batch.len();
            // Per step: reward, terminated, the value to bootstrap from at a truncation, ended.
            let mut ends: Vec<(f64, bool, f64, bool)> = Vec::with_capacity(steps);
            for _ in 0..steps {
                let obs = self.workers[w].obs;
                self.actor_pass.forward(&[obs]).map_err(net_err)?;
                let (probs, log_probs) =
                    softmax_and_log(&self.actor_pass.outputs()[0]).map_err(net_err)?;
                let u: f64 = self.rng.random();
                let action = usize::from(u >= probs[0]);
                let log_prob = log_probs[action];
                self.critic_pass.forward(&[obs]).map_err(net_err)?;
                let value = self.critic_pass.outputs()[0][0];
                let worker = &mut self.workers[w];
                let step = worker
                    .env
                    .step(action)
                    .map_err(|source| PpoError::Env { iteration, source })?;
                worker.episode_return += step.reward;
                let mut bootstrap = 0.0;
                if step.truncated && !step.terminated {
                    bootstrap = self.value(&step.observation, iteration)?;
                }
                let worker = &mut self.workers[w];
                if step.done() {
                    episodes += 1;
                    return_sum += worker.episode_return;
                    worker.episode_return = 0.0;
                    worker.obs = worker.env.reset(&mut self.rng);
                } else {
                    worker.obs = step.observation;
                }
                ends.push((step.reward, step.terminated, bootstrap, step.done()));
                batch.push(Sample {
                    obs,
                    action,
                    log_prob,
                    value,
                    advantage: 0.0,
                    target: 0.0,
                });
            }
            // GAE(λ) backwards over this worker's steps (Schulman et al. 2016, eq. 16).
            let last_value = self.value(&self.workers[w].obs, iteration)?;
            let mut gae = 0.0;
            for t in (0..steps).rev() {
                let (reward, terminated, bootstrap, ended) = ends[t];
                let next_value = if terminated {
                    0.0
                } else if ended {
                    bootstrap
                } else if t + 1 == steps {
                    last_value
                } else {
                    batch[start + t + 1].value
                };
                let sample = &mut batch[start + t];
                let delta = reward + gamma * next_value - sample.value;
                let carry = if ended { 0.0 } else { gae };
                gae = delta + gamma * lambda * carry;
                if !gae.is_finite() {
                    return Err(PpoError::NonFinite {
                        iteration,
                        what: "advantage",
                    });
                }
                sample.advantage = gae;
                sample.target = gae + sample.value;
            }
        }
        Ok((episodes, return_sum))
    }

    /// One mini-batch step of both networks; returns the sums over the mini-batch of the
    /// surrogate, value loss, entropy, approximate KL and clipped indicator.
    pub(super) fn update(
        &mut self,
        iteration: usize,
        schedule: f64,
        batch: &[Sample],
        chunk: &[usize],
    ) -> Result<[f64; 5], PpoError> {
        let net_err = |source| PpoError::Network { iteration, source };
        let non_finite = |what| PpoError::NonFinite { iteration, what };
        let n = chunk.len() as f64;
        let (mean, std) = if self.config.normalize_advantages {
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
        let eps = self.config.clip_epsilon * schedule;
        let c_h = self.config.entropy_coefficient;
        let Scratch {
            obs,
            actor_delta,
            critic_delta,
            actor_grad,
            critic_grad,
        } = &mut self.scratch;
        obs.clear();
        obs.extend(chunk.iter().map(|&i| batch[i].obs));
        self.actor_pass.load(&self.actor).map_err(net_err)?;
        self.actor_pass.forward(obs).map_err(net_err)?;
        self.critic_pass.load(&self.critic).map_err(net_err)?;
        self.critic_pass.forward(obs).map_err(net_err)?;
        actor_delta.clear();
        critic_delta.clear();
        let mut sums = [0.0; 5];
        let outputs = self
            .actor_pass
            .outputs()
            .iter()
            .zip(self.critic_pass.outputs());
        for (&i, (logits, value)) in chunk.iter().zip(outputs) {
            let s = &batch[i];
            let adv = (s.advantage - mean) / std;
            // Actor.
            let (probs, log_probs) = softmax_and_log(logits).map_err(net_err)?;
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
            actor_delta.push(dz);
            // Critic.
            let err = value[0] - s.target;
            critic_delta.push([err / n]);
            sums[0] += unclipped.min(clipped);
            sums[1] += 0.5 * err * err;
            sums[2] += entropy;
            sums[3] += (ratio - 1.0) - log_ratio;
            sums[4] += f64::from(u8::from((ratio - 1.0).abs() > eps));
        }
        self.actor_pass.backward(obs, actor_delta, actor_grad);
        self.critic_pass.backward(obs, critic_delta, critic_grad);
        if !sums.iter().all(|x| x.is_finite()) {
            return Err(non_finite("loss"));
        }
        if !actor_grad.iter().all(|x| x.is_finite()) {
            return Err(non_finite("actor gradient"));
        }
        if !critic_grad.iter().all(|x| x.is_finite()) {
            return Err(non_finite("critic gradient"));
        }
        clip_global_norm(actor_grad, self.config.max_grad_norm);
        clip_global_norm(critic_grad, self.config.max_grad_norm);
        adam_step(
            &mut self.actor_adam,
            &mut self.actor,
            actor_grad,
            self.config.actor_learning_rate * schedule,
            iteration,
        )?;
        adam_step(
            &mut self.critic_adam,
            &mut self.critic,
            critic_grad,
            self.config.critic_learning_rate * schedule,
            iteration,
        )?;
        if !self.actor.iter().all(|x| x.is_finite()) {
            return Err(non_finite("actor weights"));
        }
        if !self.critic.iter().all(|x| x.is_finite()) {
            return Err(non_finite("critic weights"));
        }
        Ok(sums)
    }
}

/// Trains PPO on CartPole-v1 for [`PpoConfig::iterations`] iterations from `seed`, calling
/// `observer` after each iteration, and returns the final expert with a summary of the run.
///
/// # Errors
/// As [`PpoTrainer::new`] and [`PpoTrainer::iteration`].
pub fn train(
    config: &PpoConfig,
    seed: u64,
    mut observer: impl FnMut(&IterationStats),
) -> Result<(PpoExpert, TrainingSummary), PpoError> {
    let mut trainer = PpoTrainer::new(config, seed)?;
    while !trainer.is_done() {
        let stats = trainer.iteration()?;
        observer(&stats);
    }
    Ok((trainer.expert(), trainer.summary()))
}

pub(super) fn networks(hidden: usize) -> Result<(MlpSoftmax, Mlp), PolicyError> {
    Ok((
        MlpSoftmax::new(OBSERVATION_DIM, hidden, ACTIONS)?,
        Mlp::new(OBSERVATION_DIM, hidden, 1)?,
    ))
}

/// `(softmax(z), log softmax(z))`: the operations of [`crate::policy::softmax_probs`] and of
/// [`crate::policy::log_softmax`]
/// for each action, in their order, sharing the exponentials and the logarithm of their sum
/// (which both compute identically).
///
/// # Errors
/// [`PolicyError::NonFinite`] for non-finite logits or probabilities, as
/// [`crate::policy::softmax_probs`].
pub(super) fn softmax_and_log(
    z: &[f64; ACTIONS],
) -> Result<([f64; ACTIONS], [f64; ACTIONS]), PolicyError> {
    let mut c = f64::NEG_INFINITY;
    for &x in z {
        if !x.is_finite() {
            return Err(PolicyError::NonFinite { param: "logits" });
        }
        c = c.max(x);
    }
    let e = z.map(|x| (x - c).exp());
    let total = e.iter().fold(0.0, |acc, x| acc + x);
    let probs = e.map(|x| x / total);
    if !probs.iter().all(|p| p.is_finite()) {
        return Err(PolicyError::NonFinite { param: "softmax" });
    }
    let ln_total = total.ln();
    Ok((probs, z.map(|x| x - c - ln_total)))
}
