//! The rows that read the table's inputs ([`TableInputs`]): the proof-step rows with their closing
//! algebra, the tight instances, the errata rows that take an expectation of the oracle, and the
//! constants' lower check. They are exact (or enclosed) and cheap, so the table runs them once as
//! they are and once more under each deliberate error of [`crate::perturbation::fixed_list`], and
//! reports what each error turned (rows P1, P2, …).

use crate::certify::box_constants::{ToyConstants, b_f};
use crate::certify::global::GlobalConstants;
use crate::checks::{attained, errata, o2nc_formula, proof_o2nc, proof_sgd, proof_storm, tight};
use crate::inputs::{ConstantKind, TableInputs};
use crate::perturbation::{Perturbation, fixed_list, outcome, rows as perturbation_rows};
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
    /// The box the constants `k` hold on.
    pub domain: Vec<[f64; 2]>,
}

/// The input-reading rows' own runs and their exact evaluation with the table's inputs as they
/// are, computed once: a perturbation that changes neither the runs nor the oracle's moments (a
/// formula, or a constant the runs do not use as a hyper-parameter) reuses them, which is the same
/// computation. Within them the SGD step slacks (rows 1.s1–1.s6) and the STORM step rows
/// (2c.s1a–2c.s3c) are kept with the constants they read ([`crate::reuse::Keyed`]), so an error
/// in another constant or in a formula reuses them too; the tight instances' search reads no
/// input, so an oracle bias repeats only their certification.
#[derive(Debug, Clone)]
pub struct Runs {
    o2nc: proof_o2nc::Evaluated,
    sgd: proof_sgd::Evaluated,
    tight: tight::PreparedAll,
    storm: proof_storm::Evaluated,
}

impl Runs {
    /// Record and evaluate every run of the input-reading rows with the unperturbed inputs.
    ///
    /// # Errors
    /// A message if a run or an evaluation fails.
    pub fn compute(c: &Certified) -> Result<Runs, String> {
        let inputs = TableInputs::thesis();
        let inputs = &inputs;
        // The four parts share nothing and each is seeded on its own: they run side by side.
        std::thread::scope(|scope| {
            let o2nc = scope.spawn(move || {
                let runs = proof_o2nc::record(inputs, &c.m1, &c.k, &c.domain, &O2NC_SIZES)?;
                proof_o2nc::evaluate(inputs, &c.m1, runs)
            });
            let storm = scope.spawn(move || {
                let states = proof_storm::visit(&c.m1, &c.g, storm_sizes(c.profile))?;
                proof_storm::evaluate(inputs, &c.m1, &c.g, &states)
            });
            let tight = scope.spawn(move || tight::prepare(inputs, tight_sizes(c.profile)));
            let sgd = proof_sgd::evaluate(inputs, &c.k, &c.domain, sgd_sizes());
            let panicked = |what: &str| format!("the thread of {what} panicked");
            Ok(Runs {
                o2nc: o2nc.join().map_err(|_| panicked("the O2NC runs"))??,
                sgd: sgd?,
                tight: tight.join().map_err(|_| panicked("the tight instances"))?,
                storm: storm.join().map_err(|_| panicked("the STORM runs"))??,
            })
        })
    }
}

/// The O2NC proof-step rows' runs (both profiles: the rows are exact, and every perturbation
/// reruns them).
const O2NC_SIZES: proof_o2nc::StepSizes = proof_o2nc::StepSizes::QUICK;

/// The SGD proof-step rows' runs (the quick size in both profiles, as for O2NC).
fn sgd_sizes() -> proof_sgd::Sizes {
    proof_sgd::sizes(false)
}

/// The STORM proof-step rows' states. Their runs use the certified L = max(L_F, L̃) of the
/// schedule (3.43), not the inputs' constants (the rows read those), so only the oracle changes
/// what is cached.
fn storm_sizes(profile: Profile) -> proof_storm::Sizes {
    proof_storm::Sizes::for_profile(profile)
}

/// The tight instances' search and certification budget.
fn tight_sizes(profile: Profile) -> tight::Sizes {
    match profile {
        Profile::Quick => tight::Sizes::quick(),
        Profile::Full => tight::Sizes::full(),
    }
}

/// Whether `inputs` changes what [`Runs`] holds: the oracle (every exact moment), or a constant
/// that Algorithm 5 takes as a hyper-parameter (G², Δ₀ = B_F).
fn changes_runs(inputs: &TableInputs) -> bool {
    inputs.oracle_bias.is_some()
        || matches!(
            inputs.constant_scale,
            Some((ConstantKind::G2 | ConstantKind::BF, _))
        )
}

fn q(s: &str) -> BigRational {
    parse_exact(s).expect("constant")
}

/// The rows under `inputs`.
///
/// # Errors
/// A message if a row cannot be computed.
pub fn input_rows(c: &Certified, runs: &Runs, inputs: &TableInputs) -> Result<Vec<Check>, String> {
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
    rows.push(o2nc_formula::row(inputs, c.profile.sizes().o2nc_cases, 1));
    rows.extend(if inputs.oracle_bias.is_some() {
        proof_sgd::rows(inputs, &c.k, &c.domain, sgd_sizes())?
    } else {
        proof_sgd::rows_from(inputs, &c.k, &runs.sgd, sgd_sizes())?
    });
    let storm_k = storm_sizes(c.profile).k_close;
    rows.extend(if inputs.oracle_bias.is_some() {
        let ev = proof_storm::evaluate(inputs, &c.m1, &c.g, runs.storm.visited())?;
        proof_storm::rows_from(inputs, &c.g, &ev, storm_k)?
    } else {
        proof_storm::rows_from(inputs, &c.g, &runs.storm, storm_k)?
    });
    rows.extend(if inputs.oracle_bias.is_some() {
        let sizes = tight_sizes(c.profile);
        tight::rows_from(inputs, sizes, &runs.tight.recertified(inputs, sizes))
    } else {
        tight::rows_from(inputs, tight_sizes(c.profile), &runs.tight)
    });
    rows.extend(if changes_runs(inputs) {
        proof_o2nc::rows(inputs, &c.m1, &c.k, &c.domain, &O2NC_SIZES)?
    } else {
        proof_o2nc::rows_from(inputs, &c.m1, &c.k, &runs.o2nc, &O2NC_SIZES)?
    });
    Ok(rows)
}

/// The input-reading rows as they are, then one negative-control row per deliberate error
/// ([`crate::perturbation::rows`]).
///
/// # Errors
/// As [`input_rows`].
pub fn with_perturbations(c: &Certified) -> Result<Vec<Check>, String> {
    let runs = Runs::compute(c)?;
    let base = input_rows(c, &runs, &TableInputs::thesis())?;
    let list = fixed_list();
    // The perturbations are independent: they run on every core, each taking the next index of
    // `order`, and their rows are put back in the list's order (the same whatever the number of
    // cores or the order). The costliest start first, so that no core is left with one of them
    // at the end: an oracle bias recomputes every run's exact moments, a change of Algorithm 5's
    // hyper-parameters its runs.
    let cost = |p: &Perturbation| {
        if p.inputs.oracle_bias.is_some() {
            0
        } else if changes_runs(&p.inputs) {
            1
        } else {
            2
        }
    };
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_by_key(|&i| cost(&list[i]));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut done: Vec<(usize, Result<Vec<Check>, String>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads.min(list.len()))
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = vec![];
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some((i, p)) = order.get(i).map(|&i| (i, &list[i])) else {
                            break;
                        };
                        mine.push((i, input_rows(c, &runs, &p.inputs)));
                    }
                    mine
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_default())
            .collect()
    });
    if done.len() != list.len() {
        return Err("a perturbation's thread panicked".into());
    }
    done.sort_by_key(|(i, _)| *i);
    let mut outcomes = vec![];
    for ((_, rows), p) in done.into_iter().zip(&list) {
        outcomes.push(outcome(p.name, &base, &rows?));
    }
    let mut rows = base;
    rows.extend(perturbation_rows(&outcomes));
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::box_constants::{self, tied_softmax_g_inf_closed_form};
    use crate::perturbation::fixed_list;
    use crate::protocol::m1_tied;

    /// A perturbation [`changes_runs`] says leaves the runs alone records the same runs (and,
    /// without an oracle bias, the same exact moments): reusing [`Runs`] is the same computation.
    #[test]
    fn reused_runs_are_the_runs_a_perturbation_would_record() {
        let r = 1000.0 * 0.05 * tied_softmax_g_inf_closed_form(3, 0.5);
        let domain = vec![[-r, r]];
        let m1 = m1_tied();
        let k =
            box_constants::compute(&m1, &[q("0")], Some(&q("7/8")), &domain, 1e-1, 20_000).unwrap();
        let small = proof_o2nc::StepSizes {
            budget: 20,
            runs: 1,
            ..O2NC_SIZES
        };
        let thesis = proof_o2nc::record(&TableInputs::thesis(), &m1, &k, &domain, &small).unwrap();
        let mut reused = 0;
        for p in fixed_list() {
            let runs = proof_o2nc::record(&p.inputs, &m1, &k, &domain, &small).unwrap();
            if changes_runs(&p.inputs) {
                assert!(
                    runs != thesis || p.inputs.oracle_bias.is_some(),
                    "{}: said to change the runs, but does not",
                    p.name
                );
            } else {
                assert_eq!(runs, thesis, "{}", p.name);
                assert!(p.inputs.oracle_bias.is_none());
                reused += 1;
            }
        }
        assert!(reused > 0);
    }
}
