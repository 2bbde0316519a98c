//! Axes: the position of a value on a linear, log or log(1 + x) scale, the ticks and their labels.

use super::*;

/// A transformed point: (x, mean, band low, band high); a band low of `None` runs to the
/// bottom of the axis (a lower end ≤ 0 on a log axis).
pub type BandPoint = (f64, f64, Option<f64>, f64);

/// The position of value `v` on an axis of scale `scale`: `None` if it cannot be drawn
/// (non-finite, ≤ 0 on a log axis, < 0 on a log(1 + x) axis).
pub(super) fn tr(v: f64, scale: Scale) -> Option<f64> {
    if !v.is_finite() {
        return None;
    }
    match scale {
        Scale::Linear => Some(v),
        Scale::Log => (v > 0.0).then(|| v.log10()),
        Scale::Log1p => (v >= 0.0).then(|| v.ln_1p() / std::f64::consts::LN_10),
    }
}

/// The tick positions of a log(1 + x) axis spanning positions `x0..=x1`: the values 0 and the
/// whole decades 1, 10, 100, … within it, and when that gives fewer than three decades also 2×
/// and 5× each decade (so a short axis still has ticks).
pub(super) fn log1p_ticks(x0: f64, x1: f64) -> Vec<f64> {
    let decades: Vec<f64> = (0..16).map(|k| 10f64.powi(k)).collect();
    let within =
        |v: &f64| tr(*v, Scale::Log1p).is_some_and(|p| (x0 - 1e-12..=x1 + 1e-12).contains(&p));
    let mut values: Vec<f64> = decades.iter().copied().filter(within).collect();
    if values.len() < 3 {
        values = decades
            .iter()
            .flat_map(|d| [*d, 2.0 * d, 5.0 * d])
            .filter(within)
            .collect();
    }
    std::iter::once(0.0)
        .filter(within)
        .chain(values)
        .filter_map(|v| tr(v, Scale::Log1p))
        .collect()
}

/// A tick label on a log(1 + x) axis, `v` the position: the value 10^v − 1, a whole count as the
/// ticks of [`log1p_ticks`] are (rounded to remove the floating-point noise of the transform),
/// `1eK` from a million on.
pub(super) fn fmt_log1p_tick(v: f64) -> String {
    let x = (10f64.powf(v) - 1.0).max(0.0);
    if x < 1e6 {
        format!("{}", x.round())
    } else {
        format!("1e{}", x.log10().round())
    }
}

/// `v` rounded to two significant digits, printed without trailing noise.
pub(super) fn two_digits(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    let digits = (1 - e).max(0) as usize;
    let scale = 10f64.powi(e - 1);
    format!("{:.digits$}", (v / scale).round() * scale)
}

/// A tick label. On a log axis `v` is log10 of the value: whole decades print as 0.001, …, 1, 10, 100,
/// 1000, 10000 or 1eK, other ticks with two significant digits. On a linear axis a tick within
/// `1e-9 × span` of zero prints as `0` (not `-5.6e-17`).
pub fn fmt_tick(v: f64, log: bool, span: f64) -> String {
    if log {
        let x = 10f64.powf(v);
        if (v - v.round()).abs() < 1e-9 {
            let k = v.round() as i32;
            if (-3..=4).contains(&k) {
                let digits = (-k).max(0) as usize;
                format!("{:.digits$}", 10f64.powi(k))
            } else {
                format!("1e{k}")
            }
        } else if (0.01..1e5).contains(&x) {
            two_digits(x)
        } else {
            format!("{x:.1e}")
        }
    } else if v.abs() < 1e-9 * span.abs() || v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e5 || v.abs() < 1e-3 {
        format!("{v:.1e}")
    } else {
        format!("{}", (v * 1000.0).round() / 1000.0)
    }
}

/// How many key points to ask plotters for: on a log axis, whole decades when the range spans at
/// least three (at most ten labels), half decades otherwise.
pub(super) fn label_count(lo: f64, hi: f64, log: bool) -> usize {
    if !log {
        return 10;
    }
    let decades = (hi.floor() - lo.ceil()) as i64 + 1;
    if decades >= 3 {
        decades.min(10) as usize
    } else {
        (2 * decades.max(1) + 2) as usize
    }
}

/// The x coordinate of a chart: plotters' `f64` range, with the tick positions fixed when
/// `ticks` is given (plotters would tick round positions, not the whole values a log(1 + x) axis
/// needs); no light grid lines then.
pub(super) struct XCoord {
    pub(super) inner: RangedCoordf64,
    pub(super) ticks: Option<Vec<f64>>,
}

impl XCoord {
    /// The coordinate from `x0` to `x1` on an axis of scale `scale`.
    pub(super) fn new(x0: f64, x1: f64, scale: Scale) -> Self {
        XCoord {
            inner: (x0..x1).into(),
            ticks: (scale == Scale::Log1p).then(|| log1p_ticks(x0, x1)),
        }
    }
}

impl Ranged for XCoord {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        match &self.ticks {
            None => self.inner.key_points(hint),
            Some(_) if hint.weight().allow_light_points() => vec![],
            Some(ticks) => ticks.clone(),
        }
    }

    fn range(&self) -> Range<f64> {
        self.inner.range()
    }

    fn axis_pixel_range(&self, limit: (i32, i32)) -> Range<i32> {
        self.inner.axis_pixel_range(limit)
    }
}

/// A tick label for position `v` on an axis of scale `scale` spanning `span` positions.
pub(super) fn tick_label(v: f64, scale: Scale, span: f64) -> String {
    match scale {
        Scale::Linear => fmt_tick(v, false, span),
        Scale::Log => fmt_tick(v, true, span),
        Scale::Log1p => fmt_log1p_tick(v),
    }
}

pub(super) fn clamp_to(v: f64, range: Option<(f64, f64)>) -> f64 {
    match range {
        Some((a, b)) if v.is_finite() => v.max(a).min(b),
        _ => v,
    }
}
