//! A small multilayer perceptron with one hidden tanh layer, used as the logits of a softmax
//! policy ([`MlpSoftmax`]) or as the mean of a Gaussian policy ([`MlpGaussian`]).
//!
//! Forward pass, with `u` the hidden activations and `o` the output:
//! `u = tanh(W₁φ + b₁)`, `o = W₂u + b₂`.
//!
//! Back-propagation of an output gradient `δ = ∂J/∂o` (for J = the loss or log π):
//! `∂J/∂W₂ = δuᵀ`, `∂J/∂b₂ = δ`, `γ = (W₂ᵀδ) ⊙ (1 − u²)` (as `tanh′ = 1 − tanh²`),
//! `∂J/∂W₁ = γφᵀ`, `∂J/∂b₁ = γ`.
//!
//! The heads supply δ: for the softmax head, `∂l/∂z` of the Brier loss and `e_a − π` for the score
//! (see [`super::softmax`]); for the Gaussian head, `2(o − π*(s))` for the loss and `(a − o)/σ_π²`
//! for the score (as in P3, math.md §1.3).
//!
//! **Layout of θ** (`d = hn + h + kh + k`): `[W₁ | b₁ | W₂ | b₂]`, with `W₁ ∈ S^{h×n}` and
//! `W₂ ∈ S^{k×h}` row-major: `θ[i·n + j] = (W₁)_ij`, `θ[hn + i] = (b₁)_i`,
//! `θ[hn + h + r·h + i] = (W₂)_ri`, `θ[hn + h + kh + r] = (b₂)_r`.

use super::softmax::{check_action, log_softmax, sample_probs, score_logits};
use super::{
    LikelihoodRatio, Policy, PolicyError, brier_logit_gradient, check_out, check_positive,
    check_size, check_vec, from_f64_exact, mat_vec_in_order, softmax_probs,
};
use crate::problem::KitRng;
use crate::sampling::standard_normal;
use crate::scalar::{Real, Scalar};

/// `tanh x`, evaluated overflow-free as `(1 − e^{−2x})/(1 + e^{−2x})` for `x ≥ 0` and
/// `(e^{2x} − 1)/(e^{2x} + 1)` for `x < 0`. Both are exact identities, so branching on the `f64`
/// approximation of x keeps intervals rigorous.
///
/// # Errors
/// [`PolicyError::NonFinite`] for a non-finite `x`.
pub fn tanh<S: Real>(x: &S) -> Result<S, PolicyError> {
    let xf = x.to_f64();
    if !x.is_finite() || !xf.is_finite() {
        return Err(PolicyError::NonFinite {
            param: "tanh argument",
        });
    }
    if xf >= 0.0 {
        let t = (S::from_i64(-2) * x).exp();
        Ok((S::one() - &t) / (S::one() + t))
    } else {
        let t = (S::from_i64(2) * x).exp();
        Ok((t.clone() - S::one()) / (t + S::one()))
    }
}

/// The network `φ ∈ Sⁿ ↦ o ∈ Sᵏ` with `h` hidden tanh units (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mlp {
    inputs: usize,
    hidden: usize,
    outputs: usize,
}

/// The activations of one forward pass.
#[derive(Debug, Clone, PartialEq)]
pub struct Forward<S> {
    /// Hidden activations `u = tanh(W₁φ + b₁)`.
    pub hidden: Vec<S>,
    /// Output `o = W₂u + b₂`.
    pub output: Vec<S>,
}

impl Mlp {
    /// A validated network shape: `n`, `h`, `k` ≥ 1.
    ///
    /// # Errors
    /// [`PolicyError::TooSmall`] naming the zero size.
    pub fn new(inputs: usize, hidden: usize, outputs: usize) -> Result<Self, PolicyError> {
        check_size("inputs", inputs, 1)?;
        check_size("hidden", hidden, 1)?;
        check_size("outputs", outputs, 1)?;
        Ok(Self {
            inputs,
            hidden,
            outputs,
        })
    }

    /// Number of parameters `hn + h + kh + k`.
    pub fn param_dim(&self) -> usize {
        let (n, h, k) = (self.inputs, self.hidden, self.outputs);
        h * n + h + k * h + k
    }
    /// n.
    pub fn inputs(&self) -> usize {
        self.inputs
    }
    /// k.
    pub fn outputs(&self) -> usize {
        self.outputs
    }

    /// Glorot-uniform initialisation, seeded: `(W₁)_ij ∼ U[−r₁, r₁]`, `r₁ = √(6/(n + h))`,
    /// `(W₂)_ri ∼ U[−r₂, r₂]`, `r₂ = √(6/(h + k))`, biases 0. The draws are `f64` converted exactly,
    /// so every scalar type starts from the same point.
    pub fn init<S: Scalar>(&self, rng: &mut KitRng) -> Vec<S> {
        let (n, h, k) = (self.inputs, self.hidden, self.outputs);
        let mut draw = |fan: usize, count: usize, out: &mut Vec<S>| {
            let r = (6.0 / fan as f64).sqrt();
            for _ in 0..count {
                let u: f64 = rand::Rng::random(rng);
                // (2u − 1)·r is finite for u ∈ [0, 1).
                out.push(
                    from_f64_exact((2.0 * u - 1.0) * r, "initial weight")
                        .unwrap_or_else(|_| S::zero()),
                );
            }
        };
        let mut theta = Vec::with_capacity(self.param_dim());
        draw(n + h, h * n, &mut theta);
        theta.extend((0..h).map(|_| S::zero()));
        draw(h + k, k * h, &mut theta);
        theta.extend((0..k).map(|_| S::zero()));
        theta
    }

    /// The forward pass (module docs).
    ///
    /// # Errors
    /// [`PolicyError::Shape`] / [`PolicyError::NonFinite`] for a bad θ or φ.
    pub fn forward<S: Real>(&self, theta: &[S], phi: &[S]) -> Result<Forward<S>, PolicyError> {
        check_vec("theta", theta, self.param_dim())?;
        check_vec("phi", phi, self.inputs)?;
        let (w1, b1, w2, b2) = self.split(theta);
        let hidden = mat_vec_in_order(w1, phi, self.hidden)
            .into_iter()
            .zip(b1)
            .map(|(a, b)| tanh(&(a + b)))
            .collect::<Result<Vec<S>, _>>()?;
        let output = mat_vec_in_order(w2, &hidden, self.outputs)
            .into_iter()
            .zip(b2)
            .map(|(a, b)| a + b)
            .collect();
        Ok(Forward { hidden, output })
    }

    /// Back-propagate the output gradient `delta = ∂J/∂o` to `∂J/∂θ` (module docs), given the
    /// forward pass at the same θ and φ.
    ///
    /// # Errors
    /// [`PolicyError::Shape`] for inconsistent sizes.
    pub fn backward<S: Scalar>(
        &self,
        theta: &[S],
        phi: &[S],
        forward: &Forward<S>,
        delta: &[S],
    ) -> Result<Vec<S>, PolicyError> {
        let mut grad = vec![S::zero(); self.param_dim()];
        self.backward_into(theta, phi, forward, delta, &mut grad)?;
        Ok(grad)
    }

    /// [`Mlp::backward`] written into `grad` (length [`Mlp::param_dim`]), allocating nothing: the
    /// hidden layer's back-propagated `γ` is formed in the `b1` block and the `W1` block is read
    /// off it.
    ///
    /// # Errors
    /// As [`Mlp::backward`], and [`PolicyError::Shape`] for a `grad` of the wrong length.
    pub fn backward_into<S: Scalar>(
        &self,
        theta: &[S],
        phi: &[S],
        forward: &Forward<S>,
        delta: &[S],
        grad: &mut [S],
    ) -> Result<(), PolicyError> {
        check_vec("theta", theta, self.param_dim())?;
        check_vec("phi", phi, self.inputs)?;
        check_vec("hidden", &forward.hidden, self.hidden)?;
        check_vec("delta", delta, self.outputs)?;
        check_out("grad", grad, self.param_dim())?;
        let (_, _, w2, _) = self.split(theta);
        let (n, h) = (self.inputs, self.hidden);
        let (dw1, rest) = grad.split_at_mut(h * n);
        let (gamma, rest) = rest.split_at_mut(h);
        let (dw2, db2) = rest.split_at_mut(self.outputs * h);
        for (i, gi) in gamma.iter_mut().enumerate() {
            let back =
                (0..self.outputs).fold(S::zero(), |acc, r| acc + w2[r * h + i].clone() * &delta[r]);
            *gi = back * (S::one() - forward.hidden[i].square());
        }
        write_outer(gamma, phi, dw1);
        write_outer(delta, &forward.hidden, dw2);
        db2.clone_from_slice(delta);
        Ok(())
    }

    fn split<'a, S>(&self, theta: &'a [S]) -> (&'a [S], &'a [S], &'a [S], &'a [S]) {
        let (n, h, k) = (self.inputs, self.hidden, self.outputs);
        let (w1, rest) = theta.split_at(h * n);
        let (b1, rest) = rest.split_at(h);
        let (w2, b2) = rest.split_at(k * h);
        (w1, b1, w2, b2)
    }
}

/// The row-major outer product `u vᵀ` written into `out` (`u.len() · v.len()` entries).
fn write_outer<S: Scalar>(u: &[S], v: &[S], out: &mut [S]) {
    for (row, ui) in out.chunks_exact_mut(v.len().max(1)).zip(u) {
        for (o, vj) in row.iter_mut().zip(v) {
            *o = ui.clone() * vj;
        }
    }
}

/// Softmax policy whose logits are an [`Mlp`]'s output (`k = A ≥ 2` actions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MlpSoftmax {
    net: Mlp,
}

impl MlpSoftmax {
    /// `A ≥ 2` actions, `n` features, `h` hidden units.
    ///
    /// # Errors
    /// [`PolicyError::TooSmall`] naming the offending size.
    pub fn new(features: usize, hidden: usize, actions: usize) -> Result<Self, PolicyError> {
        check_size("actions", actions, 2)?;
        Ok(Self {
            net: Mlp::new(features, hidden, actions)?,
        })
    }
    /// The network.
    pub fn net(&self) -> &Mlp {
        &self.net
    }
    /// `π_θ(·|s) = softmax(o)`.
    ///
    /// # Errors
    /// As [`Mlp::forward`].
    pub fn probs<S: Real>(&self, theta: &[S], phi: &[S]) -> Result<Vec<S>, PolicyError> {
        softmax_probs(&self.net.forward(theta, phi)?.output)
    }
    /// `log π_θ(a|s)`.
    ///
    /// # Errors
    /// As [`Mlp::forward`], and [`PolicyError::Action`].
    pub fn log_prob<S: Real>(&self, theta: &[S], phi: &[S], a: usize) -> Result<S, PolicyError> {
        log_softmax(&self.net.forward(theta, phi)?.output, a)
    }
}

impl<S: Real> Policy<S> for MlpSoftmax {
    type Action = usize;
    type Label = usize;

    fn param_dim(&self) -> usize {
        self.net.param_dim()
    }
    fn feature_dim(&self) -> usize {
        self.net.inputs
    }

    /// Brier loss on `softmax(o)`, back-propagated from `∂l/∂z` ([`brier_logit_gradient`]) into
    /// `grad` (the forward pass's layers are allocated, the gradient is not).
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &usize,
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        check_action(*label, self.net.outputs)?;
        let f = self.net.forward(theta, phi)?;
        let p = softmax_probs(&f.output)?;
        let (l, dz) = brier_logit_gradient(&p, *label);
        self.net.backward_into(theta, phi, &f, &dz, grad)?;
        Ok(l)
    }

    /// `∇_θ log π(a|s)`, back-propagated from `e_a − π` into `score`.
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &usize,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        check_action(*action, self.net.outputs)?;
        let f = self.net.forward(theta, phi)?;
        let p = softmax_probs(&f.output)?;
        self.net
            .backward_into(theta, phi, &f, &score_logits(&p, *action), score)
    }

    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<usize, PolicyError> {
        sample_probs(&self.probs(theta, phi)?, rng)
    }
}

/// Gaussian policy `N(a; o(φ), σ_π² I_k)` whose mean is an [`Mlp`]'s output.
#[derive(Debug, Clone, PartialEq)]
pub struct MlpGaussian<S> {
    net: Mlp,
    sigma: S,
    sigma_sq: S,
}

impl<S: Scalar> MlpGaussian<S> {
    /// `k` action coordinates, `n` features, `h` hidden units, σ_π finite and certainly > 0.
    ///
    /// # Errors
    /// [`PolicyError::TooSmall`], [`PolicyError::NonFinite`] or [`PolicyError::NotPositive`]
    /// naming the parameter.
    pub fn new(
        features: usize,
        hidden: usize,
        actions: usize,
        sigma: S,
    ) -> Result<Self, PolicyError> {
        let net = Mlp::new(features, hidden, actions)?;
        check_positive("sigma", &sigma)?;
        Ok(Self {
            net,
            sigma_sq: sigma.square(),
            sigma,
        })
    }
    /// The network.
    pub fn net(&self) -> &Mlp {
        &self.net
    }
}

impl<S: Real> MlpGaussian<S> {
    /// `log π_θ(a|s) + (k/2) ln 2π = −‖a − o‖²/(2σ_π²) − k ln σ_π` (see
    /// [`LinearGaussian::log_prob_unnormalised`](super::LinearGaussian::log_prob_unnormalised)).
    ///
    /// # Errors
    /// As [`Mlp::forward`], and [`PolicyError::Shape`] for an action of the wrong length.
    pub fn log_prob_unnormalised(
        &self,
        theta: &[S],
        phi: &[S],
        action: &[S],
    ) -> Result<S, PolicyError> {
        check_vec("action", action, self.net.outputs)?;
        let o = self.net.forward(theta, phi)?.output;
        let r: Vec<S> = action.iter().zip(&o).map(|(a, m)| a.clone() - m).collect();
        let k = S::from_i64(self.net.outputs as i64);
        Ok(-(crate::scalar::norm_sq(&r) / (S::from_i64(2) * &self.sigma_sq)) - k * self.sigma.ln())
    }
}

impl<S: Real> Policy<S> for MlpGaussian<S> {
    type Action = Vec<S>;
    type Label = [S];

    fn param_dim(&self) -> usize {
        self.net.param_dim()
    }
    fn feature_dim(&self) -> usize {
        self.net.inputs
    }

    /// `l = ‖o − π*(s)‖²`, back-propagated from `2(o − π*)` into `grad` (the forward pass's
    /// layers are allocated, the gradient is not).
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        check_vec("label", label, self.net.outputs)?;
        let f = self.net.forward(theta, phi)?;
        let r: Vec<S> = f
            .output
            .iter()
            .zip(label)
            .map(|(o, y)| o.clone() - y)
            .collect();
        let delta: Vec<S> = r.iter().map(|x| S::from_i64(2) * x).collect();
        self.net.backward_into(theta, phi, &f, &delta, grad)?;
        Ok(crate::scalar::norm_sq(&r))
    }

    /// `∇_θ log π(a|s)`, back-propagated from `(a − o)/σ_π²` into `score`.
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &Vec<S>,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        check_vec("action", action, self.net.outputs)?;
        let f = self.net.forward(theta, phi)?;
        let delta: Vec<S> = action
            .iter()
            .zip(&f.output)
            .map(|(a, o)| (a.clone() - o) / &self.sigma_sq)
            .collect();
        self.net.backward_into(theta, phi, &f, &delta, score)
    }

    /// `a = o + σ_π ε`, ε drawn as `k` f64 standard normals converted exactly.
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<Vec<S>, PolicyError> {
        let o = self.net.forward(theta, phi)?.output;
        Ok(o.into_iter()
            .map(|m| m + self.sigma.clone() * standard_normal::<S>(rng))
            .collect())
    }
}

impl<S: Real> LikelihoodRatio<S> for MlpSoftmax {
    fn log_prob(&self, theta: &[S], phi: &[S], action: &usize) -> Result<S, PolicyError> {
        MlpSoftmax::log_prob(self, theta, phi, *action)
    }
}

impl<S: Real> LikelihoodRatio<S> for MlpGaussian<S> {
    /// [`MlpGaussian::log_prob_unnormalised`].
    fn log_prob(&self, theta: &[S], phi: &[S], action: &Vec<S>) -> Result<S, PolicyError> {
        self.log_prob_unnormalised(theta, phi, action)
    }
}
