//! The figures' axes, styles and layout.

use super::*;

#[test]
fn log1p_keeps_zero_at_the_origin_and_puts_decades_near_integers() {
    assert_eq!(tr(0.0, Scale::Log1p), Some(0.0));
    assert_eq!(tr(-1.0, Scale::Log1p), None);
    assert_eq!(tr(f64::NAN, Scale::Log1p), None);
    for k in 0..7 {
        let d = 10f64.powi(k);
        // 1 + (10^k − 1) is a whole decade: exactly k.
        let p = tr(d - 1.0, Scale::Log1p).expect("drawn");
        assert!((p - f64::from(k)).abs() < 1e-12, "{k}: {p}");
        // The value 10^k itself sits log10(1 + 10^-k) above k, rounding to k.
        let p = tr(d, Scale::Log1p).expect("drawn");
        assert!((p - (f64::from(k) + (1.0 + 1.0 / d).log10())).abs() < 1e-12);
        assert_eq!(p.round(), f64::from(k));
    }
    // The other scales are unchanged.
    assert_eq!(tr(0.0, Scale::Log), None);
    assert_eq!(tr(100.0, Scale::Log), Some(2.0));
    assert_eq!(tr(-3.0, Scale::Linear), Some(-3.0));
}

#[test]
fn log1p_ticks_are_zero_and_whole_decades_labelled_with_the_value() {
    let end = tr(5700.0, Scale::Log1p).expect("drawn");
    let ticks = log1p_ticks(0.0, end);
    assert_eq!(ticks[0], 0.0, "0 at the origin");
    let labels: Vec<String> = ticks.iter().map(|v| fmt_log1p_tick(*v)).collect();
    assert_eq!(labels, ["0", "1", "10", "100", "1000"]);
    assert_eq!(tick_label(ticks[3], Scale::Log1p, end), "100");
    // A short axis also ticks 2× and 5× each decade.
    let short = log1p_ticks(0.0, tr(60.0, Scale::Log1p).expect("drawn"));
    let labels: Vec<String> = short.iter().map(|v| fmt_log1p_tick(*v)).collect();
    assert_eq!(labels, ["0", "1", "2", "5", "10", "20", "50"]);
    // An axis that starts after 0 has no tick at 0.
    let from_ten = log1p_ticks(tr(10.0, Scale::Log1p).expect("drawn"), end);
    assert_eq!(fmt_log1p_tick(from_ten[0]), "10");
    assert_eq!(fmt_log1p_tick(tr(2e7, Scale::Log1p).expect("drawn")), "1e7");
}

fn counts_figure(x: Vec<f64>) -> Figure {
    let mut s = Series::new("BC");
    s.mean = x.iter().map(|_| 0.5).collect();
    s.lo = x.iter().map(|_| 0.4).collect();
    s.hi = x.iter().map(|_| 0.6).collect();
    s.x = x;
    Figure {
        title: "t".into(),
        x_label: "trajectories (log scale of 1 + count)".into(),
        y_label: "y".into(),
        x_scale: Scale::Log1p,
        log_y: false,
        y_range: None,
        series: vec![s],
        panels: None,
        show_title: false,
        notes: vec![],
    }
}

#[test]
fn a_log1p_axis_draws_the_points_at_zero() {
    let fig = counts_figure(vec![0.0, 9.0, 99.0, 5700.0]);
    let (pts, notes) = fig.points();
    assert_eq!(pts[0].len(), 4, "every point drawn");
    assert_eq!(pts[0][0].0, 0.0);
    assert!((pts[0][2].0 - 2.0).abs() < 1e-12);
    assert!(notes.is_empty(), "{notes:?}");
    for f in [fig.clone(), fig.in_panels(3)] {
        let svg = f.to_svg().expect("draws");
        assert!(!svg.contains("not drawn"), "a point left out");
        for label in ["0", "1", "10", "100", "1000"] {
            assert!(svg.contains(&format!("\n{label}\n")), "no tick {label}");
        }
    }
    // A negative count cannot be drawn, and is noted.
    let (pts, notes) = counts_figure(vec![-1.0, 0.0, 10.0]).points();
    assert_eq!(pts[0].len(), 2);
    assert!(notes[0].contains("< 0 on a log(1 + x) axis"), "{notes:?}");
}
