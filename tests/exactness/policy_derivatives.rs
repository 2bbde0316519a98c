//! Every policy's analytic ∇π, ∇log π and the Brier ∇l (math.md §§1.2–1.3) equal the exact
//! derivatives computed by forward-mode `Dual<BigRational>` arithmetic through the generic
//! probability code — two independent routes, compared with `==`.

use crate::common;

use crate::common::{theta_for, toy_mdp};
use ilopt::scalar::{BigRational, Dual, Scalar};
use ilopt::toy::policy::brier_value;
use ilopt::toy::{ToyMdp, ToyProblem};
use proptest::prelude::*;

type Q = BigRational;

fn check(mdp: &ToyMdp, theta: &[Q]) -> Result<(), String> {
    let spec = &mdp.policy;
    let table = ToyProblem::<Q>::new(mdp)
        .table(theta)
        .map_err(|e| e.to_string())?;
    let c = spec.c.clone().unwrap_or_else(Q::zero);
    let block = spec.block();
    for o in 0..spec.group_count() {
        let local = &theta[o * block..(o + 1) * block];
        let vars = Dual::variables(local);
        let probs = spec
            .group_probs(&vars, &Dual::constant(c.clone()))
            .map_err(|e| e.to_string())?;
        for (a, p) in probs.iter().enumerate() {
            let grad = p.gradient_padded(block);
            if p.value() != &table.probs[o][a] {
                return Err(format!("π({a}|{o}) value"));
            }
            if grad != table.jacobian[o][a] {
                return Err(format!(
                    "∇π({a}|{o}): dual {grad:?} vs analytic {:?}",
                    table.jacobian[o][a]
                ));
            }
            // ∇log π = ∇π / π by the chain rule applied to the dual value.
            let score: Vec<Q> = grad.iter().map(|g| g.clone() / p.value()).collect();
            if score != table.score[o][a] {
                return Err(format!("ψ({a}|{o})"));
            }
        }
        for s in (0..mdp.states).filter(|&s| spec.groups[s] == o) {
            let l = brier_value(&probs, mdp.expert[s]);
            if l.value() != &table.loss[s] || l.gradient_padded(block) != table.loss_grad[s] {
                return Err(format!("Brier loss or ∇l at state {s}"));
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn analytic_derivatives_equal_dual_derivatives(
        (mdp, theta) in toy_mdp().prop_flat_map(|m| { let t = theta_for(&m); (Just(m), t) })
    ) {
        prop_assert_eq!(check(&mdp, &theta), Ok(()));
    }
}

/// The tied softmax's p′(θ) has the closed form of math.md §1.3 (c = 1/2):
/// p′ = (−2θ² + 2θ + 1)/(2θ² − 2θ + 2)²; and its range endpoints are p((1 ∓ √3)/2).
#[test]
fn tied_softmax_closed_form() {
    let mdp = common::example("m1-tied.json");
    let p = ToyProblem::<Q>::new(&mdp);
    for (n, d) in [(0i64, 1i64), (1, 2), (1, 1), (2, 1), (-3, 2), (7, 3)] {
        let th = Q::new(n.into(), d.into());
        let t = p.table(std::slice::from_ref(&th)).unwrap();
        let den = Q::from_i64(2) * &th * &th - Q::from_i64(2) * &th + Q::from_i64(2);
        let want =
            (Q::from_i64(-2) * &th * &th + Q::from_i64(2) * &th + Q::one()) / (den.clone() * &den);
        assert_eq!(t.jacobian[0][1], vec![want.clone()], "p′({th})");
        assert_eq!(t.jacobian[0][0], vec![-want], "d(1 − p)/dθ at {th}");
    }
    // p(0) = 1/4, p(1/2) = 1/2, p(1) = p(2) = 3/4.
    for (th, want) in [("0", "1/4"), ("1/2", "1/2"), ("1", "3/4"), ("2", "3/4")] {
        let t = p.table(&[common::q(th)]).unwrap();
        assert_eq!(t.probs[0][1], common::q(want));
    }
}
