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

use crate::check::{Check, Measured, Method, Role, Verdict};
use ilopt::env::obstacle::ObstacleConfig;
use ilopt::oracle::EstimatorKernel;
use ilopt::policy::{LikelihoodRatio, LinearGaussian, Softmax, SpeedLimitedGaussian};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::task::cartpole::{self, CartPoleTask};
use ilopt::task::obstacle::{self, ObstacleTask};
use ilopt::task::{AfterEnd, Horizon, Task, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;
use std::borrow::Borrow;

/// The standard normal upper quantile Φ⁻¹(1 − p) = −Φ⁻¹(p) for 0 < p < 1/2 (statrs' inverse
/// CDF, taken at p so that small p keeps its precision).
pub fn normal_upper_quantile(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    -Normal::standard().inverse_cdf(p)
}

/// Φ⁻¹(0.8): the minimum detectable bias is the bias flagged with probability ≥ 0.8.
pub const POWER_Z: f64 = 0.841_621_2;

fn mean_var(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    (
        m,
        xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0),
    )
}

/// Sizes of the check.
#[derive(Debug, Clone, Copy)]
pub struct RealSizes {
    /// Trajectories N per estimator.
    pub n_oracle: usize,
    /// Paired roll-outs per finite difference N′.
    pub n_fd: usize,
    /// Step h (the reference uses h and h/2).
    pub h: f64,
    /// False-alarm probability of each row.
    pub alpha: f64,
}

/// `f(i)` for `i` in `0..n`, on up to two threads (the machine's budget), in order.
fn par_map<T: Send>(
    n: usize,
    f: impl Fn(usize) -> Result<T, String> + Sync,
) -> Result<Vec<T>, String> {
    let threads = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .clamp(1, 2);
    if threads == 1 || n < 8 {
        return (0..n).map(f).collect();
    }
    let mid = n / 2;
    let f = &f;
    let (a, b) = std::thread::scope(|s| {
        let h = s.spawn(move || (mid..n).map(f).collect::<Result<Vec<T>, String>>());
        let a = (0..mid).map(f).collect::<Result<Vec<T>, String>>();
        (a, h.join().expect("worker thread"))
    });
    let mut a = a?;
    a.extend(b?);
    Ok(a)
}

/// The finite-difference reference ∇F(θ) (see the module docs).
#[derive(Debug, Clone)]
pub struct Reference {
    /// Step h (differences at h and h/2).
    pub h: f64,
    /// Paired roll-outs per difference N′.
    pub n_fd: usize,
    /// Richardson's `(4·FD(h/2) − FD(h))/3` per coordinate.
    pub mean: Vec<f64>,
    /// Its standard error (the finite-difference noise, Richardson's included).
    pub se: Vec<f64>,
    /// The O(h²) term Richardson removed from FD(h/2), `(FD(h) − FD(h/2))/3`.
    pub h2_term: Vec<f64>,
    /// Its standard error.
    pub h2_se: Vec<f64>,
}

fn loss_at<P: IlProblem<f64>>(p: &P, theta: &DVector<f64>, seed: u64) -> Result<f64, String> {
    let mut rng = KitRng::seed_from_u64(seed);
    let mut c = Cost::default();
    let t = p
        .rollout(&Behaviour::Learner(theta), &mut rng, &mut c)
        .map_err(|e| e.to_string())?;
    p.trajectory_loss(theta, &t).map_err(|e| e.to_string())
}

/// Seeds of the reference: coordinate j uses `REFERENCE_SEEDS + j·10⁷ + i`, disjoint from the
/// estimators' seeds (below 10⁹).
const REFERENCE_SEEDS: u64 = 1_000_000_000;

/// The reference at θ with N′ common-random-number pairs at h and at h/2 per coordinate.
///
/// # Errors
/// A roll-out's error.
pub fn reference<P: IlProblem<f64> + Sync>(
    p: &P,
    theta: &DVector<f64>,
    n_fd: usize,
    h: f64,
) -> Result<Reference, String> {
    let d = theta.len();
    let per_coord = par_map(d, |j| {
        let seed0 = REFERENCE_SEEDS + (j as u64) * 10_000_000;
        let mut rich = Vec::with_capacity(n_fd);
        let mut h2 = Vec::with_capacity(n_fd);
        for i in 0..n_fd {
            let s = seed0 + i as u64;
            let fd = |step: f64| -> Result<f64, String> {
                let mut up = theta.clone();
                up[j] += step;
                let mut down = theta.clone();
                down[j] -= step;
                Ok((loss_at(p, &up, s)? - loss_at(p, &down, s)?) / (2.0 * step))
            };
            let (f1, f2) = (fd(h)?, fd(h / 2.0)?);
            rich.push((4.0 * f2 - f1) / 3.0);
            h2.push((f1 - f2) / 3.0);
        }
        let ((m, v), (hm, hv)) = (mean_var(&rich), mean_var(&h2));
        Ok((m, (v / n_fd as f64).sqrt(), hm, (hv / n_fd as f64).sqrt()))
    })?;
    Ok(Reference {
        h,
        n_fd,
        mean: per_coord.iter().map(|x| x.0).collect(),
        se: per_coord.iter().map(|x| x.1).collect(),
        h2_term: per_coord.iter().map(|x| x.2).collect(),
        h2_se: per_coord.iter().map(|x| x.3).collect(),
    })
}

/// A deliberately wrong eq. 3.15 (a negative control), or the right one re-implemented here.
///
/// On a trajectory with decisions t = 1..n, losses l_t, scores ψ_t and absorbing losses L_abs
/// (zero if the stream did not absorb), eq. 3.15 is
/// `g = Σ_t ∇l_t + Σ_t l_t Σ_{i<t} ψ_i + L_abs Σ_{i≤n} ψ_i`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mutation {
    /// Eq. 3.15 itself (must agree with the library's estimate).
    None,
    /// A dropped score term: ψ_1, the first decision's score, is left out of every sum.
    DropFirstScore,
    /// A mis-indexed causal sum in the absorbing tail: `L_abs Σ_{i<n} ψ_i` instead of `Σ_{i≤n}`,
    /// without the score of the decision that ended the episode (on a stream that never
    /// absorbs, eq. 3.15 itself).
    DropEndScore,
    /// Dropped score terms: the absorbing tail's `L_abs Σ_{i≤n} ψ_i` left out (the absorbing
    /// losses ignored by the estimator; on a stream that never absorbs, eq. 3.15 itself).
    DropTail,
    /// A dropped score term: the score sum restarts at every reset of a fixed-horizon stream
    /// (each loss weighted by the scores of its own episode only; the terms crossing a reset are
    /// dropped, although the reset time depends on earlier actions).
    DropCrossReset,
    /// The causal sum mis-indexed as `Σ_{i<t−1}` (each loss loses its predecessor's score).
    Lagged,
    /// The causal sum mis-indexed as `Σ_{i>t}` (the inequality reversed).
    Reversed,
    /// The causal sum mis-indexed as `Σ_{i≤t}`. **Unbiased** (E[ψ_t | s_t] = 0 and l_t depends on
    /// s_t only): a mutation the check must *not* flag.
    Inclusive,
}

impl Mutation {
    /// Its label in the table.
    pub fn label(self) -> &'static str {
        match self {
            Mutation::None => "eq. 3.15 re-implemented",
            Mutation::DropFirstScore => "dropped score term (ψ_1 left out)",
            Mutation::DropEndScore => "mis-indexed causal sum in the absorbing tail (Σ_{i<n} ψ_i)",
            Mutation::DropTail => "dropped score terms (the absorbing tail's L_abs Σ_{i≤n} ψ_i)",
            Mutation::DropCrossReset => "dropped score terms (score sum restarted at each reset)",
            Mutation::Lagged => "mis-indexed causal sum (Σ_{i<t−1} ψ_i)",
            Mutation::Reversed => "mis-indexed causal sum (Σ_{i>t} ψ_i)",
            Mutation::Inclusive => "mis-indexed causal sum (Σ_{i≤t} ψ_i, unbiased)",
        }
    }
}

/// The estimate of `m` at θ on one trajectory (f64); `episode_starts`: the decisions at which an
/// episode starts after a reset (for [`Mutation::DropCrossReset`]).
///
/// # Errors
/// A policy's error, or a malformed trajectory.
pub fn mutated_estimate<T, P>(
    p: &TaskProblem<T, P>,
    theta: &DVector<f64>,
    t: &TaskTrajectory<f64, T::Label, T::Action>,
    episode_starts: &[usize],
    m: Mutation,
) -> Result<DVector<f64>, String>
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let d = p.policy.param_dim();
    let n = t.len();
    if n == 0 || t.labels.len() != n {
        return Err("malformed trajectory".into());
    }
    let (mut grad, mut score) = (vec![0.0; d], vec![0.0; d]);
    let mut g = DVector::zeros(d);
    // Σ of the scores of the decisions before the current one (all, as eq. 3.15 needs), and
    // the same sum lagged by one decision (for `Lagged`).
    let mut before = DVector::zeros(d);
    let mut before_prev = DVector::zeros(d);
    // For `Reversed`: Σ_t l_t Σ_{i>t} ψ_i = Σ_i ψ_i Σ_{t<i} l_t, with the running loss sum.
    let mut loss_before = 0.0;
    for (step, ((phi, a), y)) in t.feature_rows().zip(&t.actions).zip(&t.labels).enumerate() {
        if m == Mutation::DropCrossReset && episode_starts.contains(&step) {
            before.fill(0.0);
            before_prev.fill(0.0);
        }
        let l = p
            .policy
            .loss_score_into(theta.as_slice(), phi, y.borrow(), a, &mut grad, &mut score)
            .map_err(|e| e.to_string())?;
        let psi = if m == Mutation::DropFirstScore && step == 0 {
            DVector::zeros(d)
        } else {
            DVector::from_column_slice(&score)
        };
        g += DVector::from_column_slice(&grad);
        match m {
            Mutation::Lagged => g += &before_prev * l,
            Mutation::Reversed => g += &psi * loss_before,
            _ => g += &before * l,
        }
        loss_before += l;
        if m == Mutation::Inclusive {
            g += &psi * l;
        }
        before_prev.copy_from(&before);
        before += &psi;
        if step + 1 == n
            && let Some(tail) = t.absorbed
        {
            let sum = match m {
                Mutation::DropEndScore => &before - &psi,
                Mutation::DropTail => DVector::zeros(d),
                _ => before.clone(),
            };
            g += sum * tail;
        }
    }
    Ok(g)
}

/// A learner's roll-out under the problem's horizon, written here from the task's and the
/// policy's public steps (the library's roll-out does not record where resets happen): the
/// trajectory and the decisions at which an episode started after a reset. The same law as the
/// library's roll-out (not the same random draws).
///
/// # Errors
/// An environment's, expert's or policy's error.
#[allow(clippy::type_complexity)]
pub fn rollout_marking_resets<T, P>(
    p: &TaskProblem<T, P>,
    theta: &DVector<f64>,
    rng: &mut KitRng,
) -> Result<(TaskTrajectory<f64, T::Label, T::Action>, Vec<usize>), String>
where
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
{
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let (limit, after_end) = match p.horizon {
        Horizon::Episodic => (usize::MAX, None),
        Horizon::Fixed { steps, after_end } => (steps, Some(after_end)),
    };
    let (mut feats, mut actions, mut labels, mut starts) = (vec![], vec![], vec![], vec![]);
    let mut absorbed = None;
    let mut ep = p.task.start(rng).map_err(|x| e(&x))?;
    loop {
        let phi = p.task.features(&ep);
        let (label, _) = p.task.expert(&ep).map_err(|x| e(&x))?;
        let a = p
            .policy
            .sample(theta.as_slice(), &phi, rng)
            .map_err(|x| e(&x))?;
        let done = p.task.advance(&mut ep, &a).map_err(|x| e(&x))?;
        feats.push(phi);
        actions.push(a);
        labels.push(label);
        let n = actions.len();
        if n >= limit {
            break;
        }
        if done {
            match after_end {
                None => break,
                Some(AfterEnd::Reset) => {
                    starts.push(n);
                    ep = p.task.start(rng).map_err(|x| e(&x))?;
                }
                Some(AfterEnd::Absorb) => {
                    let c = p.task.absorbing_loss(&ep).ok_or("no absorbing loss")?;
                    absorbed = Some((limit - n) as f64 * c);
                    break;
                }
            }
        }
    }
    let mut t = TaskTrajectory::from_parts(feats, actions, labels).map_err(|x| e(&x))?;
    t.absorbed = absorbed;
    t.resets = starts.len();
    Ok((t, starts))
}

/// Which estimate is averaged against the reference ∇F(θ).
#[derive(Debug, Clone)]
pub enum Estimator {
    /// The library's eq. 3.15 estimate at θ, trajectories from θ.
    Oracle,
    /// The library's eq. 3.15 estimate at θ, trajectories from θ′ (the unweighted old-point term).
    OldPoint(DVector<f64>),
    /// The library's importance-weighted estimate of ∇F(θ) from trajectories of θ′.
    Weighted(DVector<f64>, Weighting),
    /// A mutation (this module), trajectories from θ.
    Mutated(Mutation),
}

/// Seeds of estimator `k`'s N trajectories: `k·10⁷ + i`.
fn estimator_seed(k: u64, i: usize) -> u64 {
    k * 10_000_000 + i as u64
}

/// N per-trajectory estimates of `e` (seed family `k`).
///
/// # Errors
/// A roll-out's or an estimate's error.
pub fn samples<T, P>(
    p: &TaskProblem<T, P>,
    theta: &DVector<f64>,
    e: &Estimator,
    n: usize,
    k: u64,
) -> Result<Vec<DVector<f64>>, String>
where
    TaskProblem<T, P>: Sync,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let sample_at = match e {
        Estimator::OldPoint(x) | Estimator::Weighted(x, _) => x,
        _ => theta,
    };
    par_map(n, |i| {
        let mut rng = KitRng::seed_from_u64(estimator_seed(k, i));
        if let Estimator::Mutated(m) = e {
            let (t, starts) = rollout_marking_resets(p, theta, &mut rng)?;
            return mutated_estimate(p, theta, &t, &starts, *m);
        }
        let mut c = Cost::default();
        let t = p
            .rollout(&Behaviour::Learner(sample_at), &mut rng, &mut c)
            .map_err(|e| e.to_string())?;
        match e {
            Estimator::Oracle | Estimator::OldPoint(_) => p
                .estimate(theta, &t, EstimatorForm::Causal, &mut c)
                .map_err(|e| e.to_string()),
            Estimator::Weighted(x, w) => p
                .weighted_estimate(theta, x, &t, *w, &mut c)
                .map_err(|e| e.to_string()),
            Estimator::Mutated(_) => unreachable!("rolled out below"),
        }
    })
}

/// The effective sample size `(Σw)²/Σw²` of the trajectory weights `w = Π π_θ(a_i|s_i)/π_θ′(a_i|s_i)`
/// (over the decisions that weigh a loss) of the N trajectories of θ′ that estimator `k` uses:
/// how many of them the weighted mean effectively rests on.
///
/// # Errors
/// A roll-out's or a policy's error.
pub fn effective_sample_size<T, P>(
    p: &TaskProblem<T, P>,
    theta: &DVector<f64>,
    theta_new: &DVector<f64>,
    n: usize,
    k: u64,
) -> Result<f64, String>
where
    TaskProblem<T, P>: Sync,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let logs = par_map(n, |i| {
        let mut rng = KitRng::seed_from_u64(estimator_seed(k, i));
        let mut c = Cost::default();
        let t = p
            .rollout(&Behaviour::Learner(theta_new), &mut rng, &mut c)
            .map_err(|e| e.to_string())?;
        let scored = if t.absorbed.is_some() {
            t.len()
        } else {
            t.len() - 1
        };
        let mut lw = 0.0;
        for (phi, a) in t.feature_rows().zip(&t.actions).take(scored) {
            lw += p
                .policy
                .log_likelihood_ratio(theta.as_slice(), theta_new.as_slice(), phi, a)
                .map_err(|e| e.to_string())?;
        }
        Ok(lw)
    })?;
    let top = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (s1, s2) = logs.iter().fold((0.0, 0.0), |(a, b), l| {
        let w = (l - top).exp();
        (a + w, b + w * w)
    });
    Ok(s1 * s1 / s2)
}

/// An estimator's samples against the reference, per coordinate.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Trajectories N.
    pub n: usize,
    /// ḡ_j.
    pub mean: Vec<f64>,
    /// ḡ_j − ref_j, the estimated bias.
    pub bias: Vec<f64>,
    /// `√(s_g²/N + s_ref²/N′)`: the estimator's and the reference's noise.
    pub se: Vec<f64>,
    /// The reference's share of it, `s_ref/√N′`.
    pub se_reference: Vec<f64>,
    /// `z_j = bias_j / se_j`.
    pub z: Vec<f64>,
    /// `(z_crit + z_{0.8})·se_j`.
    pub mdb: Vec<f64>,
    /// `Φ⁻¹(1 − α/(2d))`.
    pub z_crit: f64,
    /// `max_j |z_j|` with the first N/16, N/4 and N samples (the 1/√N behaviour).
    pub trend: Vec<(usize, f64)>,
}

impl Comparison {
    /// `max_j |z_j|` and its coordinate.
    pub fn worst(&self) -> (f64, usize) {
        self.z
            .iter()
            .enumerate()
            .map(|(j, z)| (z.abs(), j))
            .fold((f64::NEG_INFINITY, 0), |a, b| if b.0 > a.0 { b } else { a })
    }
    /// Flagged at the row's α.
    pub fn flagged(&self) -> bool {
        self.worst().0 > self.z_crit
    }
    /// Whether `other`'s measured bias is at least this row's MDB on some coordinate.
    pub fn detects(&self, other: &Comparison) -> bool {
        other.bias.iter().zip(&self.mdb).any(|(b, m)| b.abs() >= *m)
    }
}

/// Compare samples with the reference at false-alarm probability α.
pub fn compare(samples: &[DVector<f64>], r: &Reference, alpha: f64) -> Comparison {
    let n = samples.len();
    let d = r.mean.len();
    let z_crit = normal_upper_quantile(alpha / (2.0 * d as f64));
    let cols: Vec<Vec<f64>> = (0..d)
        .map(|j| samples.iter().map(|g| g[j]).collect())
        .collect();
    let stats = |m: usize| -> Vec<(f64, f64)> {
        cols.iter()
            .zip(&r.se)
            .map(|(c, sr)| {
                let (gm, gv) = mean_var(&c[..m]);
                (gm, (gv / m as f64 + sr * sr).sqrt())
            })
            .collect()
    };
    let full = stats(n);
    let bias: Vec<f64> = full.iter().zip(&r.mean).map(|(s, rm)| s.0 - rm).collect();
    let se: Vec<f64> = full.iter().map(|s| s.1).collect();
    let trend = [16usize, 4, 1]
        .into_iter()
        .map(|k| {
            let m = (n / k).max(2);
            let w = stats(m)
                .iter()
                .zip(&r.mean)
                .map(|(s, rm)| ((s.0 - rm) / s.1).abs())
                .fold(0.0f64, f64::max);
            (m, w)
        })
        .collect();
    Comparison {
        n,
        mean: full.iter().map(|s| s.0).collect(),
        z: bias.iter().zip(&se).map(|(b, s)| b / s).collect(),
        mdb: se.iter().map(|s| (z_crit + POWER_Z) * s).collect(),
        bias,
        se,
        se_reference: r.se.clone(),
        z_crit,
        trend,
    }
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
    Check {
        id: id.into(),
        result: "Unbiasedness on the real environments (Fig. 4.2)".into(),
        claim,
        assumptions: vec![
            "CLT for the means (normal approximation); finite-difference reference with common random numbers, Richardson-extrapolated (its noise in the SE, O(h⁴) bias left)".into(),
        ],
        constants: vec![],
        bound: Some(c.z_crit),
        measured: Some(Measured {
            value: worst,
            lcb: None,
            ucb: None,
            runs: Some(c.n),
            alpha: Some(alpha),
        }),
        tightness: None,
        method: Method::Statistical,
        verdict,
        erratum: erratum.map(Into::into),
        role: match kind {
            RowKind::Claim => Role::Thesis,
            RowKind::Control => Role::NegativeControl,
        },
        details: format!(
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
        ),
    }
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
    TaskProblem<T, P>: Sync,
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
    let oracle = run(Estimator::Oracle, 20)?;
    let inclusive = run(Estimator::Mutated(Mutation::Inclusive), 21)?;
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
    Ok(rows)
}

/// The CartPole problem of the checks: softmax learner over the task's features, LQR expert, the
/// thesis's objective (T = 500 decisions, a reset after every crash).
///
/// # Errors
/// A message if the task cannot be built.
pub fn cartpole_fixed() -> Result<TaskProblem<CartPoleTask<f64>, Softmax>, String> {
    TaskProblem::fixed(
        CartPoleTask::with_lqr().map_err(|e| e.to_string())?,
        Softmax::new(2, cartpole::FEATURES).map_err(|e| e.to_string())?,
        500,
        AfterEnd::Reset,
    )
    .map_err(|e| e.to_string())
}

/// CartPole's θ: a partly competent learner (push right when the pole leans right).
pub fn cartpole_theta() -> DVector<f64> {
    DVector::from_vec(vec![0.0, 0.0, -2.0, -0.5, 0.0, 0.0, 0.0, 2.0, 0.5, 0.0])
}

/// The obstacle task's problem (the experiments' types).
pub type ObstacleProblem = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

/// The obstacle problem of the checks: the experiments' learner (linear-Gaussian over the basic
/// features, σ = `sigma`, loss of the executed speed-clipped velocity), the velocity-obstacle
/// expert, and `horizon`.
///
/// # Errors
/// A message if the task cannot be built.
pub fn obstacle_problem(sigma: f64, horizon: Horizon) -> Result<ObstacleProblem, String> {
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let v_max = ObstacleConfig::default().agent_max_speed;
    let inner = LinearGaussian::new(2, obstacle::FEATURES, sigma)
        .and_then(LinearGaussian::with_actions::<[f64; 2]>)
        .map_err(|x| e(&x))?;
    Ok(TaskProblem {
        task: ObstacleTask::thesis()
            .map_err(|x| e(&x))?
            .with_actions::<[f64; 2]>(),
        policy: SpeedLimitedGaussian::new(inner, v_max).map_err(|x| e(&x))?,
        horizon,
    })
}

/// The obstacle task's θ: a proportional pull towards the goal, v = 0.05·(goal − agent) (the
/// θ of the experiments' gradient-error figure).
pub fn obstacle_theta() -> DVector<f64> {
    let mut theta = DVector::zeros(2 * obstacle::FEATURES);
    theta[0] = 0.05;
    theta[obstacle::FEATURES + 1] = 0.05;
    theta
}

#[cfg(test)]
mod tests {
    use super::normal_upper_quantile;

    #[test]
    fn normal_quantiles() {
        assert!((normal_upper_quantile(0.025) - 1.959_964).abs() < 1e-5);
        assert!((normal_upper_quantile(0.005) - 2.575_829).abs() < 1e-5);
        assert!((normal_upper_quantile(1e-6) - 4.753_424).abs() < 1e-4);
        assert!((normal_upper_quantile(0.2) - super::POWER_Z).abs() < 1e-5);
    }
}
