//! The appendix's rendering: the kit-vs-thesis speed-up table and the figures' clamping and
//! tick labels, checked on hand-made numbers.

use paper_checks::experiment::{SeedTiming, TaskKind};
use paper_checks::pipeline::ConfigTiming;
use paper_checks::plots::{Figure, Marker, Series, Style, fmt_tick, style_for};
use paper_checks::report::speedup::{
    SpeedupRow, TimeBasis, kit_time, speedup_cells, speedup_row, speedup_total,
};

fn timing(train: &[f64], converge: &[Option<f64>]) -> ConfigTiming {
    ConfigTiming {
        task: TaskKind::Obstacle,
        label: "STORM".into(),
        runs: train
            .iter()
            .zip(converge)
            .enumerate()
            .map(|(i, (t, c))| SeedTiming {
                seed_index: i as u32,
                train_seconds: *t,
                checkpoint_seconds: vec![],
                converge_seconds: *c,
            })
            .collect(),
        wall_seconds: train.iter().sum(),
    }
}

#[test]
fn kit_time_is_to_converge_over_converged_seeds_else_none() {
    let t = timing(&[4.0, 6.0, 8.0], &[Some(1.0), None, Some(3.0)]);
    let (s, basis) = kit_time(&t);
    assert_eq!(s.mean, 2.0);
    assert_eq!(s.n, 2);
    assert_eq!(
        basis,
        TimeBasis::ToConverge {
            converged: 2,
            seeds: 3
        }
    );
    let never = timing(&[4.0, 6.0, 8.0], &[None, None, None]);
    let (s, basis) = kit_time(&never);
    assert_eq!(s.n, 0);
    assert_eq!(basis, TimeBasis::WholeRun { seeds: 3 });
    assert_eq!(basis.text(), "— (0/3 converged)");
}

#[test]
fn speed_up_is_thesis_over_kit_with_a_total_row() {
    let thesis = [("STORM", 561.37), ("SGD", 786.64)];
    let storm = timing(&[4.0, 6.0], &[Some(2.0), Some(4.0)]); // mean 3 s to converge
    let sgd = timing(&[1.0, 3.0], &[None, None]); // never converged: no ratio
    let rows: Vec<SpeedupRow> = vec![
        speedup_row("STORM", Some(&storm), &thesis),
        speedup_row("SGD", Some(&sgd), &thesis),
        speedup_row("IS-STORM", Some(&sgd), &thesis), // no thesis number
        speedup_row("Adam", None, &thesis),           // no timing file
    ];
    assert_eq!(rows[0].ratio(), Some(561.37 / 3.0));
    assert_eq!(rows[1].ratio(), None);
    assert_eq!(rows[2].ratio(), None);
    assert_eq!(rows[3].ratio(), None);
    let (kit, th, ratio, n) = speedup_total(&rows);
    assert_eq!((kit, th, n), (3.0, 561.37, 1));
    assert_eq!(ratio, Some(561.37 / 3.0));
    let cells = speedup_cells("4.2", &rows);
    assert_eq!(cells.len(), 5);
    assert_eq!(cells[0][1], "STORM");
    assert_eq!(cells[0][3], "to converge (2/2 seeds)");
    assert_eq!(cells[0][5], "187.1×");
    assert_eq!(cells[1][3], "— (0/2 converged)");
    assert_eq!(cells[1][5], "—");
    assert_eq!(cells[2][5], "—");
    assert_eq!(cells[3][3], "no timing file");
    assert_eq!(cells[4][1], "total (1 algorithms with both times)");
    assert_eq!(cells[4][5], "187.1×");
}

fn figure(range: Option<(f64, f64)>, log_y: bool) -> Figure {
    let mut s = Series::new("rate");
    s.x = vec![0.0, 1.0, 2.0, 3.0];
    s.mean = vec![0.05, 0.5, 0.95, f64::NAN];
    s.lo = vec![-0.2, 0.3, 0.8, f64::NAN];
    s.hi = vec![0.3, 0.7, 1.3, f64::NAN];
    Figure {
        title: "t".into(),
        x_label: "x".into(),
        y_label: "y".into(),
        log_x: false,
        log_y,
        y_range: range,
        series: vec![s],
    }
}

#[test]
fn bands_are_clamped_to_the_physical_range_and_non_finite_points_noted() {
    let (pts, notes) = figure(Some((0.0, 1.0)), false).points();
    assert_eq!(pts.len(), 1);
    // The NaN point is skipped, not the series.
    assert_eq!(pts[0].len(), 3);
    assert_eq!(pts[0][0], (0.0, 0.05, Some(0.0), 0.3));
    assert_eq!(pts[0][2], (2.0, 0.95, Some(0.8), 1.0));
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("rate 1"), "{notes:?}");
    // Unclamped, the band leaves [0, 1].
    let (pts, _) = figure(None, false).points();
    assert_eq!(pts[0][0].2, Some(-0.2));
    assert_eq!(pts[0][2].3, 1.3);
    // On a log axis a lower end clamped to 0 runs to the bottom of the axis.
    let (pts, _) = figure(Some((0.0, 1.0)), true).points();
    assert_eq!(pts[0][0].2, None);
    // The SVG draws the note.
    let svg = figure(Some((0.0, 1.0)), false).to_svg().expect("draws");
    assert!(svg.contains("points not drawn"), "no note in the SVG");
    assert!(svg.contains("\nrate\n"), "no legend entry in the SVG");
}

#[test]
fn ticks_near_zero_print_as_zero() {
    assert_eq!(fmt_tick(-5.6e-17, false, 0.7), "0");
    assert_eq!(fmt_tick(0.1, false, 0.7), "0.1");
    assert_eq!(fmt_tick(2e-4, false, 1e-3), "2.0e-4");
    assert_eq!(fmt_tick(2.0, true, 3.0), "100");
    assert_eq!(fmt_tick(50.0, true, 300.0), "1e50");
    assert_eq!(fmt_tick(0.5, true, 2.0), "3.2");
}

/// The algorithms of the committed profiles.
const ALGORITHMS: [&str; 10] = [
    "BC",
    "DAgger",
    "DAgger (minibatch)",
    "SGD",
    "Adam",
    "Adam (episodic objective)",
    "RMSProp",
    "STORM",
    "IS-STORM (trajectory)",
    "IS-STORM (per-decision)",
];

fn hex(s: &Style) -> String {
    let c = s.color;
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

fn figure_of(labels: &[&str]) -> Figure {
    Figure {
        title: "t".into(),
        x_label: "x".into(),
        y_label: "y".into(),
        log_x: false,
        log_y: false,
        y_range: None,
        series: labels
            .iter()
            .map(|l| {
                let mut s = Series::new(*l);
                s.x = vec![0.0, 1.0];
                s.mean = vec![0.2, 0.4];
                s.lo = vec![0.1, 0.3];
                s.hi = vec![0.3, 0.5];
                s
            })
            .collect(),
    }
}

#[test]
fn each_algorithm_keeps_its_colour_and_marker_in_every_figure() {
    // Every algorithm is told apart from every other by colour, marker, fill or line.
    let styles: Vec<Style> = ALGORITHMS.iter().map(|a| style_for(a)).collect();
    for i in 0..styles.len() {
        for j in i + 1..styles.len() {
            assert_ne!(
                styles[i], styles[j],
                "{} and {}",
                ALGORITHMS[i], ALGORITHMS[j]
            );
        }
    }
    // The style is a function of the name, not of the series' position: STORM is drawn in its
    // colour first, last or alone, and a figure without STORM does not use that colour.
    let storm = hex(&style_for("STORM"));
    for labels in [
        &["STORM", "SGD"][..],
        &["SGD", "Adam", "RMSProp", "STORM"][..],
        &["STORM"][..],
    ] {
        let svg = figure_of(labels).to_svg().expect("draws");
        assert!(
            svg.to_uppercase().contains(&format!("STROKE=\"{storm}\"")),
            "STORM not in {storm} in {labels:?}"
        );
    }
    let without = figure_of(&["SGD", "Adam", "RMSProp", "DAgger"])
        .to_svg()
        .expect("draws")
        .to_uppercase();
    assert!(
        !without.contains(&storm),
        "STORM's colour used without STORM"
    );
    // Reference lines are grey and carry no marker.
    for r in [
        "Expert (VO) (ref.)",
        "Straight to goal (ref.)",
        "Expert (PPO) (ref.)",
    ] {
        let s = style_for(r);
        assert_eq!(s.marker, Marker::None, "{r}");
        assert!(
            s.color.0 == s.color.1 && s.color.1 == s.color.2,
            "{r} not grey"
        );
    }
}

#[test]
fn the_legend_lists_only_drawn_series() {
    let mut f = figure_of(&["SGD", "STORM"]);
    // STORM has no finite point: it is not drawn, so it is not in the legend.
    f.series[1].mean = vec![f64::NAN, f64::NAN];
    let svg = f.to_svg().expect("draws");
    assert!(svg.contains("\nSGD\n"), "SGD missing from the legend");
    assert!(
        !svg.contains("\nSTORM\n"),
        "an undrawn series in the legend"
    );
}
