//! Figures: mean curves with shaded 95% confidence bands (plotters' SVG backend), optionally
//! rendered to PNG with resvg (system fonts through fontdb).

use crate::error::Error;
use plotters::prelude::*;
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
    /// log10 x axis.
    pub log_x: bool,
    /// log10 y axis.
    pub log_y: bool,
    /// The quantity's physical range `[min, max]` (either end may be infinite): means and bands
    /// are clamped to it before drawing (a t interval is symmetric and can leave it, e.g. a
    /// success rate's band below 0).
    pub y_range: Option<(f64, f64)>,
    /// The curves.
    pub series: Vec<Series>,
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
/// a 10 pt article), 0.48 pt per pixel: the smallest text below (15 px) prints at 7.2 pt.
const WIDTH: u32 = 720;
/// Height of the plot (axes and labels), in pixels.
const PLOT_HEIGHT: u32 = 440;
/// Font sizes in pixels: tick labels, axis descriptions, legend, notes.
const TICK_FONT: u32 = 16;
const AXIS_FONT: u32 = 17;
const LEGEND_FONT: u32 = 16;
const NOTE_FONT: u32 = 15;
/// Legend row height in pixels.
const LEGEND_ROW: u32 = 24;

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

fn tr(v: f64, log: bool) -> Option<f64> {
    if !v.is_finite() {
        return None;
    }
    if log {
        (v > 0.0).then(|| v.log10())
    } else {
        Some(v)
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

    /// The drawn points of each series after clamping to [`Figure::y_range`] and the axes'
    /// transforms (log10 on log axes), and the notes on what was left out: per series
    /// `(x, mean, band low, band high)` in axis units (a band low of `None` runs to the bottom of
    /// a log axis).
    pub fn points(&self) -> (Vec<Vec<BandPoint>>, Vec<String>) {
        let mut all = Vec::new();
        let (mut not_drawn, mut left_out, mut off) = (Vec::new(), Vec::new(), Vec::new());
        for s in &self.series {
            let mut v = Vec::new();
            let mut skipped = 0;
            for k in 0..s.x.len() {
                let m = clamp_to(s.mean[k], self.y_range);
                let (Some(x), Some(m)) = (tr(s.x[k], self.log_x), tr(m, self.log_y)) else {
                    skipped += 1;
                    continue;
                };
                let lo = clamp_to(s.lo.get(k).copied().unwrap_or(f64::NAN), self.y_range);
                let hi = clamp_to(s.hi.get(k).copied().unwrap_or(f64::NAN), self.y_range);
                let lo = if self.log_y && lo.is_finite() && lo <= 0.0 {
                    None
                } else {
                    Some(tr(lo, self.log_y).unwrap_or(m).min(m))
                };
                let hi = tr(hi, self.log_y).unwrap_or(m).max(m);
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
                if self.log_x || self.log_y {
                    ", or ≤ 0 on a log axis"
                } else {
                    ""
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
        let (pts, notes) = self.points();
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
        let (y0, y1) = (y0 - pad, y1 + pad);
        // The legend lists the series that are drawn, in columns under the plot.
        let styles: Vec<Style> = self.series.iter().map(|s| style_for(&s.label)).collect();
        let shown: Vec<usize> = (0..self.series.len())
            .filter(|&i| !pts[i].is_empty())
            .collect();
        let longest = shown
            .iter()
            .map(|&i| self.series[i].label.chars().count())
            .max()
            .unwrap_or(0) as u32;
        let column_width = 48 + longest * LEGEND_FONT * 55 / 100;
        let columns = ((WIDTH - 20) / column_width.max(1)).clamp(1, 4);
        let legend_rows = (shown.len() as u32).div_ceil(columns);
        let legend_height = legend_rows * LEGEND_ROW + 8;
        let note_chars = ((WIDTH - 24) * 100 / (NOTE_FONT * 52)) as usize;
        let note_lines: Vec<String> = notes
            .iter()
            .flat_map(|n| wrap(&format!("Note: {n}."), note_chars))
            .collect();
        let note_height = (NOTE_FONT + 5) * note_lines.len() as u32 + 6;
        {
            let root =
                SVGBackend::with_string(out, (WIDTH, PLOT_HEIGHT + legend_height + note_height))
                    .into_drawing_area();
            root.fill(&WHITE)?;
            let (plot_area, rest) = root.split_vertically(PLOT_HEIGHT);
            let (legend_area, note_area) = rest.split_vertically(legend_height);
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(10)
                .margin_right(24)
                .x_label_area_size(50)
                .y_label_area_size(78)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            let (lx, ly) = (self.log_x, self.log_y);
            let (sx, sy) = (x1 - x0, y1 - y0);
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .x_labels(label_count(x0, x1, lx).min(8))
                .y_labels(label_count(y0, y1, ly))
                .x_label_formatter(&|v| fmt_tick(*v, lx, sx))
                .y_label_formatter(&|v| fmt_tick(*v, ly, sy))
                .light_line_style(WHITE.mix(0.0))
                .bold_line_style(RGBColor(235, 235, 235))
                .label_style(("sans-serif", TICK_FONT))
                .axis_desc_style(("sans-serif", AXIS_FONT))
                .draw()?;
            // Bands first (light fill and thin edges), so no band covers another series' line.
            for (i, v) in pts.iter().enumerate() {
                let (s, st) = (&self.series[i], &styles[i]);
                if s.reference || v.len() < 2 {
                    continue;
                }
                let lo: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.2.unwrap_or(y0))).collect();
                let hi: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.3)).collect();
                let mut poly = lo.clone();
                poly.extend(hi.iter().rev());
                chart.draw_series(std::iter::once(Polygon::new(poly, st.color.mix(0.10))))?;
                let edge = ShapeStyle::from(&st.color.mix(0.45)).stroke_width(1);
                chart.draw_series(LineSeries::new(lo, edge))?;
                chart.draw_series(LineSeries::new(hi, edge))?;
            }
            for (i, v) in pts.iter().enumerate() {
                let st = &styles[i];
                let style = ShapeStyle::from(&st.color).stroke_width(2);
                let line: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.1)).collect();
                if st.dashed {
                    chart.draw_series(DashedLineSeries::new(line.clone(), 9, 5, style))?;
                } else {
                    chart.draw_series(LineSeries::new(line.clone(), style))?;
                }
                for p in &line {
                    draw_marker(&root, chart.backend_coord(p), st)?;
                }
            }
            let font = ("sans-serif", LEGEND_FONT).into_font();
            let origin = legend_area.get_base_pixel();
            for (k, &i) in shown.iter().enumerate() {
                let (col, row) = (k as u32 % columns, k as u32 / columns);
                let x = origin.0 + 16 + (col * column_width) as i32;
                let y = origin.1 + 4 + (row * LEGEND_ROW + LEGEND_ROW / 2) as i32;
                let st = &styles[i];
                let style = ShapeStyle::from(&st.color).stroke_width(2);
                if st.dashed {
                    root.draw(&PathElement::new(vec![(x, y), (x + 10, y)], style))?;
                    root.draw(&PathElement::new(vec![(x + 16, y), (x + 30, y)], style))?;
                } else {
                    root.draw(&PathElement::new(vec![(x, y), (x + 30, y)], style))?;
                }
                draw_marker(&root, (x + 15, y), st)?;
                root.draw(&Text::new(
                    self.series[i].label.clone(),
                    (x + 38, y - (LEGEND_FONT as i32) / 2 - 1),
                    font.clone(),
                ))?;
            }
            for (k, n) in note_lines.iter().enumerate() {
                note_area.draw(&Text::new(
                    n.clone(),
                    (12, 2 + (NOTE_FONT as i32 + 5) * k as i32),
                    ("sans-serif", NOTE_FONT).into_font(),
                ))?;
            }
            root.present()?;
        }
        Ok(())
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
