//! STORM's mean linearisation measured on the two tasks (math.md §10.4).
//!
//! For the thesis's unweighted old-point term, the linearised direction recursion is
//! `d_{k+1} ≈ (1 − a)(I − η J_τ) d_k + a g` with `J_τ = ∂g(θ, τ)/∂θ` at a fixed recorded trajectory
//! τ; its mean dynamics matrix is `(1 − a)(I − η E[J])`, where `E[J] = ∇²F − E[g ∇log pᵀ]` is not
//! the Hessian. For the importance-weighted term the per-trajectory linearisation is
//! `J̃_τ = ∂/∂θ_old [w_{θ_old→θ}(τ) g(θ_old, τ)]` at θ_old = θ, whose mean is ∇²F.
//!
//! [`measure`] estimates both means by Monte Carlo over N trajectories drawn at θ, each Jacobian by
//! central differences of the oracle's own estimates at the recorded trajectory (the calls the
//! STORM step makes: [`IlProblem::estimate`] for the unweighted term,
//! [`IlProblem::weighted_estimate`] for the weighted one). From each mean it reports the
//! eigenvalues that decide stability (full and symmetrised part), the spectral radius
//! `ρ((1 − a)(I − ηA))` on a grid of (η, a) and the amplification threshold η*(a)
//! ([`ilopt::algo::storm_stability`]). The uncertainty is a delete-one-batch jackknife: the N
//! trajectories are split into B batches, every statistic is recomputed from the mean of the other
//! B − 1 batches, and the standard error is `√((B − 1)/B Σ_b (x_(−b) − x̄_(·))²)`.

use crate::config::{Profile, TaskExperiment};
use crate::error::Error;
use crate::experiment::TaskKind;
use crate::experiment::{TaskLearner, task_learner};
use ilopt::algo::storm_stability::{eigenvalues, mean_radius, threshold};
use ilopt::algo::{AlgorithmConfig, Runner, StoppingRule};
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, Weighting};
use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;

/// What [`measure`] does.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Trajectories N drawn at θ.
    pub trajectories: usize,
    /// Batches B of the jackknife (N must be a multiple of B, B ≥ 2).
    pub batches: usize,
    /// The central-difference step for coordinate j is `relative_step · max(1, |θ_j|)`.
    pub relative_step: f64,
    /// The weighting of the importance-weighted term.
    pub weighting: Weighting,
    /// Step sizes η of the radius grid.
    pub etas: Vec<f64>,
    /// Momentum weights a.
    pub momenta: Vec<f64>,
    /// The RNG seed of the trajectories.
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            trajectories: 256,
            batches: 8,
            relative_step: 1e-6,
            weighting: Weighting::PerDecision,
            etas: (-16..=0).map(|k| 10f64.powf(f64::from(k) / 2.0)).collect(),
            momenta: vec![0.1, 0.5, 0.9],
            seed: 0,
        }
    }
}

/// A statistic with its jackknife standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stat {
    /// The value from all N trajectories.
    pub value: f64,
    /// The delete-one-batch jackknife standard error.
    pub stderr: f64,
}

/// The stability statistics of one mean linearisation A.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// The smallest real part of an eigenvalue of A.
    pub min_re: Stat,
    /// The largest real part.
    pub max_re: Stat,
    /// The largest |Im λ|.
    pub max_im: Stat,
    /// The smallest eigenvalue of (A + Aᵀ)/2.
    pub sym_min: Stat,
    /// The largest eigenvalue of (A + Aᵀ)/2.
    pub sym_max: Stat,
    /// ‖A − Aᵀ‖_F / ‖A + Aᵀ‖_F.
    pub asymmetry: Stat,
    /// η*(a) per entry of [`Options::momenta`].
    pub thresholds: Vec<Stat>,
    /// ρ((1 − a)(I − ηA)), `radii[i][j]` for momenta\[i\], etas\[j\].
    pub radii: Vec<Vec<Stat>>,
}

/// The second moment along one direction v (‖v‖ = 1): from `d_k = v` the homogeneous linearised
/// recursion gives `E‖d_{k+1}‖² = (1 − a)²(1 − 2η vᵀE[J]v + η² E‖J_τ v‖²)`, which exceeds 1 exactly
/// for `η > (m + √(m² + q s))/s` with `m = vᵀE[J]v`, `s = E‖J_τ v‖²`, `q = 1/(1 − a)² − 1`
/// (math.md §10.2). Measured on N fresh trajectories, `J_τ v` by a central difference along v.
#[derive(Debug, Clone, PartialEq)]
pub struct Directional {
    /// m = vᵀ E\[J\] v.
    pub rayleigh: Stat,
    /// s = E‖J_τ v‖².
    pub mean_square: Stat,
    /// The one-step growth threshold per entry of [`Options::momenta`].
    pub thresholds: Vec<Stat>,
}

/// What [`measure`] reports.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// The parameter dimension d.
    pub dim: usize,
    /// The options used.
    pub options: Options,
    /// E\[J\] of the unweighted old-point term.
    pub unweighted: Spectrum,
    /// E\[J̃\] of the importance-weighted term (an estimate of ∇²F).
    pub weighted: Spectrum,
    /// Along v = the eigenvector of the smallest eigenvalue of E\[J\]'s symmetric part: the
    /// second moment of the unweighted term's J_τ v.
    pub unweighted_direction: Directional,
    /// Along the same v: the second moment of the importance-weighted term's J̃_τ v.
    pub weighted_direction: Directional,
    /// ‖E\[J̃\] − E\[J\]‖_F / ‖E\[J̃\]‖_F: the relative size of the covariance term C.
    pub covariance_share: Stat,
    /// Seconds spent.
    pub seconds: f64,
}

/// The scalar statistics of one matrix, in the order of [`Spectrum`]'s fields.
fn statistics(m: &DMatrix<f64>, opts: &Options) -> Result<Vec<f64>, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("storm stability", x);
    let eig = eigenvalues(m).map_err(|x| e(&x))?;
    let sym = (m + m.transpose()) * 0.5;
    let se = sym.symmetric_eigenvalues();
    let anti = (m - m.transpose()).norm();
    let mut out = vec![
        eig.iter().map(|l| l.re).fold(f64::INFINITY, f64::min),
        eig.iter().map(|l| l.re).fold(f64::NEG_INFINITY, f64::max),
        eig.iter().map(|l| l.im.abs()).fold(0.0, f64::max),
        se.min(),
        se.max(),
        anti / (2.0 * sym.norm()),
    ];
    for &a in &opts.momenta {
        out.push(threshold(&eig, a).map_err(|x| e(&x))?);
    }
    for &a in &opts.momenta {
        for &eta in &opts.etas {
            out.push(mean_radius(&eig, eta, a).map_err(|x| e(&x))?);
        }
    }
    Ok(out)
}

/// Point values from the full mean, standard errors from the delete-one-batch means.
fn jackknife(full: &[f64], deleted: &[Vec<f64>]) -> Vec<Stat> {
    let b = deleted.len() as f64;
    (0..full.len())
        .map(|i| {
            let mean = deleted.iter().map(|x| x[i]).sum::<f64>() / b;
            let ss = deleted.iter().map(|x| (x[i] - mean).powi(2)).sum::<f64>();
            Stat {
                value: full[i],
                stderr: ((b - 1.0) / b * ss).sqrt(),
            }
        })
        .collect()
}

fn spectrum(stats: Vec<Stat>, opts: &Options) -> Spectrum {
    let (na, ne) = (opts.momenta.len(), opts.etas.len());
    let thresholds = stats[6..6 + na].to_vec();
    let radii = (0..na)
        .map(|i| stats[6 + na + i * ne..6 + na + (i + 1) * ne].to_vec())
        .collect();
    Spectrum {
        min_re: stats[0],
        max_re: stats[1],
        max_im: stats[2],
        sym_min: stats[3],
        sym_max: stats[4],
        asymmetry: stats[5],
        thresholds,
        radii,
    }
}

/// Add `scale · (x − y)` to column `j` of `m`.
fn add_column(m: &mut DMatrix<f64>, j: usize, x: &DVector<f64>, y: &DVector<f64>, scale: f64) {
    for (i, (a, b)) in x.iter().zip(y.iter()).enumerate() {
        m[(i, j)] += scale * (a - b);
    }
}

/// Estimate E\[J\] and E\[J̃\] at θ on `problem` and report their stability statistics (module docs).
///
/// # Errors
/// [`Error::Experiment`] for invalid options (N not a positive multiple of B, B < 2, a step or
/// momentum out of range), a failing roll-out or estimate, or a non-finite mean.
pub fn measure<P: IlProblem<f64>>(
    problem: &mut P,
    theta: &DVector<f64>,
    opts: &Options,
) -> Result<Measurement, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("storm stability", x);
    let start = std::time::Instant::now();
    let d = problem.dim();
    if theta.len() != d {
        return Err(e(&format!(
            "θ has {} entries, the problem {d}",
            theta.len()
        )));
    }
    if opts.batches < 2 || opts.trajectories == 0 || !opts.trajectories.is_multiple_of(opts.batches)
    {
        return Err(e(&format!(
            "N = {} trajectories must be a positive multiple of B = {} ≥ 2 batches",
            opts.trajectories, opts.batches
        )));
    }
    if !(opts.relative_step.is_finite() && opts.relative_step > 0.0) {
        return Err(e(&format!(
            "the relative step must be positive, got {}",
            opts.relative_step
        )));
    }
    if let Some(a) = opts.momenta.iter().find(|a| !(0.0..1.0).contains(*a)) {
        return Err(e(&format!("a momentum weight must lie in [0, 1), got {a}")));
    }
    if let Some(x) = opts.etas.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
        return Err(e(&format!("a step size must be finite and ≥ 0, got {x}")));
    }
    let mut rng = KitRng::seed_from_u64(opts.seed);
    let mut cost = Cost::default();
    let per_batch = opts.trajectories / opts.batches;
    let mut batch_j = Vec::with_capacity(opts.batches);
    let mut batch_w = Vec::with_capacity(opts.batches);
    for _ in 0..opts.batches {
        let mut sj = DMatrix::<f64>::zeros(d, d);
        let mut sw = DMatrix::<f64>::zeros(d, d);
        for _ in 0..per_batch {
            let tau = problem
                .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .map_err(|x| e(&x))?;
            for j in 0..d {
                let h = opts.relative_step * theta[j].abs().max(1.0);
                let (mut plus, mut minus) = (theta.clone(), theta.clone());
                plus[j] += h;
                minus[j] -= h;
                let scale = 1.0 / (plus[j] - minus[j]);
                let gp = problem.estimate(&plus, &tau, EstimatorForm::Causal, &mut cost);
                let gm = problem.estimate(&minus, &tau, EstimatorForm::Causal, &mut cost);
                add_column(
                    &mut sj,
                    j,
                    &gp.map_err(|x| e(&x))?,
                    &gm.map_err(|x| e(&x))?,
                    scale,
                );
                let wp = problem.weighted_estimate(&plus, theta, &tau, opts.weighting, &mut cost);
                let wm = problem.weighted_estimate(&minus, theta, &tau, opts.weighting, &mut cost);
                add_column(
                    &mut sw,
                    j,
                    &wp.map_err(|x| e(&x))?,
                    &wm.map_err(|x| e(&x))?,
                    scale,
                );
            }
        }
        batch_j.push(sj);
        batch_w.push(sw);
    }
    let mean_without = |batches: &[DMatrix<f64>], skip: Option<usize>| {
        let mut m = DMatrix::<f64>::zeros(d, d);
        let mut n = 0usize;
        for (b, x) in batches.iter().enumerate() {
            if Some(b) != skip {
                m += x;
                n += per_batch;
            }
        }
        m / n as f64
    };
    let mut full = [Vec::new(), Vec::new()];
    let mut deleted = [Vec::new(), Vec::new()];
    let mut share = (0.0, Vec::new());
    for skip in std::iter::once(None).chain((0..opts.batches).map(Some)) {
        let (mj, mw) = (mean_without(&batch_j, skip), mean_without(&batch_w, skip));
        if mj.iter().chain(mw.iter()).any(|x| !x.is_finite()) {
            return Err(e(&"a non-finite mean Jacobian"));
        }
        let s = (&mw - &mj).norm() / mw.norm();
        let (sj, sw) = (statistics(&mj, opts)?, statistics(&mw, opts)?);
        match skip {
            None => {
                full = [sj, sw];
                share.0 = s;
            }
            Some(_) => {
                deleted[0].push(sj);
                deleted[1].push(sw);
                share.1.push(vec![s]);
            }
        }
    }
    // The direction: the most negative eigenvalue of E[J]'s symmetric part (all N trajectories).
    let mj = mean_without(&batch_j, None);
    let eigen = ((&mj + mj.transpose()) * 0.5).symmetric_eigen();
    let k = eigen.eigenvalues.imin();
    let v = eigen.eigenvectors.column(k).into_owned();
    let h = opts.relative_step * theta.amax().max(1.0);
    let (plus, minus) = (theta + &v * h, theta - &v * h);
    // Per batch: Σ vᵀJv, Σ ‖Jv‖² for the unweighted, then the weighted term.
    let mut sums = Vec::with_capacity(opts.batches);
    for _ in 0..opts.batches {
        let mut acc = [0.0f64; 4];
        for _ in 0..per_batch {
            let tau = problem
                .rollout(&Behaviour::Learner(theta), &mut rng, &mut cost)
                .map_err(|x| e(&x))?;
            let gp = problem.estimate(&plus, &tau, EstimatorForm::Causal, &mut cost);
            let gm = problem.estimate(&minus, &tau, EstimatorForm::Causal, &mut cost);
            let jv = (gp.map_err(|x| e(&x))? - gm.map_err(|x| e(&x))?) / (2.0 * h);
            let wp = problem.weighted_estimate(&plus, theta, &tau, opts.weighting, &mut cost);
            let wm = problem.weighted_estimate(&minus, theta, &tau, opts.weighting, &mut cost);
            let wv = (wp.map_err(|x| e(&x))? - wm.map_err(|x| e(&x))?) / (2.0 * h);
            for (a, x) in
                acc.iter_mut()
                    .zip([v.dot(&jv), jv.norm_squared(), v.dot(&wv), wv.norm_squared()])
            {
                *a += x;
            }
        }
        sums.push(acc);
    }
    let directional = |skip: Option<usize>| -> Result<Vec<f64>, Error> {
        let (mut t, mut n) = ([0.0f64; 4], 0.0);
        for (b, x) in sums.iter().enumerate() {
            if Some(b) != skip {
                for (ti, xi) in t.iter_mut().zip(x) {
                    *ti += xi;
                }
                n += per_batch as f64;
            }
        }
        let mut out = Vec::new();
        for (m, sq) in [(t[0] / n, t[1] / n), (t[2] / n, t[3] / n)] {
            out.extend([m, sq]);
            for &a in &opts.momenta {
                // The quadratic s η² − 2 m η − q of the docs: its threshold is η₊ of an
                // eigenvalue with real part m and squared modulus s.
                let l = nalgebra::Complex::new(m, (sq - m * m).max(0.0).sqrt());
                out.push(
                    ilopt::algo::storm_stability::eigenvalue_threshold(l, a).map_err(|x| e(&x))?,
                );
            }
        }
        Ok(out)
    };
    let dfull = directional(None)?;
    let ddel = (0..opts.batches)
        .map(|b| directional(Some(b)))
        .collect::<Result<Vec<_>, _>>()?;
    let dstats = jackknife(&dfull, &ddel);
    let na = opts.momenta.len();
    let direction = |o: usize| Directional {
        rayleigh: dstats[o],
        mean_square: dstats[o + 1],
        thresholds: dstats[o + 2..o + 2 + na].to_vec(),
    };
    Ok(Measurement {
        dim: d,
        options: opts.clone(),
        unweighted: spectrum(jackknife(&full[0], &deleted[0]), opts),
        weighted: spectrum(jackknife(&full[1], &deleted[1]), opts),
        unweighted_direction: direction(0),
        weighted_direction: direction(2 + na),
        covariance_share: jackknife(&[share.0], &share.1)[0],
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// [`measure`] on a bench's problem.
///
/// # Errors
/// As [`measure`].
pub fn measure_bench(
    bench: &TaskLearner,
    theta: &DVector<f64>,
    opts: &Options,
) -> Result<Measurement, Error> {
    ilopt::with_task_learner!(bench, l => measure(&mut l.problem.clone(), theta, opts))
}

/// A task's bench as the profile sets it up (learner, expert, objective).
///
/// # Errors
/// As [`task_learner`].
pub fn bench_of(profile: &Profile, kind: TaskKind) -> Result<TaskLearner, Error> {
    let task = task_of(profile, kind);
    let horizon = task
        .horizon
        .unwrap_or_else(|| crate::config::default_horizon(kind));
    task_learner(kind, task, horizon)
}

fn task_of(profile: &Profile, kind: TaskKind) -> &TaskExperiment {
    match kind {
        TaskKind::Obstacle => &profile.obstacle,
        TaskKind::Cartpole => &profile.cartpole,
    }
}

/// A DAgger solution: the profile's first DAgger row (its configured hyper-parameters), run from
/// θ₁ = 0 on the bench's problem until the task's budget in gradient calls. Returns θ and the
/// number of DAgger iterations.
///
/// # Errors
/// [`Error::Experiment`] if the profile has no DAgger row or the run fails.
pub fn dagger_solution(
    profile: &Profile,
    kind: TaskKind,
    bench: &TaskLearner,
    seed: u64,
) -> Result<(DVector<f64>, u64), Error> {
    let task = task_of(profile, kind);
    let entry = task
        .algorithms
        .iter()
        .find(|a| matches!(a.config, AlgorithmConfig::Dagger(_)))
        .ok_or_else(|| Error::experiment(kind.name(), "the profile has no DAgger row"))?;
    ilopt::with_task_learner!(bench, l => train(&mut l.problem.clone(), &entry.config, task.budget, seed))
}

fn train<P: IlProblem<f64>>(
    problem: &mut P,
    config: &AlgorithmConfig,
    budget: u64,
    seed: u64,
) -> Result<(DVector<f64>, u64), Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("DAgger", x);
    let mut algorithm = config.build::<f64, P>().map_err(|x| e(&x))?;
    let rec = Runner::new(StoppingRule::gradient_budget(budget))
        .map_err(|x| e(&x))?
        .keep_history(false)
        .run(
            algorithm.as_mut(),
            problem,
            DVector::zeros(problem.dim()),
            seed,
        )
        .map_err(|x| e(&x))?;
    if let Some(d) = rec.termination.divergence() {
        return Err(e(d));
    }
    Ok((rec.theta, rec.iterations))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bad options are errors, not panics.
    #[test]
    fn bad_options_are_refused() {
        let bench =
            TaskLearner::obstacle(0.1, Default::default(), ilopt::task::Horizon::Episodic).unwrap();
        let theta = DVector::zeros(bench.dim());
        for opts in [
            Options {
                trajectories: 3,
                batches: 2,
                ..Options::default()
            },
            Options {
                batches: 1,
                trajectories: 4,
                ..Options::default()
            },
            Options {
                momenta: vec![1.0],
                ..Options::default()
            },
            Options {
                relative_step: 0.0,
                ..Options::default()
            },
        ] {
            assert!(measure_bench(&bench, &theta, &opts).is_err(), "{opts:?}");
        }
        let short = DVector::zeros(bench.dim() + 1);
        assert!(measure_bench(&bench, &short, &Options::default()).is_err());
    }

    /// On M1 (d = 1) the Monte-Carlo E[J] and E[J̃] agree with the exact engine's E[J] and ∇²F
    /// (rationals, duals; no finite differences) within five jackknife standard errors.
    #[test]
    fn the_estimates_agree_with_the_exact_engine_on_a_toy() {
        use ilopt::exact::storm_jacobian::{hessian, unweighted};
        use ilopt::scalar::{BigRational, Scalar};
        use ilopt::toy::{ToyMdp, ToyProblem};
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/toy/m1-tied.json");
        let mdp = ToyMdp::load(&path).unwrap();
        for x in [0i64, 2] {
            let exact = ToyProblem::<BigRational>::new(&mdp);
            let th = [BigRational::from_i64(x)];
            let j = unweighted(&exact, &th).unwrap().mean_jacobian[0][0].to_f64();
            let h = hessian(&exact, &th).unwrap()[0][0].to_f64();
            let opts = Options {
                trajectories: 4000,
                batches: 10,
                etas: vec![0.1],
                seed: 7 + x as u64,
                ..Options::default()
            };
            let m = measure(
                &mut ToyProblem::<f64>::new(&mdp),
                &DVector::from_element(1, x as f64),
                &opts,
            )
            .unwrap();
            for (name, got, want) in [
                ("E[J]", m.unweighted.min_re, j),
                ("E[J̃]", m.weighted.min_re, h),
            ] {
                assert!(
                    (got.value - want).abs() <= 5.0 * got.stderr + 1e-9,
                    "θ = {x}: {name} = {} ± {} vs exact {want}",
                    got.value,
                    got.stderr
                );
            }
        }
    }
}
