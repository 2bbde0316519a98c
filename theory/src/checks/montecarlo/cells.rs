//! Rigorous enclosures of ∇F at the many iterates of the Monte-Carlo checks, by the mean-value
//! form on a fixed grid of cells.
//!
//! For a problem with d ≤ [`MAX_CELL_DIM`] parameters the parameter space is cut into cells
//! `C_k = Π_j [k_j·w, (k_j+1)·w]` of dyadic width `w` ([`CELL_WIDTH`] for one parameter,
//! [`CELL_WIDTH_2D`] for two), with centre `c_k`. For θ ∈ C_k the mean-value theorem, applied to
//! each partial derivative, gives `∂_iF(θ) = ∂_iF(c_k) + Σ_j ∂_j∂_iF(ξ_i)(θ_j − c_{k,j})` for
//! some ξ_i ∈ C_k, so
//!
//! `∂_iF(θ) ∈ ∂_iF([c_k, c_k]) + Σ_j H_ij(C_k) · ([θ_j, θ_j] − [c_{k,j}, c_{k,j}])`,
//!
//! with `∇F([c_k, c_k])` the forward DP (X2) in interval arithmetic at the centre and `H(C_k)` the
//! same DP in `Dual<Interval>` (one direction per parameter) over the whole cell, which also
//! encloses `∇F(C_k)`; the result is intersected with it. Both are computed once per cell and kept,
//! so an iterate costs d² interval multiply-adds instead of a forward pass. The enclosure is as
//! rigorous as the point one: every operation rounds outward. Its width is at most
//! `wid ∇F([c_k, c_k]) + Σ_j wid H_ij(C_k) · w/2`: about 10⁻⁵ on M1 (one parameter), and on the
//! second toy (two parameters, coarser cells, so that the cells its runs visit stay few) small
//! beside the statistics' resolution (the tests bound it). The values do not depend on which cells
//! were visited before, so results are the same in any order and on any number of threads.
//!
//! Problems with more than [`MAX_CELL_DIM`] parameters take the point enclosure (no cells).

use ilopt::exact::forward::forward;
use ilopt::scalar::{Dual, Interval, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use std::collections::HashMap;

/// The cell width for one parameter, w = 2⁻¹⁴: centres and ends are exact in f64 for |θ| < 2³⁸.
pub const CELL_WIDTH: f64 = 1.0 / 16384.0;

/// The cell width for two parameters, w = 2⁻¹⁰ (exact ends and centres as above). Coarser than
/// [`CELL_WIDTH`]: the cells a run visits grow with 1/w², and each costs a `Dual<Interval>` pass.
pub const CELL_WIDTH_2D: f64 = 1.0 / 1024.0;

/// The most parameters a problem may have to use cells.
pub const MAX_CELL_DIM: usize = 2;

/// Beyond this |θ_j| the point enclosure is used (the grid index would lose exactness long after;
/// iterates this far out are rare and need no cache).
const CELL_RANGE: f64 = 1e6;

/// A cell's precomputed parts (the first d entries of each array are used): centre c,
/// ∇F([c, c]), H(C) by rows and ∇F(C).
#[derive(Debug, Clone, Copy)]
struct Cell {
    centre: [f64; MAX_CELL_DIM],
    grad_centre: [Interval; MAX_CELL_DIM],
    hessian: [[Interval; MAX_CELL_DIM]; MAX_CELL_DIM],
    grad_cell: [Interval; MAX_CELL_DIM],
}

/// ∇F enclosures at points of one toy problem (module docs).
#[derive(Debug, Clone)]
pub struct GradientCells {
    point: ToyProblem<Interval>,
    jet: ToyProblem<Dual<Interval>>,
    dim: usize,
    cells: HashMap<[i64; MAX_CELL_DIM], Cell>,
}

fn point_interval(x: f64) -> Result<Interval, String> {
    Interval::try_from((x, x)).map_err(|e| format!("θ = {x}: {e:?}"))
}

/// The cell width for `dim` parameters (`dim` ≤ [`MAX_CELL_DIM`]).
fn width(dim: usize) -> f64 {
    if dim == 1 { CELL_WIDTH } else { CELL_WIDTH_2D }
}

impl GradientCells {
    /// For the problem `mdp` (no cells computed yet).
    pub fn new(mdp: &ToyMdp) -> Self {
        Self {
            point: ToyProblem::<Interval>::new(mdp),
            jet: ToyProblem::<Dual<Interval>>::new(mdp),
            dim: mdp.policy.dim(),
            cells: HashMap::new(),
        }
    }

    /// The point enclosure: X2 in intervals at θ (each coordinate exactly).
    ///
    /// # Errors
    /// If θ is not finite or the forward pass fails.
    pub fn at_point(&self, theta: &[f64]) -> Result<Vec<Interval>, String> {
        let th: Vec<Interval> = theta
            .iter()
            .map(|x| point_interval(*x))
            .collect::<Result<_, _>>()?;
        forward(&self.point, &th)
            .map(|f| f.gradient)
            .map_err(|e| e.to_string())
    }

    /// An enclosure of ∇F(θ): the mean-value form on θ's cell for up to [`MAX_CELL_DIM`]
    /// parameters, the point enclosure otherwise.
    ///
    /// # Errors
    /// If θ is not finite or a forward pass fails.
    pub fn enclose(&mut self, theta: &[f64]) -> Result<Vec<Interval>, String> {
        let d = self.dim;
        let near = theta.iter().all(|x| x.is_finite() && x.abs() < CELL_RANGE);
        if d > MAX_CELL_DIM || theta.len() != d || !near {
            return self.at_point(theta);
        }
        let w = width(d);
        let mut key = [0i64; MAX_CELL_DIM];
        for (k, x) in key.iter_mut().zip(theta) {
            *k = (x / w).floor() as i64;
        }
        let cell = match self.cells.get(&key) {
            Some(c) => *c,
            None => {
                let c = self.cell(key)?;
                self.cells.insert(key, c);
                c
            }
        };
        let mut offset = [Interval::EMPTY; MAX_CELL_DIM];
        for j in 0..d {
            offset[j] = point_interval(theta[j])? - point_interval(cell.centre[j])?;
        }
        (0..d)
            .map(|i| {
                let mut mean_value = cell.grad_centre[i];
                for j in 0..d {
                    mean_value += cell.hessian[i][j].product(&offset[j]);
                }
                let g = mean_value.intersection(cell.grad_cell[i]);
                if g.is_empty() {
                    return Err(format!(
                        "θ = {theta:?}: the cell's enclosures of ∂F/∂θ_{i} do not meet (an engine error)"
                    ));
                }
                Ok(g)
            })
            .collect()
    }

    /// The parts of the cell with grid index `key`.
    fn cell(&self, key: [i64; MAX_CELL_DIM]) -> Result<Cell, String> {
        let d = self.dim;
        let w = width(d);
        let mut centre = [0.0; MAX_CELL_DIM];
        let mut whole = Vec::with_capacity(d);
        for j in 0..d {
            let k = key[j];
            let (lo, hi) = (k as f64 * w, (k + 1) as f64 * w);
            centre[j] = (k as f64 + 0.5) * w;
            let x = Interval::try_from((lo, hi)).map_err(|e| format!("cell {key:?}: {e:?}"))?;
            whole.push(Dual::variable(x, j, d));
        }
        let at_centre = self.at_point(&centre[..d])?;
        let over_cell = forward(&self.jet, &whole)
            .map_err(|e| e.to_string())?
            .gradient;
        let mut cell = Cell {
            centre,
            grad_centre: [Interval::EMPTY; MAX_CELL_DIM],
            hessian: [[Interval::EMPTY; MAX_CELL_DIM]; MAX_CELL_DIM],
            grad_cell: [Interval::EMPTY; MAX_CELL_DIM],
        };
        for (i, g) in over_cell.iter().enumerate() {
            cell.grad_centre[i] = at_centre[i];
            cell.grad_cell[i] = *g.value();
            for (j, h) in g.gradient_padded(d).into_iter().enumerate() {
                cell.hessian[i][j] = h;
            }
        }
        Ok(cell)
    }

    /// How many cells have been computed.
    pub fn cells(&self) -> usize {
        self.cells.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ilopt::scalar::BigRational;

    fn exact_gradient(mdp: &ToyMdp, x: f64) -> BigRational {
        let p = ToyProblem::<BigRational>::new(mdp);
        let q = BigRational::from_float(x).expect("finite");
        forward(&p, &[q]).expect("evaluable").gradient[0].clone()
    }

    #[test]
    fn cell_enclosures_contain_the_exact_gradient_and_are_narrow() {
        let mdp = crate::protocol::m1_tied();
        let mut cells = GradientCells::new(&mdp);
        // Points spread over many cells, cell ends and centres included, and repeats.
        let mut xs: Vec<f64> = (0..400).map(|i| -3.0 + 0.0153 * i as f64).collect();
        xs.extend([
            0.0,
            CELL_WIDTH,
            0.5 * CELL_WIDTH,
            -CELL_WIDTH,
            1.0 - 1e-12,
            2.0,
        ]);
        xs.extend((0..50).map(|i| 0.25 + 1e-7 * i as f64));
        for x in xs {
            let g = cells.enclose(&[x]).expect("enclosure")[0];
            let exact = exact_gradient(&mdp, x);
            let lo = BigRational::from_float(g.inf()).expect("finite");
            let hi = BigRational::from_float(g.sup()).expect("finite");
            assert!(lo <= exact && exact <= hi, "θ = {x}: {g:?} misses F′");
            assert!(g.wid() < 1e-4, "θ = {x}: width {}", g.wid());
            let point = cells.at_point(&[x]).expect("point")[0];
            assert!((g.mid() - point.mid()).abs() < 1e-4);
        }
        assert!(cells.cells() < 460, "{} cells", cells.cells());
    }

    #[test]
    fn a_wrong_hessian_would_be_caught_by_the_exact_comparison() {
        // The same comparison with the second-order term dropped misses F′ at points away from
        // the centre: the test above can fail.
        let mdp = crate::protocol::m1_tied();
        let cells = GradientCells::new(&mdp);
        let x = 0.3 + 0.4 * CELL_WIDTH;
        let k = (x / CELL_WIDTH).floor() as i64;
        let cell = cells.cell([k, 0]).expect("cell");
        let exact = exact_gradient(&mdp, x);
        let lo = BigRational::from_float(cell.grad_centre[0].inf()).expect("finite");
        let hi = BigRational::from_float(cell.grad_centre[0].sup()).expect("finite");
        assert!(!(lo <= exact && exact <= hi));
    }

    fn exact_gradient_2d(mdp: &ToyMdp, x: [f64; 2]) -> Vec<BigRational> {
        let p = ToyProblem::<BigRational>::new(mdp);
        let q: Vec<BigRational> = x
            .iter()
            .map(|t| BigRational::from_float(*t).expect("finite"))
            .collect();
        forward(&p, &q).expect("evaluable").gradient
    }

    fn contains(g: &Interval, exact: &BigRational) -> bool {
        let lo = BigRational::from_float(g.inf()).expect("finite");
        let hi = BigRational::from_float(g.sup()).expect("finite");
        &lo <= exact && exact <= &hi
    }

    /// Points of the second toy's SGD region (|θ_i| ≤ 1.4, where its runs stay) and beyond:
    /// a lattice not aligned with the cells, cell corners, centres, edges, and repeats.
    fn points_2d() -> Vec<[f64; 2]> {
        let mut xs: Vec<[f64; 2]> = (0..30)
            .flat_map(|i| {
                (0..30).map(move |j| [-1.5 + 0.1037 * i as f64, -1.5 + 0.0991 * j as f64])
            })
            .collect();
        let w = CELL_WIDTH_2D;
        xs.extend([
            [0.0, 0.0],
            [w, w],
            [0.5 * w, 0.5 * w],
            [-w, 3.0 * w],
            [0.3, 0.7 - 1e-12],
            [5.0, -6.0],
        ]);
        xs.extend((0..20).map(|i| [0.25 + 1e-7 * i as f64, -0.4]));
        xs
    }

    #[test]
    fn two_parameter_cells_contain_the_exact_gradient_and_are_narrow() {
        let mdp = crate::checks::second_toy::m2_two_groups();
        let mut cells = GradientCells::new(&mdp);
        let xs = points_2d();
        let mut widest: f64 = 0.0;
        for x in &xs {
            let g = cells.enclose(x).expect("enclosure");
            let point = cells.at_point(x).expect("point");
            for (i, e) in exact_gradient_2d(&mdp, *x).iter().enumerate() {
                assert!(contains(&g[i], e), "θ = {x:?}: {:?} misses ∂F/∂θ_{i}", g[i]);
                // Both enclose the same number and are narrower than 2·10⁻⁴ (checked below for
                // the cells; the point enclosures are far narrower), so their midpoints differ by
                // less than that.
                assert!((g[i].mid() - point[i].mid()).abs() < 2e-4);
                widest = widest.max(g[i].wid());
            }
        }
        // Widths of about 10⁻⁴ or below move each run's statistic by far less than the
        // second toy's row resolves (its minimum detectable violation is about 2·10⁻⁴ of a
        // statistic near 0.06).
        assert!(widest < 2e-4, "widest enclosure {widest}");
        assert!(cells.cells() < xs.len(), "{} cells", cells.cells());
    }

    #[test]
    fn two_parameter_cells_without_the_cross_terms_would_be_caught() {
        // The same comparison with the Hessian's off-diagonal entries dropped misses ∇F at some
        // of the points: the test above can fail.
        let mdp = crate::checks::second_toy::m2_two_groups();
        let cells = GradientCells::new(&mdp);
        let w = CELL_WIDTH_2D;
        let mut missed = 0;
        for x in points_2d() {
            if x.iter().any(|t| t.abs() > 2.0) {
                continue;
            }
            let key = [(x[0] / w).floor() as i64, (x[1] / w).floor() as i64];
            let cell = cells.cell(key).expect("cell");
            let exact = exact_gradient_2d(&mdp, x);
            for i in 0..2 {
                let off = point_interval(x[i]).expect("finite")
                    - point_interval(cell.centre[i]).expect("finite");
                let diagonal_only = cell.grad_centre[i] + cell.hessian[i][i] * off;
                if !contains(&diagonal_only, &exact[i]) {
                    missed += 1;
                }
            }
        }
        assert!(missed > 0, "dropping the cross terms went unnoticed");
    }
}
