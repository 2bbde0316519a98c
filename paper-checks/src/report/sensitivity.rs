//! The sensitivity figures: for each task, one cell per tuned row with every grid point tried,
//! its tuning score against its step — the area under the learning curve above, the median
//! calls to sustained convergence below — the pick ringed and diverged points drawn as crosses.

use super::aggregate::num;
use super::blocks::Block;
use crate::error::Error;
use crate::experiment::TaskKind;
use crate::protocol::{PointResult, TuningResult};
use crate::results::Results;
use ilopt_plot::render_png;
use plotters::prelude::*;
use std::path::Path;

/// Columns of cells.
const COLUMNS: usize = 4;
/// One cell's size in pixels (two stacked charts).
const CELL: (u32, u32) = (330, 330);
const M1: RGBColor = RGBColor(0, 114, 178);
const M16: RGBColor = RGBColor(230, 159, 0);
const OTHER: RGBColor = RGBColor(120, 120, 120);
const DIVERGED: RGBColor = RGBColor(213, 94, 0);

/// A call count as a short tick label (`300k`, `1.5M`).
fn calls_tick(v: f64) -> String {
    if v >= 1e6 {
        format!("{}M", num(v / 1e6))
    } else if v >= 1e3 {
        format!("{}k", num(v / 1e3))
    } else {
        num(v)
    }
}

/// The point's step (its first log dimension), if it has one.
fn step(p: &PointResult) -> Option<f64> {
    p.score.as_ref().map(|s| s.step).filter(|x| x.is_finite())
}

fn colour(p: &PointResult) -> RGBColor {
    match p.point.m {
        1 => M1,
        16 => M16,
        _ => OTHER,
    }
}

/// Whether every tuning run of the point diverged.
fn diverged(p: &PointResult) -> bool {
    p.score
        .as_ref()
        .is_some_and(|s| s.diverged > 0 && s.diverged == p.runs.len())
}

/// The figure of one task as SVG text; `None` when the task has no tuned row.
fn svg(rows: &[&TuningResult], kind: TaskKind) -> Result<Option<String>, String> {
    if rows.is_empty() {
        return Ok(None);
    }
    let cells_y = rows.len().div_ceil(COLUMNS);
    let size = (CELL.0 * COLUMNS as u32, CELL.1 * cells_y as u32 + 40);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (title, body) = root.split_vertically(40);
        title
            .titled(
                &format!(
                    "Tuning sensitivity, {} task: every point tried (blue m = 1, orange m = 16, \
                     grey other; ▲ adaptive STORM's k; × all runs diverged; ring = pick)",
                    kind.name()
                ),
                ("sans-serif", 15),
            )
            .map_err(|e| e.to_string())?;
        let cells = body.split_evenly((cells_y, COLUMNS));
        for (cell, t) in cells.iter().zip(rows) {
            draw_cell(cell, t).map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(Some(out))
}

type Cell<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

fn draw_cell<'a>(cell: &Cell<'a>, t: &TuningResult) -> Result<(), Box<dyn std::error::Error + 'a>> {
    let pts: Vec<&PointResult> = t.points.iter().filter(|p| step(p).is_some()).collect();
    let xs: Vec<f64> = pts.iter().filter_map(|p| step(p)).map(f64::log10).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    let (lo, hi) = if lo.is_finite() {
        (lo - 0.5, hi + 0.5)
    } else {
        (-1.0, 1.0)
    };
    let (top, bottom) = cell.split_vertically(CELL.1 / 2 + 10);
    let budget = t.budget as f64;
    let chosen = t.selected;
    // Above: the area under the learning curve (mean checkpoint score) at the rung reached.
    let mut c = ChartBuilder::on(&top)
        .caption(&t.label, ("sans-serif", 13))
        .margin(4)
        .x_label_area_size(18)
        .y_label_area_size(46)
        .build_cartesian_2d(lo..hi, 0.0..1.0)?;
    c.configure_mesh()
        .disable_mesh()
        .x_labels(5)
        .y_labels(5)
        .x_label_formatter(&|v| format!("1e{}", v.round() as i64))
        .y_desc("area")
        .label_style(("sans-serif", 10))
        .draw()?;
    // Below: the median calls to sustained convergence; a point whose median run did not
    // converge sits on the top line, "none".
    let mut d = ChartBuilder::on(&bottom)
        .margin(4)
        .x_label_area_size(28)
        .y_label_area_size(46)
        .build_cartesian_2d(lo..hi, 0.0..budget * 1.12)?;
    d.configure_mesh()
        .disable_mesh()
        .x_labels(5)
        .y_labels(4)
        .x_label_formatter(&|v| format!("1e{}", v.round() as i64))
        .y_label_formatter(&|v| calls_tick(*v))
        .x_desc("step (log10)")
        .y_desc("median calls")
        .label_style(("sans-serif", 10))
        .draw()?;
    d.draw_series(std::iter::once(Text::new(
        "not converged",
        (lo, budget * 1.11),
        ("sans-serif", 10).into_font().color(&OTHER),
    )))?;
    for (i, p) in t.points.iter().enumerate() {
        let Some(x) = step(p).map(f64::log10) else {
            continue;
        };
        let Some(s) = &p.score else { continue };
        let calls = if s.median_calls.is_finite() {
            s.median_calls
        } else {
            budget * 1.05
        };
        let style = colour(p);
        // Points scored at a lower rung of successive halving are drawn smaller.
        let r = if p.rung + 1 == t.rounds.last().map_or(1, |x| x.rungs.len()) {
            4
        } else {
            2
        };
        let adaptive = p.point.values.iter().any(|(k, _)| k == "schedule.k");
        for (chart_y, which) in [(s.auc, 0), (calls, 1)] {
            let at = (x, chart_y);
            let drawn: Result<(), _> = if diverged(p) {
                if which == 0 {
                    c.draw_series(std::iter::once(Cross::new(at, 4, DIVERGED.stroke_width(2))))
                        .map(|_| ())
                } else {
                    d.draw_series(std::iter::once(Cross::new(at, 4, DIVERGED.stroke_width(2))))
                        .map(|_| ())
                }
            } else if adaptive {
                if which == 0 {
                    c.draw_series(std::iter::once(TriangleMarker::new(
                        at,
                        r + 1,
                        style.filled(),
                    )))
                    .map(|_| ())
                } else {
                    d.draw_series(std::iter::once(TriangleMarker::new(
                        at,
                        r + 1,
                        style.filled(),
                    )))
                    .map(|_| ())
                }
            } else if which == 0 {
                c.draw_series(std::iter::once(Circle::new(at, r, style.filled())))
                    .map(|_| ())
            } else {
                d.draw_series(std::iter::once(Circle::new(at, r, style.filled())))
                    .map(|_| ())
            };
            drawn?;
            if i == chosen {
                if which == 0 {
                    c.draw_series(std::iter::once(Circle::new(at, 8, BLACK.stroke_width(2))))?;
                } else {
                    d.draw_series(std::iter::once(Circle::new(at, 8, BLACK.stroke_width(2))))?;
                }
            }
        }
    }
    Ok(())
}

/// Write the sensitivity figure of each task with a tuned row into `dir` (SVG, and PNG when
/// `png`), and return the appendix's blocks that show them.
///
/// # Errors
/// [`Error::Io`] on a write failure; a drawing failure as [`Error::experiment`].
pub fn write(r: &Results, dir: &Path, png: bool) -> Result<Vec<Block>, Error> {
    let mut blocks = Vec::new();
    for kind in [TaskKind::Obstacle, TaskKind::Cartpole] {
        let rows: Vec<&TuningResult> = r
            .tuning
            .iter()
            .filter(|t| t.task == kind && t.is_tuned())
            .collect();
        let Some(text) =
            svg(&rows, kind).map_err(|e| Error::experiment("sensitivity figure", e))?
        else {
            continue;
        };
        let stem = format!("sensitivity-{}", kind.name());
        let svg_path = dir.join(format!("{stem}.svg"));
        std::fs::write(&svg_path, &text).map_err(|e| Error::io(&svg_path, e))?;
        let mut ext = "svg";
        if png {
            match render_png(&text) {
                Ok(bytes) => {
                    let p = dir.join(format!("{stem}.png"));
                    std::fs::write(&p, bytes).map_err(|e| Error::io(&p, e))?;
                    ext = "png";
                }
                Err(e) => eprintln!("warning: PNG rendering of {stem} failed ({e}); SVG only"),
            }
        }
        blocks.push(Block::Figure {
            path: format!("figures/{stem}.{ext}"),
            caption: format!(
                "Tuning sensitivity on the {} task (beyond the thesis): for each tuned row, every \
                 grid point tried, its area under the learning curve (top) and median gradient \
                 calls to sustained convergence (bottom; \"none\": the median tuning run did not \
                 converge, drawn on the top line) against its step (η, α or, as triangles, adaptive STORM's k), on the \
                 tuning seeds. Large marks were scored at the whole budget, small ones at the \
                 lower rung of successive halving where they stopped; crosses: every tuning run \
                 of the point diverged; ringed: the pick. Why the unweighted STORM rows diverge \
                 at steps where the importance-weighted rows do not is the next section's \
                 subject.",
                kind.name()
            ),
        });
    }
    Ok(blocks)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::RunStatus;
    use crate::grid::GridDim;
    use crate::protocol::{Round, Score, TuningRun};

    fn run(status: RunStatus) -> TuningRun {
        TuningRun {
            seed_index: 0,
            seed: 0,
            budget: 100,
            status,
            gradient_evaluations: 100,
            scores: vec![0.0, 0.5],
            calls: vec![0, 100],
        }
    }

    /// A row with a converged pick and a diverged point draws a cell titled by the row, a ring
    /// (the pick) and a cross (the diverged point); a task without tuned rows draws nothing.
    #[test]
    fn the_figure_marks_the_pick_and_the_diverged_points() {
        let config: ilopt::algo::AlgorithmConfig = serde_json::from_value(serde_json::json!({
            "algorithm": "sgd", "form": "causal", "step": {"kind": "constant", "eta": 1e-3}
        }))
        .unwrap();
        let points = crate::grid::points(
            &config,
            None,
            None,
            &[vec![GridDim::log("step.eta", 1e-3, 3e-3)]],
        )
        .unwrap();
        let conv = RunStatus::Converged {
            checkpoint: 0,
            gradient_evaluations: 50,
        };
        let div = RunStatus::Diverged {
            reason: "x".into(),
            gradient_evaluations: 50,
        };
        let results: Vec<PointResult> = points
            .iter()
            .zip([conv, div])
            .map(|(p, st)| {
                let runs = vec![run(st)];
                PointResult {
                    score: Some(Score::of(p, &runs, 100, 100)),
                    point: p.clone(),
                    runs,
                    rung: 0,
                }
            })
            .collect();
        let t = TuningResult {
            task: TaskKind::Obstacle,
            label: "SGD-in-a-test".into(),
            key_hash: String::new(),
            dims: vec!["step.eta".into()],
            points: results,
            selected: 0,
            budget: 100,
            rounds: vec![Round {
                points: 2,
                rungs: vec![],
                pick: String::new(),
                extended: vec![],
            }],
            on_edge: vec![],
            tied_with: vec![],
            tuning_seeds: 1,
        };
        assert!(diverged(&t.points[1]) && !diverged(&t.points[0]));
        let text = svg(&[&t], TaskKind::Obstacle).unwrap().expect("a figure");
        assert!(text.contains("SGD-in-a-test"));
        assert!(text.contains("not converged"));
        // The pick's ring: a circle of radius 8 drawn with a stroke, not filled.
        assert!(text.contains(r#"r="8""#), "no ring");
        assert!(svg(&[], TaskKind::Cartpole).unwrap().is_none());
        assert_eq!(calls_tick(2.5e6), "2.500M");
        assert_eq!(calls_tick(300_000.0), "300.0k");
    }
}
