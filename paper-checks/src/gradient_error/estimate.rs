//! The statistics of Fig. 4.2 over repetitions: nested-mean errors per stream, the RMSE with its
//! Student-t interval and the reference correction, the log-log slope with its bootstrap interval.

use super::{RmsePoint, SlopeCi, ToyRoute};
use crate::error::Error;
use crate::stats::{Summary, derive_seed};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng};
use ilopt::scalar::{BigRational, Scalar, parse_exact_list};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// Least-squares slope of log y vs log x over the points with y > 0.
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| **a > 0.0 && **b > 0.0 && b.is_finite())
        .map(|(a, b)| (a.ln(), b.ln()))
        .collect();
    if pts.len() < 2 {
        return f64::NAN;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// The nested-mean errors of `repetitions` streams: for repetition r (seed derived from `key`
/// and r), the squared error of each block of (mean of the first N draws) − `reference`, for
/// every N of `ns`. Each repetition draws from its own sampler made by `sampler` (an oracle of
/// its own: the `&mut` receiver stays in one stream). Blocks are `(start, len)` ranges of the
/// gradient.
///
/// # Errors
/// The first failing draw.
pub fn repetition_errors<F, G>(
    ns: &[u64],
    repetitions: u32,
    key: &str,
    blocks: &[(usize, usize)],
    reference: &[f64],
    sampler: F,
) -> Result<Vec<Vec<Vec<f64>>>, Error>
where
    F: Fn() -> G + Sync,
    G: FnMut(&mut KitRng) -> Result<DVector<f64>, Error>,
{
    (0..repetitions)
        .into_par_iter()
        .map(|r| {
            let mut rng = KitRng::seed_from_u64(derive_seed(key, u64::from(r)));
            let mut sample = sampler();
            let mut sum = DVector::<f64>::zeros(reference.len());
            let mut k = 0u64;
            let mut out = Vec::with_capacity(ns.len());
            for &n in ns {
                while k < n {
                    let g = sample(&mut rng)?;
                    if g.len() != reference.len() {
                        return Err(Error::experiment(
                            "gradient error",
                            format!("estimate of length {} for {}", g.len(), reference.len()),
                        ));
                    }
                    sum += g;
                    k += 1;
                }
                let inv = 1.0 / n as f64;
                out.push(
                    blocks
                        .iter()
                        .map(|&(s, l)| {
                            (s..s + l)
                                .map(|i| (sum[i] * inv - reference[i]).powi(2))
                                .sum::<f64>()
                        })
                        .collect(),
                );
            }
            Ok(out)
        })
        .collect()
}

/// Total squared error per repetition and N (the blocks summed).
pub(super) fn totals(sq: &[Vec<Vec<f64>>]) -> Vec<Vec<f64>> {
    sq.iter()
        .map(|rep| rep.iter().map(|b| b.iter().sum()).collect())
        .collect()
}

pub(super) fn corrected_rmse(mse: f64, reference_variance: f64) -> f64 {
    (mse - reference_variance).max(0.0).sqrt()
}

/// RMSE per N with intervals, and the slope with its bootstrap interval.
///
/// # Panics
/// Never for ≥ 1 repetition (the bootstrap indexes within the repetitions).
pub fn summarise(
    ns: &[u64],
    squared_errors: &[Vec<Vec<f64>>],
    sigma2: f64,
    reference_variance: f64,
    bootstrap: u32,
    key: &str,
) -> (Vec<RmsePoint>, SlopeCi) {
    let tot = totals(squared_errors);
    let reps = tot.len();
    let x: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    let mut points = Vec::with_capacity(ns.len());
    for (i, &n) in ns.iter().enumerate() {
        let col: Vec<f64> = tot.iter().map(|r| r[i]).collect();
        let s = Summary::of(&col);
        let sq = |v: f64| v.max(0.0).sqrt();
        points.push(RmsePoint {
            n,
            raw: sq(s.mean),
            raw_lo: sq(s.lo()),
            raw_hi: sq(s.hi()),
            corrected: corrected_rmse(s.mean, reference_variance),
            corrected_lo: corrected_rmse(s.lo(), reference_variance),
            corrected_hi: corrected_rmse(s.hi(), reference_variance),
            line: (sigma2 / n as f64).sqrt(),
        });
    }
    let curve = |idx: &mut dyn Iterator<Item = usize>| -> Vec<f64> {
        let mut acc = vec![0.0; ns.len()];
        let mut m = 0usize;
        for r in idx {
            for (a, v) in acc.iter_mut().zip(&tot[r]) {
                *a += v;
            }
            m += 1;
        }
        acc.iter()
            .map(|a| corrected_rmse(a / m.max(1) as f64, reference_variance))
            .collect()
    };
    let estimate = loglog_slope(&x, &curve(&mut (0..reps)));
    let mut rng = KitRng::seed_from_u64(derive_seed(&format!("{key}|bootstrap"), 0));
    let mut slopes: Vec<f64> = (0..bootstrap)
        .map(|_| {
            let draws: Vec<usize> = (0..reps).map(|_| rng.random_range(0..reps)).collect();
            loglog_slope(&x, &curve(&mut draws.into_iter()))
        })
        .filter(|s| s.is_finite())
        .collect();
    slopes.sort_by(f64::total_cmp);
    let q = |p: f64| -> f64 {
        if slopes.is_empty() {
            return f64::NAN;
        }
        let i = ((slopes.len() - 1) as f64 * p).round() as usize;
        slopes[i]
    };
    (
        points,
        SlopeCi {
            estimate,
            lo: q(0.025),
            hi: q(0.975),
            n: reps,
        },
    )
}

/// The exact standard deviation of ‖g − ∇F‖² over trajectories: √(E‖g − ∇F‖⁴ − σ⁴), by
/// enumerating every trajectory in rationals.
///
/// # Errors
/// As [`toy_exact`](super::toy_exact).
pub fn squared_error_sd(
    mdp: &ToyMdp,
    route: &ToyRoute,
    grad: &[BigRational],
    sigma2: &BigRational,
) -> Result<f64, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("Fig. 4.2 (toy, exact)", x);
    let theta = parse_exact_list(&route.theta.join(","))
        .map_err(|(i, x)| e(&format!("θ entry {i}: {x}")))?;
    let p = ToyProblem::<BigRational>::new(mdp);
    let mut m4 = <BigRational as Scalar>::zero();
    for q in ilopt::exact::enumerate::prefixes(&p, &theta).map_err(|x| e(&x))? {
        let sq = q
            .estimate
            .iter()
            .zip(grad)
            .fold(<BigRational as Scalar>::zero(), |a, (x, y)| {
                let d = x.clone() - y;
                a + d.clone() * d
            });
        m4 += q.prob * sq.clone() * sq;
    }
    Ok((m4 - sigma2.clone() * sigma2).to_f64().max(0.0).sqrt())
}

/// One eq. 3.15 estimate (causal form) on any problem at θ, from a fresh roll-out; `what` names
/// the route in an error.
///
/// # Errors
/// If the oracle fails.
pub fn draw<P: IlProblem<f64>>(
    p: &mut P,
    theta: &DVector<f64>,
    rng: &mut KitRng,
    what: &str,
) -> Result<DVector<f64>, Error> {
    let mut cost = Cost::default();
    let t = p
        .rollout(&Behaviour::Learner(theta), rng, &mut cost)
        .map_err(|e| Error::experiment(what, e))?;
    p.estimate(theta, &t, EstimatorForm::Causal, &mut cost)
        .map_err(|e| Error::experiment(what, e))
}
