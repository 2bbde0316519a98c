//! Row 8.lower: every constant the rows use is at least a value its quantity attains.
//!
//! A rigorous constant (L_F, σ², G_F, …) is an upper bound on a supremum; its branch-and-bound also
//! records the largest value of the quantity it evaluated at a point (`Constant::attained`), a
//! lower bound on the same supremum. A constant below that value is no upper bound: the row fails.
//! An exact constant (B_F) must equal its recomputation from the MDP. The row is cheap (no
//! enclosure is recomputed), so the perturbation test runs it with every deliberate error; the
//! full re-check of each certificate by a second route is row 8 / 8b.

use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::record::constant::{Constant, Provenance};

/// The row for the constants `used` by the rows, against `exact` recomputations of the exact
/// ones (by name).
pub fn row(id: &str, what: &str, used: &[Constant], exact: &[(String, f64)]) -> Check {
    let mut failures = vec![];
    let mut worst = f64::INFINITY;
    for c in used {
        match c.provenance {
            Provenance::Exact => match exact.iter().find(|(n, _)| *n == c.name) {
                Some((_, v)) if *v == c.value => {}
                Some((_, v)) => failures.push(format!("{} = {} ≠ {v} recomputed", c.name, c.value)),
                None => failures.push(format!("{}: no recomputation", c.name)),
            },
            _ => {
                if let Some(a) = c.attained {
                    let ratio = c.value / a;
                    worst = worst.min(ratio);
                    if c.value < a {
                        failures.push(format!("{} = {:.6} < {a:.6} attained", c.name, c.value));
                    }
                }
            }
        }
    }
    let names: Vec<&str> = used.iter().map(|c| c.name.as_str()).collect();
    Check::builder(
        id,
        "Rigorous constants (math.md §7.1)",
        format!(
            "{what}: every constant used ({}) is ≥ the largest value of its quantity attained at an evaluated point; exact ones equal their recomputation",
            names.join(", ")
        ),
        Role::Corrected,
    )
    .measured(Measured::exact(worst))
    .details(if failures.is_empty() {
        format!("smallest constant / attained = {worst:.4}")
    } else {
        failures.join("; ")
    })
    .decided(Method::Exact, Verdict::from_bool(failures.is_empty()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(name: &str, value: f64, attained: Option<f64>, p: Provenance) -> Constant {
        Constant {
            name: name.into(),
            value,
            rational: String::new(),
            provenance: p,
            how: String::new(),
            certificate: None,
            charts: vec![],
            attained,
        }
    }

    #[test]
    fn a_constant_below_its_attained_value_or_an_exact_one_changed_fails() {
        let exact = [("B_F".to_string(), 0.5)];
        let good = [
            constant("B_F", 0.5, None, Provenance::Exact),
            constant("σ²", 2.9, Some(2.8), Provenance::Rigorous),
        ];
        assert_eq!(row("8.lower", "M1", &good, &exact).verdict, Verdict::Holds);
        let halved = [constant("σ²", 1.45, Some(2.8), Provenance::Rigorous)];
        assert_eq!(
            row("8.lower", "M1", &halved, &exact).verdict,
            Verdict::Fails
        );
        let bf = [constant("B_F", 0.25, None, Provenance::Exact)];
        assert_eq!(row("8.lower", "M1", &bf, &exact).verdict, Verdict::Fails);
    }
}
