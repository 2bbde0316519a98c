//! Why an algorithm could not be built or could not step ([`AlgoError`]), and the checks that
//! produce those errors.

use crate::problem::OracleError;
use crate::scalar::{Scalar, Undecidable};
use nalgebra::DVector;
use std::cmp::Ordering;

/// Why an algorithm could not be built or could not take a step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AlgoError {
    /// A hyper-parameter is invalid (negative or NaN step size, β ∉ [0, 1], zero budget, …).
    #[error("invalid hyper-parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter, as named in the docs and in the JSON config.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The algorithm (or the chosen schedule) needs square or cube roots, which the scalar lacks
    /// (exact rationals; see [`crate::scalar::Roots`]): build it in a scalar with roots or pick a
    /// schedule of field operations only.
    #[error("{algorithm} needs {operation}, which this scalar type does not provide")]
    NeedsRoots {
        /// The algorithm or schedule.
        algorithm: &'static str,
        /// The missing operation.
        operation: &'static str,
    },
    /// The gradient oracle failed.
    #[error(transparent)]
    Oracle(#[from] OracleError),
    /// Interval arithmetic could not decide a branch.
    #[error(transparent)]
    Undecidable(#[from] Undecidable),
    /// A value that must be finite is not (the run stops; nothing is silently NaN).
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// θ has the wrong length.
    #[error("θ has {got} entries, the problem needs {expected}")]
    Dimension {
        /// Entries the problem needs.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// `step` was called before `init`, or after the algorithm finished.
    #[error("algorithm state: {0}")]
    State(&'static str),
    /// A dataset learner has no data to train on.
    #[error("empty dataset")]
    EmptyDataset,
}

impl From<crate::scalar::NonFiniteNumber> for AlgoError {
    /// [`AlgoError::InvalidParameter`]: the parameter "is not finite".
    fn from(e: crate::scalar::NonFiniteNumber) -> AlgoError {
        invalid(e.name, "is not finite")
    }
}

/// Shorthand for [`AlgoError::InvalidParameter`].
pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> AlgoError {
    AlgoError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

/// Error if any entry is not finite.
pub(crate) fn check_finite<S: Scalar>(x: &DVector<S>, what: &'static str) -> Result<(), AlgoError> {
    if crate::scalar::all_finite(x.as_slice()) {
        Ok(())
    } else {
        Err(AlgoError::NonFinite(what))
    }
}

/// Error if θ has the wrong length.
pub(crate) fn check_dim<S>(expected: usize, theta: &DVector<S>) -> Result<(), AlgoError> {
    if theta.len() == expected {
        Ok(())
    } else {
        Err(AlgoError::Dimension {
            expected,
            got: theta.len(),
        })
    }
}

/// `min(1, x)` with a certain comparison.
pub(crate) fn min_one<S: Scalar>(x: S, what: &'static str) -> Result<S, AlgoError> {
    match x.certain_cmp(&S::one()) {
        Some(Ordering::Greater) => Ok(S::one()),
        Some(_) => Ok(x),
        None => Err(Undecidable { what }.into()),
    }
}
