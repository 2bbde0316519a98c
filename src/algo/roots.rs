//! Roots for the algorithms: the check, at construction, that the scalar has the roots a
//! configuration needs ([`crate::scalar::Roots`]), and the root operations after that check.

use super::error::AlgoError;
use crate::scalar::Scalar;

/// Reject, when an algorithm is built, a configuration that needs roots in a scalar without them.
///
/// # Errors
/// [`AlgoError::NeedsRoots`] naming `algorithm` and `operation` when `S` has no roots.
pub(crate) fn require_roots<S: Scalar>(
    algorithm: &'static str,
    operation: &'static str,
) -> Result<(), AlgoError> {
    if S::HAS_ROOTS {
        Ok(())
    } else {
        Err(AlgoError::NeedsRoots {
            algorithm,
            operation,
        })
    }
}

/// `√x` for an algorithm built with [`require_roots`].
///
/// # Errors
/// [`AlgoError::NeedsRoots`] when `S` has no roots (not reached after [`require_roots`]).
pub(crate) fn sqrt<S: Scalar>(x: &S, algorithm: &'static str) -> Result<S, AlgoError> {
    x.try_sqrt().ok_or(AlgoError::NeedsRoots {
        algorithm,
        operation: "square roots",
    })
}

/// `∛x` for an algorithm built with [`require_roots`].
///
/// # Errors
/// [`AlgoError::NeedsRoots`] when `S` has no roots (not reached after [`require_roots`]).
pub(crate) fn cbrt<S: Scalar>(x: &S, algorithm: &'static str) -> Result<S, AlgoError> {
    x.try_cbrt().ok_or(AlgoError::NeedsRoots {
        algorithm,
        operation: "cube roots",
    })
}
