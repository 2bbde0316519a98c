//! STORM's mean linearisation (math.md §10), exactly: for the unweighted old-point term
//! E[J] + C = ∇²F with C = E[g ∇log pᵀ] ≠ 0 in general, and for the importance-weighted terms
//! E[J̃] = ∇²F. Here ∇²F comes from X2 differentiated in duals, E[J] and C from one enumeration,
//! E[J̃] from the oracle's weighted estimate: three computations that share only the policy table.

use crate::common::{example, q};
use ilopt::algo::storm_stability::{eigenvalues, mean_radius, threshold};
use ilopt::exact::importance::bias;
use ilopt::exact::storm_jacobian::{Matrix, hessian, unweighted, weighted};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Scalar};
use ilopt::toy::ToyProblem;
use nalgebra::DMatrix;

/// The example MDPs with rational θ inside each one's domain (the direct parameterisation needs
/// θ in the open simplex).
fn cases() -> Vec<(&'static str, Vec<Vec<&'static str>>)> {
    vec![
        (
            "m1-tied.json",
            vec![vec!["0"], vec!["1/2"], vec!["-3/2"], vec!["2"]],
        ),
        ("m1-softmax.json", vec![vec!["1/3", "-1"], vec!["0", "2"]]),
        (
            "m2-tied-two-groups.json",
            vec![vec!["0", "0"], vec!["1/2", "-1"], vec!["2", "1/3"]],
        ),
        (
            "three-state.json",
            vec![vec!["1/2", "-1", "1", "1/3", "-1/2", "2"]],
        ),
        ("terminal-absorb.json", vec![vec!["1/3"], vec!["3/4"]]),
        ("terminal-reset.json", vec![vec!["1/3"], vec!["1/5"]]),
        ("m1-direct.json", vec![vec!["1/4"], vec!["2/3"]]),
    ]
}

fn theta<S: Scalar>(xs: &[&str]) -> Vec<S> {
    xs.iter().map(|x| S::from_rational(&q(x))).collect()
}

fn sum<S: Scalar>(a: &Matrix<S>, b: &Matrix<S>) -> Matrix<S> {
    a.iter()
        .zip(b)
        .map(|(r, s)| r.iter().zip(s).map(|(x, y)| x.clone() + y).collect())
        .collect()
}

fn is_zero<S: Scalar>(m: &Matrix<S>) -> bool {
    m.iter().flatten().all(|x| *x == S::zero())
}

/// E[J] + C = ∇²F and E[J̃] = ∇²F (both weightings) on every case, with equality of scalars.
/// Returns how many cases had C ≠ 0.
fn identities_hold<S: Scalar>() -> usize {
    let mut nonzero = 0;
    for (file, thetas) in cases() {
        let p = ToyProblem::<S>::new(&example(file));
        for xs in thetas {
            let th = theta::<S>(&xs);
            let h = hessian(&p, &th).unwrap();
            let u = unweighted(&p, &th).unwrap();
            assert_eq!(
                sum(&u.mean_jacobian, &u.covariance),
                h,
                "{file} at {xs:?}: E[J] + C ≠ ∇²F"
            );
            for w in [Weighting::Trajectory, Weighting::PerDecision] {
                assert_eq!(
                    weighted(&p, &th, w).unwrap(),
                    h,
                    "{file} at {xs:?}: E[J̃] ({w:?}) ≠ ∇²F"
                );
            }
            if !is_zero(&u.covariance) {
                assert_ne!(u.mean_jacobian, h, "{file} at {xs:?}");
                nonzero += 1;
            }
        }
    }
    nonzero
}

fn identities_hold_and_c_is_not_zero<S: Scalar>() {
    let nonzero = identities_hold::<S>();
    assert!(nonzero >= 5, "C ≠ 0 in only {nonzero} cases");
}

/// The check can fail: a perturbed C, or the importance-weighted Jacobian in place of E[J], breaks
/// E[J] + C = ∇²F where C ≠ 0.
fn mutants_break_the_identity<S: Scalar>() {
    let p = ToyProblem::<S>::new(&example("m2-tied-two-groups.json"));
    let th = theta::<S>(&["1/2", "-1"]);
    let h = hessian(&p, &th).unwrap();
    let u = unweighted(&p, &th).unwrap();
    assert!(!is_zero(&u.covariance));
    let mut c = u.covariance.clone();
    c[1][0] += S::from_ratio(1, 1000);
    assert_ne!(sum(&u.mean_jacobian, &c), h, "a perturbed C");
    let is = weighted(&p, &th, Weighting::Trajectory).unwrap();
    assert_ne!(sum(&is, &u.covariance), h, "the IS Jacobian as E[J]");
    // E[J] itself is not symmetric here: its antisymmetric part is −C's.
    assert_ne!(u.mean_jacobian[0][1], u.mean_jacobian[1][0]);
}

/// C is the first-order coefficient of the old-point bias (I4, math.md §4):
/// `∂b(θ, θ′)/∂θ′ at θ′ = θ` equals C, with b the kit's own [`bias`] evaluated in duals (θ′ seeded
/// as variables, θ constant). A route to C that shares no code with [`unweighted`] but the
/// enumeration and the estimator.
fn c_is_the_derivative_of_the_bias<S: Scalar>() {
    for (file, thetas) in cases() {
        let mdp = example(file);
        let (p, pd) = (ToyProblem::<S>::new(&mdp), ToyProblem::<Dual<S>>::new(&mdp));
        for xs in thetas {
            let th = theta::<S>(&xs);
            let fixed: Vec<Dual<S>> = th.iter().cloned().map(Dual::constant).collect();
            let b = bias(&pd, &fixed, &Dual::variables(&th)).unwrap();
            let c: Matrix<S> = b.into_iter().map(|x| x.into_parts(th.len()).1).collect();
            assert_eq!(
                c,
                unweighted(&p, &th).unwrap().covariance,
                "{file} at {xs:?}"
            );
        }
    }
}

macro_rules! for_each_exact_scalar {
    ($body:ident: $($name:ident => $t:ty),+ $(,)?) => {
        mod $body {
            use super::*;
            $( #[test] fn $name() { $body::<$t>(); } )+
        }
    };
}

for_each_exact_scalar!(identities_hold_and_c_is_not_zero:
    rational => BigRational,
    dual_rational => Dual<BigRational>,
);
for_each_exact_scalar!(c_is_the_derivative_of_the_bias:
    rational => BigRational,
    dual_rational => Dual<BigRational>,
);
for_each_exact_scalar!(mutants_break_the_identity:
    rational => BigRational,
    dual_rational => Dual<BigRational>,
);

fn to_f64(m: &Matrix<BigRational>) -> DMatrix<f64> {
    let d = m.len();
    DMatrix::from_fn(d, d, |i, j| m[i][j].to_f64())
}

/// On M1 there is a θ and a step size at which the unweighted mean recursion amplifies while
/// the importance-weighted one contracts: the mean thresholds η*(a) of E[J] and ∇²F, computed
/// from the exact matrices, differ, and a step between them separates the radii.
#[test]
fn the_unweighted_recursion_amplifies_where_the_weighted_one_contracts() {
    let p = ToyProblem::<BigRational>::new(&example("m1-tied.json"));
    let mut found = 0;
    for x in ["-2", "-1", "-1/2", "0", "1/4", "1/2", "1", "2", "3"] {
        let th = vec![q(x)];
        let u = eigenvalues(&to_f64(&unweighted(&p, &th).unwrap().mean_jacobian)).unwrap();
        let h = eigenvalues(&to_f64(&hessian(&p, &th).unwrap())).unwrap();
        for a in [0.1, 0.5, 0.9] {
            let (tu, th_) = (threshold(&u, a).unwrap(), threshold(&h, a).unwrap());
            if tu < th_ {
                let eta = (tu * th_).sqrt();
                let eta = if eta.is_finite() { eta } else { 2.0 * tu };
                assert!(mean_radius(&u, eta, a).unwrap() > 1.0);
                assert!(mean_radius(&h, eta, a).unwrap() < 1.0);
                found += 1;
            }
        }
    }
    assert!(found > 0, "no separating (θ, a) on M1");
}
