//! Check 6: unbiasedness of the eq. 3.15 oracle on the real environments (thesis Fig. 4.2), under
//! the objective the chapter-4 experiments use (the thesis's fixed horizon: CartPole T = 500 with
//! a reset after every crash, the obstacle task T = 200 with absorbing ends).
//!
//! For a problem P and a fixed θ, per coordinate j:
//! * the **reference** ∇F_j(θ): central finite differences of Monte-Carlo F with **common random
//!   numbers** (the same seed i for θ ± he_j), at h and h/2, combined per seed by Richardson,
//!   `r_i = (4·FD_i(h/2) − FD_i(h))/3`, which cancels the O(h²) term. The reference is the mean of
//!   the r_i and its standard error is theirs: the finite-difference noise, Richardson's
//!   amplification of it included, is **in the standard error**, nothing is subtracted from the
//!   statistic. The remaining bias is O(h⁴); the O(h²) term it removed is reported with its own
//!   standard error, so a reader sees it is resolved;
//! * an estimator's mean ḡ_j over N independent trajectories (seeds disjoint from the reference's);
//! * `z_j = (ḡ_j − ref_j)/√(s_g²/N + s_ref²/N′)`; a row is flagged when `max_j |z_j| > z_crit =
//!   Φ⁻¹(1 − α/(2d))` (normal approximation, Bonferroni over the d coordinates);
//! * its power: the **minimum detectable bias** `MDB_j = (z_crit + z_{0.8})·SE_j`, the bias on
//!   coordinate j the row flags with probability ≥ 0.8 (normal approximation).
//!
//! The estimators checked against the same reference, through the same verdict code:
//! * the eq. 3.15 oracle (the claim);
//! * the importance-weighted old-point term of IS-STORM (math.md §4), trajectory and per-decision
//!   weights: trajectories from θ′ = θ − η∇F(θ) (one STORM-sized step), estimating ∇F(θ) (claims);
//! * negative controls, each a mutation implemented here (not in the library), which must be
//!   flagged at the same size: the unweighted old-point term at the same θ′ (the printed
//!   Algorithms 4/5, E10/E11), a dropped score term, a mis-indexed causal sum.
//!
//! A claim row says "holds" only if its power suffices: for every control, some coordinate where
//! the control's measured bias is at least the row's own MDB. Otherwise the row is
//! "inconclusive (uninformative)", whatever its z.

mod comparison;
mod estimators;
mod reference;
mod tasks;
mod variance;

pub use crate::stats::normal_upper_quantile;
pub use comparison::{Comparison, POWER_Z, compare, variance_ratio};
pub use estimators::{
    Estimator, Mutation, effective_sample_size, mutated_estimate, rollout_marking_resets, samples,
};
pub use reference::{Reference, reference};
pub use tasks::{
    ObstacleProblem, cartpole_fixed, cartpole_theta, obstacle_problem, obstacle_theta,
};
pub use variance::{
    At, Ratio, Reduction, STATE_FIT, STATE_FITS, dagger_solution, fits_verdict, reduction,
    reduction_verdict, variance_rows,
};

use crate::protocol::RealSizes;

/// Trajectories per sample of the baselined rows (6a.b, 6b.b): the chapter-4 "+ baseline" rows'
/// m.
pub const BASELINE_M: usize = 16;
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use ilopt::oracle::EstimatorKernel;
use ilopt::policy::LikelihoodRatio;
use ilopt::problem::Weighting;
use ilopt::task::{Task, TaskProblem};
use nalgebra::DVector;
use std::borrow::Borrow;

fn mean_var(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    (
        m,
        xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0),
    )
}

/// `f(oracle, i)` for `i` in `0..n`, on up to two threads (the machine's budget), in order, each
/// thread with its own copy of `oracle` (the oracles here are stateless: a copy gives the same
/// estimates, and the `&mut` receiver stays with one thread).
fn par_map<P: Clone + Send, T: Send>(
    oracle: &P,
    n: usize,
    f: impl Fn(&mut P, usize) -> Result<T, String> + Sync,
) -> Result<Vec<T>, String> {
    let threads = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .clamp(1, 2);
    let mut own = oracle.clone();
    if threads == 1 || n < 8 {
        return (0..n).map(|i| f(&mut own, i)).collect();
    }
    let mid = n / 2;
    let f = &f;
    let mut other = oracle.clone();
    let (a, b) = std::thread::scope(|s| {
        let h = s.spawn(move || {
            (mid..n)
                .map(|i| f(&mut other, i))
                .collect::<Result<Vec<T>, String>>()
        });
        let a = (0..mid)
            .map(|i| f(&mut own, i))
            .collect::<Result<Vec<T>, String>>();
        (a, h.join().expect("worker thread"))
    });
    let mut a = a?;
    a.extend(b?);
    Ok(a)
}

/// What a row checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowKind {
    /// A claim (unbiasedness); `holds` needs the power to see every control.
    Claim,
    /// A mutation that must be flagged.
    Control,
}

/// A row of the table from a comparison. `controls`: the task's controls (label, comparison),
/// which a claim row must be able to detect.
#[allow(clippy::too_many_arguments)]
pub fn row_from(
    id: &str,
    claim: String,
    kind: RowKind,
    erratum: Option<&str>,
    c: &Comparison,
    r: &Reference,
    alpha: f64,
    controls: &[(String, &Comparison)],
    note: &str,
) -> Check {
    let (worst, wj) = c.worst();
    let d = c.z.len();
    let max_se = c.se.iter().copied().fold(0.0, f64::max);
    let max_mdb = c.mdb.iter().copied().fold(0.0, f64::max);
    let min_mdb = c.mdb.iter().copied().fold(f64::INFINITY, f64::min);
    let ref_share = c
        .se_reference
        .iter()
        .zip(&c.se)
        .map(|(a, b)| (a / b).powi(2))
        .fold(0.0, f64::max);
    let h2_res = r
        .h2_term
        .iter()
        .zip(&r.h2_se)
        .map(|(t, s)| (t / s).abs())
        .fold(0.0, f64::max);
    let undetected: Vec<&str> = controls
        .iter()
        .filter(|(_, k)| !c.detects(k))
        .map(|(l, _)| l.as_str())
        .collect();
    let finite = c.z.iter().chain(&c.mdb).all(|x| x.is_finite());
    let degenerate = !finite || note.contains("uninformative");
    let verdict = match kind {
        _ if degenerate => Verdict::Uninformative,
        RowKind::Control => Verdict::from_bool(!c.flagged()),
        RowKind::Claim if c.flagged() => Verdict::Fails,
        RowKind::Claim if !undetected.is_empty() => Verdict::Uninformative,
        RowKind::Claim => Verdict::Holds,
    };
    let power = match kind {
        _ if !finite => "; NON-FINITE estimates (overflow): no verdict".into(),
        RowKind::Control => String::new(),
        RowKind::Claim if undetected.is_empty() => format!(
            "; power: every control's bias ≥ this row's MDB on some coordinate ({})",
            controls
                .iter()
                .map(|(l, _)| l.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        RowKind::Claim => format!(
            "; UNINFORMATIVE: cannot detect the bias of {}",
            undetected.join(", ")
        ),
    };
    let per_coord = (0..d)
        .map(|j| {
            format!(
                "{j}: {:+.2e}±{:.1e} (MDB {:.1e}, z {:+.2})",
                c.bias[j], c.se[j], c.mdb[j], c.z[j]
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let role = match kind {
        RowKind::Claim => Role::Thesis,
        RowKind::Control => Role::NegativeControl,
    };
    Check::builder(
        id,
        "Unbiasedness on the real environments (Fig. 4.2)",
        claim,
        role,
    )
    .assumptions([
        "CLT for the means (normal approximation); finite-difference reference with common random numbers, Richardson-extrapolated (its noise in the SE, O(h⁴) bias left)",
    ])
    .bound(c.z_crit)
    .measured(Measured::statistic(worst).with_runs(c.n).with_alpha(alpha))
    .maybe_erratum(erratum.map(Into::into))
    .details(format!(
            "N = {}, N′ = {} CRN pairs at h = {} and h/2; worst |z| = {worst:.2} (coordinate {wj}) vs z_crit = {:.2} (α = {alpha:.0e}, Bonferroni over d = {d}); SE ≤ {max_se:.2e} (reference noise ≤ {:.0}% of the variance); MDB (power 0.8) {min_mdb:.2e}…{max_mdb:.2e}; O(h²) term removed by Richardson ≤ {h2_res:.1} of its s.e.; worst |z| with N = {}{power}{note}; per coordinate bias±SE: {per_coord}",
            c.n,
            r.n_fd,
            r.h,
            c.z_crit,
            100.0 * ref_share,
            c.trend
                .iter()
                .map(|(n, z)| format!("{n}: {z:.2}"))
                .collect::<Vec<_>>()
                .join(", "),
    ))
    .decided(Method::Statistical, verdict)
}

/// Below this effective sample size of the importance weights, a weighted row is uninformative
/// (its mean rests on a handful of trajectories; the normal approximation does not apply).
pub const MIN_ESS: f64 = 100.0;

/// The problem, θ and the STORM step of one task.
pub struct TaskSetup<'a, T, P> {
    /// Row label ("CartPole, fixed-500-reset, softmax learner").
    pub name: String,
    /// The problem.
    pub problem: &'a TaskProblem<T, P>,
    /// θ.
    pub theta: DVector<f64>,
    /// STORM's step size η: θ′ = θ − η·∇F(θ) (the reference) is one STORM-sized step back.
    pub eta: f64,
    /// Which controls apply (the absorbing-tail mutation only where streams absorb).
    pub controls: Vec<Mutation>,
    /// A note for the oracle row (appended to its details).
    pub note: String,
}

/// Every row of check 6 on one task: the oracle, the IS-weighted old-point terms, and the
/// controls, against one reference at θ. Rows ids: `6.<tag>` …
///
/// # Errors
/// A roll-out's or an estimate's error.
pub fn task_rows<T, P>(
    tag: &str,
    s: &TaskSetup<'_, T, P>,
    z: RealSizes,
) -> Result<Vec<Check>, String>
where
    TaskProblem<T, P>: Sync + Send + Clone,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let p = s.problem;
    let theta = &s.theta;
    let r = reference(p, theta, z.n_fd, z.h)?;
    let grad = DVector::from_vec(r.mean.clone());
    let theta_old = theta - &grad * s.eta;
    let step = (&theta_old - theta).norm();
    let run = |e: Estimator, k: u64| -> Result<Comparison, String> {
        Ok(compare(&samples(p, theta, &e, z.n_oracle, k)?, &r, z.alpha))
    };
    // Controls first: the claims' power is judged against them.
    let mut controls: Vec<(String, Comparison)> = vec![(
        format!(
            "old-point term at a STORM step (η = {:.0e}, ‖θ′ − θ‖ = {step:.2e})",
            s.eta
        ),
        run(Estimator::OldPoint(theta_old.clone()), 1)?,
    )];
    for (i, m) in s.controls.iter().enumerate() {
        controls.push((m.label().into(), run(Estimator::Mutated(*m), 2 + i as u64)?));
    }
    let plain = samples(p, theta, &Estimator::Oracle, z.n_oracle, 20)?;
    let oracle = compare(&plain, &r, z.alpha);
    let inclusive = run(Estimator::Mutated(Mutation::Inclusive), 21)?;
    // The same number of trajectories as the oracle row, BASELINE_M per sample.
    let leave_one_out = ilopt::baseline::Baseline::LeaveOneOut;
    let baselined_samples = samples(
        p,
        theta,
        &Estimator::Baselined(leave_one_out, BASELINE_M),
        (z.n_oracle / BASELINE_M).max(2),
        24,
    )?;
    let baselined = compare(&baselined_samples, &r, z.alpha);
    // The state-dependent baseline with the decision index, fitted on other trajectories at θ.
    let state = ilopt::baseline::Baseline::StateDependent {
        features: None,
        time: true,
        decay: None,
        ridge: None,
        // Every fitting trajectory enters the weights.
        fit_every: Some(1),
    };
    let state_samples = samples(
        p,
        theta,
        &Estimator::Fitted(state, STATE_FIT),
        z.n_oracle,
        27,
    )?;
    let state_dependent = compare(&state_samples, &r, z.alpha);
    let (s_ratio, s_lo, s_hi) = variance_ratio(&plain, &state_samples, 1, 400, 28, z.alpha);
    // The baselined row's own control: a baseline that peeks at a_i (the plain rows are not
    // asked to resolve it; their noise is the variance the baseline removes).
    let peeking_label = Mutation::PeekingBaseline.label();
    let peeking = run(Estimator::Mutated(Mutation::PeekingBaseline), 26)?;
    let (ratio, ratio_lo, ratio_hi) =
        variance_ratio(&plain, &baselined_samples, BASELINE_M, 400, 25, z.alpha);
    let weighted: Vec<(Weighting, Comparison, f64)> =
        [(Weighting::Trajectory, 22), (Weighting::PerDecision, 23)]
            .into_iter()
            .map(|(w, k)| {
                Ok((
                    w,
                    run(Estimator::Weighted(theta_old.clone(), w), k)?,
                    effective_sample_size(p, theta, &theta_old, z.n_oracle, k)?,
                ))
            })
            .collect::<Result<_, String>>()?;
    let refs: Vec<(String, &Comparison)> = controls.iter().map(|(l, c)| (l.clone(), c)).collect();
    let name = &s.name;
    let mut rows = vec![row_from(
        &format!("6{tag}"),
        format!(
            "{name}: E_{{τ∼θ}}[g(θ, τ)] = ∇F(θ) (eq. 3.15, d = {})",
            theta.len()
        ),
        RowKind::Claim,
        None,
        &oracle,
        &r,
        z.alpha,
        &refs,
        &s.note,
    )];
    for (w, c, ess) in &weighted {
        let wl = match w {
            Weighting::Trajectory => "trajectory",
            Weighting::PerDecision => "per-decision",
        };
        rows.push(row_from(
            &format!("6{tag}.is-{}", if *w == Weighting::Trajectory { "tr" } else { "pd" }),
            format!("{name}: E_{{τ∼θ′}}[w·g(θ, τ)] = ∇F(θ), {wl} weights, θ′ one STORM step away (math.md §4)"),
            RowKind::Claim,
            None,
            c,
            &r,
            z.alpha,
            &refs,
            &format!(
                "; θ′ = θ − η∇F(θ), η = {:.0e}, ‖θ′ − θ‖ = {step:.2e}; trajectory weights' effective sample size {ess:.0} of {}{}",
                s.eta,
                c.n,
                if *ess < MIN_ESS { " — TOO FEW for the normal approximation: uninformative" } else { "" }
            ),
        ));
        // The weighted old-point term is math.md §4's correction of the printed algorithms.
        if let Some(last) = rows.last_mut() {
            last.role = Role::Corrected;
        }
    }
    let mut refs_b = refs.clone();
    refs_b.push((peeking_label.to_string(), &peeking));
    rows.push(row_from(
        &format!("6{tag}.b"),
        format!(
            "{name}: E[g_b(θ, τ)] = ∇F(θ), g_b = g − Σ_i b_i ψ_i with the leave-one-out baseline over m = {BASELINE_M} trajectories (docs/math.md §9; beyond the thesis)"
        ),
        RowKind::Claim,
        None,
        &baselined,
        &r,
        z.alpha,
        &refs_b,
        &format!(
            "; {} samples of m = {BASELINE_M} trajectories (as many trajectories as row 6{tag}); variance per trajectory tr Var(g)/tr Var(g_b) = {ratio:.3} [{ratio_lo:.3}, {ratio_hi:.3}] (level 1 − α, α = {a:.0e}: log ratio ± z·bootstrap s.e., 400 resamples)",
            baselined.n,
            a = z.alpha
        ),
    ));
    if let Some(last) = rows.last_mut() {
        last.role = Role::Corrected;
    }
    rows.push(row_from(
        &format!("6{tag}.b.s"),
        format!(
            "{name}: E[g_b(θ, τ)] = ∇F(θ), g_b = g − Σ_i b_i ψ_i with the state-dependent baseline b_i = w·(φ(s_i), i, 1), w fitted on {} other trajectories at θ (docs/math.md §9; beyond the thesis)",
            STATE_FIT
        ),
        RowKind::Claim,
        None,
        &state_dependent,
        &r,
        z.alpha,
        &refs_b,
        &format!(
            "; {} estimates of one trajectory each; variance per trajectory tr Var(g)/tr Var(g_b) = {s_ratio:.3} [{s_lo:.3}, {s_hi:.3}] (level 1 − α, α = {a:.0e}: log ratio ± z·bootstrap s.e., 400 resamples; for this one fit, whose own variability the interval leaves out: rows 6{tag}.b.var.s0/D measure {STATE_FITS} fits)",
            state_dependent.n,
            a = z.alpha
        ),
    ));
    if let Some(last) = rows.last_mut() {
        last.role = Role::Corrected;
    }
    rows.push(row_from(
        &format!("6{tag}.incl"),
        format!("{name}: a mutation that is unbiased, Σ_{{i≤t}} ψ_i (E[ψ_t | s_t] = 0): must not be flagged"),
        RowKind::Claim,
        None,
        &inclusive,
        &r,
        z.alpha,
        &refs,
        "",
    ));
    for (i, (label, c)) in controls.iter().enumerate() {
        rows.push(row_from(
            &format!("6{tag}.c{}", i + 1),
            format!("{name}: control, {label}: E ≠ ∇F(θ), must be flagged"),
            RowKind::Control,
            if i == 0 { Some("E10, E11") } else { None },
            c,
            &r,
            z.alpha,
            &[],
            "",
        ));
    }
    rows.push(row_from(
        &format!("6{tag}.b.ctl"),
        format!("{name}: control of row 6{tag}.b, {peeking_label}: E ≠ ∇F(θ), must be flagged"),
        RowKind::Control,
        None,
        &peeking,
        &r,
        z.alpha,
        &[],
        "",
    ));
    Ok(rows)
}
