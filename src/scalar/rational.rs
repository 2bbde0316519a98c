//! Exact rationals ([`BigRational`]) and the exact number syntax of the kit's files and CLI.
//!
//! Syntax (toy-MDP format, `--theta` lists): an optional sign, then either a fraction of integers
//! `p/q` (`q > 0`) or a decimal `12.5`, `.25`, `3.`, optionally with an exponent `1e-3`. Decimals
//! are read **exactly** (`0.1` is 1/10, never the float nearest to it).

use super::{BigRational, Scalar};
use num_bigint::BigInt;
use num_traits::{One, ToPrimitive, Zero};
use std::cmp::Ordering;

impl Scalar for BigRational {
    const NON_FINITE_PROPAGATES: bool = true;
    fn zero() -> Self {
        <BigRational as Zero>::zero()
    }
    fn one() -> Self {
        <BigRational as One>::one()
    }
    fn from_ratio(num: i64, den: i64) -> Self {
        assert!(den != 0, "from_ratio: zero denominator");
        BigRational::new(num.into(), den.into())
    }
    fn from_rational(q: &BigRational) -> Self {
        q.clone()
    }
    fn to_f64(&self) -> f64 {
        ToPrimitive::to_f64(self).unwrap_or(f64::NAN)
    }
    fn certain_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
    fn is_finite(&self) -> bool {
        true
    }
}

/// Largest decimal exponent accepted, so that `1e999999999` cannot exhaust memory and an exact
/// computation on the number stays within seconds.
pub const MAX_EXPONENT: i64 = 1000;
/// Most digits accepted in a mantissa, a numerator or a denominator (same reason).
pub const MAX_DIGITS: usize = 1000;

/// Why a string is not an exact number.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ParseExactError {
    /// Nothing to parse.
    #[error("empty number")]
    Empty,
    /// A character that has no place in an exact number.
    #[error(
        "`{0}` is not an exact number (expected an integer, a decimal like 0.25 or a fraction like -7/2)"
    )]
    Syntax(String),
    /// `p/0`.
    #[error("`{0}` has a zero denominator")]
    ZeroDenominator(String),
    /// The decimal exponent is beyond ±[`MAX_EXPONENT`].
    #[error("`{0}` has an exponent beyond ±{MAX_EXPONENT}")]
    ExponentTooLarge(String),
    /// More than [`MAX_DIGITS`] digits in a mantissa, numerator or denominator.
    #[error("`{number}` has {digits} digits, more than the {MAX_DIGITS} accepted")]
    TooManyDigits {
        /// The number as written (its first 40 characters and `…` when longer).
        number: String,
        /// Its significant digits.
        digits: usize,
    },
}

fn parse_uint(digits: &str) -> Option<BigInt> {
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    BigInt::parse_bytes(digits.as_bytes(), 10)
}

/// [`parse_uint`] with the [`MAX_DIGITS`] bound (leading zeros do not count); `whole` is the
/// number as written, for the error.
fn parse_bounded(digits: &str, whole: &str) -> Result<Option<BigInt>, ParseExactError> {
    let significant = digits.trim_start_matches('0').len();
    if significant > MAX_DIGITS {
        let mut number: String = whole.chars().take(40).collect();
        if whole.chars().count() > 40 {
            number.push('…');
        }
        return Err(ParseExactError::TooManyDigits {
            number,
            digits: significant,
        });
    }
    Ok(parse_uint(digits))
}

/// Parse one exact number (see the module docs for the syntax).
///
/// # Errors
/// [`ParseExactError`] naming the offending text.
pub fn parse_exact(text: &str) -> Result<BigRational, ParseExactError> {
    let s = text.trim();
    if s.is_empty() {
        return Err(ParseExactError::Empty);
    }
    let syntax = || ParseExactError::Syntax(s.to_string());
    let (negative, body) = match s.as_bytes()[0] {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    let value = if let Some((p, q)) = body.split_once('/') {
        let p = parse_bounded(p, s)?.ok_or_else(syntax)?;
        let q = parse_bounded(q, s)?.ok_or_else(syntax)?;
        if q.is_zero() {
            return Err(ParseExactError::ZeroDenominator(s.to_string()));
        }
        BigRational::new(p, q)
    } else {
        let (mantissa, exponent) = match body.find(['e', 'E']) {
            Some(i) => {
                let e = &body[i + 1..];
                let (eneg, edigits) = match e.as_bytes().first() {
                    Some(b'-') => (true, &e[1..]),
                    Some(b'+') => (false, &e[1..]),
                    _ => (false, e),
                };
                let mag = parse_uint(edigits).ok_or_else(syntax)?;
                let mag = mag
                    .to_i64()
                    .filter(|m| *m <= MAX_EXPONENT)
                    .ok_or_else(|| ParseExactError::ExponentTooLarge(s.to_string()))?;
                (&body[..i], if eneg { -mag } else { mag })
            }
            None => (body, 0),
        };
        let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
        if int.is_empty() && frac.is_empty() {
            return Err(syntax());
        }
        let digits = format!("{int}{frac}");
        let m = parse_bounded(&digits, s)?.ok_or_else(syntax)?;
        let scale = exponent - frac.len() as i64;
        let ten = BigInt::from(10u8);
        let pow = num_traits::pow(ten, scale.unsigned_abs() as usize);
        if scale >= 0 {
            BigRational::from_integer(m * pow)
        } else {
            BigRational::new(m, pow)
        }
    };
    Ok(if negative { -value } else { value })
}

/// Parse a comma-separated list of exact numbers (`"1/2,-3,0.25"`).
///
/// # Errors
/// The first entry that does not parse, with its 0-based index.
pub fn parse_exact_list(text: &str) -> Result<Vec<BigRational>, (usize, ParseExactError)> {
    text.split(',')
        .enumerate()
        .map(|(i, t)| parse_exact(t).map_err(|e| (i, e)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64, d: i64) -> BigRational {
        BigRational::from_ratio(n, d)
    }

    #[test]
    fn parses_the_documented_forms() {
        assert_eq!(parse_exact("1/3").unwrap(), q(1, 3));
        assert_eq!(parse_exact("-7/2").unwrap(), q(-7, 2));
        assert_eq!(parse_exact("0.25").unwrap(), q(1, 4));
        assert_eq!(parse_exact("0.1").unwrap(), q(1, 10));
        assert_eq!(parse_exact("-.5").unwrap(), q(-1, 2));
        assert_eq!(parse_exact("3.").unwrap(), q(3, 1));
        assert_eq!(parse_exact("+12").unwrap(), q(12, 1));
        assert_eq!(parse_exact("1e-3").unwrap(), q(1, 1000));
        assert_eq!(parse_exact("2.5E2").unwrap(), q(250, 1));
        assert_eq!(parse_exact("6/4").unwrap(), q(3, 2));
    }

    #[test]
    fn rejects_what_is_not_exact() {
        for bad in [
            "", " ", "abc", "1/", "/2", "1/-2", "--1", "1.2.3", "nan", "inf", "0x10", ".", "e5",
            "1e", "1/2/3",
        ] {
            assert!(parse_exact(bad).is_err(), "{bad:?} accepted");
        }
        assert_eq!(
            parse_exact("1/0"),
            Err(ParseExactError::ZeroDenominator("1/0".into()))
        );
        assert!(matches!(
            parse_exact("1e5000"),
            Err(ParseExactError::ExponentTooLarge(_))
        ));
        assert!(parse_exact("1e1000").is_ok() && parse_exact("1e-1000").is_ok());
        assert!(matches!(
            parse_exact("1e1001"),
            Err(ParseExactError::ExponentTooLarge(_))
        ));
        // Digits are bounded in every form; leading zeros are free.
        let many = "7".repeat(MAX_DIGITS + 1);
        for text in [
            many.clone(),
            format!("1/{many}"),
            format!("{many}/3"),
            format!("0.{many}"),
        ] {
            let e = parse_exact(&text).unwrap_err();
            assert_eq!(
                e,
                ParseExactError::TooManyDigits {
                    number: text.chars().take(40).collect::<String>() + "…",
                    digits: MAX_DIGITS + 1
                }
            );
            assert!(e.to_string().contains("1001 digits"), "{e}");
        }
        assert!(parse_exact(&format!("{}{}", "0".repeat(50), "7".repeat(MAX_DIGITS))).is_ok());
    }

    #[test]
    fn lists_name_the_bad_index() {
        assert_eq!(
            parse_exact_list("1/2,-3,0.25").unwrap(),
            vec![q(1, 2), q(-3, 1), q(1, 4)]
        );
        assert_eq!(parse_exact_list("1,x").unwrap_err().0, 1);
    }
}
