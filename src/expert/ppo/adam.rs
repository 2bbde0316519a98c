//! The optimiser of PPO's actor and critic: Adam on a flat `f64` vector, and global-norm
//! gradient clipping.

use super::*;

/// A minimal Adam (Kingma & Ba 2015) on a flat `f64` parameter vector, minimising.
#[derive(Debug, Clone)]
pub(super) struct Adam {
    pub(super) m: Vec<f64>,
    pub(super) v: Vec<f64>,
    pub(super) t: i32,
    pub(super) beta1: f64,
    pub(super) beta2: f64,
    pub(super) epsilon: f64,
}

impl Adam {
    pub(super) fn new(dim: usize, config: &PpoConfig) -> Self {
        Adam {
            m: vec![0.0; dim],
            v: vec![0.0; dim],
            t: 0,
            beta1: config.adam_beta1,
            beta2: config.adam_beta2,
            epsilon: config.adam_epsilon,
        }
    }

    /// `m ← β₁m + (1 − β₁)g`, `v ← β₂v + (1 − β₂)g²`,
    /// `θ ← θ − lr · (m/(1 − β₁ᵗ)) / (√(v/(1 − β₂ᵗ)) + ε)`.
    pub(super) fn step(&mut self, params: &mut [f64], grad: &[f64], lr: f64) {
        self.t = self.t.saturating_add(1);
        let bc1 = 1.0 - self.beta1.powi(self.t);
        let bc2 = 1.0 - self.beta2.powi(self.t);
        for (((p, g), m), v) in params
            .iter_mut()
            .zip(grad)
            .zip(&mut self.m)
            .zip(&mut self.v)
        {
            *m = self.beta1 * *m + (1.0 - self.beta1) * g;
            *v = self.beta2 * *v + (1.0 - self.beta2) * g * g;
            *p -= lr * (*m / bc1) / ((*v / bc2).sqrt() + self.epsilon);
        }
    }
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
