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

/// A transformed point: (x, mean, band low, band high).
type BandPoint = (f64, f64, f64, f64);

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

fn fmt_tick(v: f64, log: bool) -> String {
    if log {
        let x = 10f64.powf(v);
        if (0.01..1e5).contains(&x) {
            format!("{}", (x * 1000.0).round() / 1000.0)
        } else {
            format!("1e{v:.0}")
        }
    } else if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:.1e}")
    } else {
        format!("{}", (v * 1000.0).round() / 1000.0)
    }
}

impl Figure {
    /// Write the figure as SVG (and `.png` next to it if `png`).
    ///
    /// # Errors
    /// [`Error::Experiment`] if drawing fails, [`Error::Io`] if writing fails.
    pub fn write(&self, svg_path: &Path, png: bool) -> Result<(), Error> {
        let mut svg = String::new();
        self.draw(&mut svg).map_err(|e| plot_err(svg_path, e))?;
        crate::pipeline::write_atomic(svg_path, svg.as_bytes())?;
        if png {
            let png_bytes = render_png(&svg).map_err(|e| plot_err(svg_path, e))?;
            crate::pipeline::write_atomic(&svg_path.with_extension("png"), &png_bytes)?;
        }
        Ok(())
    }

    fn draw(&self, out: &mut String) -> Result<(), Box<dyn std::error::Error + '_>> {
        // Transformed data and ranges.
        let mut pts: Vec<(usize, Vec<BandPoint>)> = Vec::new();
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (i, s) in self.series.iter().enumerate() {
            let mut v = Vec::new();
            for k in 0..s.x.len() {
                let (Some(x), Some(m)) = (tr(s.x[k], self.log_x), tr(s.mean[k], self.log_y)) else {
                    continue;
                };
                let lo = tr(s.lo[k], self.log_y).unwrap_or(m).min(m);
                let hi = tr(s.hi[k], self.log_y).unwrap_or(m).max(m);
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(lo);
                y1 = y1.max(hi);
                v.push((x, m, lo, hi));
            }
            pts.push((i, v));
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
        {
            let root = SVGBackend::with_string(out, (800, 520)).into_drawing_area();
            root.fill(&WHITE)?;
            let mut chart = ChartBuilder::on(&root)
                .caption(&self.title, ("sans-serif", 24))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(75)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            let (lx, ly) = (self.log_x, self.log_y);
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .x_label_formatter(&|v| fmt_tick(*v, lx))
                .y_label_formatter(&|v| fmt_tick(*v, ly))
                .light_line_style(WHITE.mix(0.0))
                .label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 16))
                .draw()?;
            for (i, v) in &pts {
                let s = &self.series[*i];
                let color = if s.reference {
                    BLACK
                } else {
                    COLORS[*i % COLORS.len()]
                };
                if !s.reference && v.len() > 1 {
                    let mut poly: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.2)).collect();
                    poly.extend(v.iter().rev().map(|p| (p.0, p.3)));
                    chart.draw_series(std::iter::once(Polygon::new(poly, color.mix(0.18))))?;
                }
                let style = ShapeStyle::from(&color).stroke_width(2);
                let line: Vec<(f64, f64)> = v.iter().map(|p| (p.0, p.1)).collect();
                let anno = if s.reference {
                    chart.draw_series(DashedLineSeries::new(line, 8, 5, style))?
                } else {
                    chart.draw_series(LineSeries::new(line.clone(), style))?;
                    chart.draw_series(line.iter().map(|p| Circle::new(*p, 3, color.filled())))?
                };
                anno.label(s.label.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
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
