//! Interval branch-and-bound: a rigorous upper bound on `sup_{x ∈ box} f(x)` (math.md §7.1).
//!
//! `f` maps an interval box to an enclosure of f over it. Boxes are bisected along their widest
//! side, largest upper endpoint first, until the upper bound is within `tol` of the best lower
//! bound (f at box midpoints) or the box budget is spent. The result carries its **certificate**:
//! the final partition of the domain with each box's enclosure, so a reader can re-check it (every
//! box's enclosure is ≤ the bound, and the boxes cover the domain).

use crate::record::certificate::{CertifiedBox, SupBound};
use inari::Interval;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::tiling::verify_certificate;
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
}
