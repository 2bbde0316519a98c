//! Helpers and fixtures shared by the theory tests.

use ilopt::exact::enumerate::prefixes;
use ilopt::scalar::{BigRational, Scalar, parse_exact};
use ilopt::toy::ToyProblem;
use ilopt_theory::certify::global::{GlobalConstants, GlobalSizes};
use ilopt_theory::protocol::m1_tied;
use ilopt_theory::protocol::{FAMILY_ALPHA, Profile, STATISTICAL_CLAIMS};
use ilopt_theory::stats::bonferroni;
use std::sync::OnceLock;

/// The exact rational written `s` ("7/8", "-2").
pub fn q(s: &str) -> BigRational {
    parse_exact(s).unwrap()
}

/// The global constants of M1 at θ₁ = 0 at the quick profile's sizes (as the table computes
/// them), computed once for every test of the binary.
pub fn quick_global_constants() -> &'static GlobalConstants {
    static K: OnceLock<GlobalConstants> = OnceLock::new();
    K.get_or_init(|| {
        let s = Profile::Quick.sizes();
        GlobalConstants::compute(
            &m1_tied(),
            &[q("0")],
            Some(&q("7/8")),
            GlobalSizes {
                tol: s.bnb_tol,
                max_boxes: 200_000,
                l_tilde_tol: s.l_tilde_tol,
                l_tilde_boxes: s.l_tilde_boxes,
            },
        )
        .unwrap()
    })
}

/// The table's per-check false-alarm probability (the family α split over the statistical claims).
pub fn table_alpha() -> f64 {
    bonferroni(FAMILY_ALPHA, STATISTICAL_CLAIMS)
}

/// V_IS(θ, θ′) = Σ_τ̄ p(τ̄; θ′) ‖g(θ′, τ̄) − w g(θ, τ̄)‖² with the trajectory weight
/// w = p(τ̄; θ)/p(τ̄; θ′), exactly, from the prefix enumeration (independent of the engine's
/// importance-weighted estimator).
pub fn v_is_trajectory(
    p: &ToyProblem<BigRational>,
    theta: &BigRational,
    prime: &BigRational,
) -> BigRational {
    let a = prefixes(p, std::slice::from_ref(theta)).unwrap();
    let b = prefixes(p, std::slice::from_ref(prime)).unwrap();
    a.iter().zip(&b).fold(BigRational::zero(), |acc, (x, y)| {
        assert_eq!((&x.states, &x.actions), (&y.states, &y.actions));
        let w = x.prob.clone() / &y.prob;
        let d = y.estimate[0].clone() - w * &x.estimate[0];
        acc + y.prob.clone() * &d * &d
    })
}

/// V_b(θ, θ′) = Σ_τ̄ p(τ̄; θ′) (g_b(θ′, τ̄) − w g_b(θ, τ̄))², w = p(τ̄; θ)/p(τ̄; θ′), exactly: g from
/// the prefix enumeration and `g_b = g − b Σ_i ψ(a_i|s_i)` with the scores read off the tables.
pub fn v_b(
    p: &ToyProblem<BigRational>,
    b: &BigRational,
    theta: &BigRational,
    prime: &BigRational,
) -> BigRational {
    let (t_old, t_new) = (
        p.table(std::slice::from_ref(theta)).unwrap(),
        p.table(std::slice::from_ref(prime)).unwrap(),
    );
    let at = prefixes(p, std::slice::from_ref(theta)).unwrap();
    let pr = prefixes(p, std::slice::from_ref(prime)).unwrap();
    let score_sum =
        |t: &ilopt::toy::PolicyTable<BigRational>, states: &[usize], actions: &[usize]| {
            states
                .iter()
                .zip(actions)
                .fold(BigRational::zero(), |a, (&s, &act)| a + &t.score(s, act)[0])
        };
    at.iter().zip(&pr).fold(BigRational::zero(), |acc, (x, y)| {
        assert_eq!((&x.states, &x.actions), (&y.states, &y.actions));
        let w = x.prob.clone() / &y.prob;
        let old = x.estimate[0].clone() - b.clone() * score_sum(&t_old, &x.states, &x.actions);
        let new = y.estimate[0].clone() - b.clone() * score_sum(&t_new, &y.states, &y.actions);
        let d = new - w * old;
        acc + y.prob.clone() * &d * &d
    })
}
