//! A **second route** to every rigorous constant: each box of a branch-and-bound certificate is
//! re-evaluated by code that shares nothing with the code that produced the enclosures (math.md
//! §7.1, "report every constant with its certificate").
//!
//! The first route ([`crate::certify::box_constants`], [`crate::certify::global`]) builds the engine's policy table and
//! runs the engine's prefix enumeration and estimator in nested dual numbers over intervals. This
//! module instead writes the tied softmax (P2'), its θ-derivatives, the prefix enumeration, the
//! Brier loss and the estimator (3.15) again from math.md §§1.1–1.4, by hand:
//!
//! * p = π(1|o) as a closed form in the chart coordinate x (core θ = x; tail θ = 1/u,
//!   `p = (1 + cu²)/((1 + cu²) + (u − 1)² + cu²)`), expanded as a truncated Taylor series in x to
//!   third order, from which dp/dθ, d²p/dθ², d³p/dθ³ follow (in the tail through d/dθ = −u² d/du:
//!   `p_θ = −u²p_u`, `p_θθ = u⁴p_uu + 2u³p_u`, `p_θθθ = −(u⁶p_uuu + 6u⁵p_uu + 6u⁴p_u)`);
//! * derivatives in θ by a second-order multivariate jet written here ([`Jet`]), not the kit's
//!   dual numbers;
//! * the Brier loss of two actions in closed form, `l(s) = 2q²`, `∇l = −4q∇π(a*|s)`, with
//!   q = 1 − π(a*(s)|s), and the estimator in the form `g = Σ_t [∇l_t + l_t Σ_{i<t} ψ_i]`
//!   (the engine accumulates the equivalent `Σ_i ψ_i Σ_{t>i} l_t` backwards).
//!
//! Each certificate box X (in chart coordinates) is then checked in two ways:
//!
//! 1. **Values at the corners.** The quantity is enclosed at every corner of X (the same code in
//!    [`Interval`] at a point: a rigorous enclosure a few ulps wide; the code also runs in
//!    [`ilopt::scalar::BigRational`], where the tests compare it exactly with math.md's reference
//!    values and the engine). A corner enclosure entirely outside the recorded enclosure is a certain error (so a
//!    recorded bound lowered below a value f takes at a corner is caught).
//! 2. **An upper bound of the box from the corners.** The same code run in `Dual<Interval>` over X
//!    encloses the gradient ∂h/∂x on X by `[d⁻, d⁺]`; for every x ∈ X and every corner c,
//!    `h(x) ≤ h(c) + Σ_i max over x_i of ∂_ih·(x_i − c_i)`, which is `d⁺_i w_i` when c_i is the
//!    lower end and `−d⁻_i w_i` when it is the upper end (positive parts). The minimum over the
//!    corners bounds sup_X h. If it does not prove the box's recorded bound, X is bisected (at most
//!    [`MAX_DEPTH`] times) and every piece must prove it.
//!
//! A box passes if its corner values can lie in its recorded enclosure, its recorded bound is
//! proved to within the certificate's own precision (upper bound minus attained value, capped at
//! 1 % of the certified bound, at least a relative 10⁻⁹) and the bound proved is ≤ the constant's
//! certified bound (no slack); the
//! certificate passes if every box passes and the boxes tile the domain exactly
//! ([`crate::certify::tiling::verify_tiling`]). A core-chart side with |θ| ≥ R is evaluated in the tail
//! coordinate u = 1/θ (same function, smooth there), which keeps wide far-out boxes cheap.

mod jet;
mod second_route;

pub use jet::Jet;
pub use second_route::{Quantity, p_theta_derivatives, pieces};

use crate::certify::tiling::verify_tiling;
use crate::record::certificate::{CORE_RADIUS, Chart, SupBound};
use ilopt::scalar::{Dual, Interval};
use ilopt::toy::ToyMdp;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// How often a box may be bisected when its corner bound does not prove the recorded bound.
pub const MAX_DEPTH: u32 = 12;

/// Relative slack on a box's own recorded bound (never on the constant's certified bound).
const BOX_SLACK: f64 = 1e-9;

/// The largest slack on a box's own recorded bound, as a share of the certified bound.
const BOX_SHARE: f64 = 0.01;

/// The outcome of re-checking one certificate.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Recheck {
    /// Certificate boxes re-checked.
    pub boxes: usize,
    /// Pieces the corner bound was evaluated on (boxes plus bisections).
    pub pieces: usize,
    /// Distinct corners enclosed.
    pub corners: usize,
    /// The largest upper bound the second route proved on a box, in the certificate's units
    /// (e.g. G_F², or 2L̃²).
    pub max_upper: f64,
    /// The same in the constant's own units (G_F, L̃, …), set by the constant's re-check, which
    /// compares it with the constant; `None` before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_in_constant_units: Option<f64>,
    /// Whether the boxes tile the domain exactly.
    pub tiling: bool,
    /// The first failures (at most five), empty if the certificate passed.
    pub failures: Vec<String>,
}

impl Recheck {
    /// Every box passed and the boxes tile the domain.
    pub fn passed(&self) -> bool {
        self.tiling && self.failures.is_empty()
    }
    fn fail(&mut self, msg: String) {
        if self.failures.len() < 5 {
            self.failures.push(msg);
        } else if self.failures.len() == 5 {
            self.failures.push("…".into());
        }
    }
    /// No certificate yet: the identity of [`Recheck::merge`].
    pub fn empty() -> Self {
        Self {
            max_upper: f64::NEG_INFINITY,
            tiling: true,
            ..Self::default()
        }
    }
    /// Merge another certificate's outcome (a constant with several chart regions).
    pub fn merge(&mut self, o: Recheck) {
        self.boxes += o.boxes;
        self.pieces += o.pieces;
        self.corners += o.corners;
        self.max_upper = self.max_upper.max(o.max_upper);
        self.tiling &= o.tiling;
        for f in o.failures {
            self.fail(f);
        }
    }
}

/// Corner enclosures, keyed by the corner's coordinates and the chart each is evaluated in.
type Corners = HashMap<Vec<(u64, bool)>, Result<Vec<Interval>, String>>;

fn point(x: f64) -> Interval {
    Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE)
}

struct BoxProver<'a> {
    mdp: &'a ToyMdp,
    q: Quantity,
    charts: &'a [Chart],
    groups: usize,
    cache: Corners,
}

/// One side of a piece in the coordinate it is evaluated in: the chart, the enclosure of the
/// coordinate's range, and the enclosures of its lower and upper ends (with the θ-value each
/// comes from, for the cache).
struct Side {
    chart: Chart,
    range: Interval,
    ends: [(Interval, f64); 2],
}

impl BoxProver<'_> {
    /// A core-chart side with |θ| ≥ R on all of it is evaluated in the tail coordinate u = 1/θ,
    /// where every quantity is smooth and small; the same function, so the same supremum. The
    /// end θ = a maps to u = 1/a, the upper end of the u-range on either side of 0.
    fn side(&self, i: usize, [l, h]: [f64; 2]) -> Side {
        let far = self.charts[i] == Chart::Core && (l >= CORE_RADIUS || h <= -CORE_RADIUS);
        if far {
            let one = point(1.0);
            let (lo, hi) = (one / point(h), one / point(l));
            Side {
                chart: Chart::Tail,
                range: lo.convex_hull(hi),
                ends: [(lo, h), (hi, l)],
            }
        } else {
            Side {
                chart: self.charts[i],
                range: Interval::try_from((l, h)).unwrap_or(Interval::ENTIRE),
                ends: [(point(l), l), (point(h), h)],
            }
        }
    }

    fn corner(&mut self, charts: &[Chart], x: &[(Interval, f64)]) -> Result<Vec<Interval>, String> {
        let key: Vec<(u64, bool)> = x
            .iter()
            .zip(charts)
            .map(|((_, t), c)| (t.to_bits(), *c == Chart::Tail))
            .collect();
        if let Some(v) = self.cache.get(&key) {
            return v.clone();
        }
        let xs: Vec<Interval> = x.iter().map(|(v, _)| *v).collect();
        let v = pieces(self.mdp, self.q, charts, &xs);
        self.cache.insert(key, v.clone());
        v
    }

    /// A rigorous upper bound of sup_X (the quantity) from the corners and the gradient
    /// enclosure, in the quantity's own units (|·|, the max, or √·), and the enclosures of the
    /// quantity at the corners.
    fn box_bound(&mut self, b: &[[f64; 2]]) -> Result<(f64, Vec<Interval>), String> {
        let n = b.len();
        let sides: Vec<Side> = b
            .iter()
            .enumerate()
            .map(|(i, s)| self.side(i, *s))
            .collect();
        let charts: Vec<Chart> = sides.iter().map(|s| s.chart).collect();
        let vars: Vec<Dual<Interval>> = sides
            .iter()
            .enumerate()
            .map(|(i, s)| Dual::variable(s.range, i, n))
            .collect();
        let mut corner_vals: Vec<Vec<Interval>> = vec![];
        let mut corner_sides: Vec<Vec<bool>> = vec![];
        for mask in 0..(1usize << n) {
            let upper: Vec<bool> = (0..n).map(|i| mask >> i & 1 == 1).collect();
            let x: Vec<(Interval, f64)> = (0..n)
                .map(|i| sides[i].ends[usize::from(upper[i])])
                .collect();
            corner_vals.push(self.corner(&charts, &x)?);
            corner_sides.push(upper);
        }
        // An enclosure that cannot be formed on X (a probability not certainly positive on a wide
        // box) bounds nothing: the gradient is unbounded and X is bisected.
        let grads: Vec<Vec<Interval>> = match pieces(self.mdp, self.q, &charts, &vars) {
            Ok(p) => p.into_iter().map(|p| p.gradient_padded(n)).collect(),
            Err(_) => vec![vec![Interval::ENTIRE; n]; corner_vals[0].len()],
        };
        let widths: Vec<Interval> = sides.iter().map(|s| s.ends[1].0 - s.ends[0].0).collect();
        let abs = self.q.is_abs(self.groups);
        let bound_piece = |k: usize, sign: f64| -> f64 {
            let mut best = f64::INFINITY;
            for (vals, upper) in corner_vals.iter().zip(&corner_sides) {
                let mut u = vals[k] * point(sign);
                for i in 0..n {
                    let d = grads[k][i] * point(sign);
                    // The slope towards the inside of X from this corner, and its positive part
                    // times the width: max of ∂_ih·(x_i − c_i) over the side.
                    let slope = if upper[i] { -d } else { d };
                    let pos = if slope.is_empty() || slope.sup().is_nan() {
                        Interval::ENTIRE
                    } else {
                        point(slope.sup().max(0.0))
                    };
                    u += pos * point(widths[i].sup());
                }
                best = best.min(if u.is_empty() { f64::INFINITY } else { u.sup() });
            }
            best
        };
        let mut sup = f64::NEG_INFINITY;
        for k in 0..grads.len() {
            sup = sup.max(bound_piece(k, 1.0));
            if abs {
                sup = sup.max(bound_piece(k, -1.0));
            }
        }
        if self.q.is_sqrt(self.groups) {
            sup = sup.max(0.0).sqrt().next_up();
        }
        // The quantity at each corner: |·| and the max over pieces, as enclosures.
        let at_corners: Vec<Interval> = corner_vals
            .iter()
            .map(|vals| {
                let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
                for v in vals {
                    let v = if abs { v.abs() } else { *v };
                    lo = lo.max(v.inf());
                    hi = hi.max(v.sup());
                }
                Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE)
            })
            .collect();
        Ok((sup, at_corners))
    }

    /// Prove sup over the box ≤ `target`, bisecting at most `depth` more times. Returns the
    /// largest bound proved and the number of pieces used, or the bound that failed. `known` is
    /// the box's own [`BoxProver::box_bound`] if the caller has already formed it (it is a
    /// function of the box alone, so it is not formed twice).
    fn prove(
        &mut self,
        b: &[[f64; 2]],
        target: f64,
        depth: u32,
        known: Option<f64>,
    ) -> Result<(f64, usize), String> {
        let sup = match known {
            Some(sup) => sup,
            None => self.box_bound(b)?.0,
        };
        if sup <= target {
            return Ok((sup, 1));
        }
        let (dim, _) = b
            .iter()
            .enumerate()
            .map(|(i, [l, h])| (i, h - l))
            .max_by(|a, c| a.1.total_cmp(&c.1))
            .expect("non-empty");
        let [l, h] = b[dim];
        let m = l + (h - l) / 2.0;
        if depth == 0 || !(l < m && m < h) {
            return Err(format!("the second route bounds it by {sup} only"));
        }
        let (mut best, mut count) = (f64::NEG_INFINITY, 1);
        for half in [[l, m], [m, h]] {
            let mut c = b.to_vec();
            c[dim] = half;
            let (s, k) = self.prove(&c, target, depth - 1, None)?;
            best = best.max(s);
            count += k;
        }
        Ok((best, count))
    }
}

/// Boxes per region the quick profile re-checks (besides those within 1 % of the bound).
pub const QUICK_SAMPLE: usize = 200;

/// The coverage of a profile: every box at full size, a seeded sample in the quick profile (the
/// L̃ certificates hold the most boxes, and re-checking all of them is the full profile's cost).
pub fn coverage_for(full: bool) -> Coverage {
    if full {
        Coverage::All
    } else {
        Coverage::Sample(QUICK_SAMPLE)
    }
}

/// Which boxes to re-check: all, or a seeded random sample of a given size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Coverage {
    /// Every box.
    All,
    /// This many boxes drawn without replacement (seeded), plus every box whose recorded bound is
    /// within 1 % of the certified bound (the ones the constant rests on).
    Sample(usize),
}

/// Re-check one certificate of `q` on `domain` in `charts` (module docs). `certified` is the
/// constant's bound in the certificate's units (≥ every box's recorded bound).
pub fn recheck(
    mdp: &ToyMdp,
    q: Quantity,
    charts: &[Chart],
    domain: &[[f64; 2]],
    cert: &SupBound,
    certified: f64,
    coverage: Coverage,
) -> Recheck {
    let boxes: Vec<&[[f64; 2]]> = cert
        .certificate
        .iter()
        .map(|b| b.bounds.as_slice())
        .collect();
    let mut out = Recheck::empty();
    if let Err(e) = verify_tiling(&boxes, domain) {
        out.tiling = false;
        out.fail(format!("{charts:?}: not a tiling: {e}"));
    }
    let groups = mdp.policy.group_count();
    let mut prover = BoxProver {
        mdp,
        q,
        charts,
        groups,
        cache: HashMap::new(),
    };
    let chosen: Vec<usize> = match coverage {
        Coverage::All => (0..boxes.len()).collect(),
        Coverage::Sample(n) => sample_indices(cert, certified, n),
    };
    let sqrt = q.is_sqrt(groups);
    for i in chosen {
        let b = &cert.certificate[i];
        out.boxes += 1;
        let [lo, hi] = b.enclosure;
        if hi.is_nan() || hi > certified {
            out.fail(format!(
                "box {:?}: recorded {hi} > certified {certified}",
                b.bounds
            ));
            continue;
        }
        // The quantity at every corner must lie in the recorded enclosure: a corner enclosure
        // entirely outside it is a certain violation. For a recorded √h compare squares.
        // (For ‖∇²F‖_F the first route records ‖mag H‖_F on both ends, an upper bound only, so
        // only the upper end is compared.)
        let (rl, rh) = if sqrt {
            (point(f64::MIN), point(hi).sqr())
        } else {
            (point(lo), point(hi))
        };
        let inside = |v: &Interval| !(v.inf() > rh.sup() || v.sup() < rl.inf());
        // The box's own bound, re-proved to within the certificate's stated precision (its
        // upper bound minus the value it attained) but at most 1 % of the certified bound, never
        // beyond the certified bound.
        let gap = if (cert.upper - cert.lower).is_nan() {
            0.0
        } else {
            (cert.upper - cert.lower).max(0.0)
        };
        let slack = gap
            .min(BOX_SHARE * certified.abs())
            .max(BOX_SLACK * hi.abs());
        let target = (hi + slack).min(certified);
        match prover.box_bound(&b.bounds) {
            Err(e) => out.fail(format!("box {:?}: {e}", b.bounds)),
            Ok((sup, exact)) => {
                if let Some(v) = exact.iter().find(|v| !inside(v)) {
                    out.fail(format!(
                        "box {:?}: the value at a corner, in [{}, {}], is outside the recorded [{lo}, {hi}]",
                        b.bounds,
                        v.inf(),
                        v.sup()
                    ));
                    continue;
                }
                match prover.prove(&b.bounds, target, MAX_DEPTH, Some(sup)) {
                    Ok((s, k)) => {
                        out.pieces += k;
                        out.max_upper = out.max_upper.max(s);
                    }
                    Err(e) => out.fail(format!(
                        "box {:?} of {charts:?}: recorded bound {hi} not proved: {e}",
                        b.bounds
                    )),
                }
            }
        }
    }
    out.corners = prover.cache.len();
    out
}

/// Indices of a seeded sample of `n` boxes plus every box within 1 % of the certified bound.
fn sample_indices(cert: &SupBound, certified: f64, n: usize) -> Vec<usize> {
    use rand::SeedableRng;
    use rand::seq::index::sample;
    let len = cert.certificate.len();
    let mut rng = rand::rngs::StdRng::seed_from_u64(0x5ec0_4d20);
    let mut idx: Vec<usize> = sample(&mut rng, len, n.min(len)).into_vec();
    let near = certified - 0.01 * certified.abs();
    idx.extend((0..len).filter(|&i| cert.certificate[i].enclosure[1] >= near));
    idx.sort_unstable();
    idx.dedup();
    idx
}
