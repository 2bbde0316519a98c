//! The range checks of hyper-parameters given as [`ConfigNumber`]s.

use super::error::{AlgoError, invalid};
use crate::scalar::{BigRational, ConfigNumber};

/// Validate a hyper-parameter: exact value, `> 0` (`strict`) or `≥ 0`.
pub(crate) fn positive(
    n: &ConfigNumber,
    name: &'static str,
    strict: bool,
) -> Result<BigRational, AlgoError> {
    let q = n.exact(name)?;
    let zero = BigRational::from_integer(0.into());
    if q < zero || (strict && q == zero) {
        return Err(invalid(
            name,
            format!("must be {} 0, got {q}", if strict { ">" } else { "≥" }),
        ));
    }
    Ok(q)
}

/// Validate a hyper-parameter in `[lo, hi]` (`open_lo`/`open_hi` exclude the endpoints).
pub(crate) fn in_range(
    n: &ConfigNumber,
    name: &'static str,
    (lo, open_lo): (i64, bool),
    (hi, open_hi): (i64, bool),
) -> Result<BigRational, AlgoError> {
    let q = n.exact(name)?;
    let l = BigRational::from_integer(lo.into());
    let h = BigRational::from_integer(hi.into());
    let bad_lo = if open_lo { q <= l } else { q < l };
    let bad_hi = if open_hi { q >= h } else { q > h };
    if bad_lo || bad_hi {
        return Err(invalid(
            name,
            format!(
                "must lie in {}{lo}, {hi}{}, got {q}",
                if open_lo { "(" } else { "[" },
                if open_hi { ")" } else { "]" }
            ),
        ));
    }
    Ok(q)
}
