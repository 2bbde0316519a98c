//! A trained PPO actor and critic, its greedy action and its evaluation on CartPole-v1.

use super::*;

/// A trained PPO actor (and its critic) for CartPole-v1. As an expert it acts **greedily**: the
/// action of largest probability, so its labels are deterministic.
#[derive(Debug, Clone, PartialEq)]
pub struct PpoExpert {
    pub(super) actor_net: MlpSoftmax,
    pub(super) critic_net: Mlp,
    pub(super) actor: Vec<f64>,
    pub(super) critic: Vec<f64>,
}

impl PpoExpert {
    /// An expert from weights: `actor` in the layout of [`MlpSoftmax`] with 4 inputs, `hidden`
    /// units and 2 outputs, `critic` in the layout of [`Mlp`] with 4 inputs, `hidden` units and 1
    /// output.
    ///
    /// # Errors
    /// [`PpoError::InvalidConfig`] for `hidden = 0`; [`PpoError::Act`] with
    /// [`PolicyError::Shape`] or [`PolicyError::NonFinite`] naming `actor` or `critic`.
    pub fn new(hidden: usize, actor: Vec<f64>, critic: Vec<f64>) -> Result<Self, PpoError> {
        check_at_least("hidden", hidden, 1)?;
        let (actor_net, critic_net) = networks(hidden).map_err(PpoError::Act)?;
        for (param, w, dim) in [
            ("actor", &actor, actor_net.net().param_dim()),
            ("critic", &critic, critic_net.param_dim()),
        ] {
            if w.len() != dim {
                return Err(PpoError::Act(PolicyError::Shape {
                    param,
                    expected: dim,
                    got: w.len(),
                }));
            }
            if !w.iter().all(|x| x.is_finite()) {
                return Err(PpoError::Act(PolicyError::NonFinite { param }));
            }
        }
        Ok(PpoExpert {
            actor_net,
            critic_net,
            actor,
            critic,
        })
    }

    /// Hidden units of each network.
    pub fn hidden(&self) -> usize {
        (self.critic_net.param_dim() - 1) / (OBSERVATION_DIM + 2)
    }

    /// The actor's weights (layout of [`Mlp`]).
    pub fn actor_weights(&self) -> &[f64] {
        &self.actor
    }

    /// The critic's weights (layout of [`Mlp`]).
    pub fn critic_weights(&self) -> &[f64] {
        &self.critic
    }

    /// `π(·|s)`: the actor's probabilities of pushing left and right.
    ///
    /// # Errors
    /// [`PpoError::Act`] for a non-finite state or activation.
    pub fn probabilities(&self, state: &[f64; 4]) -> Result<[f64; 2], PpoError> {
        let p = self
            .actor_net
            .probs(&self.actor, state)
            .map_err(PpoError::Act)?;
        Ok([p[0], p[1]])
    }

    /// The expert's (greedy) action: the argmax of `π(·|s)`, decided on the logits (softmax is
    /// strictly increasing, so `π(1|s) > π(0|s)` ⟺ `z₁ > z₀`, and comparing logits avoids ties
    /// made by rounding the probabilities): `1` if `z₁ > z₀`, else `0` (ties go to 0, as for
    /// [`crate::expert::lqr::LqrExpert::action`]).
    ///
    /// # Errors
    /// [`PpoError::Act`] for a non-finite state or activation.
    pub fn action(&self, state: &[f64; 4]) -> Result<usize, PpoError> {
        let z = self
            .actor_net
            .net()
            .forward(&self.actor, state)
            .map_err(PpoError::Act)?
            .output;
        Ok(usize::from(z[1] > z[0]))
    }

    /// [`PpoExpert::action`] evaluated in any [`Real`] scalar (intervals, dual numbers): the
    /// weights are converted exactly ([`from_f64_exact`]) and the logits compared with
    /// [`Scalar::certain_cmp`]. Slower than [`PpoExpert::action`] (the conversion is per call).
    ///
    /// # Errors
    /// [`PpoError::Act`] for a non-finite state or activation, and with
    /// [`PolicyError::Undecidable`] when the scalar cannot order the two logits (an interval
    /// straddling the decision boundary, or NaN).
    pub fn action_in<S: Real>(&self, state: &[S; 4]) -> Result<usize, PpoError> {
        let weights = self
            .actor
            .iter()
            .map(|&w| from_f64_exact::<S>(w, "actor"))
            .collect::<Result<Vec<S>, _>>()
            .map_err(PpoError::Act)?;
        let z = self
            .actor_net
            .net()
            .forward(&weights, state)
            .map_err(PpoError::Act)?
            .output;
        match z[1].certain_cmp(&z[0]) {
            Some(Ordering::Greater) => Ok(1),
            Some(_) => Ok(0),
            None => Err(PpoError::Act(PolicyError::Undecidable(Undecidable {
                what: "PPO expert: order of the two logits",
            }))),
        }
    }

    /// The greedy actor with its weights converted to `S` once: [`PpoGreedy::action`] gives
    /// [`PpoExpert::action_in`]'s result without converting or allocating per call.
    ///
    /// # Errors
    /// [`PpoError::Act`] if a weight cannot be represented in `S`.
    pub fn greedy_in<S: Real>(&self) -> Result<PpoGreedy<S>, PpoError> {
        PpoGreedy::new(self)
    }

    /// An action sampled from `π(·|s)`: `0` if `u < π(0|s)` for `u` uniform on `[0, 1)` from
    /// `rng`, else `1` (as in training).
    ///
    /// # Errors
    /// As [`PpoExpert::probabilities`].
    pub fn act_stochastic(&self, state: &[f64; 4], rng: &mut KitRng) -> Result<usize, PpoError> {
        let [p0, _] = self.probabilities(state)?;
        let u: f64 = rng.random();
        Ok(usize::from(u >= p0))
    }

    /// The critic's value estimate `V(s)` (discounted with the training `γ`).
    ///
    /// # Errors
    /// As [`PpoExpert::probabilities`].
    pub fn value(&self, state: &[f64; 4]) -> Result<f64, PpoError> {
        let f = self
            .critic_net
            .forward(&self.critic, state)
            .map_err(PpoError::Act)?;
        Ok(f.output[0])
    }

    /// The greedy actor's [`evaluate_cartpole`] on the standard seeds (`0..100`), acting through
    /// [`PpoExpert::greedy_in`]`::<f64>` (the actions of [`PpoExpert::action`], without its
    /// per-call allocations).
    ///
    /// # Errors
    /// As [`evaluate_cartpole`].
    pub fn evaluate(&self) -> Result<Evaluation, PpoError> {
        let greedy = self.greedy_in::<f64>()?;
        evaluate_cartpole(|s| greedy.action(s), EVAL_FIRST_SEED, EVAL_EPISODES)
    }

    /// Loads and validates a stored expert ([`PpoExpertFile::read`]).
    ///
    /// # Errors
    /// As [`PpoExpertFile::read`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, PpoError> {
        PpoExpertFile::read(path)?.expert()
    }
}

/// Returns of a controller on CartPole-v1 over seeded episodes ([`evaluate_cartpole`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Evaluation {
    /// Seed of the first episode; episode `i` uses `first_seed + i`.
    pub first_seed: u64,
    /// The return of each episode, in seed order.
    pub returns: Vec<f64>,
    /// Mean of `returns`.
    pub mean_return: f64,
    /// Smallest of `returns`.
    pub min_return: f64,
}

/// Runs `episodes` episodes of CartPole-v1 (time limit [`MAX_EPISODE_STEPS`]) with the
/// controller `act`: episode `i` resets a fresh environment with a [`KitRng`] seeded with
/// `first_seed + i` and runs until it terminates or is truncated; its return is the sum of the
/// rewards (1 per step).
///
/// # Errors
/// [`PpoError::Evaluation`] naming the seed and step if the controller or the environment fails
/// (and, with step 0, for `episodes = 0`).
pub fn evaluate_cartpole<E: Display>(
    mut act: impl FnMut(&[f64; 4]) -> Result<usize, E>,
    first_seed: u64,
    episodes: usize,
) -> Result<Evaluation, PpoError> {
    if episodes == 0 {
        return Err(PpoError::Evaluation {
            seed: first_seed,
            step: 0,
            message: "no episodes to evaluate".into(),
        });
    }
    let mut returns = Vec::with_capacity(episodes);
    for i in 0..episodes {
        let seed = first_seed.wrapping_add(i as u64);
        let mut env = CartPole::<f64>::new();
        let mut rng = KitRng::seed_from_u64(seed);
        let mut obs = env.reset(&mut rng);
        let mut ret = 0.0;
        for step in 1..=MAX_EPISODE_STEPS {
            let fail = |message: String| PpoError::Evaluation {
                seed,
                step,
                message,
            };
            let a = act(&obs).map_err(|e| fail(e.to_string()))?;
            let s = env.step(a).map_err(|e| fail(e.to_string()))?;
            ret += s.reward;
            if s.done() {
                break;
            }
            obs = s.observation;
        }
        returns.push(ret);
    }
    let mean_return = returns.iter().sum::<f64>() / returns.len() as f64;
    let min_return = returns.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(Evaluation {
        first_seed,
        returns,
        mean_return,
        min_return,
    })
}
