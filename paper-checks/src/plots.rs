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

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Width of the legend panel right of the plot, in pixels.
const LEGEND_WIDTH: u32 = 200;

/// Colours of the dashed reference lines, in order (black, mid grey, dark teal).
const REFERENCE_COLORS: [RGBColor; 3] = [BLACK, RGBColor(140, 140, 140), RGBColor(0, 110, 110)];

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

/// A tick label. On a log axis `v` is log10 of the value: whole decades print as 1, 10, 100,
/// 1000, 10000 or 1eK, other ticks with two significant digits. On a linear axis a tick within
/// `1e-9 × span` of zero prints as `0` (not `-5.6e-17`).
pub fn fmt_tick(v: f64, log: bool, span: f64) -> String {
    if log {
        let x = 10f64.powf(v);
        if (v - v.round()).abs() < 1e-9 {
            let k = v.round() as i32;
            if (0..=4).contains(&k) {
                format!("{}", 10f64.powi(k))
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
        crate::pipeline::write_atomic(svg_path, svg.as_bytes())?;
        if png {
            let png_bytes = render_png(&svg).map_err(|e| plot_err(svg_path, e))?;
            crate::pipeline::write_atomic(&svg_path.with_extension("png"), &png_bytes)?;
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
        let note_height = 22 * notes.len() as u32 + if notes.is_empty() { 0 } else { 6 };
        {
            let root = SVGBackend::with_string(out, (800 + LEGEND_WIDTH, 520 + note_height))
                .into_drawing_area();
            root.fill(&WHITE)?;
            let root = root.titled(&self.title, ("sans-serif", 24))?;
            let (main, note_area) = root.split_vertically(root.dim_in_pixel().1 - note_height);
            let (plot_area, legend_area) = main.split_horizontally(800);
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(12)
                .margin_right(28)
                .x_label_area_size(45)
                .y_label_area_size(75)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            let (lx, ly) = (self.log_x, self.log_y);
            let (sx, sy) = (x1 - x0, y1 - y0);
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .x_labels(label_count(x0, x1, lx))
                .y_labels(label_count(y0, y1, ly))
                .x_label_formatter(&|v| fmt_tick(*v, lx, sx))
                .y_label_formatter(&|v| fmt_tick(*v, ly, sy))
                .light_line_style(WHITE.mix(0.0))
                .label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 16))
                .draw()?;
            let mut legend = Vec::new();
            let mut references = 0;
            for (i, v) in pts.iter().enumerate() {
                let s = &self.series[i];
                let color = if s.reference {
                    references += 1;
                    REFERENCE_COLORS[(references - 1) % REFERENCE_COLORS.len()]
                } else {
                    COLORS[i % COLORS.len()]
                };
                legend.push((s.label.clone(), color, s.reference));
                if !s.reference && v.len() > 1 {
                    let mut poly: Vec<(f64, f64)> =
                        v.iter().map(|p| (p.0, p.2.unwrap_or(y0))).collect();
                    poly.extend(v.iter().rev().map(|p| (p.0, p.3)));
                    chart.draw_series(std::iter::once(Polygon::new(poly, color.mix(0.2))))?;
                }
                let style = ShapeStyle::from(&color).stroke_width(2);
                let line: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.1)).collect();
                if s.reference {
                    chart.draw_series(DashedLineSeries::new(line, 8, 5, style))?;
                } else {
                    chart.draw_series(LineSeries::new(line.clone(), style))?;
                    chart.draw_series(line.iter().map(|p| Circle::new(*p, 3, color.filled())))?;
                }
            }
            // The legend in its own panel, so it never covers the curves.
            let font = ("sans-serif", 14).into_font();
            for (k, (label, color, dashed)) in legend.iter().enumerate() {
                let y = 30 + 24 * k as i32;
                let style = ShapeStyle::from(color).stroke_width(2);
                if *dashed {
                    legend_area.draw(&PathElement::new(vec![(4, y), (12, y)], style))?;
                    legend_area.draw(&PathElement::new(vec![(18, y), (26, y)], style))?;
                } else {
                    legend_area.draw(&Rectangle::new(
                        [(4, y - 6), (28, y + 6)],
                        color.mix(0.2).filled(),
                    ))?;
                    legend_area.draw(&PathElement::new(vec![(4, y), (28, y)], style))?;
                }
                legend_area.draw(&Text::new(label.clone(), (34, y - 8), font.clone()))?;
            }
            for (k, n) in notes.iter().enumerate() {
                note_area.draw(&Text::new(
                    format!("Note: {n}."),
                    (12, 2 + 20 * k as i32),
                    ("sans-serif", 13).into_font(),
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
