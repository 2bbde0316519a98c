//! Mutation testing of the table itself: a fixed list of deliberate errors in the table's inputs —
//! a certified constant halved, a factor dropped from a bound's formula, a small bias on every
//! gradient estimate — and, for each, the rows whose verdict it turns.
//!
//! A table that cannot see an error of its inputs cannot be trusted to have checked them: each
//! perturbation must turn at least one verdict ([`Outcome::seen`]). The list extends the errors an
//! independent audit tried (σ² × 1/2, the factor 14 dropped from (3.60\*), biases of 10⁻³ and 10⁻²)
//! to every certified constant and a factor of each bound's formula.

use crate::bounds::{self, O2ncParams, harmonic};
use crate::inputs::{ConstantKind, Formulas, TableInputs};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use ilopt::scalar::{BigRational, parse_exact};

/// One deliberate error: its name and the inputs that carry it.
#[derive(Debug, Clone)]
pub struct Perturbation {
    /// What was changed, as the report names it.
    pub name: &'static str,
    /// The table's inputs with the error.
    pub inputs: TableInputs,
}

/// (3.60\*) with the factor 14 dropped: `4[2LB_F + σ²(1 + (H_{K+7} − H_7))]/Σ_k (7/(k+7))^{1/3}`.
fn storm_without_14(l: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    let denom: f64 = (1..=k).map(|i| (7.0 / (i as f64 + 7.0)).cbrt()).sum();
    4.0 * (2.0 * l * b_f + sigma2 * (1.0 + (harmonic(k + 7) - harmonic(7)))) / denom
}

/// (3.60\*) with the leading 4 dropped.
fn storm_without_4(l: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    bounds::storm_fixed(l, sigma2, b_f, k) / 4.0
}

/// (3.27) with the 2 of 2B_F/(ηK) dropped.
fn sgd_without_2(l: f64, eta: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    l * eta * sigma2 + b_f / (eta * k as f64)
}

/// (3.27) with the L of Lησ² dropped (a smaller bound: L > 1 on every toy of the table).
fn sgd_without_l(_l: f64, eta: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    eta * sigma2 + 2.0 * b_f / (eta * k as f64)
}

/// (3.25)/(3.26) with the 2 of 2B_F dropped.
fn sgd_weighted_without_2(l: f64, etas: &[f64], sigma2: f64, b_f: f64) -> f64 {
    let s1: f64 = etas.iter().sum();
    let s2: f64 = etas.iter().map(|e| e * e).sum();
    (b_f + l * sigma2 * s2) / s1
}

/// Thm 3.8's bound with the σ/√T term dropped.
fn o2nc_without_sigma(delta0: f64, delta: f64, g: f64, _sigma: f64, p: O2ncParams) -> f64 {
    bounds::o2nc_theorem(delta0, delta, g, 0.0, p)
}

/// Thm 3.8's bound with the G/√T term dropped.
fn o2nc_without_g(delta0: f64, delta: f64, _g: f64, sigma: f64, p: O2ncParams) -> f64 {
    let t = (p.t as f64).sqrt();
    let d = delta / p.t as f64;
    delta0 / (d * p.m as f64) + sigma / t
}

/// (3.71) with its first term's 2 dropped.
fn corollary_without_2(delta0: f64, delta: f64, g: f64, n: u64) -> f64 {
    bounds::o2nc_corollary(delta0, delta, g, n) - delta0 / (delta * n as f64)
}

fn q(s: &str) -> BigRational {
    parse_exact(s).expect("a constant")
}

fn scaled(name: &'static str, kind: ConstantKind) -> Perturbation {
    Perturbation {
        name,
        inputs: TableInputs {
            constant_scale: Some((kind, q("1/2"))),
            ..TableInputs::thesis()
        },
    }
}

fn formula(name: &'static str, f: impl FnOnce(&mut Formulas)) -> Perturbation {
    let mut inputs = TableInputs::thesis();
    f(&mut inputs.formulas);
    Perturbation { name, inputs }
}

fn biased(name: &'static str, b: &str) -> Perturbation {
    Perturbation {
        name,
        inputs: TableInputs {
            oracle_bias: Some(q(b)),
            ..TableInputs::thesis()
        },
    }
}

/// The fixed list of deliberate errors.
pub fn fixed_list() -> Vec<Perturbation> {
    use ConstantKind::*;
    vec![
        scaled("σ² × 1/2", Sigma2),
        scaled("L_F × 1/2", LF),
        scaled("L̃ × 1/2", LTilde),
        scaled("B_F × 1/2", BF),
        scaled("G² × 1/2", G2),
        scaled("G_F × 1/2", GF),
        scaled("G_∞ × 1/2", GInf),
        formula("(3.60*) without the factor 14", |f| {
            f.storm_fixed = storm_without_14
        }),
        formula("(3.60*) without the factor 4", |f| {
            f.storm_fixed = storm_without_4
        }),
        formula("(3.27) without the 2 of 2B_F", |f| {
            f.sgd_constant = sgd_without_2
        }),
        formula("(3.27) without the L of Lησ²", |f| {
            f.sgd_constant = sgd_without_l
        }),
        formula("(3.25)/(3.26) without the 2 of 2B_F", |f| {
            f.sgd_weighted = sgd_weighted_without_2
        }),
        formula("Thm 3.8 without σ/√T", |f| {
            f.o2nc_theorem = o2nc_without_sigma
        }),
        formula("Thm 3.8 without G/√T", |f| {
            f.o2nc_theorem = o2nc_without_g
        }),
        formula("(3.71) without the 2 of 2Δ₀/(δN)", |f| {
            f.o2nc_corollary = corollary_without_2
        }),
        biased("oracle bias + 10⁻³", "1/1000"),
        biased("oracle bias + 10⁻²", "1/100"),
    ]
}

/// What one perturbation did to the table: the rows whose verdict it turned.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The perturbation's name.
    pub name: &'static str,
    /// `(row id, verdict unperturbed, verdict perturbed)` for every row whose verdict changed, and
    /// for every row present in only one of the two tables (verdict `"absent"`).
    pub turned: Vec<(String, String, String)>,
}

impl Outcome {
    /// Whether the table saw the error: some row's verdict turned.
    pub fn seen(&self) -> bool {
        !self.turned.is_empty()
    }
}

/// Compare the rows of the unperturbed table with those of a perturbed one, by row id.
pub fn outcome(name: &'static str, base: &[Check], perturbed: &[Check]) -> Outcome {
    let find = |rows: &[Check], id: &str| {
        rows.iter()
            .find(|c| c.id == id)
            .map_or("absent", |c| c.verdict.name())
    };
    let mut turned = vec![];
    for c in base {
        let after = find(perturbed, &c.id);
        if after != c.verdict.name() {
            turned.push((
                c.id.clone(),
                c.verdict.name().to_string(),
                after.to_string(),
            ));
        }
    }
    for c in perturbed {
        if !base.iter().any(|b| b.id == c.id) {
            turned.push((c.id.clone(), "absent".into(), c.verdict.name().to_string()));
        }
    }
    Outcome { name, turned }
}

/// One negative-control row per perturbation ("P1", "P2", …): the claim that the table with the
/// error has every verdict unchanged, which must fail (the error is detected) — so an error no
/// row sees fails the table's status like any undetected control.
pub fn rows(outcomes: &[Outcome]) -> Vec<Check> {
    outcomes
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let turned = o
                .turned
                .iter()
                .map(|(id, a, b)| format!("{id} ({a} → {b})"))
                .collect::<Vec<_>>();
            Check::builder(
                format!("P{}", i + 1),
                "Perturbation test (the table's own inputs, deliberately wrong)",
                format!(
                    "with {}, every verdict of the input-reading rows is unchanged",
                    o.name
                ),
                Role::NegativeControl,
            )
            .measured(Measured::exact(o.turned.len() as f64))
            .details(if turned.is_empty() {
                "no row's verdict turned".to_string()
            } else {
                format!("rows turned: {}", turned.join(", "))
            })
            .decided(Method::Exact, Verdict::from_bool(!o.seen()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: &str, v: Verdict) -> Check {
        Check::builder(id, "r", "c", Role::Corrected).decided(Method::Exact, v)
    }

    #[test]
    fn an_outcome_lists_turned_missing_and_new_rows() {
        let base = [row("a", Verdict::Holds), row("b", Verdict::Holds)];
        let same = outcome("x", &base, &base);
        assert!(!same.seen());
        let moved = outcome(
            "y",
            &base,
            &[row("a", Verdict::Fails), row("c", Verdict::Holds)],
        );
        assert_eq!(
            moved.turned,
            vec![
                ("a".into(), "holds".into(), "fails".into()),
                ("b".into(), "holds".into(), "absent".into()),
                ("c".into(), "absent".into(), "holds".into()),
            ]
        );
        let controls = rows(&[same, moved]);
        assert_eq!(
            controls[0].verdict,
            Verdict::Holds,
            "an unseen error: control not detected"
        );
        assert!(controls[0].undetected_control());
        assert_eq!(controls[1].verdict, Verdict::Fails);
        assert!(controls[1].details.contains("a (holds → fails)"));
    }

    /// Every formula perturbation makes its bound smaller (a larger bound would be a weaker, still
    /// true claim, not an error a check must catch), and the list names each error once.
    #[test]
    fn every_formula_perturbation_lowers_its_bound() {
        let p = bounds::o2nc_params(2000, 0.1, 2.0, 0.5);
        for pert in fixed_list() {
            let f = pert.inputs.formulas;
            let t = Formulas::THESIS;
            let changed = [
                (f.storm_fixed)(6.0, 2.8, 0.5, 20_000) != (t.storm_fixed)(6.0, 2.8, 0.5, 20_000),
                (f.sgd_constant)(2.0, 0.05, 2.8, 0.5, 1000)
                    != (t.sgd_constant)(2.0, 0.05, 2.8, 0.5, 1000),
                (f.sgd_weighted)(2.0, &[0.05, 0.03], 2.8, 0.5)
                    != (t.sgd_weighted)(2.0, &[0.05, 0.03], 2.8, 0.5),
                (f.o2nc_theorem)(0.5, 0.1, 2.0, 1.7, p) != (t.o2nc_theorem)(0.5, 0.1, 2.0, 1.7, p),
                (f.o2nc_corollary)(0.5, 0.1, 2.0, 2000) != (t.o2nc_corollary)(0.5, 0.1, 2.0, 2000),
            ];
            assert!(changed.iter().filter(|c| **c).count() <= 1, "{}", pert.name);
            assert!(
                (f.storm_fixed)(6.0, 2.8, 0.5, 20_000) <= (t.storm_fixed)(6.0, 2.8, 0.5, 20_000)
            );
            assert!(
                (f.sgd_constant)(2.0, 0.05, 2.8, 0.5, 1000)
                    <= (t.sgd_constant)(2.0, 0.05, 2.8, 0.5, 1000)
            );
            assert!(
                (f.sgd_weighted)(2.0, &[0.05, 0.03], 2.8, 0.5)
                    <= (t.sgd_weighted)(2.0, &[0.05, 0.03], 2.8, 0.5)
            );
            assert!(
                (f.o2nc_theorem)(0.5, 0.1, 2.0, 1.7, p) <= (t.o2nc_theorem)(0.5, 0.1, 2.0, 1.7, p)
            );
            assert!(
                (f.o2nc_corollary)(0.5, 0.1, 2.0, 2000) <= (t.o2nc_corollary)(0.5, 0.1, 2.0, 2000)
            );
        }
        let names: std::collections::HashSet<_> = fixed_list().iter().map(|p| p.name).collect();
        assert_eq!(names.len(), fixed_list().len());
    }
}
