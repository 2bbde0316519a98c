//! The appendix's note beside the STORM verdicts: why the thesis's unweighted STORM diverges
//! (math.md §10), with the exact toy instance computed when the appendix is written.

use super::aggregate::num;
use super::blocks::Block;
use ilopt::algo::storm_stability::{eigenvalues, threshold};
use ilopt::exact::storm_jacobian::{Matrix, hessian, unweighted, weighted};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DMatrix;

/// The toy MDP of the exact instance (math.md §6's M1), embedded so that an installed binary
/// writes the same note.
const M1: &str = include_str!("../../../examples/toy/m1-tied.json");

/// The exact instance: `E[J]`, `C` and ∇²F of M1 at θ = 0 (one parameter), and the amplification
/// thresholds η*(a) of the unweighted and the importance-weighted mean recursions.
pub struct Instance {
    /// `E[J]` (1 × 1).
    pub mean_jacobian: BigRational,
    /// C = E[g ∇log pᵀ] (1 × 1).
    pub covariance: BigRational,
    /// ∇²F (1 × 1).
    pub hessian: BigRational,
    /// Whether `E[J] + C == ∇²F` and the per-decision weighted term's mean Jacobian == ∇²F, exactly.
    pub identities_hold: bool,
    /// (a, η* unweighted, η* weighted).
    pub thresholds: Vec<(f64, f64, f64)>,
}

fn first(m: &Matrix<BigRational>) -> Option<BigRational> {
    m.first()?.first().cloned()
}

fn f64_matrix(m: &Matrix<BigRational>) -> DMatrix<f64> {
    let d = m.len();
    DMatrix::from_fn(d, d, |i, j| m[i][j].to_f64())
}

/// Compute the instance.
///
/// # Errors
/// A message if the embedded MDP or the exact engine fails.
pub fn instance() -> Result<Instance, String> {
    let mdp = ToyMdp::from_json_str(M1).map_err(|e| e.to_string())?;
    let p = ToyProblem::<BigRational>::new(&mdp);
    let theta = vec![BigRational::zero(); mdp.policy.dim()];
    let u = unweighted(&p, &theta).map_err(|e| e.to_string())?;
    let h = hessian(&p, &theta).map_err(|e| e.to_string())?;
    let w = weighted(&p, &theta, Weighting::PerDecision).map_err(|e| e.to_string())?;
    let sum: Matrix<BigRational> = u
        .mean_jacobian
        .iter()
        .zip(&u.covariance)
        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x.clone() + y).collect())
        .collect();
    let (lu, lh) = (
        eigenvalues(&f64_matrix(&u.mean_jacobian)).map_err(|e| e.to_string())?,
        eigenvalues(&f64_matrix(&h)).map_err(|e| e.to_string())?,
    );
    let thresholds = [0.1, 0.5, 0.9]
        .iter()
        .map(|&a| {
            Ok((
                a,
                threshold(&lu, a).map_err(|e| e.to_string())?,
                threshold(&lh, a).map_err(|e| e.to_string())?,
            ))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Instance {
        mean_jacobian: first(&u.mean_jacobian).ok_or("empty E[J]")?,
        covariance: first(&u.covariance).ok_or("empty C")?,
        hessian: first(&h).ok_or("empty Hessian")?,
        identities_hold: sum == h && w == h,
        thresholds,
    })
}

/// The note's blocks (a paragraph saying why the instance could not be computed, if it could
/// not).
pub fn blocks() -> Vec<Block> {
    let body = match instance() {
        Ok(x) => format!(
            "On the toy MDP M1 (math.md §6) at θ = 0 the kit computes, exactly in rationals: \
             E[J] = {}, C = {}, ∇²F = {} ({}). The mean recursion amplifies above η*(a): \
             {} for the unweighted term against {} for the importance-weighted one. On the two \
             tasks, E[J] estimated from sampled trajectories is strongly negative (a \
             loss-weighted Fisher information), so the unweighted thresholds lie far below the \
             weighted ones; docs/math.md §10 gives the measured eigenvalues and thresholds and \
             `cargo run --release -p paper-checks --example storm_stability -- obstacle` \
             (or `cartpole`, `toy`) recomputes them.",
            x.mean_jacobian,
            x.covariance,
            x.hessian,
            if x.identities_hold {
                "E[J] + C = ∇²F and the weighted term's mean Jacobian = ∇²F hold with `==`"
            } else {
                "the identities E[J] + C = ∇²F and E[J̃] = ∇²F FAIL here: a defect of the kit"
            },
            x.thresholds
                .iter()
                .map(|(a, u, _)| format!("η*({a}) = {}", num(*u)))
                .collect::<Vec<_>>()
                .join(", "),
            x.thresholds
                .iter()
                .map(|(_, _, w)| num(*w))
                .collect::<Vec<_>>()
                .join(", "),
        ),
        Err(e) => format!("(The exact instance could not be computed: {e}.)"),
    };
    vec![
        Block::Heading {
            level: 2,
            text: "Why the thesis's STORM diverges (beyond the thesis)".into(),
        },
        Block::Para(
            "The unweighted STORM rows (E10) diverge where the importance-weighted rows do not. \
             Linearised, the recursion's error obeys d_{k+1} ≈ (1−a)(I − ηJ_τ) d_k + a·g, with \
             J_τ the Jacobian in θ of one trajectory's estimate at a fixed trajectory. For the \
             unweighted old-point term the mean of J_τ is not ∇²F but E[J] = ∇²F − C, with \
             C = E[g ∇log p(τ; θ)ᵀ], a covariance-sized term; for the importance-weighted term \
             its mean is ∇²F exactly. The mean recursion amplifies when the spectral radius of \
             (1−a)(I − ηE[J]) exceeds 1: for a real eigenvalue λ < 0 of E[J], as soon as \
             η > a/((1−a)|λ|) (docs/math.md §10)."
                .into(),
        ),
        Block::Para(body),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The instance is computed, its identities hold, and the unweighted threshold is the
    /// smaller at θ = 0 on M1 (the exact check's independent route is tests/exactness).
    #[test]
    fn the_exact_instance_separates_the_two_terms() {
        let x = instance().unwrap();
        assert!(x.identities_hold);
        assert_ne!(x.covariance, BigRational::zero());
        assert_eq!(
            x.mean_jacobian.clone() + x.covariance.clone(),
            x.hessian.clone()
        );
        for (_, u, w) in &x.thresholds {
            assert!(u < w, "{u} vs {w}");
        }
        let text = super::super::blocks::markdown(&blocks());
        assert!(
            text.contains(&format!("E[J] = {}, C = {}", x.mean_jacobian, x.covariance)),
            "{text}"
        );
        assert!(text.contains("hold with `==`"), "{text}");
    }
}
