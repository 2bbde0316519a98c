//! Checking a certificate's partition: the boxes tile the domain exactly (rational arithmetic on
//! the endpoints, no tolerance), and every box's enclosure is below the certified bound.

use crate::record::certificate::SupBound;
use num_rational::BigRational;

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
