//! The kit's figures: mean curves with shaded 95% confidence bands (plotters' SVG backend),
//! optionally rendered to PNG with resvg (system fonts through fontdb). The appendix's figures
//! (paper-checks) and `ilopt plot` draw through it; [`band`] is the Student-t band over seeds.
//!
//! | module | what |
//! |---|---|
//! | [`band`] | the mean and 95% Student-t interval of a sample of seeds |
//! | `axis` | the axes' scales, ticks and tick labels |
//! | `style` | one fixed colour, marker and line pattern per label ([`style_for`]) |
//! | `layout` | sizes, fonts, the legend, the notes and the grid of panels |
//! | `draw` | drawing bands, lines, markers, crosses, frames and titles |
//! | `png` | PNG rendering of the SVG ([`render_png`]) |

#![warn(missing_docs)]

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;

mod axis;
pub mod band;
mod draw;
mod layout;
mod png;
mod style;
#[cfg(test)]
mod tests;

use axis::*;
pub use axis::{BandPoint, fmt_tick};
use draw::*;
use draw::{Area, DrawResult};
use layout::*;
pub use png::render_png;
pub use style::*;

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
    /// Runs behind the curve (0 for a reference line).
    pub runs: usize,
    /// Runs that diverged: the legend or panel title says "(diverged k/n)".
    pub diverged: usize,
    /// Where each diverged run stopped, `(x, y)` of its last checkpoint: drawn as a cross.
    pub diverged_at: Vec<(f64, f64)>,
    /// How the series is drawn; `None`: the style of its label ([`style_for`]).
    pub style: Option<Style>,
    /// Whether the band is shaded (`false`: a mean without an interval, e.g. over one seed).
    pub shaded: bool,
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
            runs: 0,
            diverged: 0,
            diverged_at: vec![],
            style: None,
            shaded: true,
        }
    }

    /// The label shown in the legend or panel title: the label, and "(diverged k/n)" when runs
    /// diverged.
    pub fn shown_label(&self) -> String {
        if self.diverged > 0 {
            format!("{} (diverged {}/{})", self.label, self.diverged, self.runs)
        } else {
            self.label.clone()
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
    /// Draw the title above the plot (`false`: the title is the caption of a document that
    /// includes the figure, and the figure has none).
    pub show_title: bool,
    /// Notes drawn under the figure after the ones about points left out (e.g. how the bands
    /// were computed).
    pub notes: Vec<String>,
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
    /// transforms (log10 on log axes, log10(1 + x) on a log(1 + x) axis), and the notes: on what
    /// was left out, then the figure's own ([`Figure::notes`]); per series `(x, mean, band low, band high)` in axis units (a band low of
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
        if self.series.iter().any(|s| s.diverged > 0) {
            notes.push(
                "× marks a diverged run at its last checkpoint (its value there); after it the curve is over the other seeds"
                    .into(),
            );
        }
        notes.extend(self.notes.iter().cloned());
        (all, notes)
    }

    /// Each series' diverged-run crosses in axis units, clamped to [`Figure::y_range`] (a
    /// cross the axes cannot show, e.g. at 0 on a log axis, is left out).
    pub fn diverged_points(&self) -> Vec<Vec<(f64, f64)>> {
        self.series
            .iter()
            .map(|s| {
                s.diverged_at
                    .iter()
                    .filter_map(|&(x, y)| {
                        let y = clamp_to(y, self.y_range);
                        Some((tr(x, self.x_scale)?, tr(y, self.y_scale())?))
                    })
                    .collect()
            })
            .collect()
    }

    /// The drawn points with the crosses as points of their own (for the axes' extent).
    fn extent_points(
        &self,
        pts: &[Vec<BandPoint>],
        crosses: &[Vec<(f64, f64)>],
    ) -> Vec<Vec<BandPoint>> {
        let mut all = pts.to_vec();
        all.push(
            crosses
                .iter()
                .flatten()
                .map(|&(x, y)| (x, y, Some(y), y))
                .collect(),
        );
        all
    }

    fn draw(&self, out: &mut String) -> Result<(), Box<dyn std::error::Error + '_>> {
        match self.panels {
            Some(columns) => self.draw_panels(out, columns),
            None => self.draw_single(out),
        }
    }

    /// The styles of the series, and the indices of the series that have drawn points.
    fn styles_and_shown(&self, pts: &[Vec<BandPoint>]) -> (Vec<Style>, Vec<usize>) {
        let styles = self
            .series
            .iter()
            .map(|s| s.style.unwrap_or_else(|| style_for(&s.label)))
            .collect();
        let shown = (0..self.series.len())
            .filter(|&i| !pts[i].is_empty())
            .collect();
        (styles, shown)
    }

    /// Every series on one plot, the legend under it in columns, then the notes.
    fn draw_single(&self, out: &mut String) -> Result<(), Box<dyn std::error::Error + '_>> {
        let (pts, notes) = self.points();
        let crosses = self.diverged_points();
        let (x0, x1, y0, y1) = extent(&self.extent_points(&pts, &crosses));
        let (styles, shown) = self.styles_and_shown(&pts);
        let labels: Vec<String> = self.series.iter().map(Series::shown_label).collect();
        let entries: Vec<(&str, Style)> = shown
            .iter()
            .map(|&i| (labels[i].as_str(), styles[i]))
            .collect();
        let legend = LegendLayout::of(&entries);
        let note_lines = note_lines(&notes);
        let note_height = notes_height(&note_lines);
        let heading = heading_lines(self);
        let above = heading_height(&heading);
        {
            let root = SVGBackend::with_string(
                out,
                (WIDTH, above + PLOT_HEIGHT + legend.height + note_height),
            )
            .into_drawing_area();
            root.fill(&WHITE)?;
            draw_heading(&root, &heading)?;
            let (plot_area, rest) = root
                .clone()
                .shrink(
                    (0, above),
                    (WIDTH, PLOT_HEIGHT + legend.height + note_height),
                )
                .split_vertically(PLOT_HEIGHT);
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
                if !self.series[i].reference && self.series[i].shaded {
                    draw_band(&mut chart, v, &styles[i], y0, 0.10)?;
                }
            }
            for (i, v) in pts.iter().enumerate() {
                draw_line(&mut chart, &root, v, &styles[i])?;
            }
            for (i, c) in crosses.iter().enumerate() {
                draw_crosses(&chart, &root, c, &styles[i])?;
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
        let crosses = self.diverged_points();
        let (x0, x1, y0, y1) = extent(&self.extent_points(&pts, &crosses));
        let (styles, shown) = self.styles_and_shown(&pts);
        let labels: Vec<String> = self.series.iter().map(Series::shown_label).collect();
        let (refs, algos): (Vec<usize>, Vec<usize>) =
            shown.iter().partition(|&&i| self.series[i].reference);
        let heading = heading_lines(self);
        let grid = Grid::new(
            columns,
            &algos
                .iter()
                .map(|&i| labels[i].as_str())
                .collect::<Vec<_>>(),
            text_width(&self.y_label, AXIS_FONT) as u32 + 12,
            heading_height(&heading),
        );
        let ref_entries: Vec<(&str, Style)> = refs
            .iter()
            .map(|&i| (labels[i].as_str(), styles[i]))
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
            draw_heading(&root, &heading)?;
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
                if self.series[i].shaded {
                    draw_band(&mut chart, &pts[i], &styles[i], y0, 0.16)?;
                }
                for &j in &refs {
                    draw_line(&mut chart, &root, &pts[j], &styles[j])?;
                }
                draw_line(&mut chart, &root, &pts[i], &styles[i])?;
                draw_crosses(&chart, &root, &crosses[i], &styles[i])?;
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
