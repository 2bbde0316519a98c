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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::run_dir::SeedRecord;
    use crate::run::config::TaskName;
    use ilopt_plot::band::t975;

    /// A checkpoint at `at` calls (iteration at / 10) with objective `y`.
    fn row(at: u64, y: f64) -> Row {
        let mut values = [None; 6];
        values[5] = Some(y);
        Row {
            at_calls: at,
            calls: at as f64 + 1.0,
            iteration: at as f64 / 10.0,
            values,
        }
    }

    fn seed(seed: u64, ys: &[f64], diverged: bool) -> SeedRecord {
        SeedRecord {
            seed,
            rows: ys
                .iter()
                .enumerate()
                .map(|(k, y)| row(100 * k as u64, *y))
                .collect(),
            diverged,
        }
    }

    fn run(seeds: Vec<SeedRecord>) -> RunDir {
        RunDir {
            path: "r".into(),
            task: TaskName::Toy,
            dataset_learner: false,
            seeds,
        }
    }

    #[test]
    fn the_band_is_the_student_t_interval_of_the_seeds() {
        let r = run(vec![
            seed(1, &[1.0, 0.1], false),
            seed(2, &[2.0, 0.2], false),
            seed(3, &[3.0, 0.9], false),
        ]);
        let c = curve(
            &r,
            "a",
            Metric::Objective,
            XAxis::Calls,
            (0.0, f64::INFINITY),
        );
        let s = &c.series;
        assert_eq!(s.x, vec![1.0, 101.0], "x: the mean gradient calls");
        assert_eq!(s.mean[0], 2.0);
        // s = 1 over n = 3: half-width t(0.975, 2)/√3 = 2.48 > 2, so the lower end is below 0.
        let hw = t975(2) / 3f64.sqrt();
        assert!((s.lo[0] - (2.0 - hw)).abs() < 1e-12 && (s.hi[0] - (2.0 + hw)).abs() < 1e-12);
        assert_eq!(
            c.clamped_ends, 2,
            "both checkpoints' lower ends are below 0"
        );
        assert!(s.shaded && s.diverged == 0 && s.runs == 3);
        let by_iteration = curve(&r, "a", Metric::Objective, XAxis::Iterations, (0.0, 1.0));
        assert_eq!(by_iteration.series.x, vec![0.0, 10.0]);
        // At the second checkpoint mean 0.4 and half-width 1.08: both ends leave [0, 1] too.
        assert_eq!(by_iteration.clamped_ends, 4, "and both upper ends above 1");
    }

    #[test]
    fn a_diverged_seed_is_crossed_and_later_means_are_over_the_others() {
        let r = run(vec![
            seed(1, &[1.0, 0.5, 0.25], false),
            seed(2, &[1.0, 7.0], true),
        ]);
        let c = curve(
            &r,
            "a",
            Metric::Objective,
            XAxis::Calls,
            (0.0, f64::INFINITY),
        );
        let s = &c.series;
        assert_eq!((s.diverged, s.runs), (1, 2));
        assert_eq!(s.diverged_at, vec![(101.0, 7.0)]);
        assert_eq!(s.mean, vec![1.0, 3.75, 0.25]);
        // The last checkpoint has one seed: no interval there.
        assert_eq!((s.lo[2], s.hi[2]), (0.25, 0.25));
        let one = run(vec![seed(4, &[1.0, 0.5], false)]);
        assert!(
            !curve(&one, "b", Metric::Objective, XAxis::Calls, (0.0, 1.0))
                .series
                .shaded
        );
    }
}
