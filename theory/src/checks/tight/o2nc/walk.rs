//! Algorithm 5 (IL-correct, blocks of length T ≤ 2) walked over every path of the blocks' first
//! draws, each block's integral over s by a Riemann sum: enclosed in intervals (the rows), or by
//! the midpoint rule in `f64` (the search). See the parent module for why the walk is exact.

use super::setting::Setting;
use crate::checks::tight::paths::{Enclose, PathMean};
use crate::inputs::TableInputs;
use ilopt::algo::o2nc::O2ncParameters;
use ilopt::exact::enumerate::prefixes;
use ilopt::exact::forward::forward;
use ilopt::scalar::{Dual, Interval, Scalar, Sqrt};
use ilopt::toy::{ToyMdp, ToyProblem};

/// Cells of s ∈ [0, 1] in the certified Riemann enclosure of each block's integral.
pub const CELLS: usize = 64;
/// A scalar the walk integrates in: ∇F on a cell of s at its midpoint in `f64` (the midpoint
/// rule of the search), enclosed over the whole cell in intervals (a rigorous Riemann enclosure).
pub trait Quadrature: Enclose + Sqrt {
    /// What evaluates ∇F on the cells (built once per walk).
    type Engine;
    /// The engine for `mdp`.
    fn engine(mdp: &ToyMdp) -> Self::Engine;
    /// ∇F(θ) at one point.
    fn grad_at(engine: &Self::Engine, theta: &Self) -> Result<Self, String>;
    /// ∇F on each of the `cells` equal cells [s_j, s_{j+1}] of s ∈ [0, 1] along θ + sΔ.
    fn grads_on_cells(
        engine: &Self::Engine,
        theta: &Self,
        delta: &Self,
        cells: usize,
    ) -> Result<Vec<Self>, String>;
    /// |self|.
    fn magnitude(&self) -> Self;
    /// The projection onto [−d, d] (Algorithm 5's Π in one dimension).
    fn clamp_to(&self, d: &Self) -> Self;
}

/// ∇F(θ) (one parameter) in `S`.
pub(super) fn grad<S: Scalar>(problem: &ToyProblem<S>, theta: &S) -> Result<S, String> {
    Ok(forward(problem, std::slice::from_ref(theta))
        .map_err(|e| e.to_string())?
        .gradient[0]
        .clone())
}

impl Quadrature for f64 {
    type Engine = ToyProblem<f64>;
    fn engine(mdp: &ToyMdp) -> ToyProblem<f64> {
        ToyProblem::new(mdp)
    }
    fn grad_at(engine: &ToyProblem<f64>, theta: &f64) -> Result<f64, String> {
        grad(engine, theta)
    }
    /// At the cells' midpoints.
    fn grads_on_cells(
        engine: &ToyProblem<f64>,
        theta: &f64,
        delta: &f64,
        cells: usize,
    ) -> Result<Vec<f64>, String> {
        (0..cells)
            .map(|j| grad(engine, &(theta + (j as f64 + 0.5) / cells as f64 * delta)))
            .collect()
    }
    fn magnitude(&self) -> f64 {
        self.abs()
    }
    fn clamp_to(&self, d: &f64) -> f64 {
        self.clamp(-d, *d)
    }
}

impl Quadrature for Interval {
    type Engine = (ToyProblem<Interval>, ToyProblem<Dual<Interval>>);
    fn engine(mdp: &ToyMdp) -> Self::Engine {
        (ToyProblem::new(mdp), ToyProblem::new(mdp))
    }
    fn grad_at(engine: &Self::Engine, theta: &Interval) -> Result<Interval, String> {
        grad(&engine.0, theta)
    }
    /// The mean-value form on each cell, intersected with the direct enclosure:
    /// ∇F(θ + sΔ) ∈ ∇F(θ + m_jΔ) + F″(θ + [s_j, s_{j+1}]Δ)·([s_j, s_{j+1}] − m_j)Δ, m_j the cell's
    /// midpoint (F″ from the forward pass in `Dual<Interval>`). The direct enclosure alone widens
    /// with the forward pass's dependency on θ; the mean-value form's width falls with the cell.
    fn grads_on_cells(
        engine: &Self::Engine,
        theta: &Interval,
        delta: &Interval,
        cells: usize,
    ) -> Result<Vec<Interval>, String> {
        let n = cells as f64;
        (0..cells)
            .map(|j| {
                // The cell's ends and midpoint are multiples of 1/(2·cells), exact in `f64`.
                let (lo, hi, mid) = (j as f64 / n, (j + 1) as f64 / n, (j as f64 + 0.5) / n);
                let s = Interval::try_from((lo, hi)).map_err(|e| format!("{e:?}"))?;
                let w = *theta + s * *delta;
                let d = grad(&engine.1, &Dual::variable(w, 0, 1))?;
                let (direct, second) = d.into_parts(1);
                let at_mid = grad(
                    &engine.0,
                    &(*theta
                        + Interval::try_from((mid, mid)).map_err(|e| format!("{e:?}"))? * *delta),
                )?;
                let offset =
                    Interval::try_from((lo - mid, hi - mid)).map_err(|e| format!("{e:?}"))?;
                let mean_value = at_mid + second[0] * offset * *delta;
                Ok(mean_value.intersection(direct))
            })
            .collect()
    }
    fn magnitude(&self) -> Interval {
        self.abs()
    }
    /// Π is monotone in its argument and the radius, so the elementwise min and max enclose it.
    fn clamp_to(&self, d: &Interval) -> Interval {
        self.min(*d).max(-*d)
    }
}

/// (1/cells) Σ_j |∇F(θ) + ∇F(θ + s_j Δ)|/2 over the cells s_j of [0, 1]
/// ([`Quadrature::grads_on_cells`]): the block's ∫₀¹ |(∇F(w₁) + ∇F(w₂))/2| ds, enclosed
/// (intervals) or estimated (`f64`).
fn block_integral<S: Quadrature>(
    engine: &S::Engine,
    theta: &S,
    grad_theta: &S,
    delta: &S,
    cells: usize,
) -> Result<S, String> {
    let mut acc = S::zero();
    for g in S::grads_on_cells(engine, theta, delta, cells)? {
        acc += (g + grad_theta).magnitude();
    }
    Ok(acc / S::from_i64(2 * cells as i64))
}

/// Algorithm 5 (IL-correct, T ≤ 2) from θ₁ with the exact inputs `setting` (module docs): E X over
/// every path of the prefixes drawn at the blocks' first steps, each block's integral over s by
/// `block_integral` with `cells` cells, and the hull of every iterate θ (which holds every w).
///
/// # Errors
/// If T > 2, there are more than `max_paths` paths, or the engine fails at an iterate.
pub fn o2nc_mean<S: Quadrature>(
    mdp: &ToyMdp,
    theta1: &S,
    setting: &Setting,
    inputs: &TableInputs,
    max_paths: u64,
    cells: usize,
) -> Result<PathMean<S>, String> {
    let problem = ToyProblem::<S>::new(mdp);
    let engine = S::engine(mdp);
    let O2ncParameters { t, k, .. } = setting.params;
    let mut hull = vec![[f64::INFINITY, f64::NEG_INFINITY]];
    let widen = |hull: &mut Vec<[f64; 2]>, x: &S| {
        let [lo, hi] = x.enclosure();
        hull[0] = [hull[0][0].min(lo), hull[0][1].max(hi)];
    };
    widen(&mut hull, theta1);
    if t == 1 {
        // Δ_n = 0 at every step: every w_n = θ₁.
        return Ok(PathMean {
            mean: S::grad_at(&engine, theta1)?.magnitude(),
            hull,
            paths: 1,
        });
    }
    if t != 2 {
        return Err(format!("T = {t}: the walk is written for T ≤ 2"));
    }
    let branches = prefixes(&problem, std::slice::from_ref(theta1))
        .map_err(|e| e.to_string())?
        .len() as u64;
    let paths = u32::try_from(k)
        .ok()
        .and_then(|k| branches.checked_pow(k))
        .filter(|p| *p <= max_paths)
        .ok_or_else(|| format!("{branches}^{k} paths exceed the limit of {max_paths}"))?;
    let d = S::from_rational(&setting.params.d);
    let eta = d.clone() / (S::from_rational(&setting.g) * S::from_i64(2).sqrt());
    let mut total = S::zero();
    // Depth-first over paths: (blocks done, θ at the block's start, path probability, Σ of the
    // blocks' integrals so far).
    let mut stack = vec![(0u64, theta1.clone(), S::one(), S::zero())];
    while let Some((done, theta, prob, acc)) = stack.pop() {
        widen(&mut hull, &theta);
        if done == k {
            total += prob * acc;
            continue;
        }
        let grad_theta = S::grad_at(&engine, &theta)?;
        for pre in prefixes(&problem, std::slice::from_ref(&theta)).map_err(|e| e.to_string())? {
            let g = inputs.estimate(pre.estimate)[0].clone();
            let step = (S::zero() - eta.clone() * g).clamp_to(&d);
            let integral = block_integral::<S>(&engine, &theta, &grad_theta, &step, cells)?;
            let next = theta.clone() + step;
            stack.push((
                done + 1,
                next,
                prob.clone() * &pre.prob,
                acc.clone() + integral,
            ));
        }
    }
    Ok(PathMean {
        mean: total / S::from_i64(k as i64),
        hull,
        paths,
    })
}
