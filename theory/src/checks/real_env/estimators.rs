//! The estimators check 6 compares with the reference: the eq. 3.15 oracle, the importance-weighted
//! old-point terms of IS-STORM, and the mutated negative controls, each sampled over seeded
//! trajectories; and the effective sample size of the importance weights.

use ilopt::oracle::EstimatorKernel;
use ilopt::policy::LikelihoodRatio;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use ilopt::task::{AfterEnd, Horizon, Task, TaskProblem, TaskTrajectory};
use nalgebra::DVector;
use rand::SeedableRng;
use std::borrow::Borrow;

use super::par_map;

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
    /// A baseline that looks at the decision it multiplies: `b_i` = the trajectory's own
    /// loss-to-go after decision i (a function of a_i), which cancels every score term and leaves
    /// `Σ_t ∇l_t`. Biased: `E[b_i ψ_i] ≠ 0` once b_i depends on a_i (docs/math.md §9).
    PeekingBaseline,
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
            Mutation::PeekingBaseline => {
                "a baseline that peeks at a_i (b_i = its own loss-to-go: no score terms)"
            }
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
            Mutation::PeekingBaseline => {}
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
                Mutation::DropTail | Mutation::PeekingBaseline => DVector::zeros(d),
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
    /// The library's baselined estimate (`ilopt::baseline::Baselined`): each sample the mean
    /// of m baselined eq. 3.15 estimates at θ, trajectories from θ.
    Baselined(ilopt::baseline::Baseline, usize),
    /// The library's baselined estimate on one trajectory at θ with a baseline fitted from
    /// data first: one oracle observes this many trajectories of its own seeds at θ and commits
    /// their statistics; every sample then estimates with a copy of it (the same baseline,
    /// independent of the sample's trajectory).
    Fitted(ilopt::baseline::Baseline, usize),
}

/// The oracle of [`Estimator::Fitted`]: `fit` roll-outs at θ from seeds `k·10⁷ + 9·10⁶ + j`
/// (disjoint from the samples' for N < 9·10⁶), each estimated, then one more roll-out, which
/// commits the last one's statistics.
///
/// # Errors
/// A roll-out's or an estimate's error.
fn fitted_oracle<T, P>(
    p: &TaskProblem<T, P>,
    theta: &DVector<f64>,
    b: &ilopt::baseline::Baseline,
    fit: usize,
    k: u64,
) -> Result<ilopt::baseline::Baselined<TaskProblem<T, P>, f64>, String>
where
    TaskProblem<T, P>: Clone,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let mut q =
        ilopt::baseline::Baselined::<_, f64>::new(p.clone(), 1, b).map_err(|e| e.to_string())?;
    let mut c = Cost::default();
    for j in 0..=fit {
        let mut rng = KitRng::seed_from_u64(k * 10_000_000 + 9_000_000 + j as u64);
        let t = q
            .rollout(&Behaviour::Learner(theta), &mut rng, &mut c)
            .map_err(|e| e.to_string())?;
        if j < fit {
            q.estimate(theta, &t, EstimatorForm::Causal, &mut c)
                .map_err(|e| e.to_string())?;
        }
    }
    Ok(q)
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
    TaskProblem<T, P>: Sync + Send + Clone,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let sample_at = match e {
        Estimator::OldPoint(x) | Estimator::Weighted(x, _) => x,
        _ => theta,
    };
    let fitted = match e {
        Estimator::Fitted(b, fit) => Some(fitted_oracle(p, theta, b, *fit, k)?),
        _ => None,
    };
    // One roll-out of a baselined oracle and its estimate at θ.
    let baselined = |q: &mut ilopt::baseline::Baselined<TaskProblem<T, P>, f64>,
                     rng: &mut KitRng| {
        let mut c = Cost::default();
        let t = q
            .rollout(&Behaviour::Learner(theta), rng, &mut c)
            .map_err(|e| e.to_string())?;
        q.estimate(theta, &t, EstimatorForm::Causal, &mut c)
            .map_err(|e| e.to_string())
    };
    par_map(p, n, |p, i| {
        let mut rng = KitRng::seed_from_u64(estimator_seed(k, i));
        if let Some(q) = &fitted {
            // Each sample from the fitted oracle as it stands: its own copy.
            return baselined(&mut q.clone(), &mut rng);
        }
        if let Estimator::Baselined(b, m) = e {
            // A fresh oracle per sample: an estimated baseline then learns only from earlier
            // trajectories of the same sample, and samples stay independent.
            let mut q = ilopt::baseline::Baselined::<_, f64>::new(p.clone(), *m, b)
                .map_err(|e| e.to_string())?;
            return baselined(&mut q, &mut rng);
        }
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
            Estimator::Mutated(_) | Estimator::Baselined(..) | Estimator::Fitted(..) => {
                unreachable!("returned above")
            }
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
    TaskProblem<T, P>: Sync + Send + Clone,
    T: Task<f64>,
    P: LikelihoodRatio<f64, Action = T::Action> + EstimatorKernel<f64>,
    T::Label: Borrow<P::Label>,
{
    let logs = par_map(p, n, |p, i| {
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
