//! Route (b): the obstacle task (fixed horizon, absorbing ends) against an independent reference
//! of M trajectories, with its own variance.

use super::{GradientError, ObstacleRoute, RouteResult, draw, repetition_errors, summarise};
use crate::error::Error;
use crate::stats::derive_seed;
use ilopt::env::obstacle::ObstacleConfig;
use ilopt::expert::vo_policy::VoExpertParams;
use ilopt::policy::{LinearGaussian, SpeedLimitedGaussian};
use ilopt::problem::KitRng;
use ilopt::task::obstacle::{ObstacleFeatures, ObstacleTask};
use ilopt::task::{AfterEnd, TaskProblem};
use nalgebra::DVector;
use rand::SeedableRng;
use rayon::prelude::*;

/// The obstacle task's IL problem of route (b): linear-Gaussian learner (σ) over the 9 basic
/// features with the executed (speed-clipped) velocity's loss, fixed horizon, absorbing ends.
pub type ObstacleFixed = TaskProblem<ObstacleTask<[f64; 2]>, SpeedLimitedGaussian<f64, [f64; 2]>>;

/// Build route (b)'s problem.
///
/// # Errors
/// [`Error::Experiment`] if the task or policy cannot be built.
pub fn obstacle_problem(route: &ObstacleRoute) -> Result<ObstacleFixed, Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("Fig. 4.2 (obstacle)", x);
    let env = ObstacleConfig::default();
    let task = ObstacleTask::new(env.clone(), VoExpertParams::default())
        .and_then(|t| t.with_features(ObstacleFeatures::Basic))
        .map_err(|x| e(&x))?
        .with_actions::<[f64; 2]>();
    let inner = LinearGaussian::new(2, task.feature_dim(), route.sigma)
        .and_then(LinearGaussian::with_actions::<[f64; 2]>)
        .map_err(|x| e(&x))?;
    let policy = SpeedLimitedGaussian::new(inner, env.agent_max_speed).map_err(|x| e(&x))?;
    TaskProblem::fixed(task, policy, route.horizon, AfterEnd::Absorb).map_err(|x| e(&x))
}

/// Mean and per-component sum of squared deviations of `m` draws (Chan et al.'s merge of
/// chunks, in chunk order: the same numbers for any thread count).
#[derive(Debug, Clone)]
pub struct Moments {
    /// Draws.
    pub count: u64,
    /// Mean per component.
    pub mean: DVector<f64>,
    /// Σ (g_i − mean)² per component.
    pub m2: DVector<f64>,
}

impl Moments {
    fn merge(&mut self, o: &Moments) {
        if o.count == 0 {
            return;
        }
        let (na, nb) = (self.count as f64, o.count as f64);
        let n = na + nb;
        let delta = &o.mean - &self.mean;
        self.m2 += &o.m2 + delta.component_mul(&delta) * (na * nb / n);
        self.mean += delta * (nb / n);
        self.count += o.count;
    }

    /// Unbiased sample variance of one draw, summed over the components in `range`.
    pub fn variance(&self, range: std::ops::Range<usize>) -> f64 {
        self.m2.rows(range.start, range.len()).sum() / (self.count.saturating_sub(1)).max(1) as f64
    }
}

/// The moments of `m` draws, in chunks of `chunk` with seeds derived from `key` and the chunk
/// index, each chunk from its own sampler made by `sampler`.
///
/// # Errors
/// The first failing draw.
pub fn reference_moments<F, G>(
    m: u64,
    dim: usize,
    chunk: u64,
    key: &str,
    sampler: F,
) -> Result<Moments, Error>
where
    F: Fn() -> G + Sync,
    G: FnMut(&mut KitRng) -> Result<DVector<f64>, Error>,
{
    let parts = (0..m.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let n = chunk.min(m - chunk * c);
            let mut rng = KitRng::seed_from_u64(derive_seed(key, c));
            let mut sample = sampler();
            let draws = (0..n)
                .map(|_| sample(&mut rng))
                .collect::<Result<Vec<_>, Error>>()?;
            let mut mean = DVector::zeros(dim);
            for g in &draws {
                mean += g;
            }
            mean /= n as f64;
            let mut m2 = DVector::zeros(dim);
            for g in &draws {
                let d = g - &mean;
                m2 += d.component_mul(&d);
            }
            Ok(Moments { count: n, mean, m2 })
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let mut all = Moments {
        count: 0,
        mean: DVector::zeros(dim),
        m2: DVector::zeros(dim),
    };
    for p in &parts {
        all.merge(p);
    }
    Ok(all)
}

/// Route (b): the obstacle task against an M-trajectory reference.
///
/// # Errors
/// If the problem cannot be built or a draw fails.
pub fn obstacle_route(g: &GradientError) -> Result<RouteResult, Error> {
    let start = std::time::Instant::now();
    let o = &g.obstacle;
    let p = obstacle_problem(o)?;
    let theta = DVector::from_vec(o.theta.clone());
    let d = theta.len();
    let key = format!(
        "gradient-error|obstacle|{}|{}",
        serde_json::to_string(o).unwrap_or_default(),
        g.repetitions
    );
    let mom = reference_moments(
        o.reference_trajectories,
        d,
        1024,
        &format!("{key}|reference"),
        || {
            let (mut p, theta) = (p.clone(), &theta);
            move |rng: &mut KitRng| draw(&mut p, theta, rng, "Fig. 4.2")
        },
    )?;
    let reference: Vec<f64> = mom.mean.iter().copied().collect();
    let sigma2 = mom.variance(0..d);
    let reference_variance = sigma2 / o.reference_trajectories as f64;
    let h = d / 2;
    let sq = repetition_errors(
        &o.ns,
        g.repetitions,
        &key,
        &[(0, h), (h, h)],
        &reference,
        || {
            let (mut p, theta) = (p.clone(), &theta);
            move |rng: &mut KitRng| draw(&mut p, theta, rng, "Fig. 4.2")
        },
    )?;
    let (rmse, slope) = summarise(&o.ns, &sq, sigma2, reference_variance, g.bootstrap, &key);
    let block_slopes = [("x-row", 0..h), ("y-row", h..d)]
        .into_iter()
        .enumerate()
        .map(|(b, (name, range))| {
            let only: Vec<Vec<Vec<f64>>> = sq
                .iter()
                .map(|rep| rep.iter().map(|v| vec![v[b]]).collect())
                .collect();
            let s2 = mom.variance(range);
            let (_, slope) = summarise(
                &o.ns,
                &only,
                s2,
                s2 / o.reference_trajectories as f64,
                g.bootstrap,
                &format!("{key}|{name}"),
            );
            (name.to_string(), slope)
        })
        .collect();
    Ok(RouteResult {
        ns: o.ns.clone(),
        blocks: vec!["x-row".into(), "y-row".into()],
        squared_errors: sq,
        reference,
        sigma2,
        sigma2_exact: None,
        squared_error_sd_n1: None,
        reference_variance,
        reference_trajectories: Some(o.reference_trajectories),
        rmse,
        slope,
        block_slopes,
        seconds: start.elapsed().as_secs_f64(),
    })
}
