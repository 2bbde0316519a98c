//! The deterministic action of a policy, the one the thesis's evaluations take (chapter 4: the
//! learned policy is scored acting on its output, not on samples): the most probable action of a
//! softmax or logistic policy, the mean of a Gaussian one.

use super::{ActionVector, LinearGaussian, Logistic, Policy, PolicyError, Softmax};
use crate::scalar::{Real, Scalar, certainly_less};

/// A policy's deterministic action at φ.
pub trait Greedy<S: Scalar>: Policy<S> {
    /// The action the policy takes when it does not sample.
    ///
    /// # Errors
    /// As the policy's output (θ or φ of the wrong length, non-finite entries).
    fn greedy(&self, theta: &[S], phi: &[S]) -> Result<Self::Action, PolicyError>;
}

/// `argmax_a z_a` over the logits `z = Θφ`; among equal logits the smallest index.
///
/// # Errors
/// Also [`PolicyError::Undecidable`] when a comparison of logits cannot be decided (an interval
/// overlap, a NaN from an overflowing product).
impl<S: Real> Greedy<S> for Softmax {
    fn greedy(&self, theta: &[S], phi: &[S]) -> Result<usize, PolicyError> {
        let z = self.logits(theta, phi)?;
        let mut best = 0;
        for (a, za) in z.iter().enumerate().skip(1) {
            if certainly_less(&z[best], za, "softmax: the largest logit")? {
                best = a;
            }
        }
        Ok(best)
    }
}

/// Action 1 iff `π_θ(1|s) > ½`, i.e. `θ·φ > 0` (a tie gives action 0).
///
/// # Errors
/// Also [`PolicyError::Undecidable`] when the sign of the logit cannot be decided.
impl<S: Real> Greedy<S> for Logistic {
    fn greedy(&self, theta: &[S], phi: &[S]) -> Result<usize, PolicyError> {
        let z = self.logit(theta, phi)?;
        Ok(usize::from(certainly_less(
            &S::zero(),
            &z,
            "logistic: the sign of the logit",
        )?))
    }
}

/// The mean `Wφ` (math.md §1.3, P3).
impl<S: Scalar, A: ActionVector<S>> Greedy<S> for LinearGaussian<S, A> {
    fn greedy(&self, theta: &[S], phi: &[S]) -> Result<A, PolicyError> {
        let m = self.mean(theta, phi)?;
        Ok(A::build(m.len(), |i| m[i].clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softmax_takes_the_largest_logit_and_the_first_of_a_tie() {
        let p = Softmax::new(3, 1).unwrap();
        assert_eq!(p.greedy(&[1.0, 3.0, 2.0], &[1.0]).unwrap(), 1);
        assert_eq!(p.greedy(&[2.0, 1.0, 2.0], &[1.0]).unwrap(), 0);
        assert_eq!(p.greedy(&[1.0, 2.0, 2.0], &[-1.0]).unwrap(), 0);
        assert!(p.greedy(&[1.0, 2.0], &[1.0]).is_err());
    }

    #[test]
    fn logistic_takes_one_above_a_half() {
        let p = Logistic::new(2).unwrap();
        assert_eq!(p.greedy(&[1.0, -0.5], &[1.0, 1.0]).unwrap(), 1);
        assert_eq!(p.greedy(&[1.0, -1.0], &[1.0, 1.0]).unwrap(), 0);
        assert_eq!(p.greedy(&[1.0, -2.0], &[1.0, 1.0]).unwrap(), 0);
    }

    #[test]
    fn linear_gaussian_takes_its_mean() {
        let p = LinearGaussian::<f64>::new(2, 2, 0.5).unwrap();
        let theta = [1.0, 2.0, 3.0, 4.0];
        let a: Vec<f64> = p.greedy(&theta, &[1.0, -1.0]).unwrap();
        assert_eq!(a, p.mean(&theta, &[1.0, -1.0]).unwrap());
        assert_eq!(a, vec![-1.0, -1.0]);
    }
}
