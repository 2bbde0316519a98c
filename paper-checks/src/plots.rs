//! Figures: mean curves with shaded 95% confidence bands (plotters' SVG backend), optionally
//! rendered to PNG with resvg (system fonts through fontdb).

use crate::error::Error;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;
use std::path::Path;

/// One curve: x, mean and the band `[lo, hi]` (same lengths).
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// x values.
    pub x: Vec<f64>,
    /// Mean y values.
    pub mean: Vec<f64>,
    /// Lower band.
    pub lo: Vec<f64>,
    /// Upper band.
    pub hi: Vec<f64>,
    /// Draw as a dashed reference line without a band.
    pub reference: bool,
    /// Per-seed values left out of the means because they were not finite (diverged runs); the
    /// figure notes them.
    pub non_finite: usize,
    /// Checkpoints left out because they lie off the evaluation schedule (the last checkpoint of
    /// a run that stopped early); the figure notes them.
    pub off_schedule: usize,
}

impl Series {
    /// A series without points.
    pub fn new(label: impl Into<String>) -> Self {
        Series {
            label: label.into(),
            x: vec![],
            mean: vec![],
            lo: vec![],
            hi: vec![],
            reference: false,
            non_finite: 0,
            off_schedule: 0,
        }
    }
}

/// A figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// How the x axis places values.
    pub x_scale: Scale,
    /// log10 y axis.
    pub log_y: bool,
    /// The quantity's physical range `[min, max]` (either end may be infinite): means and bands
    /// are clamped to it before drawing (a t interval is symmetric and can leave it, e.g. a
    /// success rate's band below 0).
    pub y_range: Option<(f64, f64)>,
    /// The curves.
    pub series: Vec<Series>,
    /// `Some(columns)`: small multiples, one panel per drawn non-reference series in a grid of
    /// that many columns, every panel on the same axes and with the reference lines; `None`:
    /// every series on one plot.
    pub panels: Option<usize>,
}

/// How an axis places values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Position = value.
    Linear,
    /// Position = log10(value); values ≤ 0 are not drawn (and noted).
    Log,
    /// Position = log10(1 + value), for counts that start at 0: 0 sits at the origin and the
    /// large counts are compressed like on a log axis. Ticks at 0 and whole decades of the value
    /// (1, 10, 100, …), labelled with the value; values < 0 are not drawn (and noted).
    Log1p,
}

/// The Okabe–Ito palette (distinguishable under the common colour-vision deficiencies).
pub mod okabe_ito {
    use plotters::style::RGBColor;
    /// Orange.
    pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
    /// Sky blue.
    pub const SKY_BLUE: RGBColor = RGBColor(86, 180, 233);
    /// Bluish green.
    pub const BLUISH_GREEN: RGBColor = RGBColor(0, 158, 115);
    /// Yellow, darkened so that a line on white stays visible.
    pub const DARK_YELLOW: RGBColor = RGBColor(181, 165, 0);
    /// Blue.
    pub const BLUE: RGBColor = RGBColor(0, 114, 178);
    /// Vermillion.
    pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
    /// Reddish purple.
    pub const REDDISH_PURPLE: RGBColor = RGBColor(204, 121, 167);
    /// Black.
    pub const BLACK: RGBColor = RGBColor(0, 0, 0);
}

/// A point marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Circle.
    Circle,
    /// Square.
    Square,
    /// Upward triangle.
    Triangle,
    /// Downward triangle.
    TriangleDown,
    /// Diamond.
    Diamond,
    /// Plus sign.
    Plus,
    /// Diagonal cross.
    Cross,
    /// No marker (reference lines).
    None,
}

/// How a series is drawn, the same in every figure: a colour, a marker (filled or hollow) and a
/// line pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Line, marker and band colour.
    pub color: RGBColor,
    /// Marker at each point.
    pub marker: Marker,
    /// Filled marker (`false`: outline only).
    pub filled: bool,
    /// Dashed line (variants of an algorithm, reference lines).
    pub dashed: bool,
}

/// The style of a series, a function of its label alone, so an algorithm looks the same in every
/// figure whatever else the figure shows. Variants of an algorithm (DAgger (minibatch), the
/// episodic-objective control, the IS-STORM pair) share their family's colour and differ by
/// marker and a dashed line; reference policies and reference lines are grey and dashed, without
/// markers; a label not listed gets a colour and marker derived from a hash of its text.
pub fn style_for(label: &str) -> Style {
    use okabe_ito::*;
    let s = |color, marker, filled, dashed| Style {
        color,
        marker,
        filled,
        dashed,
    };
    let grey = |v: u8| s(RGBColor(v, v, v), Marker::None, false, true);
    match label {
        "BC" => s(BLACK, Marker::Circle, false, false),
        "DAgger" => s(ORANGE, Marker::Square, true, false),
        "DAgger (minibatch)" => s(ORANGE, Marker::Square, false, true),
        "SGD" => s(SKY_BLUE, Marker::TriangleDown, true, false),
        "Adam" => s(BLUE, Marker::Diamond, true, false),
        "Adam (episodic objective)" => s(BLUE, Marker::Diamond, false, true),
        "RMSProp" => s(BLUISH_GREEN, Marker::Triangle, true, false),
        "STORM" => s(VERMILLION, Marker::Circle, true, false),
        "IS-STORM (trajectory)" => s(REDDISH_PURPLE, Marker::Cross, true, false),
        "IS-STORM (per-decision)" => s(REDDISH_PURPLE, Marker::Plus, true, true),
        "SGD + baseline" => s(SKY_BLUE, Marker::TriangleDown, false, true),
        "STORM + baseline" => s(VERMILLION, Marker::Circle, false, true),
        "IS-STORM + baseline" => s(DARK_YELLOW, Marker::Square, false, true),
        // Fig. 4.2's estimates.
        "RMSE (95% CI)" | "vs reference (95% CI)" => s(BLUE, Marker::Circle, true, false),
        "− ref. variance (95% CI)" => s(VERMILLION, Marker::Square, true, false),
        l if l.starts_with("Expert") || l.starts_with("σ") => grey(0),
        l if l.starts_with("Straight to goal") || l.starts_with("reference SE") => grey(130),
        other => {
            const COLORS: [RGBColor; 7] = [
                ORANGE,
                SKY_BLUE,
                BLUISH_GREEN,
                DARK_YELLOW,
                BLUE,
                VERMILLION,
                REDDISH_PURPLE,
            ];
            const MARKERS: [Marker; 7] = [
                Marker::Circle,
                Marker::Square,
                Marker::Triangle,
                Marker::TriangleDown,
                Marker::Diamond,
                Marker::Plus,
                Marker::Cross,
            ];
            let h = crate::stats::fnv1a(other);
            s(
                COLORS[(h % 7) as usize],
                MARKERS[((h / 7) % 7) as usize],
                true,
                false,
            )
        }
    }
}

/// Canvas width in SVG pixels. The LaTeX appendix includes figures at the line width (345 pt in
/// a 10 pt article), 0.48 pt per pixel. Font sizes below are plotters sizes; the SVG's is
/// `size / 1.24`, so the smallest (19) is 15.3 px and prints at 7.35 pt.
const WIDTH: u32 = 720;
/// Height of the plot (axes and labels), in pixels.
const PLOT_HEIGHT: u32 = 440;
/// Font sizes (plotters sizes): tick labels, axis descriptions, legend, notes.
const TICK_FONT: u32 = 19;
const AXIS_FONT: u32 = 20;
const LEGEND_FONT: u32 = 19;
const NOTE_FONT: u32 = 19;
/// Legend row height in pixels.
const LEGEND_ROW: u32 = 27;
/// Small multiples: the panel titles' font size (plotters size: the SVG's is `size / 1.24`, so
/// 19 prints at 7.4 pt) and line height, the width of the style sample before a title, in pixels.
const TITLE_FONT: u32 = 19;
const TITLE_ROW: u32 = 22;
const TITLE_SAMPLE: i32 = 30;
/// Small multiples, in pixels: the strip for the rotated y description, the y tick labels'
/// width (left column), the x tick labels' height, the gap between columns, the right margin,
/// the top margin and the height of the x description under the grid.
const Y_DESC_WIDTH: u32 = 26;
const PANEL_Y_TICKS: u32 = 56;
const PANEL_X_TICKS: u32 = 30;
const PANEL_GAP: u32 = 28;
const PANEL_RIGHT: u32 = 22;
const PANEL_TOP: u32 = 6;
const X_DESC_HEIGHT: u32 = 30;

/// Draw `marker` centred at pixel `c` on `area` (pixel coordinates).
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    c: (i32, i32),
    st: &Style,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let r = 5;
    let stroke = ShapeStyle::from(&st.color).stroke_width(2);
    let fill = if st.filled {
        st.color.filled()
    } else {
        WHITE.filled()
    };
    let (x, y) = c;
    let polygon = |pts: Vec<(i32, i32)>| -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        area.draw(&Polygon::new(pts.clone(), fill))?;
        let mut outline = pts;
        outline.push(outline[0]);
        area.draw(&PathElement::new(outline, stroke))
    };
    match st.marker {
        Marker::None => Ok(()),
        Marker::Circle => {
            area.draw(&Circle::new(c, r, fill))?;
            area.draw(&Circle::new(c, r, stroke))
        }
        Marker::Square => polygon(vec![
            (x - r + 1, y - r + 1),
            (x + r - 1, y - r + 1),
            (x + r - 1, y + r - 1),
            (x - r + 1, y + r - 1),
        ]),
        Marker::Triangle => polygon(vec![(x, y - r - 1), (x + r, y + r - 1), (x - r, y + r - 1)]),
        Marker::TriangleDown => {
            polygon(vec![(x, y + r + 1), (x + r, y - r + 1), (x - r, y - r + 1)])
        }
        Marker::Diamond => polygon(vec![(x, y - r - 1), (x + r, y), (x, y + r + 1), (x - r, y)]),
        Marker::Plus => {
            area.draw(&PathElement::new(vec![(x - r, y), (x + r, y)], stroke))?;
            area.draw(&PathElement::new(vec![(x, y - r), (x, y + r)], stroke))
        }
        Marker::Cross => {
            area.draw(&PathElement::new(
                vec![(x - r, y - r), (x + r, y + r)],
                stroke,
            ))?;
            area.draw(&PathElement::new(
                vec![(x - r, y + r), (x + r, y - r)],
                stroke,
            ))
        }
    }
}

/// Split `text` into lines of at most `width` characters at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for w in text.split(' ') {
        if !cur.is_empty() && cur.chars().count() + 1 + w.chars().count() > width {
            lines.push(std::mem::take(&mut cur));
        }
        if !cur.is_empty() {
            cur.push(' ');
        }
        cur += w;
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// A transformed point: (x, mean, band low, band high); a band low of `None` runs to the
/// bottom of the axis (a lower end ≤ 0 on a log axis).
pub type BandPoint = (f64, f64, Option<f64>, f64);

/// The position of value `v` on an axis of scale `scale`: `None` if it cannot be drawn
/// (non-finite, ≤ 0 on a log axis, < 0 on a log(1 + x) axis).
fn tr(v: f64, scale: Scale) -> Option<f64> {
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
fn log1p_ticks(x0: f64, x1: f64) -> Vec<f64> {
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
fn fmt_log1p_tick(v: f64) -> String {
    let x = (10f64.powf(v) - 1.0).max(0.0);
    if x < 1e6 {
        format!("{}", x.round())
    } else {
        format!("1e{}", x.log10().round())
    }
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::experiment(format!("plotting {}", path.display()), e)
}

/// `v` rounded to two significant digits, printed without trailing noise.
fn two_digits(v: f64) -> String {
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
fn label_count(lo: f64, hi: f64, log: bool) -> usize {
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
struct XCoord {
    inner: RangedCoordf64,
    ticks: Option<Vec<f64>>,
}

impl XCoord {
    /// The coordinate from `x0` to `x1` on an axis of scale `scale`.
    fn new(x0: f64, x1: f64, scale: Scale) -> Self {
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
fn tick_label(v: f64, scale: Scale, span: f64) -> String {
    match scale {
        Scale::Linear => fmt_tick(v, false, span),
        Scale::Log => fmt_tick(v, true, span),
        Scale::Log1p => fmt_log1p_tick(v),
    }
}

fn clamp_to(v: f64, range: Option<(f64, f64)>) -> f64 {
    match range {
        Some((a, b)) if v.is_finite() => v.max(a).min(b),
        _ => v,
    }
}

impl Figure {
    /// The figure with its y values clamped to the physical range `[min, max]`.
    #[must_use]
    pub fn clamped(mut self, range: (f64, f64)) -> Self {
        self.y_range = Some(range);
        self
    }

    /// The figure as small multiples, `columns` panels to a row (see [`Figure::panels`]).
    #[must_use]
    pub fn in_panels(mut self, columns: usize) -> Self {
        self.panels = Some(columns);
        self
    }

    /// Write the figure as SVG (and `.png` next to it if `png`).
    ///
    /// # Errors
    /// [`Error::Experiment`] if drawing fails, [`Error::Io`] if writing fails.
    pub fn write(&self, svg_path: &Path, png: bool) -> Result<(), Error> {
        let svg = self.to_svg().map_err(|e| plot_err(svg_path, e))?;
        crate::storage::write_atomic(svg_path, svg.as_bytes())?;
        if png {
            let png_bytes = render_png(&svg).map_err(|e| plot_err(svg_path, e))?;
            crate::storage::write_atomic(&svg_path.with_extension("png"), &png_bytes)?;
        }
        Ok(())
    }

    /// The figure as SVG text.
    ///
    /// # Errors
    /// A message if plotters fails to draw.
    pub fn to_svg(&self) -> Result<String, String> {
        let mut svg = String::new();
        self.draw(&mut svg).map_err(|e| e.to_string())?;
        Ok(svg)
    }

    /// The y axis's scale.
    fn y_scale(&self) -> Scale {
        if self.log_y {
            Scale::Log
        } else {
            Scale::Linear
        }
    }

    /// The drawn points of each series after clamping to [`Figure::y_range`] and the axes'
    /// transforms (log10 on log axes, log10(1 + x) on a log(1 + x) axis), and the notes on what
    /// was left out: per series `(x, mean, band low, band high)` in axis units (a band low of
    /// `None` runs to the bottom of a log axis).
    pub fn points(&self) -> (Vec<Vec<BandPoint>>, Vec<String>) {
        let mut all = Vec::new();
        let (mut not_drawn, mut left_out, mut off) = (Vec::new(), Vec::new(), Vec::new());
        for s in &self.series {
            let mut v = Vec::new();
            let mut skipped = 0;
            for k in 0..s.x.len() {
                let m = clamp_to(s.mean[k], self.y_range);
                let (Some(x), Some(m)) = (tr(s.x[k], self.x_scale), tr(m, self.y_scale())) else {
                    skipped += 1;
                    continue;
                };
                let lo = clamp_to(s.lo.get(k).copied().unwrap_or(f64::NAN), self.y_range);
                let hi = clamp_to(s.hi.get(k).copied().unwrap_or(f64::NAN), self.y_range);
                let lo = if self.log_y && lo.is_finite() && lo <= 0.0 {
                    None
                } else {
                    Some(tr(lo, self.y_scale()).unwrap_or(m).min(m))
                };
                let hi = tr(hi, self.y_scale()).unwrap_or(m).max(m);
                v.push((x, m, lo, hi));
            }
            if skipped > 0 {
                not_drawn.push(format!("{} {skipped}", s.label));
            }
            if s.non_finite > 0 {
                left_out.push(format!("{} {}", s.label, s.non_finite));
            }
            if s.off_schedule > 0 {
                off.push(format!("{} {}", s.label, s.off_schedule));
            }
            all.push(v);
        }
        let mut notes = Vec::new();
        if !not_drawn.is_empty() {
            notes.push(format!(
                "points not drawn (non-finite{}): {}",
                match (self.x_scale, self.log_y) {
                    (Scale::Log, _) | (_, true) => ", or ≤ 0 on a log axis",
                    (Scale::Log1p, false) => ", or < 0 on a log(1 + x) axis",
                    (Scale::Linear, false) => "",
                },
                not_drawn.join(", ")
            ));
        }
        if !left_out.is_empty() {
            notes.push(format!(
                "non-finite per-seed values left out of the means and bands: {}",
                left_out.join(", ")
            ));
        }
        if !off.is_empty() {
            notes.push(format!(
                "off-schedule final checkpoints of runs that stopped early left out (later means are over the remaining seeds): {}",
                off.join(", ")
            ));
        }
        (all, notes)
    }

    fn draw(&self, out: &mut String) -> Result<(), Box<dyn std::error::Error + '_>> {
        match self.panels {
            Some(columns) => self.draw_panels(out, columns),
            None => self.draw_single(out),
        }
    }

    /// The styles of the series, and the indices of the series that have drawn points.
    fn styles_and_shown(&self, pts: &[Vec<BandPoint>]) -> (Vec<Style>, Vec<usize>) {
        let styles = self.series.iter().map(|s| style_for(&s.label)).collect();
        let shown = (0..self.series.len())
            .filter(|&i| !pts[i].is_empty())
            .collect();
        (styles, shown)
    }

    /// Every series on one plot, the legend under it in columns, then the notes.
    fn draw_single(&self, out: &mut String) -> Result<(), Box<dyn std::error::Error + '_>> {
        let (pts, notes) = self.points();
        let (x0, x1, y0, y1) = extent(&pts);
        let (styles, shown) = self.styles_and_shown(&pts);
        let entries: Vec<(&str, Style)> = shown
            .iter()
            .map(|&i| (self.series[i].label.as_str(), styles[i]))
            .collect();
        let legend = LegendLayout::of(&entries);
        let note_lines = note_lines(&notes);
        let note_height = notes_height(&note_lines);
        {
            let root =
                SVGBackend::with_string(out, (WIDTH, PLOT_HEIGHT + legend.height + note_height))
                    .into_drawing_area();
            root.fill(&WHITE)?;
            let (plot_area, rest) = root.split_vertically(PLOT_HEIGHT);
            let (legend_area, note_area) = rest.split_vertically(legend.height);
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(10)
                .margin_right(24)
                .x_label_area_size(58)
                .y_label_area_size(92)
                .build_cartesian_2d(XCoord::new(x0, x1, self.x_scale), y0..y1)?;
            let (sx_scale, ly) = (self.x_scale, self.log_y);
            let (sx, sy) = (x1 - x0, y1 - y0);
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .x_labels(label_count(x0, x1, sx_scale != Scale::Linear).min(8))
                .y_labels(label_count(y0, y1, ly))
                .x_label_formatter(&|v| tick_label(*v, sx_scale, sx))
                .y_label_formatter(&|v| fmt_tick(*v, ly, sy))
                .light_line_style(WHITE.mix(0.0))
                .bold_line_style(RGBColor(235, 235, 235))
                .label_style(("sans-serif", TICK_FONT))
                .axis_desc_style(("sans-serif", AXIS_FONT))
                .draw()?;
            // Bands first (light fill and thin edges), so no band covers another series' line.
            for (i, v) in pts.iter().enumerate() {
                if !self.series[i].reference {
                    draw_band(&mut chart, v, &styles[i], y0, 0.10)?;
                }
            }
            for (i, v) in pts.iter().enumerate() {
                draw_line(&mut chart, &root, v, &styles[i])?;
            }
            legend.draw(&root, legend_area.get_base_pixel(), &entries)?;
            draw_notes(&note_area, &note_lines)?;
            root.present()?;
        }
        Ok(())
    }

    /// Small multiples: one panel per drawn non-reference series, `columns` to a row, titled
    /// with the series' label and drawn in its style, every panel on the same axes with the
    /// reference lines; the axis descriptions once (left and below the grid), a legend for the
    /// reference lines only, then the notes.
    fn draw_panels(
        &self,
        out: &mut String,
        columns: usize,
    ) -> Result<(), Box<dyn std::error::Error + '_>> {
        let (pts, notes) = self.points();
        let (x0, x1, y0, y1) = extent(&pts);
        let (styles, shown) = self.styles_and_shown(&pts);
        let (refs, algos): (Vec<usize>, Vec<usize>) =
            shown.iter().partition(|&&i| self.series[i].reference);
        let grid = Grid::new(
            columns,
            &algos
                .iter()
                .map(|&i| self.series[i].label.as_str())
                .collect::<Vec<_>>(),
            text_width(&self.y_label, AXIS_FONT) as u32 + 12,
        );
        let ref_entries: Vec<(&str, Style)> = refs
            .iter()
            .map(|&i| (self.series[i].label.as_str(), styles[i]))
            .collect();
        let legend = if ref_entries.is_empty() {
            LegendLayout::none()
        } else {
            LegendLayout::of(&ref_entries)
        };
        let note_lines = note_lines(&notes);
        let below = grid.height() + X_DESC_HEIGHT;
        let height = below + legend.height + notes_height(&note_lines);
        {
            let root = SVGBackend::with_string(out, (WIDTH, height)).into_drawing_area();
            root.fill(&WHITE)?;
            let (sx_scale, ly) = (self.x_scale, self.log_y);
            let (sx, sy) = (x1 - x0, y1 - y0);
            let fx = |v: &f64| tick_label(*v, sx_scale, sx);
            let fy = |v: &f64| fmt_tick(*v, ly, sy);
            let blank = |_: &f64| String::new();
            for (k, &i) in algos.iter().enumerate() {
                let cell = grid.cell(k);
                let area = root.clone().shrink(cell.origin, cell.size);
                let mut chart = ChartBuilder::on(&area)
                    .x_label_area_size(PANEL_X_TICKS)
                    .y_label_area_size(if cell.column == 0 { PANEL_Y_TICKS } else { 0 })
                    .build_cartesian_2d(XCoord::new(x0, x1, self.x_scale), y0..y1)?;
                // Tick labels on the outer edges only: the panels share their axes.
                let bottom = k + grid.columns >= algos.len();
                chart
                    .configure_mesh()
                    .x_labels(
                        label_count(x0, x1, sx_scale != Scale::Linear)
                            .min(grid.plot_width as usize / 45),
                    )
                    .y_labels(label_count(y0, y1, ly).min(grid.plot_height as usize / 28))
                    .x_label_formatter(if bottom { &fx } else { &blank })
                    .y_label_formatter(&fy)
                    .light_line_style(WHITE.mix(0.0))
                    .bold_line_style(RGBColor(235, 235, 235))
                    .axis_style(RGBColor(90, 90, 90))
                    .label_style(("sans-serif", TICK_FONT))
                    .draw()?;
                draw_frame(&root, cell.plot)?;
                draw_band(&mut chart, &pts[i], &styles[i], y0, 0.16)?;
                for &j in &refs {
                    draw_line(&mut chart, &root, &pts[j], &styles[j])?;
                }
                draw_line(&mut chart, &root, &pts[i], &styles[i])?;
                draw_title(&root, &grid.titles[k], cell.title, &styles[i])?;
            }
            self.draw_axis_descriptions(&root, &grid)?;
            let (legend_area, note_area) = root
                .split_vertically(below)
                .1
                .split_vertically(legend.height);
            legend.draw(&root, legend_area.get_base_pixel(), &ref_entries)?;
            draw_notes(&note_area, &note_lines)?;
            root.present()?;
        }
        Ok(())
    }

    /// The y description rotated along the left edge of the grid, the x description centred
    /// under it.
    fn draw_axis_descriptions(&self, root: &Area<'_>, grid: &Grid) -> DrawResult {
        let font = ("sans-serif", AXIS_FONT).into_font();
        let (left, top) = grid.plots_origin();
        let (w, h) = grid.plots_size();
        let y_style = TextStyle::from(font.clone().transform(FontTransform::Rotate270))
            .pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(
            self.y_label.clone(),
            (4, top + h as i32 / 2),
            y_style,
        ))?;
        let x_style = TextStyle::from(font).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(
            self.x_label.clone(),
            (left + w as i32 / 2, grid.height() as i32 + 4),
            x_style,
        ))
    }
}

/// The SVG drawing surface, and a chart on part of it with `f64` axes (positions: log10 of the
/// value on log axes, log10(1 + value) on a log(1 + x) axis).
type Area<'b> = DrawingArea<SVGBackend<'b>, plotters::coord::Shift>;
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<XCoord, RangedCoordf64>>;
type DrawResult = Result<(), DrawingAreaErrorKind<std::io::Error>>;

/// The axes' extent `(x0, x1, y0, y1)` over every drawn point and band, the y range padded by 5%
/// (a unit range when nothing is drawn or the range is empty).
fn extent(pts: &[Vec<BandPoint>]) -> (f64, f64, f64, f64) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in pts.iter().flatten() {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.2.unwrap_or(p.1));
        y1 = y1.max(p.3);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if x1 - x0 < 1e-12 {
        x1 = x0 + 1.0;
    }
    if y1 - y0 < 1e-12 {
        y1 = y0 + 1.0;
    }
    let pad = 0.05 * (y1 - y0);
    (x0, x1, y0 - pad, y1 + pad)
}

/// A series' band: a light fill of opacity `fill` with thin edges; a band low of `None` runs
/// to `y0`, the bottom of the axis. Nothing for fewer than two points.
fn draw_band(
    chart: &mut Chart<'_, '_>,
    v: &[BandPoint],
    st: &Style,
    y0: f64,
    fill: f64,
) -> DrawResult {
    if v.len() < 2 {
        return Ok(());
    }
    let lo: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.2.unwrap_or(y0))).collect();
    let hi: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.3)).collect();
    let mut poly = lo.clone();
    poly.extend(hi.iter().rev());
    chart.draw_series(std::iter::once(Polygon::new(poly, st.color.mix(fill))))?;
    let edge = ShapeStyle::from(&st.color.mix(0.45)).stroke_width(1);
    chart.draw_series(LineSeries::new(lo, edge))?;
    chart.draw_series(LineSeries::new(hi, edge))?;
    Ok(())
}

/// A series' mean line (solid or dashed) with its markers, drawn on `root` at the chart's
/// pixel coordinates.
fn draw_line(
    chart: &mut Chart<'_, '_>,
    root: &Area<'_>,
    v: &[BandPoint],
    st: &Style,
) -> DrawResult {
    let style = ShapeStyle::from(&st.color).stroke_width(2);
    let line: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.1)).collect();
    if st.dashed {
        chart.draw_series(DashedLineSeries::new(line.clone(), 9, 5, style))?;
    } else {
        chart.draw_series(LineSeries::new(line.clone(), style))?;
    }
    for p in &line {
        draw_marker(root, chart.backend_coord(p), st)?;
    }
    Ok(())
}

/// A line-and-marker sample of `st`, `width` pixels long, starting at `(x, y)`.
fn draw_sample(root: &Area<'_>, (x, y): (i32, i32), width: i32, st: &Style) -> DrawResult {
    let style = ShapeStyle::from(&st.color).stroke_width(2);
    if st.dashed {
        // Two dashes around the marker (10 and 14 pixels with a 6-pixel gap at width 30).
        root.draw(&PathElement::new(vec![(x, y), (x + width / 3, y)], style))?;
        root.draw(&PathElement::new(
            vec![(x + width * 8 / 15, y), (x + width, y)],
            style,
        ))?;
    } else {
        root.draw(&PathElement::new(vec![(x, y), (x + width, y)], style))?;
    }
    draw_marker(root, (x + width / 2, y), st)
}

/// The legend's layout: entries in up to four columns as wide as the longest label needs.
struct LegendLayout {
    columns: u32,
    column_width: u32,
    height: u32,
}

impl LegendLayout {
    /// The layout for `entries` (label, style).
    fn of(entries: &[(&str, Style)]) -> Self {
        let longest = entries
            .iter()
            .map(|(l, _)| l.chars().count())
            .max()
            .unwrap_or(0) as u32;
        let column_width = 48 + longest * LEGEND_FONT * 55 / 100;
        let columns = ((WIDTH - 20) / column_width.max(1)).clamp(1, 4);
        let rows = (entries.len() as u32).div_ceil(columns);
        LegendLayout {
            columns,
            column_width,
            height: rows * LEGEND_ROW + 8,
        }
    }

    /// No legend.
    fn none() -> Self {
        LegendLayout {
            columns: 1,
            column_width: 0,
            height: 0,
        }
    }

    /// Draw `entries` row by row from `origin` (pixels on `root`).
    fn draw(&self, root: &Area<'_>, origin: (i32, i32), entries: &[(&str, Style)]) -> DrawResult {
        let font = ("sans-serif", LEGEND_FONT).into_font();
        for (k, (label, st)) in entries.iter().enumerate() {
            let (col, row) = (k as u32 % self.columns, k as u32 / self.columns);
            let x = origin.0 + 16 + (col * self.column_width) as i32;
            let y = origin.1 + 4 + (row * LEGEND_ROW + LEGEND_ROW / 2) as i32;
            draw_sample(root, (x, y), 30, st)?;
            root.draw(&Text::new(
                (*label).to_string(),
                (x + 38, y - (LEGEND_FONT as i32) / 2 - 1),
                font.clone(),
            ))?;
        }
        Ok(())
    }
}

/// The notes as wrapped lines, each note starting with "Note:".
fn note_lines(notes: &[String]) -> Vec<String> {
    let chars = ((WIDTH - 24) * 100 / (NOTE_FONT * 52)) as usize;
    notes
        .iter()
        .flat_map(|n| wrap(&format!("Note: {n}."), chars))
        .collect()
}

/// The height in pixels the note lines take.
fn notes_height(lines: &[String]) -> u32 {
    (NOTE_FONT + 5) * lines.len() as u32 + 6
}

/// The note lines, top left of `area`.
fn draw_notes(area: &Area<'_>, lines: &[String]) -> DrawResult {
    for (k, n) in lines.iter().enumerate() {
        area.draw(&Text::new(
            n.clone(),
            (12, 2 + (NOTE_FONT as i32 + 5) * k as i32),
            ("sans-serif", NOTE_FONT).into_font(),
        ))?;
    }
    Ok(())
}

/// A thin frame around a panel's plot rectangle `(x, y, width, height)` (pixels), so panels
/// without their own axes stay delimited.
fn draw_frame(root: &Area<'_>, (x, y, w, h): (i32, i32, i32, i32)) -> DrawResult {
    let style = ShapeStyle::from(&RGBColor(150, 150, 150)).stroke_width(1);
    root.draw(&PathElement::new(
        vec![(x, y), (x + w, y), (x + w, y + h), (x, y + h), (x, y)],
        style,
    ))
}

/// A panel's title: a sample of the series' style, then its label (one or more lines), from
/// `(x, y)` (pixels, top left).
fn draw_title(root: &Area<'_>, lines: &[String], (x, y): (i32, i32), st: &Style) -> DrawResult {
    let row = TITLE_ROW as i32;
    draw_sample(root, (x + 1, y + row / 2), TITLE_SAMPLE - 8, st)?;
    let style = TextStyle::from(("sans-serif", TITLE_FONT).into_font())
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (k, line) in lines.iter().enumerate() {
        root.draw(&Text::new(
            line.clone(),
            (x + TITLE_SAMPLE, y + row / 2 + row * k as i32),
            style.clone(),
        ))?;
    }
    Ok(())
}

/// The estimated width in pixels of `text` in the sans-serif font at plotters size `size`
/// (the SVG's font size is `size / 1.24`), from DejaVu Sans's approximate advance widths in em.
fn text_width(text: &str, size: u32) -> f64 {
    let em: f64 = text
        .chars()
        .map(|c| match c {
            'i' | 'j' | 'l' | 'I' | '.' | ',' | ':' | '\'' => 0.3,
            ' ' | '(' | ')' | '-' | 'f' | 't' | 'r' => 0.4,
            'm' | 'w' | 'M' | 'W' => 0.95,
            c if c.is_ascii_uppercase() => 0.72,
            _ => 0.62,
        })
        .sum();
    em * f64::from(size) / 1.24
}

/// `text` split at spaces into lines no wider than `width` pixels at `size` (a single word
/// wider than that stays whole).
fn wrap_to_width(text: &str, width: f64, size: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for w in text.split(' ') {
        match lines.last_mut() {
            Some(cur) if text_width(&format!("{cur} {w}"), size) <= width => {
                cur.push(' ');
                cur.push_str(w);
            }
            _ => lines.push(w.to_string()),
        }
    }
    lines
}

/// One panel's place in the grid, in pixels.
struct Cell {
    /// Column (0: the leftmost, which carries the y tick labels).
    column: usize,
    /// The chart area's top-left corner and size (plot plus its tick-label areas).
    origin: (u32, u32),
    size: (u32, u32),
    /// The plot rectangle `(x, y, width, height)`.
    plot: (i32, i32, i32, i32),
    /// The title's top-left corner.
    title: (i32, i32),
}

/// The small-multiples grid: equal plots, a title block above each row as tall as its longest
/// wrapped title, tick labels only on the left column and under the bottom panel of each column.
struct Grid {
    columns: usize,
    plot_width: u32,
    plot_height: u32,
    /// Each panel's title lines.
    titles: Vec<Vec<String>>,
    /// Each row's top edge, and the grid's bottom edge last.
    row_tops: Vec<u32>,
}

impl Grid {
    /// The grid for panels titled `labels`, `columns` to a row, its plots and titles spanning
    /// at least `min_height` pixels from top to bottom (room for the rotated y description).
    fn new(columns: usize, labels: &[&str], min_height: u32) -> Self {
        let columns = columns.clamp(1, labels.len().max(1));
        let gaps = PANEL_GAP * (columns as u32 - 1);
        let plot_width =
            (WIDTH - Y_DESC_WIDTH - PANEL_Y_TICKS - PANEL_RIGHT - gaps) / columns as u32;
        let title_width = f64::from(plot_width + PANEL_GAP) - f64::from(TITLE_SAMPLE as u32) - 4.0;
        let titles: Vec<Vec<String>> = labels
            .iter()
            .map(|l| wrap_to_width(l, title_width, TITLE_FONT))
            .collect();
        let title_heights: Vec<u32> = titles
            .chunks(columns)
            .map(|row| row.iter().map(Vec::len).max().unwrap_or(1) as u32 * TITLE_ROW + 4)
            .collect();
        let rows = title_heights.len().max(1) as u32;
        let fixed = title_heights.iter().sum::<u32>() + (rows - 1) * PANEL_X_TICKS;
        let plot_height = (plot_width * 3 / 5)
            .clamp(110, 260)
            .max(min_height.saturating_sub(fixed).div_ceil(rows));
        let mut row_tops = vec![PANEL_TOP];
        for h in title_heights {
            let last = *row_tops.last().unwrap_or(&0);
            row_tops.push(last + h + plot_height + PANEL_X_TICKS);
        }
        Grid {
            columns,
            plot_width,
            plot_height,
            titles,
            row_tops,
        }
    }

    /// The grid's height in pixels (to the bottom of the last row's tick labels).
    fn height(&self) -> u32 {
        *self.row_tops.last().unwrap_or(&PANEL_TOP)
    }

    /// The top-left corner of the leftmost plots (pixels).
    fn plots_origin(&self) -> (i32, i32) {
        ((Y_DESC_WIDTH + PANEL_Y_TICKS) as i32, PANEL_TOP as i32)
    }

    /// The width and height spanned by the plots and the rows' titles (pixels).
    fn plots_size(&self) -> (u32, u32) {
        let n = self.columns as u32;
        (
            n * self.plot_width + (n - 1) * PANEL_GAP,
            self.height().saturating_sub(PANEL_TOP + PANEL_X_TICKS),
        )
    }

    /// The place of panel `k`.
    fn cell(&self, k: usize) -> Cell {
        let (column, row) = (k % self.columns, k / self.columns);
        let left = Y_DESC_WIDTH + PANEL_Y_TICKS + column as u32 * (self.plot_width + PANEL_GAP);
        let lines = self.titles[row * self.columns..]
            .iter()
            .take(self.columns)
            .map(Vec::len)
            .max()
            .unwrap_or(1) as u32;
        let title_top = self.row_tops[row];
        let top = title_top + lines * TITLE_ROW + 4;
        let ticks = if column == 0 { PANEL_Y_TICKS } else { 0 };
        Cell {
            column,
            origin: (left - ticks, top),
            size: (self.plot_width + ticks, self.plot_height + PANEL_X_TICKS),
            plot: (
                left as i32,
                top as i32,
                self.plot_width as i32,
                self.plot_height as i32,
            ),
            title: (left as i32, title_top as i32),
        }
    }
}

/// Render SVG text to PNG bytes with resvg (fonts: the system's, via fontdb).
///
/// # Errors
/// A message if parsing, rendering or encoding fails.
pub fn render_png(svg: &str) -> Result<Vec<u8>, String> {
    use resvg::{tiny_skia, usvg};
    let mut opt = usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_system_fonts();
    // plotters writes `font-family="sans-serif"`; map it to a font that exists.
    let family = [
        "DejaVu Sans",
        "Liberation Sans",
        "Arial",
        "Helvetica",
        "Noto Sans",
    ]
    .into_iter()
    .find(|f| {
        db.faces()
            .any(|face| face.families.iter().any(|(n, _)| n == f))
    });
    match family {
        Some(f) => db.set_sans_serif_family(f),
        None => {
            let first = db
                .faces()
                .next()
                .and_then(|face| face.families.first().map(|(n, _)| n.clone()));
            match first {
                Some(name) => db.set_sans_serif_family(name),
                None => return Err("no system font found for the PNG text".into()),
            }
        }
    }
    let tree = usvg::Tree::from_str(svg, &opt).map_err(|e| e.to_string())?;
    let size = tree.size().to_int_size();
    let scale = 2.0;
    let mut pixmap = tiny_skia::Pixmap::new(
        (size.width() as f32 * scale) as u32,
        (size.height() as f32 * scale) as u32,
    )
    .ok_or("empty image")?;
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log1p_keeps_zero_at_the_origin_and_puts_decades_near_integers() {
        assert_eq!(tr(0.0, Scale::Log1p), Some(0.0));
        assert_eq!(tr(-1.0, Scale::Log1p), None);
        assert_eq!(tr(f64::NAN, Scale::Log1p), None);
        for k in 0..7 {
            let d = 10f64.powi(k);
            // 1 + (10^k − 1) is a whole decade: exactly k.
            let p = tr(d - 1.0, Scale::Log1p).expect("drawn");
            assert!((p - f64::from(k)).abs() < 1e-12, "{k}: {p}");
            // The value 10^k itself sits log10(1 + 10^-k) above k, rounding to k.
            let p = tr(d, Scale::Log1p).expect("drawn");
            assert!((p - (f64::from(k) + (1.0 + 1.0 / d).log10())).abs() < 1e-12);
            assert_eq!(p.round(), f64::from(k));
        }
        // The other scales are unchanged.
        assert_eq!(tr(0.0, Scale::Log), None);
        assert_eq!(tr(100.0, Scale::Log), Some(2.0));
        assert_eq!(tr(-3.0, Scale::Linear), Some(-3.0));
    }

    #[test]
    fn log1p_ticks_are_zero_and_whole_decades_labelled_with_the_value() {
        let end = tr(5700.0, Scale::Log1p).expect("drawn");
        let ticks = log1p_ticks(0.0, end);
        assert_eq!(ticks[0], 0.0, "0 at the origin");
        let labels: Vec<String> = ticks.iter().map(|v| fmt_log1p_tick(*v)).collect();
        assert_eq!(labels, ["0", "1", "10", "100", "1000"]);
        assert_eq!(tick_label(ticks[3], Scale::Log1p, end), "100");
        // A short axis also ticks 2× and 5× each decade.
        let short = log1p_ticks(0.0, tr(60.0, Scale::Log1p).expect("drawn"));
        let labels: Vec<String> = short.iter().map(|v| fmt_log1p_tick(*v)).collect();
        assert_eq!(labels, ["0", "1", "2", "5", "10", "20", "50"]);
        // An axis that starts after 0 has no tick at 0.
        let from_ten = log1p_ticks(tr(10.0, Scale::Log1p).expect("drawn"), end);
        assert_eq!(fmt_log1p_tick(from_ten[0]), "10");
        assert_eq!(fmt_log1p_tick(tr(2e7, Scale::Log1p).expect("drawn")), "1e7");
    }

    fn counts_figure(x: Vec<f64>) -> Figure {
        let mut s = Series::new("BC");
        s.mean = x.iter().map(|_| 0.5).collect();
        s.lo = x.iter().map(|_| 0.4).collect();
        s.hi = x.iter().map(|_| 0.6).collect();
        s.x = x;
        Figure {
            title: "t".into(),
            x_label: "trajectories (log scale of 1 + count)".into(),
            y_label: "y".into(),
            x_scale: Scale::Log1p,
            log_y: false,
            y_range: None,
            series: vec![s],
            panels: None,
        }
    }

    #[test]
    fn a_log1p_axis_draws_the_points_at_zero() {
        let fig = counts_figure(vec![0.0, 9.0, 99.0, 5700.0]);
        let (pts, notes) = fig.points();
        assert_eq!(pts[0].len(), 4, "every point drawn");
        assert_eq!(pts[0][0].0, 0.0);
        assert!((pts[0][2].0 - 2.0).abs() < 1e-12);
        assert!(notes.is_empty(), "{notes:?}");
        for f in [fig.clone(), fig.in_panels(3)] {
            let svg = f.to_svg().expect("draws");
            assert!(!svg.contains("not drawn"), "a point left out");
            for label in ["0", "1", "10", "100", "1000"] {
                assert!(svg.contains(&format!("\n{label}\n")), "no tick {label}");
            }
        }
        // A negative count cannot be drawn, and is noted.
        let (pts, notes) = counts_figure(vec![-1.0, 0.0, 10.0]).points();
        assert_eq!(pts[0].len(), 2);
        assert!(notes[0].contains("< 0 on a log(1 + x) axis"), "{notes:?}");
    }
}
