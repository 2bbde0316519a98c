//! [`ConfigNumber`]: the numbers of a configuration (a run's hyper-parameters, a baseline's
//! constants), exact or float, converted exactly into any scalar.

use super::{BigRational, Scalar, parse_exact};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A configuration number that is NaN or infinite, with the parameter's name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{name}` is not finite")]
pub struct NonFiniteNumber {
    /// The parameter, as named in the docs and in the configuration.
    pub name: &'static str,
}

/// A number of a run configuration (hyper-parameter, θ₀ entry, target loss), independent of the
/// scalar the run uses: either a float or an exact rational. Both are converted *exactly* ([`ConfigNumber::exact`]) and then to the run's scalar with
/// [`Scalar::from_rational`], so a float hyper-parameter is the same number in `f64`, in exact
/// rationals and in intervals (a singleton), and a rational one like `1/3` is exact in
/// rationals, enclosed in intervals and correctly rounded in `f64`.
///
/// In JSON it is a string holding the exact value (`"1/3"`, `"3602879701896397/36028797018963968"`
/// for `0.1f64`). On input, strings are parsed exactly (`"1/3"`, `"0.05"` = 1/20, `"1e-8"`) and
/// JSON numbers are read as `f64` (`0.05` is then the float nearest 1/20).
#[derive(Debug, Clone)]
pub enum ConfigNumber {
    /// A float; NaN and ±∞ are representable so that constructors can reject them by name.
    Float(f64),
    /// An exact rational.
    Exact(BigRational),
}

impl ConfigNumber {
    /// The exact rational `n/d`.
    ///
    /// # Panics
    /// If `d == 0` (a programming error: callers write constants).
    pub fn ratio(n: i64, d: i64) -> ConfigNumber {
        assert!(d != 0, "ConfigNumber::ratio: zero denominator");
        ConfigNumber::Exact(BigRational::new(n.into(), d.into()))
    }

    /// The exact value, or an error naming the parameter if it is NaN or infinite.
    ///
    /// # Errors
    /// [`NonFiniteNumber`] for a non-finite float.
    pub fn exact(&self, name: &'static str) -> Result<BigRational, NonFiniteNumber> {
        match self {
            ConfigNumber::Exact(q) => Ok(q.clone()),
            ConfigNumber::Float(x) => BigRational::from_float(*x).ok_or(NonFiniteNumber { name }),
        }
    }

    /// The value in the scalar `S` (see the type docs).
    ///
    /// # Errors
    /// As [`ConfigNumber::exact`].
    pub fn to<S: Scalar>(&self, name: &'static str) -> Result<S, NonFiniteNumber> {
        Ok(S::from_rational(&self.exact(name)?))
    }
}

impl From<f64> for ConfigNumber {
    fn from(x: f64) -> ConfigNumber {
        ConfigNumber::Float(x)
    }
}

impl From<BigRational> for ConfigNumber {
    fn from(q: BigRational) -> ConfigNumber {
        ConfigNumber::Exact(q)
    }
}

impl PartialEq for ConfigNumber {
    /// Equal exact values (a float equals the rational it represents); NaN equals nothing.
    fn eq(&self, other: &ConfigNumber) -> bool {
        match (self.exact("lhs"), other.exact("rhs")) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

impl Serialize for ConfigNumber {
    fn serialize<Se: Serializer>(&self, s: Se) -> Result<Se::Ok, Se::Error> {
        match self {
            ConfigNumber::Exact(q) => s.serialize_str(&q.to_string()),
            ConfigNumber::Float(x) => match BigRational::from_float(*x) {
                Some(q) => s.serialize_str(&q.to_string()),
                None if x.is_nan() => s.serialize_str("NaN"),
                None if *x > 0.0 => s.serialize_str("inf"),
                None => s.serialize_str("-inf"),
            },
        }
    }
}

impl<'de> Deserialize<'de> for ConfigNumber {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<ConfigNumber, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Text(String),
            ConfigNumberber(f64),
        }
        match Raw::deserialize(d)? {
            Raw::ConfigNumberber(x) => Ok(ConfigNumber::Float(x)),
            Raw::Text(t) => match t.trim() {
                "NaN" => Ok(ConfigNumber::Float(f64::NAN)),
                "inf" => Ok(ConfigNumber::Float(f64::INFINITY)),
                "-inf" => Ok(ConfigNumber::Float(f64::NEG_INFINITY)),
                other => parse_exact(other)
                    .map(ConfigNumber::Exact)
                    .map_err(serde::de::Error::custom),
            },
        }
    }
}
