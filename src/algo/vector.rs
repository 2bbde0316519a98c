//! Entrywise vector operations of the update formulas, generic over the scalar.

use crate::scalar::Scalar;
use nalgebra::DVector;

/// `a·x + y`, entrywise.
pub(crate) fn axpy<S: Scalar>(a: &S, x: &DVector<S>, y: &DVector<S>) -> DVector<S> {
    x.zip_map(y, |xi, yi| a.clone() * xi + yi)
}

/// `Σ xᵢ²`.
pub(crate) fn norm_sq<S: Scalar>(x: &DVector<S>) -> S {
    x.iter().fold(S::zero(), |acc, v| acc + v.square())
}

/// `x · a`, entrywise.
pub(crate) fn scale<S: Scalar>(a: &S, x: &DVector<S>) -> DVector<S> {
    x.map(|xi| a.clone() * xi)
}
