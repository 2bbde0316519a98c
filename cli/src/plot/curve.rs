//! One run's curve: at each checkpoint, the mean of the metric over the seeds with the 95%
//! Student-t band `mean ± t_{0.975,n−1}·s/√n` ([`ilopt_plot::band::Summary`]), as the appendix
//! aligns its runs: by the nominal call count of the checkpoint, on the schedule of the seed
//! with the most checkpoints (a diverged seed stops early, and later means are over the others).

use super::metric::{Metric, XAxis};
use super::run_dir::{Row, RunDir};
use ilopt_plot::Series;
use ilopt_plot::band::Summary;

/// A run's series and how many of its band ends lie outside the metric's range (the figure
/// clamps them to it).
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// The series (label, points, band, diverged seeds).
    pub series: Series,
    /// Band ends outside the metric's range `[min, max]`.
    pub clamped_ends: usize,
}

/// The curve of `metric` against `x` over the seeds of `run`, labelled `label`; `range` is the
/// metric's range (band ends outside it are counted). With one seed there is no band. A
/// diverged seed adds a cross at its last checkpoint.
pub fn curve(run: &RunDir, label: &str, metric: Metric, x: XAxis, range: (f64, f64)) -> Curve {
    let xf = |r: &Row| match x {
        XAxis::Calls => r.calls,
        XAxis::Iterations => r.iteration,
    };
    let schedule: Vec<u64> = run
        .seeds
        .iter()
        .max_by_key(|s| s.rows.len())
        .map(|s| s.rows.iter().map(|r| r.at_calls).collect())
        .unwrap_or_default();
    let mut s = Series::new(label);
    s.runs = run.seeds.len();
    s.shaded = run.seeds.len() >= 2;
    for seed in run.seeds.iter().filter(|s| s.diverged) {
        s.diverged += 1;
        if let Some(r) = seed.rows.last()
            && let Some(y) = r.value(metric).filter(|y| y.is_finite())
        {
            s.diverged_at.push((xf(r), y));
        }
    }
    s.off_schedule = run
        .seeds
        .iter()
        .flat_map(|s| &s.rows)
        .filter(|r| !schedule.contains(&r.at_calls))
        .count();
    let mut clamped_ends = 0;
    for at in schedule {
        let rows: Vec<&Row> = run
            .seeds
            .iter()
            .filter_map(|s| s.rows.iter().find(|r| r.at_calls == at))
            .collect();
        let all: Vec<f64> = rows.iter().filter_map(|r| r.value(metric)).collect();
        let ys: Vec<f64> = all.iter().copied().filter(|y| y.is_finite()).collect();
        s.non_finite += all.len() - ys.len();
        if ys.is_empty() {
            continue;
        }
        let sm = Summary::of(&ys);
        let (lo, hi) = if sm.half_width.is_finite() {
            (sm.lo(), sm.hi())
        } else {
            (sm.mean, sm.mean)
        };
        clamped_ends += usize::from(lo < range.0) + usize::from(hi > range.1);
        s.x.push(rows.iter().map(|r| xf(r)).sum::<f64>() / rows.len() as f64);
        s.mean.push(sm.mean);
        s.lo.push(lo);
        s.hi.push(hi);
    }
    Curve {
        series: s,
        clamped_ends,
    }
}
