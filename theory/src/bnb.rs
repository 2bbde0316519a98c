//! Interval branch-and-bound: a rigorous upper bound on `sup_{x ∈ box} f(x)` (math.md §7.1).
//!
//! `f` maps an interval box to an enclosure of f over it. Boxes are bisected along their widest
//! side, largest upper endpoint first, until the upper bound is within `tol` of the best lower
//! bound (f at box midpoints) or the box budget is spent. The result carries its **certificate**:
//! the final partition of the domain with each box's enclosure, so a reader can re-check it (every
//! box's enclosure is ≤ the bound, and the boxes cover the domain).

use inari::Interval;
use num_rational::BigRational;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// One box of the final partition and the enclosure of f on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CertifiedBox {
    /// [lo, hi] per dimension.
    pub bounds: Vec<[f64; 2]>,
    /// [inf, sup] of the enclosure of f on the box.
    pub enclosure: [f64; 2],
}

/// A rigorous upper bound with its certificate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SupBound {
    /// Upper bound on the supremum (max of the boxes' enclosure sups).
    pub upper: f64,
    /// A value f attains (certified lower end of an enclosure at a point): sup f ≥ lower.
    pub lower: f64,
    /// The partition of the domain with enclosures.
    pub certificate: Vec<CertifiedBox>,
}

/// Why branch-and-bound failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BnbError {
    /// `f` could not be evaluated on a box.
    #[error("evaluation failed on box {bounds:?}: {message}")]
    Evaluation {
        /// The box.
        bounds: Vec<[f64; 2]>,
        /// What went wrong.
        message: String,
    },
    /// The domain is empty or not finite.
    #[error("invalid domain {0:?}")]
    Domain(Vec<[f64; 2]>),
}

struct Node {
    sup: f64,
    inf: f64,
    bounds: Vec<[f64; 2]>,
}

impl PartialEq for Node {
    fn eq(&self, o: &Self) -> bool {
        self.sup.total_cmp(&o.sup) == Ordering::Equal
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Node {
    fn cmp(&self, o: &Self) -> Ordering {
        self.sup.total_cmp(&o.sup)
    }
}

fn to_intervals(b: &[[f64; 2]]) -> Vec<Interval> {
    b.iter()
        .map(|[lo, hi]| Interval::try_from((*lo, *hi)).expect("valid box"))
        .collect()
}

/// Rigorous `sup_{x ∈ domain} f(x)` (see the module docs).
///
/// # Errors
/// [`BnbError`] when the domain is invalid or `f` fails on a box.
pub fn sup_bound<E: std::fmt::Display>(
    f: impl Fn(&[Interval]) -> Result<Interval, E>,
    domain: &[[f64; 2]],
    tol: f64,
    max_boxes: usize,
) -> Result<SupBound, BnbError> {
    if domain.is_empty()
        || domain
            .iter()
            .any(|[l, h]| !(l.is_finite() && h.is_finite() && l <= h))
    {
        return Err(BnbError::Domain(domain.to_vec()));
    }
    let eval = |b: &[[f64; 2]]| -> Result<Interval, BnbError> {
        f(&to_intervals(b)).map_err(|e| BnbError::Evaluation {
            bounds: b.to_vec(),
            message: e.to_string(),
        })
    };
    let point_lower = |b: &[[f64; 2]]| -> Result<f64, BnbError> {
        let mid: Vec<[f64; 2]> = b
            .iter()
            .map(|[l, h]| {
                let m = l + (h - l) / 2.0;
                [m, m]
            })
            .collect();
        let v = eval(&mid)?;
        Ok(if v.is_empty() || v.inf().is_nan() {
            f64::NEG_INFINITY
        } else {
            v.inf()
        })
    };
    let node = |b: Vec<[f64; 2]>| -> Result<Node, BnbError> {
        let e = eval(&b)?;
        // An empty or NaN enclosure says nothing about f on the box: count it as unbounded, so
        // it is split further and, if it never resolves, the bound is +∞ (never silently dropped).
        let (inf, sup) = if e.is_empty() || e.inf().is_nan() || e.sup().is_nan() {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (e.inf(), e.sup())
        };
        Ok(Node {
            sup,
            inf,
            bounds: b,
        })
    };
    let mut heap = BinaryHeap::new();
    let mut lower = point_lower(domain)?;
    heap.push(node(domain.to_vec())?);
    while heap.len() < max_boxes {
        let top = heap.peek().expect("non-empty");
        if top.sup - lower <= tol {
            break;
        }
        let top = heap.pop().expect("non-empty");
        let (dim, _) = top
            .bounds
            .iter()
            .enumerate()
            .map(|(i, [l, h])| (i, h - l))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("non-empty box");
        let [l, h] = top.bounds[dim];
        let m = l + (h - l) / 2.0;
        if !(l < m && m < h) {
            // Cannot split further in floating point: keep the box as it is.
            heap.push(top);
            break;
        }
        for half in [[l, m], [m, h]] {
            let mut b = top.bounds.clone();
            b[dim] = half;
            lower = lower.max(point_lower(&b)?);
            heap.push(node(b)?);
        }
    }
    let certificate: Vec<CertifiedBox> = heap
        .into_sorted_vec()
        .into_iter()
        .rev()
        .map(|n| CertifiedBox {
            bounds: n.bounds,
            enclosure: [n.inf, n.sup],
        })
        .collect();
    // NaN never reaches here (mapped to +∞ above); the bound is the max over the boxes' sups.
    let upper = certificate
        .iter()
        .map(|b| b.enclosure[1])
        .fold(f64::NEG_INFINITY, f64::max);
    Ok(SupBound {
        upper,
        lower,
        certificate,
    })
}

/// Re-check a certificate: every box's enclosure is ≤ `upper` and the boxes tile `domain`
/// exactly ([`verify_tiling`]).
pub fn verify_certificate(c: &SupBound, domain: &[[f64; 2]]) -> bool {
    if c.certificate
        .iter()
        .any(|b| b.enclosure[1].is_nan() || b.enclosure[1] > c.upper)
    {
        return false;
    }
    let boxes: Vec<&[[f64; 2]]> = c.certificate.iter().map(|b| b.bounds.as_slice()).collect();
    verify_tiling(&boxes, domain).is_ok()
}

/// A box with exact rational endpoints, one `(lo, hi)` per dimension.
type QBox = Vec<(BigRational, BigRational)>;

fn to_rational_box(b: &[[f64; 2]]) -> Result<QBox, String> {
    b.iter()
        .map(
            |[l, h]| match (BigRational::from_float(*l), BigRational::from_float(*h)) {
                (Some(l), Some(h)) if l < h => Ok((l, h)),
                _ => Err(format!("box {b:?} is empty, degenerate or not finite")),
            },
        )
        .collect()
}

/// Exact tiling: the boxes cover `domain` and no two share an interior point, decided in rational
/// arithmetic on the endpoints (every `f64` is a rational; no tolerance).
///
/// In 1-D the boxes, sorted, must start at the domain's left end, each end exactly where the next
/// begins, and the last end at the right end. In d dimensions the distinct first-coordinate
/// endpoints, sorted, must run from the domain's first side to its last; each slab between two
/// consecutive ones is crossed by exactly the boxes whose first side contains it (a box never
/// straddles a slab, since all endpoints are slab ends), and those boxes' remaining sides must
/// tile the remaining (d − 1)-dimensional domain, recursively. A gap leaves a slab uncovered, an
/// overlap makes two boxes meet in a slab, and a box sticking out of the domain adds an endpoint
/// outside it: each is reported.
///
/// # Errors
/// A message naming the first defect.
pub fn verify_tiling(boxes: &[&[[f64; 2]]], domain: &[[f64; 2]]) -> Result<(), String> {
    let dom = to_rational_box(domain)?;
    let qs: Vec<QBox> = boxes
        .iter()
        .map(|b| {
            if b.len() == domain.len() {
                to_rational_box(b)
            } else {
                Err(format!("box {b:?} has the wrong dimension"))
            }
        })
        .collect::<Result<_, _>>()?;
    let refs: Vec<&[(BigRational, BigRational)]> = qs.iter().map(Vec::as_slice).collect();
    tiles(&refs, &dom)
}

fn tiles(
    boxes: &[&[(BigRational, BigRational)]],
    dom: &[(BigRational, BigRational)],
) -> Result<(), String> {
    let (lo, hi) = &dom[0];
    if dom.len() == 1 {
        let mut iv: Vec<&(BigRational, BigRational)> = boxes.iter().map(|b| &b[0]).collect();
        iv.sort_by(|a, b| a.0.cmp(&b.0));
        let mut reach = lo;
        for (l, h) in iv {
            if l != reach {
                return Err(if l > reach {
                    format!("gap [{reach}, {l}]")
                } else {
                    format!("overlap at [{l}, {reach}]")
                });
            }
            reach = h;
        }
        return if reach == hi {
            Ok(())
        } else {
            Err(format!("the boxes end at {reach}, not at {hi}"))
        };
    }
    let mut cuts: Vec<&BigRational> = boxes.iter().flat_map(|b| [&b[0].0, &b[0].1]).collect();
    cuts.sort();
    cuts.dedup();
    if cuts.first() != Some(&lo) || cuts.last() != Some(&hi) {
        return Err(format!(
            "first-coordinate endpoints span [{:?}, {:?}], not [{lo}, {hi}]",
            cuts.first().map(|x| x.to_string()),
            cuts.last().map(|x| x.to_string())
        ));
    }
    let mut order: Vec<&[(BigRational, BigRational)]> = boxes.to_vec();
    order.sort_by(|a, b| a[0].0.cmp(&b[0].0));
    let mut next = 0;
    let mut active: Vec<&[(BigRational, BigRational)]> = vec![];
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        active.retain(|x| x[0].1 > *a);
        while next < order.len() && order[next][0].0 == *a {
            active.push(order[next]);
            next += 1;
        }
        let slice: Vec<&[(BigRational, BigRational)]> = active.iter().map(|x| &x[1..]).collect();
        tiles(&slice, &dom[1..]).map_err(|e| format!("in the slab [{a}, {b}]: {e}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// sup of x(1 − x) on [0, 1] is 1/4.
    #[test]
    fn finds_a_known_supremum() {
        let one = Interval::try_from((1.0, 1.0)).unwrap();
        let f = |x: &[Interval]| Ok::<_, Infallible>(x[0] * (one - x[0]));
        let r = sup_bound(f, &[[0.0, 1.0]], 1e-6, 10_000).unwrap();
        assert!(r.upper >= 0.25 && r.upper <= 0.25 + 1e-5, "{}", r.upper);
        assert!(r.lower <= 0.25);
        assert!(verify_certificate(&r, &[[0.0, 1.0]]));
        // A tampered certificate (a box removed) no longer covers the domain.
        let mut bad = r.clone();
        bad.certificate.remove(bad.certificate.len() / 2);
        assert!(!verify_certificate(&bad, &[[0.0, 1.0]]) || bad.certificate.len() < 2);
    }

    /// A box whose enclosure is empty is never dropped: the bound becomes +∞ rather than
    /// ignoring it.
    #[test]
    fn empty_enclosures_make_the_bound_infinite() {
        let f = |x: &[Interval]| {
            let y = if x[0].sup() > 0.5 {
                Interval::EMPTY
            } else {
                x[0]
            };
            Ok::<_, Infallible>(y)
        };
        let r = sup_bound(f, &[[0.0, 1.0]], 1e-3, 64).unwrap();
        assert_eq!(r.upper, f64::INFINITY);
    }

    #[test]
    fn two_dimensional_boxes() {
        let f = |x: &[Interval]| Ok::<_, Infallible>(-(x[0] * x[0]) - x[1] * x[1]);
        let r = sup_bound(f, &[[-1.0, 2.0], [-3.0, 1.0]], 1e-4, 50_000).unwrap();
        assert!(r.upper >= 0.0 && r.upper <= 1e-3, "{}", r.upper);
        assert!(verify_certificate(&r, &[[-1.0, 2.0], [-3.0, 1.0]]));
    }

    /// A gap plus an overlap of the same area keeps the total volume but is not a tiling.
    #[test]
    fn tiling_is_exact_not_by_volume() {
        let d = [[0.0, 2.0], [0.0, 2.0]];
        let good: Vec<Vec<[f64; 2]>> = vec![
            vec![[0.0, 1.0], [0.0, 2.0]],
            vec![[1.0, 2.0], [0.0, 1.0]],
            vec![[1.0, 2.0], [1.0, 2.0]],
        ];
        let refs: Vec<&[[f64; 2]]> = good.iter().map(Vec::as_slice).collect();
        assert!(verify_tiling(&refs, &d).is_ok());
        // Move the top-right box down by 1/2: same volume, a gap above, an overlap below.
        let mut shifted = good.clone();
        shifted[2] = vec![[1.0, 2.0], [0.5, 1.5]];
        let refs: Vec<&[[f64; 2]]> = shifted.iter().map(Vec::as_slice).collect();
        assert!(verify_tiling(&refs, &d).is_err());
        // A box sticking out of the domain, a missing box, a duplicated box.
        let mut out = good.clone();
        out[0] = vec![[-1.0, 1.0], [0.0, 2.0]];
        let refs: Vec<&[[f64; 2]]> = out.iter().map(Vec::as_slice).collect();
        assert!(verify_tiling(&refs, &d).is_err());
        let refs: Vec<&[[f64; 2]]> = good[..2].iter().map(Vec::as_slice).collect();
        assert!(verify_tiling(&refs, &d).is_err());
        let mut dup = good.clone();
        dup.push(good[1].clone());
        let refs: Vec<&[[f64; 2]]> = dup.iter().map(Vec::as_slice).collect();
        assert!(verify_tiling(&refs, &d).is_err());
        // 1-D: endpoints one ulp apart are a gap.
        let a = [[0.0, 0.5]];
        let b = [[0.5f64.next_up(), 1.0]];
        assert!(verify_tiling(&[&a, &b], &[[0.0, 1.0]]).is_err());
    }
}
