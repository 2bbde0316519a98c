//! The finite-difference reference ∇F(θ) of check 6: central differences of Monte-Carlo F with
//! common random numbers at h and h/2, combined per seed by Richardson (see [`super`]).

use ilopt::problem::{Behaviour, Cost, IlProblem, KitRng};
use nalgebra::DVector;
use rand::SeedableRng;

use super::{mean_var, par_map};

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

fn loss_at<P: IlProblem<f64>>(p: &mut P, theta: &DVector<f64>, seed: u64) -> Result<f64, String> {
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
pub fn reference<P: IlProblem<f64> + Clone + Send + Sync>(
    p: &P,
    theta: &DVector<f64>,
    n_fd: usize,
    h: f64,
) -> Result<Reference, String> {
    let d = theta.len();
    let per_coord = par_map(p, d, |p, j| {
        let seed0 = REFERENCE_SEEDS + (j as u64) * 10_000_000;
        let mut rich = Vec::with_capacity(n_fd);
        let mut h2 = Vec::with_capacity(n_fd);
        for i in 0..n_fd {
            let s = seed0 + i as u64;
            let mut fd = |step: f64| -> Result<f64, String> {
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
