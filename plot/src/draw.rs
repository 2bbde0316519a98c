//! Drawing on the SVG surface: markers, bands, lines, legend samples, frames, titles and notes.

use super::*;

/// Draw `marker` centred at pixel `c` on `area` (pixel coordinates).
pub(super) fn draw_marker<DB: DrawingBackend>(
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

/// The SVG drawing surface, and a chart on part of it with `f64` axes (positions: log10 of the
/// value on log axes, log10(1 + value) on a log(1 + x) axis).
pub(super) type Area<'b> = DrawingArea<SVGBackend<'b>, plotters::coord::Shift>;
pub(super) type Chart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<XCoord, RangedCoordf64>>;
pub(super) type DrawResult = Result<(), DrawingAreaErrorKind<std::io::Error>>;

/// The axes' extent `(x0, x1, y0, y1)` over every drawn point and band, the y range padded by 5%
/// (a unit range when nothing is drawn or the range is empty).
pub(super) fn extent(pts: &[Vec<BandPoint>]) -> (f64, f64, f64, f64) {
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
pub(super) fn draw_band(
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
pub(super) fn draw_line(
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
pub(super) fn draw_sample(
    root: &Area<'_>,
    (x, y): (i32, i32),
    width: i32,
    st: &Style,
) -> DrawResult {
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

/// A drawn title's lines, from the top left of the canvas.
pub(super) fn draw_heading(root: &Area<'_>, lines: &[String]) -> DrawResult {
    let font = ("sans-serif", HEADING_FONT).into_font();
    for (k, line) in lines.iter().enumerate() {
        root.draw(&Text::new(
            line.clone(),
            (12, 6 + (HEADING_ROW * k as u32) as i32),
            font.clone(),
        ))?;
    }
    Ok(())
}

/// The note lines, top left of `area`.
pub(super) fn draw_notes(area: &Area<'_>, lines: &[String]) -> DrawResult {
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
pub(super) fn draw_frame(root: &Area<'_>, (x, y, w, h): (i32, i32, i32, i32)) -> DrawResult {
    let style = ShapeStyle::from(&RGBColor(150, 150, 150)).stroke_width(1);
    root.draw(&PathElement::new(
        vec![(x, y), (x + w, y), (x + w, y + h), (x, y + h), (x, y)],
        style,
    ))
}

/// A panel's title: a sample of the series' style, then its label (one or more lines), from
/// `(x, y)` (pixels, top left).
pub(super) fn draw_title(
    root: &Area<'_>,
    lines: &[String],
    (x, y): (i32, i32),
    st: &Style,
) -> DrawResult {
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

/// A large cross at each point of `v` (axis units, drawn at the chart's pixel coordinates): where
/// a run diverged. In the series' colour with a white halo, so it stands out from the markers
/// and bands.
pub(super) fn draw_crosses(
    chart: &Chart<'_, '_>,
    root: &Area<'_>,
    v: &[(f64, f64)],
    st: &Style,
) -> DrawResult {
    let r = 9;
    let halo = ShapeStyle::from(&WHITE).stroke_width(6);
    let stroke = ShapeStyle::from(&st.color).stroke_width(3);
    for p in v {
        let (x, y) = chart.backend_coord(p);
        for style in [halo, stroke] {
            root.draw(&PathElement::new(
                vec![(x - r, y - r), (x + r, y + r)],
                style,
            ))?;
            root.draw(&PathElement::new(
                vec![(x - r, y + r), (x + r, y - r)],
                style,
            ))?;
        }
    }
    Ok(())
}
