//! `ilopt plot RUN_DIR... --out FILE.svg|FILE.png`: the runs of `ilopt run` output directories
//! drawn as the appendix draws its learners (`ilopt-plot`): per directory the mean of a metric
//! over its seeds at each checkpoint with the 95% Student-t band, one fixed colour per directory
//! in argument order, a cross where a seed diverged, every run on one plot or one panel each.
//!
//! | module | what |
//! |---|---|
//! | [`metric`] | the metric (y), the x quantity and the layout, as the options name them |
//! | [`run_dir`] | reading a run directory: config, seed CSVs, terminations |
//! | [`curve`] | one run's mean and band over its seeds |
//! | [`error`] | the errors, naming the directory or file |

pub mod curve;
pub mod error;
pub mod metric;
pub mod run_dir;

pub use error::PlotError;
pub use metric::{Layout, Metric, XAxis};

use crate::run::config::TaskName;
use clap::Args;
use ilopt_plot::{Figure, Scale, by_position};
use run_dir::RunDir;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// `ilopt plot`'s arguments.
#[derive(Debug, Clone, Args)]
pub struct PlotArgs {
    /// `ilopt run` output directories (each with its `config.toml` and `seed-<n>.csv` files), one
    /// curve each; colours follow this order.
    #[arg(required = true, value_name = "RUN_DIR")]
    pub runs: Vec<PathBuf>,
    /// The figure file: `.svg`, or `.png` (rendered from the SVG with the system's fonts).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// The metric on the y axis [default: score; objective on a toy MDP].
    #[arg(long, value_enum)]
    pub metric: Option<Metric>,
    /// The x axis: cumulative gradient calls or iterations.
    #[arg(long, value_enum, default_value_t = XAxis::Calls)]
    pub x: XAxis,
    /// Every run on one plot, or one panel per run on shared axes.
    #[arg(long, value_enum, default_value_t = Layout::Overlay)]
    pub layout: Layout,
    /// The runs' names in the legend, comma-separated, one per directory [default: the
    /// directories' names].
    #[arg(long, value_delimiter = ',', value_name = "A,B,...")]
    pub labels: Option<Vec<String>>,
    /// The title drawn above the plot [default: the task and the metric].
    #[arg(long)]
    pub title: Option<String>,
}

/// The figure's format, from the extension of `--out`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Svg,
    Png,
}

fn format_of(out: &Path) -> Result<Format, PlotError> {
    match out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => Err(PlotError::Input(format!(
            "--out {}: the figure file must end in .svg or .png",
            out.display()
        ))),
    }
}

/// The legend labels: `--labels` (one per directory, none empty), else each directory's name,
/// or its path as given when two directories share a name.
fn labels(args: &PlotArgs) -> Result<Vec<String>, PlotError> {
    if let Some(l) = &args.labels {
        if l.len() != args.runs.len() {
            return Err(PlotError::Input(format!(
                "--labels gives {} labels for {} run directories",
                l.len(),
                args.runs.len()
            )));
        }
        if let Some(k) = l.iter().position(|s| s.trim().is_empty()) {
            return Err(PlotError::Input(format!(
                "--labels: label {} (for {}) is empty",
                k + 1,
                args.runs[k].display()
            )));
        }
        return Ok(l.clone());
    }
    let name = |p: &PathBuf| {
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    };
    let names: Vec<String> = args.runs.iter().map(name).collect();
    Ok(args
        .runs
        .iter()
        .zip(&names)
        .map(|(p, n)| {
            if names.iter().filter(|m| *m == n).count() > 1 {
                p.display().to_string()
            } else {
                n.clone()
            }
        })
        .collect())
}

/// The range `[min, max]` as the note prints it (an open end at infinity: `[0, ∞)`).
fn range_text((lo, hi): (f64, f64)) -> String {
    let end = |v: f64| {
        if v.is_finite() {
            v.to_string()
        } else if v > 0.0 {
            "∞".into()
        } else {
            "−∞".into()
        }
    };
    let open = if lo.is_finite() { '[' } else { '(' };
    let close = if hi.is_finite() { ']' } else { ')' };
    format!("{open}{}, {}{close}", end(lo), end(hi))
}

/// The task of every run in `runs`, drawn against `x`.
///
/// # Errors
/// [`PlotError::Input`] for runs of different tasks, or `--x iterations` over both a dataset
/// learner and an oracle method.
fn common_task(runs: &[RunDir], x: XAxis) -> Result<TaskName, PlotError> {
    let task = runs
        .first()
        .map(|r| r.task)
        .ok_or_else(|| PlotError::Input("no run directory given".into()))?;
    if let Some(r) = runs.iter().find(|r| r.task != task) {
        return Err(PlotError::Input(format!(
            "mixed tasks: {} is a {} run but {} is a {} run; their metrics do not share an axis",
            runs[0].path.display(),
            task.name(),
            r.path.display(),
            r.task.name()
        )));
    }
    if x == XAxis::Iterations
        && let Some(d) = runs.iter().find(|r| r.dataset_learner)
        && let Some(o) = runs.iter().find(|r| !r.dataset_learner)
    {
        return Err(PlotError::Input(format!(
            "mixed x axes: with --x iterations, {} counts rounds of a dataset learner and {} \
             gradient steps of an oracle method; use --x calls to draw them together",
            d.path.display(),
            o.path.display()
        )));
    }
    Ok(task)
}

/// Every run records `metric`.
///
/// # Errors
/// [`PlotError::Input`] naming the first run without a value of it and listing what it records.
fn check_recorded(runs: &[RunDir], metric: Metric, task: TaskName) -> Result<(), PlotError> {
    for r in runs {
        let recorded = r.recorded();
        if !recorded.contains(&metric) {
            let names: Vec<&str> = recorded.iter().map(|m| m.column()).collect();
            return Err(PlotError::Input(format!(
                "{}: no `{}` values: this {} run records {}",
                r.path.display(),
                metric.column(),
                task.name(),
                if names.is_empty() {
                    "no metric".into()
                } else {
                    names.join(", ")
                }
            )));
        }
    }
    Ok(())
}

/// The notes under the figure: how the lines and bands are computed, the clamping to the
/// metric's range (with the count of clamped band ends), the runs of one seed.
fn notes(curves: &[curve::Curve], metric: Metric, range: (f64, f64)) -> Vec<String> {
    let mut notes = vec![
        "lines: the mean over seeds at each checkpoint; bands: its 95% Student-t interval, mean ± t(0.975, n − 1)·s/√n over the n seeds"
            .to_string(),
    ];
    if range.0.is_finite() || range.1.is_finite() {
        let clamped: usize = curves.iter().map(|c| c.clamped_ends).sum();
        notes.push(format!(
            "bands clamped to the range of {} {} ({clamped} band end{} clamped)",
            metric.column(),
            range_text(range),
            if clamped == 1 { "" } else { "s" }
        ));
    }
    let single: Vec<&str> = curves
        .iter()
        .filter(|c| !c.series.shaded)
        .map(|c| c.series.label.as_str())
        .collect();
    if !single.is_empty() {
        notes.push(format!("one seed, no band: {}", single.join(", ")));
    }
    notes
}

/// Draw the runs as `args` says and write the figure; returns what was drawn (JSON).
///
/// # Errors
/// [`PlotError`]: a bad extension, a run directory that cannot be read, runs of different tasks,
/// iterations of oracle methods and dataset learners on one axis, a metric a run does not record,
/// labels that do not match the directories, or a figure that cannot be drawn or written.
pub fn run(args: &PlotArgs) -> Result<Value, PlotError> {
    let format = format_of(&args.out)?;
    let labels = labels(args)?;
    let runs: Vec<RunDir> = args
        .runs
        .iter()
        .map(|d| RunDir::read(d))
        .collect::<Result<_, _>>()?;
    let task = common_task(&runs, args.x)?;
    let metric = args.metric.unwrap_or(Metric::default_for(task));
    check_recorded(&runs, metric, task)?;
    let range = metric.range(task);
    let curves: Vec<curve::Curve> = runs
        .iter()
        .zip(&labels)
        .map(|(r, l)| curve::curve(r, l, metric, args.x, range))
        .collect();
    let notes = notes(&curves, metric, range);
    let title = args.title.clone().unwrap_or_else(|| {
        format!(
            "{} task: {} (mean over seeds, 95% band)",
            task.name(),
            metric.column()
        )
    });
    let n = curves.len();
    let figure = Figure {
        title,
        x_label: args.x.label().into(),
        y_label: metric.label(task).into(),
        x_scale: Scale::Linear,
        log_y: false,
        y_range: Some(range),
        series: curves
            .iter()
            .enumerate()
            .map(|(k, c)| ilopt_plot::Series {
                style: Some(by_position(k)),
                ..c.series.clone()
            })
            .collect(),
        panels: (args.layout == Layout::Panels).then_some(n.min(3)),
        show_title: true,
        notes,
    };
    let draw_err = |message: String| PlotError::Draw {
        path: args.out.clone(),
        message,
    };
    let svg = figure.to_svg().map_err(draw_err)?;
    let bytes = match format {
        Format::Svg => svg.into_bytes(),
        Format::Png => ilopt_plot::render_png(&svg).map_err(draw_err)?,
    };
    std::fs::write(&args.out, bytes).map_err(|source| PlotError::Write {
        path: args.out.clone(),
        source,
    })?;
    Ok(json!({
        "out": args.out.display().to_string(),
        "task": task.name(),
        "metric": metric.column(),
        "x": args.x.column(),
        "runs": runs.iter().zip(&curves).map(|(r, c)| json!({
            "dir": r.path.display().to_string(),
            "label": c.series.label,
            "seeds": r.seeds.iter().map(|s| s.seed).collect::<Vec<_>>(),
            "diverged": c.series.diverged,
            "checkpoints": c.series.x.len(),
        })).collect::<Vec<_>>(),
    }))
}
