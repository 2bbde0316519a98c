//! When STORM's linearised direction recursion amplifies (math.md §10.2): the spectral radius of
//! the mean error dynamics `M(η, a) = (1 − a)(I − η A)` and the step size at which it passes 1.
//!
//! `A` is the mean linearisation E\[J̃\] of the old-point term: E\[J\] = ∇²F − C for the thesis's
//! unweighted term, ∇²F for the importance-weighted one ([`crate::exact::storm_jacobian`] computes
//! both exactly on toy MDPs). Everything here is a function of A's eigenvalues λ (complex in
//! general: E\[J\] is not symmetric), in `f64`.
//!
//! For one eigenvalue λ = x + iy, `(1 − a)²|1 − ηλ|² > 1` reads
//! `|λ|² η² − 2x η − q > 0` with `q = 1/(1 − a)² − 1`; for 0 < a < 1 the quadratic has one negative
//! and one positive root, so the factor amplifies exactly for `η > η₊(λ) = (x + √(x² + q|λ|²))/|λ|²`.
//! For real λ < 0 this is `a/((1 − a)|λ|)`; for real λ > 0 it is `(1 + 1/(1 − a))/λ`. The mean
//! recursion amplifies iff `η > η*(a) = min_λ η₊(λ)` (λ = 0 never amplifies).
//!
//! The second moment of the linearised recursion (fresh τ each step, independent of d_k) obeys
//! `E[d_{k+1} d_{k+1}ᵀ] = (1 − a)² E[(I − ηJ) E[d_k d_kᵀ] (I − ηJ)ᵀ] + …`, whose operator on
//! vec(Σ) is `(1 − a)² (I⊗I − η(E[J]⊗I + I⊗E[J]) + η² E[J⊗J])` ([`second_moment_radius`]).

use nalgebra::{Complex, DMatrix};

/// Why a stability quantity was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StabilityError {
    /// The momentum weight must lie in \[0, 1).
    #[error("the momentum weight a must lie in [0, 1), got {0}")]
    Momentum(f64),
    /// The step size must be finite and non-negative.
    #[error("the step size η must be finite and non-negative, got {0}")]
    Step(f64),
    /// A matrix had the wrong shape or a non-finite entry.
    #[error("{0}")]
    Matrix(String),
}

fn check(eta: f64, a: f64) -> Result<(), StabilityError> {
    if !(0.0..1.0).contains(&a) {
        return Err(StabilityError::Momentum(a));
    }
    if !eta.is_finite() || eta < 0.0 {
        return Err(StabilityError::Step(eta));
    }
    Ok(())
}

/// The eigenvalues of a square matrix with finite entries (real Schur form).
///
/// # Errors
/// [`StabilityError::Matrix`] for a non-square matrix or a non-finite entry.
pub fn eigenvalues(m: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, StabilityError> {
    if !m.is_square() {
        return Err(StabilityError::Matrix(format!(
            "a {}×{} matrix has no eigenvalues",
            m.nrows(),
            m.ncols()
        )));
    }
    if m.iter().any(|x| !x.is_finite()) {
        return Err(StabilityError::Matrix("a non-finite entry".into()));
    }
    Ok(m.complex_eigenvalues().iter().copied().collect())
}

/// `ρ((1 − a)(I − ηA)) = (1 − a) max_λ |1 − ηλ|` over A's eigenvalues (1 − a for an empty list).
///
/// # Errors
/// [`StabilityError`] for a ∉ \[0, 1) or a negative or non-finite η.
pub fn mean_radius(eigenvalues: &[Complex<f64>], eta: f64, a: f64) -> Result<f64, StabilityError> {
    check(eta, a)?;
    if eigenvalues.is_empty() {
        return Ok(1.0 - a);
    }
    let worst = eigenvalues
        .iter()
        .map(|l| (Complex::new(1.0, 0.0) - l * eta).norm())
        .fold(0.0f64, f64::max);
    Ok((1.0 - a) * worst)
}

/// `η₊(λ)` of the module docs: the step size above which `(1 − a)|1 − ηλ| > 1`; +∞ for λ = 0.
///
/// # Errors
/// [`StabilityError::Momentum`] for a ∉ \[0, 1).
pub fn eigenvalue_threshold(lambda: Complex<f64>, a: f64) -> Result<f64, StabilityError> {
    check(0.0, a)?;
    let m2 = lambda.norm_sqr();
    if m2 == 0.0 {
        return Ok(f64::INFINITY);
    }
    let q = 1.0 / ((1.0 - a) * (1.0 - a)) - 1.0;
    let x = lambda.re;
    let root = (x * x + q * m2).sqrt();
    // x + √(x² + q|λ|²) without cancellation when x < 0: multiply by the conjugate.
    Ok(if x >= 0.0 {
        (x + root) / m2
    } else {
        q / (root - x)
    })
}

/// `η*(a) = min_λ η₊(λ)`: the smallest step size at which the mean recursion amplifies
/// (it amplifies for every larger η); +∞ when every eigenvalue is 0 or the list is empty.
///
/// # Errors
/// [`StabilityError::Momentum`] for a ∉ \[0, 1).
pub fn threshold(eigenvalues: &[Complex<f64>], a: f64) -> Result<f64, StabilityError> {
    let mut best = f64::INFINITY;
    for l in eigenvalues {
        best = best.min(eigenvalue_threshold(*l, a)?);
    }
    check(0.0, a)?;
    Ok(best)
}

/// The spectral radius of the second-moment operator
/// `(1 − a)² (I⊗I − η(E[J]⊗I + I⊗E[J]) + η² E[J⊗J])` on d × d matrices, given `mean` = E\[J\]
/// (d × d) and `kron` = E\[J ⊗ J\] (d² × d², row `i·d + k`, column `j·d + l` holding E\[J_ij J_kl\]).
///
/// # Errors
/// [`StabilityError`] for a bad (η, a) or matrices of the wrong shape.
pub fn second_moment_radius(
    mean: &DMatrix<f64>,
    kron: &DMatrix<f64>,
    eta: f64,
    a: f64,
) -> Result<f64, StabilityError> {
    check(eta, a)?;
    let d = mean.nrows();
    if !mean.is_square() || kron.nrows() != d * d || kron.ncols() != d * d {
        return Err(StabilityError::Matrix(format!(
            "E[J] is {}×{} and E[J⊗J] {}×{}; expected d×d and d²×d²",
            mean.nrows(),
            mean.ncols(),
            kron.nrows(),
            kron.ncols()
        )));
    }
    let id = DMatrix::<f64>::identity(d, d);
    let op = (DMatrix::<f64>::identity(d * d, d * d)
        - (mean.kronecker(&id) + id.kronecker(mean)) * eta
        + kron * (eta * eta))
        * ((1.0 - a) * (1.0 - a));
    Ok(eigenvalues(&op)?
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At η = η₊(λ) the factor's modulus is 1, just below it < 1, just above it > 1, for real
    /// eigenvalues of both signs and a complex one; the closed forms for real λ agree.
    #[test]
    fn the_threshold_is_where_the_factor_crosses_one() {
        for a in [0.1, 0.5, 0.9] {
            for l in [
                Complex::new(-3.0, 0.0),
                Complex::new(2.0, 0.0),
                Complex::new(0.5, 4.0),
                Complex::new(-1e-3, 2.0),
            ] {
                let e = eigenvalue_threshold(l, a).unwrap();
                let at = |eta: f64| mean_radius(&[l], eta, a).unwrap();
                assert!((at(e) - 1.0).abs() < 1e-12, "{l} {a}: {}", at(e));
                assert!(at(e * (1.0 - 1e-6)) < 1.0 && at(e * (1.0 + 1e-6)) > 1.0);
            }
            let neg = eigenvalue_threshold(Complex::new(-3.0, 0.0), a).unwrap();
            assert!((neg - a / ((1.0 - a) * 3.0)).abs() < 1e-14);
            let pos = eigenvalue_threshold(Complex::new(2.0, 0.0), a).unwrap();
            assert!((pos - (1.0 + 1.0 / (1.0 - a)) / 2.0).abs() < 1e-14);
        }
        assert_eq!(
            threshold(&[Complex::new(0.0, 0.0)], 0.5).unwrap(),
            f64::INFINITY
        );
    }

    /// With a deterministic J (E[J⊗J] = E[J]⊗E[J]) the second-moment radius is the square of
    /// the mean radius.
    #[test]
    fn a_deterministic_jacobian_has_the_squared_radius() {
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, -0.5, 0.3]);
        let l = eigenvalues(&m).unwrap();
        for (eta, a) in [(0.1, 0.5), (1.0, 0.1), (0.01, 0.9)] {
            let r1 = mean_radius(&l, eta, a).unwrap();
            let r2 = second_moment_radius(&m, &m.kronecker(&m), eta, a).unwrap();
            assert!((r2 - r1 * r1).abs() < 1e-10, "{r2} vs {r1}²");
        }
    }

    #[test]
    fn bad_input_is_refused() {
        assert_eq!(
            mean_radius(&[], 0.1, 1.0),
            Err(StabilityError::Momentum(1.0))
        );
        assert!(matches!(
            mean_radius(&[], f64::NAN, 0.5),
            Err(StabilityError::Step(_))
        ));
        assert!(threshold(&[], -0.1).is_err());
        let m = DMatrix::<f64>::zeros(2, 3);
        assert!(eigenvalues(&m).is_err());
        assert!(
            second_moment_radius(&DMatrix::zeros(2, 2), &DMatrix::zeros(3, 3), 0.1, 0.5).is_err()
        );
    }
}
