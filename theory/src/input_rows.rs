//! The rows that read the table's inputs ([`TableInputs`]): the proof-step rows with their closing
//! algebra, the tight instances, the errata rows that take an expectation of the oracle, and the
//! constants' lower check. They are exact (or enclosed) and cheap, so the table runs them once as
//! they are and once more under each deliberate error of [`crate::perturbation::fixed_list`], and
//! reports what each error turned (rows P1, P2, …).

use crate::certify::box_constants::{ToyConstants, b_f};
use crate::certify::global::GlobalConstants;
use crate::checks::{attained, errata};
use crate::inputs::TableInputs;
use crate::perturbation::{fixed_list, outcome, rows as perturbation_rows};
use crate::protocol::Profile;
use crate::record::check::Check;
use ilopt::scalar::{BigRational, parse_exact};
use ilopt::toy::ToyMdp;

/// What the input-reading rows need and the inputs do not change: the MDP and its certified
/// constants, computed once.
#[derive(Debug, Clone)]
pub struct Certified {
    /// The profile (sizes of the rows).
    pub profile: Profile,
    /// M1 (P2', c = 1/2).
    pub m1: ToyMdp,
    /// θ₁ and inf F of the constants' B_F.
    pub theta1: Vec<BigRational>,
    /// inf F on M1.
    pub f_inf: BigRational,
    /// The box constants of the SGD rows.
    pub k: ToyConstants,
    /// The global constants of the STORM rows.
    pub g: GlobalConstants,
}

fn q(s: &str) -> BigRational {
    parse_exact(s).expect("constant")
}

/// The rows under `inputs`.
///
/// # Errors
/// A message if a row cannot be computed.
pub fn input_rows(c: &Certified, inputs: &TableInputs) -> Result<Vec<Check>, String> {
    let b_f_exact = b_f(&c.m1, &c.theta1, Some(&c.f_inf))?.value;
    let exact = [("B_F".to_string(), b_f_exact)];
    let k = inputs.toy_constants(&c.k);
    let g = inputs.global_constants(&c.g);
    let mut rows = vec![
        attained::row("8.lower", "M1, the SGD rows' box", &k.all(), &exact),
        attained::row("8b.lower", "M1, over ℝ (ℝ² for L̃)", &g.all(), &exact),
    ];
    let cases: Vec<(ToyMdp, Vec<BigRational>)> = ["0", "1/3", "-2", "5/2", "1", "2"]
        .iter()
        .map(|t| (c.m1.clone(), vec![q(t)]))
        .collect();
    rows.extend(errata::e1_rows(inputs, &cases)?);
    Ok(rows)
}

/// The input-reading rows as they are, then one negative-control row per deliberate error
/// ([`crate::perturbation::rows`]).
///
/// # Errors
/// As [`input_rows`].
pub fn with_perturbations(c: &Certified) -> Result<Vec<Check>, String> {
    let base = input_rows(c, &TableInputs::thesis())?;
    let mut outcomes = vec![];
    for p in fixed_list() {
        let rows = input_rows(c, &p.inputs)?;
        outcomes.push(outcome(p.name, &base, &rows));
    }
    let mut rows = base;
    rows.extend(perturbation_rows(&outcomes));
    Ok(rows)
}
