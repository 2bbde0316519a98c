//! How each scalar is written in the kit's JSON output.

use super::{BigRational, Dual, Interval, Scalar};
use serde_json::Value;

/// A scalar that can be reported in JSON without losing what it means:
/// `f64`/`f32` as JSON numbers (shortest round-trip form), rationals as exact fraction strings
/// (`"-13/24"`), intervals as `[lo, hi]` pairs of numbers.
///
/// Non-finite values are never written as numbers: a NaN or infinite float is the string
/// `"NaN"`/`"inf"`/`"-inf"`, and callers should treat them as errors before reporting.
pub trait JsonScalar: Scalar {
    /// The JSON value of `self`.
    fn to_json(&self) -> Value;
}

fn float_json(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or_else(
        || {
            Value::String(if x.is_nan() {
                "NaN".into()
            } else if x > 0.0 {
                "inf".into()
            } else {
                "-inf".into()
            })
        },
        Value::Number,
    )
}

impl JsonScalar for f64 {
    fn to_json(&self) -> Value {
        float_json(*self)
    }
}

impl JsonScalar for f32 {
    fn to_json(&self) -> Value {
        float_json(f64::from(*self))
    }
}

impl JsonScalar for BigRational {
    fn to_json(&self) -> Value {
        Value::String(self.to_string())
    }
}

impl JsonScalar for Interval {
    fn to_json(&self) -> Value {
        Value::Array(vec![float_json(self.inf()), float_json(self.sup())])
    }
}

impl<S: JsonScalar> JsonScalar for Dual<S> {
    fn to_json(&self) -> Value {
        serde_json::json!({
            "value": self.value().to_json(),
            "gradient": self.gradient().iter().map(JsonScalar::to_json).collect::<Vec<_>>(),
        })
    }
}
