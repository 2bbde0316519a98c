//! PPO's networks in `f64` over a batch of observations, without allocating per call.
//!
//! [`BatchMlp`] performs, for every sample, the floating-point operations of [`Mlp::forward`]
//! (with [`crate::policy::tanh`]) and [`Mlp::backward`] in the same order, so its activations
//! and gradients are those of the generic network bit for bit; only the loops differ. The first
//! layer runs across the hidden units with W₁ stored by columns (one `h`-long column per input),
//! tanh calls `exp` once per unit and finishes across the whole batch, the output layer runs
//! four samples and all outputs at a time (independent sums, each still in hidden-unit order),
//! and the back-propagation is one pass over the hidden units per sample that adds the sample's
//! gradient into the batch's in sample order (the generic path's `grad += g`), with ∂/∂W₁
//! accumulated by columns and written in the [`Mlp`] layout at the end. The weights are checked
//! once per [`BatchMlp::load`], not per sample; the observations and the pre-activations once
//! per batch.

use super::*;
use crate::policy::check_vec;

/// The network's input size (CartPole's observation).
const N: usize = OBSERVATION_DIM;

/// A one-hidden-layer tanh [`Mlp`] with `N` inputs and `K` outputs, evaluated on batches of
/// observations in `f64` (module docs): the loaded weights, and the activations of the last
/// [`BatchMlp::forward`].
#[derive(Debug, Clone)]
pub(super) struct BatchMlp<const K: usize> {
    hidden: usize,
    /// The weights in the [`Mlp`] layout (`W₁ | b₁ | W₂ | b₂`).
    theta: Vec<f64>,
    /// W₁ by columns: `w1t[j·h + i] = (W₁)_ij`.
    w1t: Vec<f64>,
    /// Hidden activations, `h` per sample (pre-activations until tanh is applied).
    u: Vec<f64>,
    /// `exp(−2|x|)` of the pre-activations `x`, `h` per sample.
    t: Vec<f64>,
    /// Outputs, one row per sample.
    out: Vec<[f64; K]>,
    /// ∂/∂W₁ of the batch by columns (as `w1t`).
    gw1t: Vec<f64>,
}

impl<const K: usize> BatchMlp<K> {
    /// Buffers for a network of `hidden` units (no weights loaded yet).
    pub(super) fn new(hidden: usize) -> Self {
        BatchMlp {
            hidden,
            theta: Vec::with_capacity(Self::param_dim(hidden)),
            w1t: vec![0.0; N * hidden],
            u: Vec::new(),
            t: Vec::new(),
            out: Vec::new(),
            gw1t: vec![0.0; N * hidden],
        }
    }

    fn param_dim(hidden: usize) -> usize {
        hidden * N + hidden + K * hidden + K
    }

    /// Copies the weights `theta` ([`Mlp`] layout) for the following passes.
    ///
    /// # Errors
    /// [`PolicyError::Shape`] / [`PolicyError::NonFinite`] for a θ of the wrong length or with a
    /// non-finite entry (as [`Mlp::forward`]).
    pub(super) fn load(&mut self, theta: &[f64]) -> Result<(), PolicyError> {
        let h = self.hidden;
        check_vec("theta", theta, Self::param_dim(h))?;
        self.theta.clear();
        self.theta.extend_from_slice(theta);
        for (i, row) in theta[..h * N].chunks_exact(N).enumerate() {
            for (j, &w) in row.iter().enumerate() {
                self.w1t[j * h + i] = w;
            }
        }
        Ok(())
    }

    /// The outputs of the last [`BatchMlp::forward`], one per observation.
    pub(super) fn outputs(&self) -> &[[f64; K]] {
        &self.out
    }

    /// The forward pass of the loaded network at every observation of `obs`.
    ///
    /// # Errors
    /// [`PolicyError::NonFinite`] for a non-finite observation (`phi`) or hidden pre-activation
    /// (`tanh argument`), as [`Mlp::forward`].
    pub(super) fn forward(&mut self, obs: &[[f64; N]]) -> Result<(), PolicyError> {
        let h = self.hidden;
        let m = obs.len();
        if !obs.iter().flatten().fold(true, |ok, x| ok & x.is_finite()) {
            return Err(PolicyError::NonFinite { param: "phi" });
        }
        self.u.resize(m * h, 0.0);
        self.t.resize(m * h, 0.0);
        self.out.resize(m, [0.0; K]);
        let b1 = &self.theta[h * N..h * N + h];
        // x_i = Σ_j (W₁)_ij φ_j from 0, in j order, then + (b₁)_i.
        let (c0, rest) = self.w1t.split_at(h);
        let (c1, rest) = rest.split_at(h);
        let (c2, c3) = rest.split_at(h);
        for (x, &[p0, p1, p2, p3]) in self.u.chunks_exact_mut(h).zip(obs) {
            for i in 0..h {
                x[i] = 0.0 + c0[i] * p0 + c1[i] * p1 + c2[i] * p2 + c3[i] * p3 + b1[i];
            }
        }
        if !self.u.iter().fold(true, |ok, x| ok & x.is_finite()) {
            return Err(PolicyError::NonFinite {
                param: "tanh argument",
            });
        }
        // tanh x = (1 − t)/(1 + t) for x ≥ 0 and (t − 1)/(t + 1) for x < 0, t = e^{−2|x|}: the
        // exponent −2|x| equals the generic tanh's −2x (x ≥ 0) and 2x (x < 0) exactly.
        for (t, &x) in self.t.iter_mut().zip(&self.u) {
            *t = (-2.0 * x.abs()).exp();
        }
        for (x, &t) in self.u.iter_mut().zip(&self.t) {
            let num = if *x >= 0.0 { 1.0 - t } else { t - 1.0 };
            *x = num / (1.0 + t);
        }
        // o_r = Σ_i (W₂)_ri u_i from 0, in i order, then + (b₂)_r.
        let (_, w2, b2) = tail::<K>(&self.theta, h);
        let mut rows = self.u.chunks_exact(4 * h);
        let mut outs = self.out.chunks_exact_mut(4);
        for (u, o) in rows.by_ref().zip(outs.by_ref()) {
            let (u0, rest) = u.split_at(h);
            let (u1, rest) = rest.split_at(h);
            let (u2, u3) = rest.split_at(h);
            let mut acc = [[0.0; 4]; K];
            for i in 0..h {
                for (a, w) in acc.iter_mut().zip(w2.chunks_exact(h)) {
                    a[0] += w[i] * u0[i];
                    a[1] += w[i] * u1[i];
                    a[2] += w[i] * u2[i];
                    a[3] += w[i] * u3[i];
                }
            }
            for (r, a) in acc.iter().enumerate() {
                for (ol, al) in o.iter_mut().zip(a) {
                    ol[r] = al + b2[r];
                }
            }
        }
        for (u, o) in rows.remainder().chunks_exact(h).zip(outs.into_remainder()) {
            for r in 0..K {
                let w = &w2[r * h..(r + 1) * h];
                o[r] = w.iter().zip(u).fold(0.0, |acc, (a, b)| acc + a * b) + b2[r];
            }
        }
        Ok(())
    }

    /// `grad = Σ_s ∂J_s/∂θ` in the [`Mlp`] layout, the per-sample gradients (back-propagated from
    /// `delta[s] = ∂J_s/∂o` at the last [`BatchMlp::forward`]'s activations, on the same `obs`)
    /// added from 0 in sample order.
    ///
    /// # Panics
    /// If `obs` and `delta` do not match the last forward pass or `grad` is not the length of θ.
    pub(super) fn backward(&mut self, obs: &[[f64; N]], delta: &[[f64; K]], grad: &mut [f64]) {
        let h = self.hidden;
        assert_eq!(obs.len(), self.out.len(), "backward: batch size");
        assert_eq!(delta.len(), self.out.len(), "backward: batch size");
        assert_eq!(grad.len(), self.theta.len(), "backward: gradient length");
        grad.fill(0.0);
        self.gw1t.fill(0.0);
        let (_, w2, _) = tail::<K>(&self.theta, h);
        let (_, rest) = grad.split_at_mut(h * N);
        let (gb1, rest) = rest.split_at_mut(h);
        let (gw2, gb2) = rest.split_at_mut(K * h);
        let (g0, rest) = self.gw1t.split_at_mut(h);
        let (g1, rest) = rest.split_at_mut(h);
        let (g2, g3) = rest.split_at_mut(h);
        for ((u, &[p0, p1, p2, p3]), d) in self.u.chunks_exact(h).zip(obs).zip(delta) {
            for i in 0..h {
                // γ_i = (Σ_r (W₂)_ri δ_r from 0, in r order) · (1 − u_i²).
                let mut back = 0.0;
                for r in 0..K {
                    back += w2[r * h + i] * d[r];
                }
                let g = back * (1.0 - u[i] * u[i]);
                g0[i] += g * p0;
                g1[i] += g * p1;
                g2[i] += g * p2;
                g3[i] += g * p3;
                gb1[i] += g;
                for r in 0..K {
                    gw2[r * h + i] += d[r] * u[i];
                }
            }
            for (a, &dr) in gb2.iter_mut().zip(d) {
                *a += dr;
            }
        }
        for (i, row) in grad[..h * N].chunks_exact_mut(N).enumerate() {
            for (j, g) in row.iter_mut().enumerate() {
                *g = self.gw1t[j * h + i];
            }
        }
    }
}

/// The weights `theta` ([`Mlp`] layout, `h` hidden units, `K` outputs) after W₁: `(b₁, W₂, b₂)`.
fn tail<const K: usize>(theta: &[f64], h: usize) -> (&[f64], &[f64], &[f64]) {
    let (b1, rest) = theta[h * N..].split_at(h);
    let (w2, b2) = rest.split_at(K * h);
    (b1, w2, b2)
}
