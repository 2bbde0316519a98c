//! The figures' sizes, fonts and layout: text wrapping and widths, the legend's rows, the notes,
//! and the grid of small-multiple panels.

use super::*;

/// Canvas width in SVG pixels. The LaTeX appendix includes figures at the line width (345 pt in
/// a 10 pt article), 0.48 pt per pixel. Font sizes below are plotters sizes; the SVG's is
/// `size / 1.24`, so the smallest (19) is 15.3 px and prints at 7.35 pt.
pub(super) const WIDTH: u32 = 720;
/// Height of the plot (axes and labels), in pixels.
pub(super) const PLOT_HEIGHT: u32 = 440;
/// Font sizes (plotters sizes): tick labels, axis descriptions, legend, notes.
pub(super) const TICK_FONT: u32 = 19;
pub(super) const AXIS_FONT: u32 = 20;
pub(super) const LEGEND_FONT: u32 = 19;
pub(super) const NOTE_FONT: u32 = 19;
/// Legend row height in pixels.
pub(super) const LEGEND_ROW: u32 = 27;
/// Small multiples: the panel titles' font size (plotters size: the SVG's is `size / 1.24`, so
/// 19 prints at 7.4 pt) and line height, the width of the style sample before a title, in pixels.
pub(super) const TITLE_FONT: u32 = 19;
pub(super) const TITLE_ROW: u32 = 22;
pub(super) const TITLE_SAMPLE: i32 = 30;
/// Small multiples, in pixels: the strip for the rotated y description, the y tick labels'
/// width (left column), the x tick labels' height, the gap between columns, the right margin,
/// the top margin and the height of the x description under the grid.
pub(super) const Y_DESC_WIDTH: u32 = 26;
pub(super) const PANEL_Y_TICKS: u32 = 56;
pub(super) const PANEL_X_TICKS: u32 = 30;
pub(super) const PANEL_GAP: u32 = 44;
pub(super) const PANEL_RIGHT: u32 = 22;
pub(super) const PANEL_TOP: u32 = 6;
pub(super) const X_DESC_HEIGHT: u32 = 30;
/// A drawn title ([`Figure::show_title`]): its font size (plotters size) and line height, in
/// pixels.
pub(super) const HEADING_FONT: u32 = 22;
pub(super) const HEADING_ROW: u32 = 26;

/// The lines of a drawn title, wrapped to the canvas (none when the title is not drawn or
/// empty).
pub(super) fn heading_lines(fig: &Figure) -> Vec<String> {
    if !fig.show_title || fig.title.is_empty() {
        return vec![];
    }
    wrap_to_width(&fig.title, f64::from(WIDTH - 24), HEADING_FONT)
}

/// The height in pixels the title lines take (0 for none).
pub(super) fn heading_height(lines: &[String]) -> u32 {
    if lines.is_empty() {
        0
    } else {
        HEADING_ROW * lines.len() as u32 + 8
    }
}

/// Split `text` into lines of at most `width` characters at spaces.
pub(super) fn wrap(text: &str, width: usize) -> Vec<String> {
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

/// The legend's layout: entries in up to four columns as wide as the longest label needs.
pub(super) struct LegendLayout {
    pub(super) columns: u32,
    pub(super) column_width: u32,
    pub(super) height: u32,
}

impl LegendLayout {
    /// The layout for `entries` (label, style).
    pub(super) fn of(entries: &[(&str, Style)]) -> Self {
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
    pub(super) fn none() -> Self {
        LegendLayout {
            columns: 1,
            column_width: 0,
            height: 0,
        }
    }

    /// Draw `entries` row by row from `origin` (pixels on `root`).
    pub(super) fn draw(
        &self,
        root: &Area<'_>,
        origin: (i32, i32),
        entries: &[(&str, Style)],
    ) -> DrawResult {
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
pub(super) fn note_lines(notes: &[String]) -> Vec<String> {
    let chars = ((WIDTH - 24) * 100 / (NOTE_FONT * 52)) as usize;
    notes
        .iter()
        .flat_map(|n| wrap(&format!("Note: {n}."), chars))
        .collect()
}

/// The height in pixels the note lines take.
pub(super) fn notes_height(lines: &[String]) -> u32 {
    (NOTE_FONT + 5) * lines.len() as u32 + 6
}

/// The estimated width in pixels of `text` in the sans-serif font at plotters size `size`
/// (the SVG's font size is `size / 1.24`), from DejaVu Sans's approximate advance widths in em.
pub(super) fn text_width(text: &str, size: u32) -> f64 {
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
pub(super) fn wrap_to_width(text: &str, width: f64, size: u32) -> Vec<String> {
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
pub(super) struct Cell {
    /// Column (0: the leftmost, which carries the y tick labels).
    pub(super) column: usize,
    /// The chart area's top-left corner and size (plot plus its tick-label areas).
    pub(super) origin: (u32, u32),
    pub(super) size: (u32, u32),
    /// The plot rectangle `(x, y, width, height)`.
    pub(super) plot: (i32, i32, i32, i32),
    /// The title's top-left corner.
    pub(super) title: (i32, i32),
}

/// The small-multiples grid: equal plots, a title block above each row as tall as its longest
/// wrapped title, tick labels only on the left column and under the bottom panel of each column.
pub(super) struct Grid {
    pub(super) columns: usize,
    /// The top edge of the first row (pixels): the margin, below a drawn title.
    pub(super) top: u32,
    pub(super) plot_width: u32,
    pub(super) plot_height: u32,
    /// Each panel's title lines.
    pub(super) titles: Vec<Vec<String>>,
    /// Each row's top edge, and the grid's bottom edge last.
    pub(super) row_tops: Vec<u32>,
}

impl Grid {
    /// The grid for panels titled `labels`, `columns` to a row, its plots and titles spanning
    /// at least `min_height` pixels from top to bottom (room for the rotated y description),
    /// starting `above` pixels further down than the margin (a drawn title).
    pub(super) fn new(columns: usize, labels: &[&str], min_height: u32, above: u32) -> Self {
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
        let top = PANEL_TOP + above;
        let mut row_tops = vec![top];
        for h in title_heights {
            let last = *row_tops.last().unwrap_or(&0);
            row_tops.push(last + h + plot_height + PANEL_X_TICKS);
        }
        Grid {
            columns,
            top,
            plot_width,
            plot_height,
            titles,
            row_tops,
        }
    }

    /// The grid's height in pixels (to the bottom of the last row's tick labels).
    pub(super) fn height(&self) -> u32 {
        *self.row_tops.last().unwrap_or(&self.top)
    }

    /// The top-left corner of the leftmost plots (pixels).
    pub(super) fn plots_origin(&self) -> (i32, i32) {
        ((Y_DESC_WIDTH + PANEL_Y_TICKS) as i32, self.top as i32)
    }

    /// The width and height spanned by the plots and the rows' titles (pixels).
    pub(super) fn plots_size(&self) -> (u32, u32) {
        let n = self.columns as u32;
        (
            n * self.plot_width + (n - 1) * PANEL_GAP,
            self.height().saturating_sub(self.top + PANEL_X_TICKS),
        )
    }

    /// The place of panel `k`.
    pub(super) fn cell(&self, k: usize) -> Cell {
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
