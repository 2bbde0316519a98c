//! The variance the leave-one-out and the state-dependent baselines remove on the real tasks
//! (beyond the thesis), per coordinate, at θ = 0 and at a DAgger solution.
//!
//! Per trajectory, coordinate j: `r_j = Var(g_j) / Var(g_{b,j})`, from `N` plain estimates (one
//! trajectory each) and `N/m` baselined ones (each the mean of m trajectories, so
//! `Var(g_b) = m·Var(sample)`); the total `tr Var(g) / tr Var(g_b)` likewise. Intervals are at
//! level 1 − α, the α of the other real-environment rows: log r̂ ± z_{α/2}·s, where s is the
//! bootstrap standard error of log r̂ (both sets resampled, seeded; a normal interval on the log
//! scale, since percentiles at α = 10⁻³ would need far more resamples). The claim "the baseline reduces
//! the variance" holds when the total's interval lies above 1, fails when it lies below 1, and is
//! inconclusive otherwise. Its negative control: a constant baseline far below every loss-to-go
//! (b = −4·F̂, F̂ the mean loss of a trajectory), unbiased like every constant but with a larger
//! variance, which the same rule must find to fail.

use super::estimators::{Estimator, samples};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::stats::normal_upper_quantile;
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::{ConfigNumber, Runner, StoppingRule, Termination};
use ilopt::baseline::Baseline;
use ilopt::oracle::EstimatorKernel;
use ilopt::policy::LikelihoodRatio;
use ilopt::problem::{Behaviour, Cost, IlProblem, KitRng};
use ilopt::task::{Task, TaskProblem};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use std::borrow::Borrow;

/// A ratio with its interval at level 1 − α (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ratio {
    /// The point estimate.
    pub value: f64,
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl Ratio {
    /// `value [lo, hi]`.
    fn text(&self) -> String {
        format!("{:.3} [{:.3}, {:.3}]", self.value, self.lo, self.hi)
    }
}

/// The variance reduction per trajectory: the total and each coordinate's (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Reduction {
    /// `tr Var(g) / tr Var(g_b)`.
    pub total: Ratio,
    /// `Var(g_j) / Var(g_{b,j})` per coordinate.
    pub per_coordinate: Vec<Ratio>,
    /// Plain estimates.
    pub n_plain: usize,
    /// Baselined estimates (each of `m` trajectories).
    pub n_baselined: usize,
    /// Trajectories per baselined estimate.
    pub m: usize,
}

/// Per-coordinate sample variances of `xs` (n ≥ 2).
fn variances(xs: &[&DVector<f64>]) -> DVector<f64> {
    let n = xs.len() as f64;
    let mean = xs.iter().fold(DVector::zeros(xs[0].len()), |a, x| a + *x) / n;
    xs.iter().fold(DVector::zeros(mean.len()), |a, x| {
        a + (*x - &mean).map(|v| v * v)
    }) / (n - 1.0)
}

/// The ratios of one pair of (re)samples: the total first, then each coordinate.
fn ratios(plain: &[&DVector<f64>], baselined: &[&DVector<f64>], m: usize) -> Vec<f64> {
    let (a, b) = (variances(plain), variances(baselined) * m as f64);
    let mut out = vec![a.sum() / b.sum()];
    out.extend(a.iter().zip(b.iter()).map(|(x, y)| x / y));
    out
}

/// The variance reduction of `baselined` (means of `m` trajectories) against `plain` (one
/// trajectory each), with intervals at level 1 − `alpha` from `reps` bootstrap resamples drawn
/// from `seed` (module docs).
///
/// # Panics
/// If either set has fewer than two samples, `reps < 2`, `alpha` is outside (0, 1), or the
/// dimensions differ.
pub fn reduction(
    plain: &[DVector<f64>],
    baselined: &[DVector<f64>],
    m: usize,
    reps: usize,
    seed: u64,
    alpha: f64,
) -> Reduction {
    assert!(plain.len() >= 2 && baselined.len() >= 2, "two samples each");
    assert!(
        reps >= 2 && alpha > 0.0 && alpha < 1.0,
        "reps ≥ 2, α in (0, 1)"
    );
    fn draw<'a>(v: &'a [DVector<f64>], rng: &mut KitRng) -> Vec<&'a DVector<f64>> {
        (0..v.len())
            .map(|_| &v[rng.random_range(0..v.len())])
            .collect()
    }
    let (all_plain, all_baselined): (Vec<_>, Vec<_>) =
        (plain.iter().collect(), baselined.iter().collect());
    let point = ratios(&all_plain, &all_baselined, m);
    let mut rng = KitRng::seed_from_u64(seed);
    let boot: Vec<Vec<f64>> = (0..reps)
        .map(|_| {
            let a = draw(plain, &mut rng);
            let b = draw(baselined, &mut rng);
            ratios(&a, &b, m)
        })
        .collect();
    let z = normal_upper_quantile(alpha / 2.0);
    let interval = |k: usize| {
        let logs: Vec<f64> = boot.iter().map(|r| r[k].ln()).collect();
        let mean = logs.iter().sum::<f64>() / reps as f64;
        let var = logs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (reps - 1) as f64;
        let half = z * var.sqrt();
        let log_point = point[k].ln();
        Ratio {
            value: point[k],
            lo: (log_point - half).exp(),
            hi: (log_point + half).exp(),
        }
    };
    Reduction {
        total: interval(0),
        per_coordinate: (1..point.len()).map(interval).collect(),
        n_plain: plain.len(),
        n_baselined: baselined.len(),
        m,
    }
}

/// "The baseline reduces the variance": holds when the total's interval lies above 1, fails
/// when it lies below 1, inconclusive otherwise.
pub fn reduction_verdict(r: &Reduction) -> Verdict {
    if r.total.lo > 1.0 {
        Verdict::Holds
    } else if r.total.hi < 1.0 {
        Verdict::Fails
    } else {
        Verdict::Inconclusive
    }
}

/// A DAgger solution of `p`: Algorithm 2 (one trajectory per round, β_i = 0.5^i, the aggregated
/// set, warm-started full-batch Adam epochs with α = 0.01, 20 epochs) for `rounds` rounds from
/// θ = 0, seeded.
///
/// # Errors
/// If the run fails.
pub fn dagger_solution<P: IlProblem<f64>>(
    p: &mut P,
    rounds: u64,
    seed: u64,
) -> Result<DVector<f64>, String> {
    let algorithm: AlgorithmConfig = serde_json::from_value(serde_json::json!({
        "algorithm": "dagger", "trajectories_per_iteration": 1, "aggregate": true,
        "retrain": "warm-start", "beta": {"kind": "exponential", "p": 0.5},
        "inner": {"iterations": 20, "rule": {"rule": "adam", "alpha": 0.01, "beta1": 0.9,
                  "beta2": 0.999, "epsilon": 1e-8}}
    }))
    .map_err(|e| e.to_string())?;
    let cfg = RunConfig {
        algorithm,
        theta0: vec![ConfigNumber::Float(0.0); p.dim()],
        seed,
        stop: StoppingRule::iterations(rounds),
    };
    let rec = Runner::new(cfg.stop.clone())
        .and_then(|r| r.keep_history(false).run_config(&cfg, p))
        .map_err(|e| e.to_string())?;
    if let Termination::Diverged(e) = &rec.termination {
        return Err(format!("DAgger: {e}"));
    }
    Ok(DVector::from_iterator(p.dim(), rec.theta.iter().copied()))
}

/// The mean loss of a learner's trajectory at θ over `n` roll-outs (F̂, for the control's
/// baseline).
fn mean_loss<T, P>(p: &TaskProblem<T, P>, theta: &DVector<f64>, n: usize) -> Result<f64, String>
where
    TaskProblem<T, P>: Clone,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let mut rng = KitRng::seed_from_u64(0x7661_7269_616e_6365);
    let mut total = 0.0;
    let mut p = p.clone();
    for _ in 0..n {
        let mut c = Cost::default();
        let t = p
            .rollout(&Behaviour::Learner(theta), &mut rng, &mut c)
            .map_err(|e| e.to_string())?;
        total += p.trajectory_loss(theta, &t).map_err(|e| e.to_string())?;
    }
    Ok(total / n as f64)
}

/// Trajectories the state-dependent baseline of rows `6<tag>.b.var.s<suffix>` is fitted on.
pub const STATE_FIT: usize = 1000;

/// Independent fits of the state-dependent baseline in rows `6<tag>.b.var.s<suffix>`: the
/// reduction depends on the fit (on the trajectories it saw), so each row measures it for this
/// many fits, each from its own seed family, and judges every one ([`fits_verdict`]).
pub const STATE_FITS: usize = 4;

/// "The fitted baseline reduces the variance", over independent fits, each with its interval at
/// level 1 − α/F (so that the row's false-alarm probability stays α): holds when every fit's
/// interval lies above 1, fails when some fit's lies below 1, inconclusive otherwise.
///
/// # Panics
/// Without fits.
pub fn fits_verdict(fits: &[Reduction]) -> Verdict {
    assert!(!fits.is_empty(), "at least one fit");
    if fits.iter().any(|r| r.total.hi < 1.0) {
        Verdict::Fails
    } else if fits.iter().all(|r| r.total.lo > 1.0) {
        Verdict::Holds
    } else {
        Verdict::Inconclusive
    }
}

/// One point of the variance rows: where θ is, and θ.
pub struct At<'a> {
    /// Row id suffix ("0", "D").
    pub suffix: &'a str,
    /// How θ was chosen, for the claim.
    pub what: String,
    /// θ.
    pub theta: DVector<f64>,
}

/// Rows `6<tag>.b.var<suffix>` per point of `at` (`n` plain trajectories against `n/m`
/// leave-one-out samples of `m`), `6<tag>.b.var.s<suffix>` (against `n` estimates with the
/// state-dependent baseline fitted on [`STATE_FIT`] other trajectories), and the control
/// `6<tag>.b.var.ctl` at the last point.
///
/// # Errors
/// A roll-out's or an estimate's error.
pub fn variance_rows<T, P>(
    tag: &str,
    name: &str,
    p: &TaskProblem<T, P>,
    at: &[At<'_>],
    n: usize,
    m: usize,
    alpha: f64,
) -> Result<Vec<Check>, String>
where
    TaskProblem<T, P>: Sync + Send + Clone,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let mut rows = vec![];
    let batches = (n / m).max(2);
    for (i, point) in at.iter().enumerate() {
        let seed = 40 + 4 * i as u64;
        let plain = samples(p, &point.theta, &Estimator::Oracle, n, seed)?;
        let loo = samples(
            p,
            &point.theta,
            &Estimator::Baselined(Baseline::LeaveOneOut, m),
            batches,
            seed + 1,
        )?;
        let r = reduction(&plain, &loo, m, 400, seed + 2, alpha);
        let f = mean_loss(p, &point.theta, 200)?;
        let what = format!("{} (F̂ = {f:.3}, 200 roll-outs)", point.what);
        rows.push(row(
            &format!("6{tag}.b.var{}", point.suffix),
            &format!("{name}, {what}: the leave-one-out baseline (m = {m}) reduces the variance per trajectory, tr Var(g_b) < tr Var(g)"),
            Role::Corrected,
            &r,
            alpha,
        ));
        let state = Baseline::StateDependent {
            features: None,
            time: true,
            decay: None,
            ridge: None,
            // Every fitting trajectory enters the weights.
            fit_every: Some(1),
        };
        // The n estimates split over the fits; fit f's family is 1000·(f + 1) + the point's
        // (the points' families are 40 + 4i …, so every family is its own).
        let per_fit = (n / STATE_FITS).max(2);
        let fits = (0..STATE_FITS as u64)
            .map(|f| {
                let fitted = samples(
                    p,
                    &point.theta,
                    &Estimator::Fitted(state.clone(), STATE_FIT),
                    per_fit,
                    1000 * (f + 1) + seed,
                )?;
                let level = alpha / STATE_FITS as f64;
                Ok(reduction(
                    &plain,
                    &fitted,
                    1,
                    400,
                    seed + 2 + 1000 * f,
                    level,
                ))
            })
            .collect::<Result<Vec<_>, String>>()?;
        rows.push(fits_row(
            &format!("6{tag}.b.var.s{}", point.suffix),
            &format!("{name}, {what}: the state-dependent baseline b_i = w·(φ(s_i), i, 1) (the learner's features, the decision index and 1; w = A⁻¹c fitted on {STATE_FIT} other trajectories at θ) reduces the variance per trajectory, tr Var(g_b) < tr Var(g), for each of {STATE_FITS} independent fits"),
            &fits,
            alpha,
        ));
        if i + 1 == at.len() {
            let b = -4.0 * f;
            let far = Baseline::Constant {
                value: ConfigNumber::Float(b),
            };
            let ctl = samples(
                p,
                &point.theta,
                &Estimator::Baselined(far, m),
                batches,
                seed + 3,
            )?;
            let rc = reduction(&plain, &ctl, m, 400, seed + 2, alpha);
            rows.push(row(
                &format!("6{tag}.b.var.ctl"),
                &format!("{name}, {what}: a constant baseline b = −4·F̂ = {b:.3e} (unbiased, far below every loss-to-go) reduces the variance — must fail"),
                Role::NegativeControl,
                &rc,
                alpha,
            ));
        }
    }
    Ok(rows)
}

/// Row `6<tag>.b.var.s<suffix>`: every fit's reduction, the verdict by [`fits_verdict`], and as
/// the measured statistic the fit with the smallest reduction (the claim is about every fit).
fn fits_row(id: &str, claim: &str, fits: &[Reduction], alpha: f64) -> Check {
    let worst = fits
        .iter()
        .min_by(|a, b| a.total.value.total_cmp(&b.total.value))
        .expect("at least one fit");
    let each = fits
        .iter()
        .enumerate()
        .map(|(f, r)| format!("fit {}: {}", f + 1, r.total.text()))
        .collect::<Vec<_>>()
        .join("; ");
    let (lo, hi) = fits.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
        (lo.min(r.total.value), hi.max(r.total.value))
    });
    let mut check = row(id, claim, Role::Corrected, worst, alpha / fits.len() as f64);
    check.details = format!(
        "{} independent fits of the baseline, each on {STATE_FIT} trajectories of its own seeds, each judged on {} estimates of its own against the same {} plain estimates (intervals at level 1 − α/{}); tr Var(g)/tr Var(g_b) per fit: {each}; spread over the fits {lo:.3}–{hi:.3}. The measured value is the smallest fit's, in detail: {}",
        fits.len(),
        worst.n_baselined,
        worst.n_plain,
        fits.len(),
        check.details
    );
    check.verdict = fits_verdict(fits);
    // The row's level: α/fits per fit, α for the claim about every fit.
    if let Some(m) = check.measured.as_mut() {
        m.alpha = Some(alpha);
    }
    check
}

/// The standard error of a ratio whose interval at level 1 − α is `value·exp(±z·s)` on the log
/// scale: `value·s` (delta method), for the minimum detectable effect
/// ([`crate::stats::min_detectable`]).
fn ratio_se(r: &Ratio, alpha: f64) -> f64 {
    r.value * (r.hi / r.lo).ln() / (2.0 * normal_upper_quantile(alpha / 2.0))
}

fn row(id: &str, claim: &str, role: Role, r: &Reduction, alpha: f64) -> Check {
    let per = r
        .per_coordinate
        .iter()
        .enumerate()
        .map(|(j, x)| format!("{j}: {}", x.text()))
        .collect::<Vec<_>>()
        .join("; ");
    Check::builder(
        id,
        "Variance of the baselined estimator on the real environments (beyond the thesis)",
        claim,
        role,
    )
    .assumptions([format!(
        "i.i.d. trajectories; intervals at level 1 − α, α = {alpha:.0e}: log ratio ± z·(bootstrap s.e., 400 resamples)"
    )])
    .bound(1.0)
    .measured(
        Measured::statistic(r.total.value)
            .with_interval(r.total.lo, r.total.hi)
            .with_se(ratio_se(&r.total, alpha))
            .with_runs(r.n_plain)
            .with_alpha(alpha),
    )
    .details(format!(
        "{} plain estimates (one trajectory each) against {} baselined estimates of m = {} trajectories; tr Var(g)/tr Var(g_b) = {}; per coordinate Var(g_j)/Var(g_b,j): {per}",
        r.n_plain,
        r.n_baselined,
        r.m,
        r.total.text()
    ))
    .decided(Method::Statistical, reduction_verdict(r))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn alternating(n: usize, a: f64, b: f64) -> Vec<DVector<f64>> {
        (0..n)
            .map(|i| {
                let s = if i % 2 == 0 { 1.0 } else { -1.0 };
                DVector::from_vec(vec![s * a, s * b])
            })
            .collect()
    }

    /// ±a against means ±a′ of m: each ratio is a²/(m a′²) (up to the n/(n − 1) factors), the
    /// intervals contain it, and the verdict follows the interval.
    #[test]
    fn per_coordinate_ratios_and_the_verdict() {
        let plain = alternating(200, 4.0, 1.0);
        let reduced = alternating(100, 0.5, 0.5);
        let r = reduction(&plain, &reduced, 16, 200, 1, 0.05);
        let scale = (200.0 / 199.0) / (100.0 / 99.0);
        assert!((r.per_coordinate[0].value - scale * 16.0 / (16.0 * 0.25)).abs() < 1e-12);
        assert!((r.per_coordinate[1].value - scale * 1.0 / (16.0 * 0.25)).abs() < 1e-12);
        assert!((r.total.value - scale * 17.0 / (16.0 * 0.5)).abs() < 1e-12);
        for x in r.per_coordinate.iter().chain([&r.total]) {
            assert!(x.lo <= x.value && x.value <= x.hi);
        }
        assert_eq!(reduction_verdict(&r), Verdict::Holds);
        let raised = alternating(100, 2.0, 2.0);
        assert_eq!(
            reduction_verdict(&reduction(&plain, &raised, 16, 200, 1, 0.05)),
            Verdict::Fails
        );
    }

    /// A noisy pair of sets (uniform noise of widths 4 and 1, 40 each, means of m = 16): the
    /// ratio's interval straddles 1.
    fn undecided() -> Reduction {
        let mut rng = KitRng::seed_from_u64(3);
        let mut noise = |n: usize, s: f64| -> Vec<DVector<f64>> {
            (0..n)
                .map(|_| DVector::from_vec(vec![s * (rng.random::<f64>() - 0.5)]))
                .collect()
        };
        let plain = noise(40, 4.0);
        let baselined = noise(40, 1.0);
        reduction(&plain, &baselined, 16, 400, 2, 0.05)
    }

    /// The same pair of sets, a noisy one: the interval straddles 1 and the claim is undecided.
    #[test]
    fn an_interval_around_one_is_inconclusive() {
        let r = undecided();
        assert!(r.total.lo < 1.0 && r.total.hi > 1.0, "{:?}", r.total);
        assert_eq!(reduction_verdict(&r), Verdict::Inconclusive);
    }

    /// Every fit must reduce the variance: one fit that raises it fails the row, one that is
    /// undecided leaves it inconclusive, however well the others do; the row reports the
    /// smallest fit and every fit's ratio.
    #[test]
    fn a_row_over_fits_holds_only_if_every_fit_reduces_the_variance() {
        let plain = alternating(200, 4.0, 1.0);
        let good = reduction(&plain, &alternating(100, 1.0, 0.5), 1, 200, 1, 0.05);
        let better = reduction(&plain, &alternating(100, 0.5, 0.5), 1, 200, 1, 0.05);
        let worse = reduction(&plain, &alternating(100, 8.0, 8.0), 1, 200, 1, 0.05);
        let undecided = undecided();
        assert!(undecided.total.lo < 1.0 && undecided.total.hi > 1.0);
        assert_eq!(
            fits_verdict(&[good.clone(), better.clone()]),
            Verdict::Holds
        );
        assert_eq!(
            fits_verdict(&[good.clone(), worse.clone(), better.clone()]),
            Verdict::Fails
        );
        assert_eq!(
            fits_verdict(&[undecided.clone(), better.clone()]),
            Verdict::Inconclusive
        );
        let check = fits_row("x", "claim", &[better.clone(), good.clone()], 0.01);
        assert_eq!(check.verdict, Verdict::Holds);
        let measured = check.measured.expect("measured");
        assert_eq!(measured.value, good.total.value.min(better.total.value));
        assert!(check.details.contains("fit 1: ") && check.details.contains("fit 2: "));
        assert_eq!(
            fits_row("x", "claim", &[better, worse], 0.01).verdict,
            Verdict::Fails
        );
    }
}
