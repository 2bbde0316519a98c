//! The optimiser of PPO's actor and critic: the kit's Adam ([`crate::algo::adam::AdamRule`]) on
//! the flat `f64` weights with the learning rate annealed per step, and global-norm gradient
//! clipping.

use super::*;
use crate::algo::adam::{AdamConfig, AdamRule};
use crate::scalar::ConfigNumber;

/// Adam with `config`'s β₁, β₂ and ε (its α is unused: each step passes its learning rate).
pub(super) fn adam(config: &PpoConfig) -> Result<AdamRule<f64>, PpoError> {
    AdamRule::new(&AdamConfig {
        alpha: ConfigNumber::Float(1.0),
        beta1: config.adam_beta1.into(),
        beta2: config.adam_beta2.into(),
        epsilon: config.adam_epsilon.into(),
    })
    .map_err(|e| invalid("adam", e.to_string()))
}

/// One Adam step of `params` along `grad` with learning rate `lr`; a failure is
/// [`PpoError::NonFinite`] at `iteration`.
pub(super) fn adam_step(
    adam: &mut AdamRule<f64>,
    params: &mut [f64],
    grad: &[f64],
    lr: f64,
    iteration: usize,
) -> Result<(), PpoError> {
    adam.update(params, grad, &lr)
        .map_err(|_| PpoError::NonFinite {
            iteration,
            what: "Adam step",
        })
}

/// Rescale `g` to Euclidean norm `max` if it is longer.
pub(super) fn clip_global_norm(g: &mut [f64], max: Option<f64>) {
    if let Some(max) = max {
        let norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > max {
            let s = max / norm;
            g.iter_mut().for_each(|x| *x *= s);
        }
    }
}
