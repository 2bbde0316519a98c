//! The chapter-4 figures (Figs. 4.2–4.10): per-checkpoint bands over seeds with the reference
//! policies as dashed lines, and their SVG/PNG files.

use crate::config::Profile;
use crate::error::Error;
use crate::experiment::{AppendixRun, Evaluated};
use crate::experiment::{Checkpoint, TaskKind};
use crate::results::{ConfigResult, Results};
use crate::stats::{Interval, Range};
use ilopt_plot::{Figure, Scale, Series, render_png};
use std::path::Path;

/// One figure: its file stem, the thesis figure it regenerates, and the figure.
pub type NamedFigure = (&'static str, &'static str, Figure);

/// The interval kind of a figure's quantity from its physical range: bootstrap when bounded on
/// both sides, a t interval clamped to 0 when only non-negative (as in the tables).
fn range_of((lo, hi): (f64, f64)) -> Range {
    if hi.is_finite() {
        Range::Bounded { lo, hi }
    } else {
        Range::NonNegative
    }
}

/// Per-checkpoint band of a metric across seeds: (x = mean of `xf`, the 95% interval of `yf`
/// for a quantity of `range`), and where each diverged run stopped: its last checkpoint.
fn band(
    c: &ConfigResult,
    xf: impl Fn(&Checkpoint) -> f64,
    yf: impl Fn(&Checkpoint) -> Option<f64>,
    (what, range): (&str, Range),
) -> Series {
    // Checkpoints are aligned by their nominal call count, on the schedule of the longest run (a
    // diverged run stops early: its checkpoints are those it reached).
    let schedule: Vec<u64> = c
        .runs
        .iter()
        .max_by_key(|r| r.checkpoints.len())
        .map(|r| r.checkpoints.iter().map(|k| k.at_calls).collect())
        .unwrap_or_default();
    let mut s = Series::new(c.label.clone());
    s.runs = c.runs.len();
    for r in c.runs.iter().filter(|r| r.status().is_diverged()) {
        s.diverged += 1;
        if let Some(k) = r.checkpoints.last()
            && let Some(y) = yf(k).filter(|y| y.is_finite())
        {
            s.diverged_at.push((xf(k), y));
        }
    }
    s.off_schedule = c
        .runs
        .iter()
        .flat_map(|r| &r.checkpoints)
        .filter(|k| !schedule.contains(&k.at_calls))
        .count();
    for it in schedule {
        let cps: Vec<&Checkpoint> = c
            .runs
            .iter()
            .filter_map(|r| r.checkpoints.iter().find(|k| k.at_calls == it))
            .collect();
        let all: Vec<f64> = cps.iter().filter_map(|c| yf(c)).collect();
        let ys: Vec<f64> = all.iter().copied().filter(|y| y.is_finite()).collect();
        s.non_finite += all.len() - ys.len();
        if ys.is_empty() {
            continue;
        }
        let x = cps.iter().map(|c| xf(c)).sum::<f64>() / cps.len() as f64;
        let key = format!("{}/{what}/{it}", super::aggregate::key(c, "figure"));
        let sm = Interval::of(&ys, range, &key);
        s.x.push(x);
        s.mean.push(sm.mean);
        s.lo.push(if sm.has_ends() { sm.lo } else { sm.mean });
        s.hi.push(if sm.has_ends() { sm.hi } else { sm.mean });
    }
    s
}

/// A dashed reference line (no band: its band is the line itself).
fn reference_series(label: String, x: Vec<f64>, mean: Vec<f64>) -> Series {
    Series {
        label,
        x,
        lo: mean.clone(),
        hi: mean.clone(),
        mean,
        reference: true,
        ..Series::new("")
    }
}

/// Horizontal dashed lines at the mean of `f` over each baseline of `task` (reference policies,
/// no training), across the x range of the figure's learner curves: from their first positive x,
/// or from x = 0 with `from_zero` (a log(1 + x) axis, whose origin is 0).
fn baseline_lines(
    r: &Results,
    task: TaskKind,
    f: impl Fn(&Checkpoint) -> f64,
    over: &[Series],
    from_zero: bool,
) -> Vec<Series> {
    let xs = || {
        over.iter()
            .flat_map(|s| s.x.iter().copied())
            .filter(move |x| *x > 0.0 || (from_zero && *x == 0.0))
    };
    let (Some(x0), Some(x1)) = (xs().reduce(f64::min), xs().reduce(f64::max)) else {
        return vec![];
    };
    r.baselines
        .iter()
        .filter(|b| b.task == task)
        .filter_map(|b| {
            let m = b.runs.iter().map(&f).sum::<f64>() / b.runs.len().max(1) as f64;
            // A reference without the quantity (no gradient estimate) is not drawn at all.
            m.is_finite()
                .then(|| reference_series(format!("{} (ref.)", b.label), vec![x0, x1], vec![m, m]))
        })
        .collect()
}

/// Every figure of the appendix, in document order: Fig. 4.2's panels, then the obstacle
/// figures (4.3–4.6) and the CartPole figures (4.8–4.10).
pub fn figures(profile: &Profile, r: &Results) -> Vec<NamedFigure> {
    let mut figs: Vec<NamedFigure> = Vec::new();
    for (name, f) in crate::gradient_error::figures(&r.gradient_error) {
        figs.push((name, "Fig. 4.2", f));
    }
    let it = |c: &Checkpoint| c.iteration as f64;
    let traj = |c: &Checkpoint| c.trajectories as f64;
    let gc = |c: &Checkpoint| c.gradient_evaluations as f64;
    type XAxis<'a> = (&'a str, Scale, &'a dyn Fn(&Checkpoint) -> f64);
    // The episodic control runs thousands of iterations and the oracle methods thousands of
    // trajectories, while BC, DAgger and the rows of 16 trajectories per gradient take a few dozen
    // to a few hundred: a log(1 + x) axis shows both, and keeps the checkpoint at 0.
    let by_iteration: XAxis<'_> = (
        "iteration (parameter updates, log scale of 1 + count)",
        Scale::Log1p,
        &it,
    );
    let by_trajectories: XAxis<'_> = (
        "expert-labelled trajectories rolled out (cumulative, log scale of 1 + count)",
        Scale::Log1p,
        &traj,
    );
    let obstacle_fig = |title: &str,
                        y: &str,
                        log_y: bool,
                        f: &dyn Fn(&Checkpoint) -> Option<f64>,
                        skip_dataset: bool,
                        (x_label, x_scale, xf): XAxis<'_>,
                        range: (f64, f64)| {
        let series: Vec<Series> = r
            .obstacle
            .iter()
            .filter(|c| !(skip_dataset && matches!(c.0.label.as_str(), "BC" | "DAgger")))
            .map(|c| band(&c.0, xf, f, (y, range_of(range))))
            .collect();
        let lines = baseline_lines(
            r,
            TaskKind::Obstacle,
            |c| f(c).unwrap_or(f64::NAN),
            &series,
            x_scale == Scale::Log1p,
        );
        Figure {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y.into(),
            x_scale,
            log_y,
            y_range: None,
            series: series.into_iter().chain(lines).collect(),
            panels: None,
            show_title: false,
            notes: vec![],
        }
        .clamped(range)
    };
    let n_obs = f64::from(profile.obstacle.eval_episodes);
    figs.push((
        "fig4-3-success",
        "Fig. 4.3",
        obstacle_fig(
            "Fig. 4.3: obstacle task, success rate of the deterministic policy (mean over seeds, 95% interval band; dashed: reference policies; one panel per algorithm)",
            "success rate (fraction of episodes)",
            false,
            &|c| Some(c.score()),
            false,
            by_trajectories,
            (0.0, 1.0),
        )
        // A dozen methods overlap at low success rates: one panel each.
        .in_panels(3),
    ));
    figs.push((
        "fig4-4-crashes",
        "Fig. 4.4",
        obstacle_fig(
            &format!("Fig. 4.4: obstacle task, crashes in {n_obs} evaluation episodes (mean over seeds, 95% interval band; dashed: reference policies; one panel per algorithm)"),
            &format!("crashes (episodes out of {n_obs})"),
            false,
            &|c| Some(f64::from(c.crashes())),
            false,
            by_trajectories,
            (0.0, n_obs),
        )
        .in_panels(3),
    ));
    // Figs. 4.5 (gradient-estimate rows, oracle methods only) and 4.6 (loss rows), against
    // iterations on a log y axis.
    type Metric<'a> = &'a dyn Fn(&Checkpoint) -> Option<f64>;
    let rows: [(&str, &str, String, &str, Metric<'_>, bool); 4] = [
        (
            "fig4-5a-gradient-x",
            "Fig. 4.5",
            " (a): obstacle task, norm of the x-row of the gradient estimate (oracle methods; mean over seeds, 95% interval band; one panel per algorithm)".into(),
            "‖gradient estimate, x-row‖ (log scale)",
            &|c| c.grad_x,
            true,
        ),
        (
            "fig4-5b-gradient-y",
            "Fig. 4.5",
            " (b): obstacle task, norm of the y-row of the gradient estimate (oracle methods; mean over seeds, 95% interval band; one panel per algorithm)".into(),
            "‖gradient estimate, y-row‖ (log scale)",
            &|c| c.grad_y,
            true,
        ),
        (
            "fig4-6a-loss-x",
            "Fig. 4.6",
            " (a): obstacle task, loss of the x velocity per decision (mean over seeds, 95% interval band; one panel per algorithm)".into(),
            "x-velocity squared error (log scale)",
            &|c| c.loss_x,
            false,
        ),
        (
            "fig4-6b-loss-y",
            "Fig. 4.6",
            " (b): obstacle task, loss of the y velocity per decision (mean over seeds, 95% interval band; one panel per algorithm)".into(),
            "y-velocity squared error (log scale)",
            &|c| c.loss_y,
            false,
        ),
    ];
    for (name, fig, what, y, f, oracle_only) in rows {
        figs.push((
            name,
            fig,
            obstacle_fig(
                &format!("{fig}{what}"),
                y,
                true,
                f,
                oracle_only,
                by_iteration,
                (0.0, f64::INFINITY),
            )
            // The norms of a dozen methods overlap over a decade: one panel each.
            .in_panels(3),
        ));
    }
    let cart_fig = |title: &str,
                    y: &str,
                    log_y: bool,
                    f: &dyn Fn(&Checkpoint) -> Option<f64>,
                    range: (f64, f64)| {
        // Checkpoints are evenly spaced in gradient calls: a linear axis in millions shows the
        // start (0 calls) of every algorithm alike.
        let series: Vec<Series> = r
            .cartpole
            .iter()
            .map(|c| band(&c.0, |k| gc(k) / 1e6, f, (y, range_of(range))))
            .collect();
        let lines = baseline_lines(
            r,
            TaskKind::Cartpole,
            |c| f(c).unwrap_or(f64::NAN),
            &series,
            false,
        );
        Figure {
            title: title.into(),
            x_label: "gradient calls (millions, cumulative)".into(),
            y_label: y.into(),
            x_scale: Scale::Linear,
            log_y,
            y_range: None,
            series: series.into_iter().chain(lines).collect(),
            panels: None,
            show_title: false,
            notes: vec![],
        }
        .clamped(range)
    };
    figs.push((
        "fig4-8-loss",
        "Fig. 4.8",
        cart_fig(
            "Fig. 4.8: CartPole, Brier loss per decision against the expert's action (mean over seeds, 95% interval band; dashed: reference policy; one panel per algorithm)",
            "Brier loss per decision",
            false,
            &|c| Some(c.loss()),
            (0.0, f64::INFINITY),
        )
        .in_panels(3),
    ));
    figs.push((
        "fig4-9-crashes",
        "Fig. 4.9",
        cart_fig(
            &format!(
                "Fig. 4.9: CartPole, resets until one full 500-step episode, capped at {} (mean over seeds, 95% interval band; one panel per algorithm)",
                profile.cartpole.full_episode_cap
            ),
            "resets before a full episode (count)",
            false,
            &|c| c.resets_to_full_episode.map(f64::from),
            (0.0, f64::from(profile.cartpole.full_episode_cap)),
        )
        // Most algorithms sit on the cap: one panel each, so none hides another.
        .in_panels(3),
    ));
    figs.push((
        "fig4-10-reward",
        "Fig. 4.10",
        cart_fig(
            "Fig. 4.10: CartPole, mean episode reward of the deterministic policy (mean over seeds, 95% interval band; dashed: reference policy; one panel per algorithm)",
            "episode reward (steps, max. 500)",
            false,
            &|c| Some(c.reward()),
            (0.0, 500.0),
        )
        .in_panels(3),
    ));
    for (_, _, f) in figs.iter_mut().filter(|(_, n, _)| *n != "Fig. 4.2") {
        f.title = with_divergence_key(&f.title);
    }
    figs
}

/// A learner figure's caption with the key to diverged runs, inside its closing parenthesis.
fn with_divergence_key(title: &str) -> String {
    const KEY: &str = "; ×: a run that diverged, at its last checkpoint, and \"(diverged k/n)\" after \
                       the algorithm's name; the band after it is over the other seeds";
    match title.strip_suffix(')') {
        Some(t) => format!("{t}{KEY})"),
        None => format!("{title} ({})", &KEY[2..]),
    }
}

/// Write `f` as SVG to `svg_path` (and `.png` next to it if `png`), atomically.
///
/// # Errors
/// [`Error::Experiment`] if drawing fails, [`Error::Io`] if writing fails.
fn write_figure(f: &Figure, svg_path: &Path, png: bool) -> Result<(), Error> {
    let plot_err = |e: String| Error::experiment(format!("plotting {}", svg_path.display()), e);
    let svg = f.to_svg().map_err(plot_err)?;
    crate::storage::write_atomic(svg_path, svg.as_bytes())?;
    if png {
        let png_bytes = render_png(&svg).map_err(plot_err)?;
        crate::storage::write_atomic(&svg_path.with_extension("png"), &png_bytes)?;
    }
    Ok(())
}

/// Write every figure as `dir/<name>.svg` (and `.png` when `png`); returns whether the PNGs
/// were written (a failed PNG rendering falls back to SVG only, with a warning).
///
/// # Errors
/// [`Error::Io`] or a plotting failure.
pub fn write_figures(figs: &[NamedFigure], dir: &Path, png: bool) -> Result<bool, Error> {
    let mut png_ok = png;
    for (name, _, f) in figs {
        match write_figure(f, &dir.join(format!("{name}.svg")), png_ok) {
            Ok(()) => {}
            Err(e) if png_ok => {
                eprintln!("warning: PNG rendering failed ({e}); writing SVG only");
                png_ok = false;
                write_figure(f, &dir.join(format!("{name}.svg")), false)?;
            }
            Err(e) => return Err(e),
        }
    }
    Ok(png_ok)
}
