//! The corrected STORM proof (math.md §3.2, Theorem S) checked step by step, exactly, at the
//! states of real IS-STORM runs on M1, and the thesis's printed steps (3.44)–(3.59) beside it.
//!
//! Each row states one inequality of the proof at a state (θ_k, d_k) of a seeded run of the kit's
//! IS-STORM with schedule (3.43) (trajectory and per-decision weights; θ₁ = 0, the seeds of row
//! 2c), with the run's own η_k, a_{k+1} converted exactly from `f64`. Conditionally on F_k the
//! step's randomness is one prefix drawn at θ_{k+1} = θ_k − η_k d_k, so every conditional
//! expectation is a finite sum in ℚ ([`step`]); [`crate::checks::proof_step::StepSlack`] records
//! each inequality's slack. Rows 2c.s3c (the conditions over every step of the runs' schedules)
//! and 2c.close (cube roots) are decided by rigorous enclosures instead. Every constant, bound formula and gradient estimate is read through
//! [`TableInputs`], so a wrong constant, a dropped factor or a biased oracle turns a verdict.
//!
//! | row | inequality | module |
//! |---|---|---|
//! | 2c.s1a (.e10, .e9) | E[W \| F_k] = E[Z \| F_k] = 0 (unweighted term, printed Algorithm 4) | [`error`] |
//! | 2c.s1b, 2c.s1c | E‖W‖² ≤ σ² (A3), E‖Z‖² ≤ L̃²η²‖d‖² (A4) | [`error`] |
//! | 2c.s1d, 2c.s1e (.printed) | the error recursion; Lemma 3.3 (3.44) corrected (E3) and printed | [`error`] |
//! | 2c.s2 (.e5) | the descent lemma; (3.54) as printed | [`descent`] |
//! | 2c.s3, 2c.s3.e7, 2c.s3c | the potential; the thesis's potential (E7); (C1), (C2) | [`potential`] |
//! | 2c.close | Theorem S's telescoped bound = `storm_fixed` | [`closing`] |

pub mod closing;
pub mod descent;
pub mod error;
pub mod potential;
pub mod states;
pub mod step;

use crate::certify::global::GlobalConstants;
use crate::checks::proof_step::StepSlack;
use crate::inputs::{ConstantKind, TableInputs};
use crate::protocol::Profile;
use crate::record::check::{Check, Method, Role};
use crate::record::constant::Constant;
use crate::reuse::Keyed;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use states::{RunSchedule, State};
use step::Step;

type Q = BigRational;

/// The thesis result every row of this module belongs to.
pub const RESULT: &str = "STORM, Lemmas 3.3–3.4 and eqs. 3.44–3.60 → Theorem S, proof step by step";

/// How many states the rows are checked at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sizes {
    /// Seeded runs per weighting (seeds 0..runs, as row 2c's first runs).
    pub runs: u64,
    /// Every state k = 1..dense of each run is checked.
    pub dense: u64,
    /// Further states per run, spread geometrically over (dense, k_max].
    pub sparse: usize,
    /// Steps per run.
    pub k_max: u64,
    /// K of the closing row (the K of row 2c).
    pub k_close: u64,
}

impl Sizes {
    /// The sizes of a profile: 2 (quick) or 4 (full) runs per weighting of the protocol's STORM
    /// K, checked at k ≤ 60 and 40 later steps (quick: 400 states), K of the closing = K of 2c.
    pub fn for_profile(profile: Profile) -> Sizes {
        let k = profile.sizes().storm_k;
        match profile {
            Profile::Quick => Sizes {
                runs: 2,
                dense: 60,
                sparse: 40,
                k_max: k,
                k_close: k,
            },
            Profile::Full => Sizes {
                runs: 4,
                dense: 100,
                sparse: 100,
                k_max: k,
                k_close: k,
            },
        }
    }
}

/// The constants as the rows use them: each certified value (exactly, from its `f64`) as
/// [`TableInputs::constant`] gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct Constants {
    /// σ² (A3).
    pub sigma2: Q,
    /// L_F (A1).
    pub l_f: Q,
    /// L̃ (A4) for trajectory weights.
    pub l_tilde: Q,
    /// L̃ (A4) for per-decision weights.
    pub l_tilde_pd: Q,
}

impl Constants {
    /// The constants of `g` through `inputs`.
    ///
    /// # Errors
    /// A message if a constant is not finite.
    pub fn new(inputs: &TableInputs, g: &GlobalConstants) -> Result<Constants, String> {
        let get = |kind: ConstantKind, c: &Constant| {
            Q::from_float(c.value)
                .map(|q| inputs.constant(kind, q))
                .ok_or_else(|| format!("{} = {} is not finite", c.name, c.value))
        };
        Ok(Constants {
            sigma2: get(ConstantKind::Sigma2, &g.sigma2)?,
            l_f: get(ConstantKind::LF, &g.l_f)?,
            l_tilde: get(ConstantKind::LTilde, &g.l_tilde)?,
            l_tilde_pd: get(ConstantKind::LTilde, &g.l_tilde_pd)?,
        })
    }

    /// L̃ for the run's weights.
    pub fn l_tilde(&self, w: Weighting) -> &Q {
        match w {
            Weighting::Trajectory => &self.l_tilde,
            Weighting::PerDecision => &self.l_tilde_pd,
        }
    }

    /// L = max(L_F, L̃) for the run's weights.
    pub fn l(&self, w: Weighting) -> Q {
        self.l_f.clone().max(self.l_tilde(w).clone())
    }

    /// The values used, for a row's details.
    pub fn describe(&self) -> String {
        format!(
            "constants used: σ² = {:.6}, L_F = {:.6}, L̃ = {:.6}, L̃_PD = {:.6}",
            self.sigma2.to_f64(),
            self.l_f.to_f64(),
            self.l_tilde.to_f64(),
            self.l_tilde_pd.to_f64()
        )
    }
}

/// The visited states of the runs and each weighting's schedule.
#[derive(Debug, Clone, PartialEq)]
pub struct Visited {
    /// The states, run after run.
    pub states: Vec<State>,
    /// The schedule of each weighting's first run (every run of a weighting has the same).
    pub schedules: Vec<RunSchedule>,
}

/// Run IS-STORM with schedule (3.43) for L = max(L_F, L̃) as certified in `g` (the runs of row
/// 2c and 2c.pd: θ₁ = 0, seeds 0..runs) and keep the states of [`states::kept`].
///
/// # Errors
/// A message naming the run if a run fails.
pub fn visit(m1: &ToyMdp, g: &GlobalConstants, sizes: Sizes) -> Result<Visited, String> {
    let ks = states::kept(sizes.dense, sizes.sparse, sizes.k_max);
    let mut out = Visited {
        states: vec![],
        schedules: vec![],
    };
    for w in [Weighting::Trajectory, Weighting::PerDecision] {
        for seed in 0..sizes.runs {
            let (st, sch) = states::run(m1, w, g.l(w), 0.0, seed, sizes.k_max, &ks)?;
            out.states.extend(st);
            if seed == 0 {
                out.schedules.push(sch);
            }
        }
    }
    Ok(out)
}

/// One inequality of the proof, as a row states it.
#[derive(Debug, Clone)]
pub struct Inequality {
    id: &'static str,
    claim: String,
    role: Role,
    erratum: Option<String>,
    assumptions: Vec<String>,
    tightness: bool,
    refuted: bool,
}

impl Inequality {
    /// The inequality `claim` of row `id` in `role`.
    pub fn new(id: &'static str, claim: impl Into<String>, role: Role) -> Self {
        Inequality {
            id,
            claim: claim.into(),
            role,
            erratum: None,
            assumptions: vec![],
            tightness: false,
            refuted: false,
        }
    }

    /// Report the largest lhs/rhs (for a bound on a nonnegative quantity: how close the states
    /// come to it).
    #[must_use]
    pub fn tightness(mut self) -> Self {
        self.tightness = true;
        self
    }

    /// The erratum the row documents.
    #[must_use]
    pub fn erratum(mut self, e: &str) -> Self {
        self.erratum = Some(e.into());
        self
    }

    /// The inequality is the thesis's as printed and its erratum says it is false: the table
    /// expects the row to fail ([`crate::record::check::Check::expected`]).
    #[must_use]
    pub fn refuted_by_erratum(mut self) -> Self {
        self.refuted = true;
        self
    }

    /// The assumptions the inequality rests on.
    #[must_use]
    pub fn assumptions<S: Into<String>>(mut self, a: impl IntoIterator<Item = S>) -> Self {
        self.assumptions = a.into_iter().map(Into::into).collect();
        self
    }
}

/// The states, their exact steps and the constants every row of this module reads.
#[derive(Debug)]
pub struct Ctx<'a> {
    /// The visited states.
    pub states: &'a [State],
    /// The exact step at each state.
    pub steps: &'a [Step],
    /// The constants through the inputs.
    pub c: Constants,
    /// The certified constants' records ([`GlobalConstants::summary`]).
    pub constants: &'a [Constant],
}

impl Ctx<'_> {
    /// The certified constants named `names`, for a row's record.
    pub fn constants(&self, names: &[&str]) -> Vec<Constant> {
        self.constants
            .iter()
            .filter(|c| names.contains(&c.name.as_str()))
            .cloned()
            .collect()
    }

    /// The row of `ineq`: `sides(step, weighting) = (lhs, rhs)` at every state, lhs ≤ rhs
    /// decided exactly.
    pub fn check(
        &self,
        ineq: Inequality,
        constants: &[&str],
        sides: impl Fn(&Step, Weighting) -> (Q, Q),
    ) -> Check {
        let mut slack = StepSlack::new();
        // The largest lhs/rhs over the states with rhs > 0: how far the step is from its bound.
        let mut ratio = None::<Q>;
        for (state, step) in self.states.iter().zip(self.steps) {
            let (lhs, rhs) = sides(step, state.weighting);
            slack.exact(&lhs, &rhs);
            if rhs > Q::zero() {
                let r = lhs / &rhs;
                if ratio.as_ref().is_none_or(|m| r > *m) {
                    ratio = Some(r);
                }
            }
        }
        let ratio = match (ineq.tightness, ratio) {
            (false, _) => String::new(),
            (true, None) => "; no state with rhs > 0".to_string(),
            (true, Some(r)) => format!("; largest lhs/rhs {:.6}", r.to_f64()),
        };
        let at = self
            .states
            .get(slack.argmin)
            .map_or_else(|| "no state".to_string(), State::label);
        let trajectory = self
            .states
            .iter()
            .filter(|s| s.weighting == Weighting::Trajectory)
            .count();
        let row = slack.row(ineq.id, RESULT, ineq.claim, ineq.role);
        let row = if ineq.refuted {
            row.refuted_by_erratum()
        } else {
            row
        };
        row
            .assumptions(ineq.assumptions)
            .constants(self.constants(constants))
            .maybe_erratum(ineq.erratum)
            .details(format!(
                "{}; smallest slack at {at}{ratio}; states of IS-STORM runs (schedule 3.43, θ₁ = 0): {trajectory} with trajectory weights, {} per-decision; θ_{{k+1}} = θ_k − η_kd_k exactly, η_k and a_{{k+1}} the runs' f64 values; {}",
                slack.summary(),
                self.states.len() - trajectory,
                self.c.describe()
            ))
            .decided(Method::Exact, slack.verdict())
    }
}

/// The exact step at every visited state, with the gradient estimates of `inputs`.
///
/// # Errors
/// A message naming the state if an exact step cannot be computed.
fn steps(inputs: &TableInputs, m1: &ToyMdp, visited: &Visited) -> Result<Vec<Step>, String> {
    let problem = ToyProblem::<Q>::new(m1);
    visited
        .states
        .iter()
        .map(|s| Step::at(&problem, s, inputs))
        .collect()
}

/// What the step rows read besides the states and their steps: the constants through the inputs
/// and the certified constants' records.
type StepKey = (Constants, Vec<Constant>);

/// The visited states, the exact step at each under one oracle, and the rows of steps 1–3
/// (2c.s1a–2c.s3c) kept with the constants they were computed with: inputs with the same oracle
/// and the same σ², L_F, L̃ and certified records get them without recomputing ([`Keyed`]).
#[derive(Debug, Clone)]
pub struct Evaluated {
    visited: Visited,
    steps: Vec<Step>,
    step_rows: Keyed<StepKey, Vec<Check>>,
}

impl Evaluated {
    /// The visited states.
    pub fn visited(&self) -> &Visited {
        &self.visited
    }

    /// The rows of steps 1–3 for `key` (see [`Evaluated`]).
    fn step_rows_for(&self, key: StepKey) -> Vec<Check> {
        self.step_rows
            .get(&key, |k| step_rows(&self.visited, &self.steps, k))
            .into_owned()
    }
}

fn step_key(inputs: &TableInputs, g: &GlobalConstants) -> Result<StepKey, String> {
    Ok((Constants::new(inputs, g)?, g.summary()))
}

/// Rows 2c.s1a–2c.s3c: steps 1–3 at every state and (C1)/(C2) on the runs' schedules.
fn step_rows(visited: &Visited, steps: &[Step], (c, summary): &StepKey) -> Vec<Check> {
    let ctx = Ctx {
        states: &visited.states,
        steps,
        c: c.clone(),
        constants: summary,
    };
    let mut rows = error::rows(&ctx);
    rows.extend(descent::rows(&ctx));
    rows.extend(potential::rows(&ctx));
    rows.push(potential::conditions(&ctx, &visited.schedules));
    rows
}

/// The exact steps at `visited` with the gradient estimates of `inputs`, and the rows of steps
/// 1–3 with the constants of `g` through `inputs`.
///
/// # Errors
/// A message naming the state if an exact step cannot be computed, or if a constant is not
/// finite.
pub fn evaluate(
    inputs: &TableInputs,
    m1: &ToyMdp,
    g: &GlobalConstants,
    visited: &Visited,
) -> Result<Evaluated, String> {
    let steps = steps(inputs, m1, visited)?;
    let step_rows = Keyed::new(step_key(inputs, g)?, |k| step_rows(visited, &steps, k));
    Ok(Evaluated {
        visited: visited.clone(),
        steps,
        step_rows,
    })
}

/// The rows from an evaluation made with the same oracle (`inputs.oracle_bias`): steps 1–3 at
/// every state, (C1)/(C2) on the runs' schedules, and the closing at K = `k_close`.
///
/// # Errors
/// If a constant is not finite.
pub fn rows_from(
    inputs: &TableInputs,
    g: &GlobalConstants,
    ev: &Evaluated,
    k_close: u64,
) -> Result<Vec<Check>, String> {
    let mut rows = ev.step_rows_for(step_key(inputs, g)?);
    rows.push(closing::row(inputs, g, k_close));
    Ok(rows)
}

/// The proof-step rows of STORM (see the module's documentation): IS-STORM runs on M1 with the
/// constants `g`, then every row through `inputs`.
///
/// # Errors
/// As [`visit`] and [`evaluate`].
pub fn rows(
    inputs: &TableInputs,
    m1: &ToyMdp,
    g: &GlobalConstants,
    sizes: Sizes,
) -> Result<Vec<Check>, String> {
    let visited = visit(m1, g, sizes)?;
    let ev = evaluate(inputs, m1, g, &visited)?;
    rows_from(inputs, g, &ev, sizes.k_close)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::protocol::m1_tied;
    use crate::record::check::Verdict;
    use std::sync::OnceLock;

    /// The global constants of M1 at the quick profile's sizes, as the table computes them.
    pub(crate) fn quick_constants() -> &'static GlobalConstants {
        static G: OnceLock<GlobalConstants> = OnceLock::new();
        G.get_or_init(|| {
            crate::suite::global_constants(&m1_tied(), Profile::Quick.sizes()).expect("constants")
        })
    }

    /// The quick profile's visited states.
    pub(crate) fn quick_states() -> &'static Visited {
        static V: OnceLock<Visited> = OnceLock::new();
        V.get_or_init(|| {
            visit(
                &m1_tied(),
                quick_constants(),
                Sizes::for_profile(Profile::Quick),
            )
            .expect("runs")
        })
    }

    /// The exact steps at the quick states with the unbiased oracle.
    fn quick_steps() -> &'static Evaluated {
        static S: OnceLock<Evaluated> = OnceLock::new();
        S.get_or_init(|| {
            evaluate(
                &TableInputs::thesis(),
                &m1_tied(),
                quick_constants(),
                quick_states(),
            )
            .expect("steps")
        })
    }

    /// The rows at the quick states for inputs with the unbiased oracle (the steps are shared).
    fn quick_rows(inputs: &TableInputs) -> Vec<Check> {
        assert!(inputs.oracle_bias.is_none());
        rows_from(
            inputs,
            quick_constants(),
            quick_steps(),
            Sizes::for_profile(Profile::Quick).k_close,
        )
        .expect("rows")
    }

    fn scaled(kind: ConstantKind, factor: &str) -> TableInputs {
        TableInputs {
            constant_scale: Some((kind, ilopt::scalar::parse_exact(factor).unwrap())),
            ..TableInputs::thesis()
        }
    }

    fn verdict(rows: &[Check], id: &str) -> Verdict {
        rows.iter()
            .find(|r| r.id == id)
            .unwrap_or_else(|| panic!("row {id}"))
            .verdict
    }

    /// The rows, their roles, and their verdicts as the table runs them: every step of the
    /// corrected proof holds; the unweighted old-point term (E10) and the printed Algorithm 4
    /// (E9) fail the mean-zero step at every state; the printed (3.44), (3.54) and the thesis's
    /// potential hold at these states.
    #[test]
    fn the_corrected_steps_hold_and_the_printed_old_point_terms_fail() {
        let rows = quick_rows(&TableInputs::thesis());
        let ids: Vec<&str> = rows.iter().map(|r| r.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "2c.s1a",
                "2c.s1a.e10",
                "2c.s1a.e9",
                "2c.s1b",
                "2c.s1c",
                "2c.s1d",
                "2c.s1e",
                "2c.s1e.printed",
                "2c.s2",
                "2c.s2.e5",
                "2c.s3",
                "2c.s3.e7",
                "2c.s3c",
                "2c.close"
            ]
        );
        for r in &rows {
            let expected = if r.id.starts_with("2c.s1a.e") {
                Verdict::Fails
            } else {
                Verdict::Holds
            };
            assert_eq!(r.verdict, expected, "{}: {}", r.id, r.details);
        }
        let e10 = rows.iter().find(|r| r.id == "2c.s1a.e10").unwrap();
        assert!(e10.details.contains("400 violated"), "{}", e10.details);
        assert_eq!(quick_states().states.len(), 400);
    }

    /// Rows from the thesis's evaluation, whose step rows are kept for the thesis's constants,
    /// are the rows a fresh evaluation under each perturbation with the same oracle gives (at a
    /// few of the quick states): the kept rows are reused exactly where they are the same
    /// computation.
    #[test]
    fn rows_from_a_kept_evaluation_are_the_rows_computed_afresh() {
        let few = Visited {
            states: quick_states().states.iter().step_by(50).cloned().collect(),
            schedules: quick_states().schedules.clone(),
        };
        let g = quick_constants();
        let k_close = 100;
        let thesis = evaluate(&TableInputs::thesis(), &m1_tied(), g, &few).unwrap();
        let mut reused = 0;
        for p in crate::perturbation::fixed_list() {
            if p.inputs.oracle_bias.is_some() {
                continue;
            }
            reused += usize::from(step_key(&p.inputs, g).unwrap() == *thesis.step_rows.key());
            let kept = rows_from(&p.inputs, g, &thesis, k_close).unwrap();
            let ev = evaluate(&p.inputs, &m1_tied(), g, &few).unwrap();
            let fresh = rows_from(&p.inputs, g, &ev, k_close).unwrap();
            assert_eq!(format!("{kept:?}"), format!("{fresh:?}"), "{}", p.name);
        }
        assert!(reused > 0 && reused < 15, "{reused}");
    }

    /// A bias of 1/1000 on every gradient estimate breaks E[W | F_k] = 0 (it cancels in Z).
    #[test]
    fn a_biased_oracle_fails_the_mean_zero_step() {
        let biased = TableInputs {
            oracle_bias: Some(ilopt::scalar::parse_exact("1/1000").unwrap()),
            ..TableInputs::thesis()
        };
        let ev = evaluate(&biased, &m1_tied(), quick_constants(), quick_states()).unwrap();
        let rows = rows_from(
            &biased,
            quick_constants(),
            &ev,
            Sizes::for_profile(Profile::Quick).k_close,
        )
        .unwrap();
        assert_eq!(verdict(&rows, "2c.s1a"), Verdict::Fails);
    }

    /// σ² halved: some visited θ_{k+1} has Var g > σ²/2, so (A3) and the recursion fail.
    #[test]
    fn half_the_variance_bound_fails_steps_1b_and_1d() {
        let rows = quick_rows(&scaled(ConstantKind::Sigma2, "1/2"));
        assert_eq!(verdict(&rows, "2c.s1b"), Verdict::Fails);
        assert_eq!(verdict(&rows, "2c.s1d"), Verdict::Fails);
    }

    /// L̃ halved fails (A4) at the visited steps; L_F halved fails the descent lemma and the
    /// printed quadratic bound.
    #[test]
    fn half_a_smoothness_constant_fails_its_step() {
        let rows = quick_rows(&scaled(ConstantKind::LTilde, "1/2"));
        assert_eq!(verdict(&rows, "2c.s1c"), Verdict::Fails);
        let rows = quick_rows(&scaled(ConstantKind::LF, "1/2"));
        assert_eq!(verdict(&rows, "2c.s2"), Verdict::Fails);
        assert_eq!(verdict(&rows, "2c.s2.e5"), Verdict::Fails);
    }

    /// Without the noise budget (σ² = 0) Lemma 3.3, corrected and printed, and both potentials
    /// fail; an overstated L̃ (×3) breaks (C1)/(C2) for the runs' step sizes.
    #[test]
    fn the_remaining_rows_can_fail() {
        let rows = quick_rows(&scaled(ConstantKind::Sigma2, "0"));
        for id in ["2c.s1e", "2c.s1e.printed", "2c.s3", "2c.s3.e7"] {
            assert_eq!(verdict(&rows, id), Verdict::Fails, "{id}");
        }
        let rows = quick_rows(&scaled(ConstantKind::LTilde, "3"));
        assert_eq!(verdict(&rows, "2c.s3c"), Verdict::Fails);
    }

    /// `storm_fixed` with the factor 14 dropped fails the closing at the table's quick K.
    #[test]
    fn dropping_the_14_fails_the_closing() {
        let k = Profile::Quick.sizes().storm_k;
        assert_eq!(k, 20_000);
        let g = quick_constants();
        assert_eq!(
            closing::row(&TableInputs::thesis(), g, k).verdict,
            Verdict::Holds
        );
        let wrong = TableInputs {
            formulas: crate::inputs::Formulas {
                storm_fixed: closing::tests::without_14,
                ..crate::inputs::Formulas::THESIS
            },
            ..TableInputs::thesis()
        };
        assert_eq!(closing::row(&wrong, g, k).verdict, Verdict::Fails);
    }
}
