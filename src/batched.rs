//! Minibatches of trajectories: the mean of m independent eq. 3.15 estimates as one oracle call.

use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use crate::scalar::Scalar;
use nalgebra::DVector;

/// The problem `inner` with every roll-out replaced by `m` independent roll-outs of the same
/// behaviour, and every estimate by their mean: `g_m(θ) = (1/m) Σ_{j=1}^{m} g(θ, τ_j)`, unbiased
/// for ∇F(θ) wherever each `g(θ, τ_j)` is (eq. 3.15; the importance-weighted old-point estimates
/// of IS-STORM likewise, each trajectory with its own weight), with variance divided by m.
///
/// Any algorithm of the kit run on `Batched::new(p, m)` is that algorithm with m trajectories per
/// gradient; its [`Cost`] counts every trajectory and every gradient evaluation.
#[derive(Debug, Clone)]
pub struct Batched<P> {
    inner: P,
    m: usize,
}

impl<P> Batched<P> {
    /// `m` trajectories per oracle call.
    ///
    /// # Errors
    /// [`OracleError::Behaviour`] if `m` is 0.
    pub fn new(inner: P, m: usize) -> Result<Self, OracleError> {
        if m == 0 {
            return Err(OracleError::Behaviour(
                "a minibatch needs at least 1 trajectory, got 0".into(),
            ));
        }
        Ok(Self { inner, m })
    }

    /// The problem each trajectory comes from.
    pub fn inner(&self) -> &P {
        &self.inner
    }

    /// Trajectories per oracle call.
    pub fn size(&self) -> usize {
        self.m
    }
}

/// The mean of `f(τ_j)` over the batch.
///
/// # Errors
/// For an empty batch, and the first error of `f`.
pub(crate) fn mean<S: Scalar, T>(
    batch: &[T],
    mut f: impl FnMut(&T) -> Result<DVector<S>, OracleError>,
) -> Result<DVector<S>, OracleError> {
    let mut parts = batch.iter();
    let first = parts
        .next()
        .ok_or_else(|| OracleError::Trajectory("an empty minibatch".into()))?;
    let mut sum = f(first)?;
    for t in parts {
        sum += f(t)?;
    }
    let m = S::from_i64(batch.len() as i64);
    Ok(sum.map(|x| x / &m))
}

impl<S: Scalar, P: IlProblem<S>> IlProblem<S> for Batched<P> {
    type Trajectory = Vec<P::Trajectory>;
    type Labelled = P::Labelled;

    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// `m` roll-outs in turn from the one RNG.
    fn rollout(
        &mut self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<Self::Trajectory, OracleError> {
        (0..self.m)
            .map(|_| self.inner.rollout(behaviour, rng, cost))
            .collect()
    }

    fn estimate(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        mean(trajectory, |t| self.inner.estimate(theta, t, form, cost))
    }

    /// Each trajectory's estimate and loss from the inner problem's
    /// [`IlProblem::estimate_with_loss`], then the two means as [`IlProblem::estimate`] and
    /// [`IlProblem::trajectory_loss`] form them (the same values).
    fn estimate_with_loss(
        &mut self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<(DVector<S>, S), OracleError> {
        let mut losses = Vec::with_capacity(trajectory.len());
        let g = mean(trajectory, |t| {
            let (g, loss) = self.inner.estimate_with_loss(theta, t, form, cost)?;
            losses.push(loss);
            Ok(g)
        })?;
        let loss = mean(&losses, |l| Ok(DVector::from_element(1, l.clone())))?;
        Ok((g, loss[0].clone()))
    }

    fn weighted_estimate(
        &mut self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &Self::Trajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        mean(trajectory, |t| {
            self.inner
                .weighted_estimate(theta_old, theta_new, t, weighting, cost)
        })
    }

    /// The mean of the trajectories' losses (an unbiased estimate of F(θ) under the learner).
    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
    ) -> Result<S, OracleError> {
        let v = mean(trajectory, |t| {
            Ok(DVector::from_element(
                1,
                self.inner.trajectory_loss(theta, t)?,
            ))
        })?;
        Ok(v[0].clone())
    }

    /// Every trajectory's labelled states, in order.
    fn labelled_states(&self, trajectory: &Self::Trajectory) -> Vec<Self::Labelled> {
        trajectory
            .iter()
            .flat_map(|t| self.inner.labelled_states(t))
            .collect()
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &Self::Labelled,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError> {
        self.inner.supervised(theta, example, grad, cost)
    }
}
