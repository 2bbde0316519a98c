//! Fig. 4.2 for the appendix: its figures, data file, slope sentence, table rows and description.

use super::{GradientError, GradientErrorResult, RmsePoint, RouteResult};

/// Fig. 4.2's figures: (file stem, figure), (a) toy, (b) obstacle.
pub fn figures(r: &GradientErrorResult) -> Vec<(&'static str, ilopt_plot::Figure)> {
    use ilopt_plot::{Figure, Scale, Series};
    let x = |route: &RouteResult| route.rmse.iter().map(|p| p.n as f64).collect::<Vec<_>>();
    let band = |route: &RouteResult, label: &str, corrected: bool| {
        let mut s = Series::new(label);
        s.x = x(route);
        for p in &route.rmse {
            let (m, lo, hi) = if corrected {
                (p.corrected, p.corrected_lo, p.corrected_hi)
            } else {
                (p.raw, p.raw_lo, p.raw_hi)
            };
            s.mean.push(m);
            s.lo.push(lo);
            s.hi.push(hi);
        }
        s
    };
    let dashed = |label: String, xs: Vec<f64>, ys: Vec<f64>| {
        let mut s = Series::new(label);
        s.x = xs;
        s.lo.clone_from(&ys);
        s.hi.clone_from(&ys);
        s.mean = ys;
        s.reference = true;
        s
    };
    let line = |route: &RouteResult, label: &str| {
        dashed(
            label.into(),
            x(route),
            route.rmse.iter().map(|p| p.line).collect(),
        )
    };
    let t = &r.toy;
    let o = &r.obstacle;
    let reps = t.squared_errors.len();
    let mut out = vec![(
        "fig4-2a-gradient-error-toy",
        Figure {
            title: format!(
                "Fig. 4.2 (a): toy MDP, RMSE of the mean of N gradient estimates against the exact ∇F over {reps} repetitions (95% CI band; dashed: σ/√N); fitted slope {} [{}, {}]",
                fmt3(t.slope.estimate),
                fmt3(t.slope.lo),
                fmt3(t.slope.hi)
            ),
            x_label: "N, trajectories averaged (log scale)".into(),
            y_label: "RMSE of mean gradient (log scale)".into(),
            x_scale: Scale::Log,
            log_y: true,
            y_range: Some((0.0, f64::INFINITY)),
            series: vec![band(t, "RMSE (95% CI)", false), line(t, "σ/√N (exact σ)")],
            panels: None,
            show_title: false,
            notes: vec![],
        },
    )];
    let m = o.reference_trajectories.unwrap_or(0);
    let floor = o.reference_variance.sqrt();
    let (x0, x1) = (
        o.ns.first().copied().unwrap_or(1) as f64,
        o.ns.last().copied().unwrap_or(1) as f64,
    );
    out.push((
        "fig4-2b-gradient-error-obstacle",
        Figure {
            title: format!(
                "Fig. 4.2 (b): obstacle task, RMSE of the mean of N gradient estimates against an M = {m} trajectory reference over {} repetitions (95% CI bands; dashed: σ̂/√N and the reference's standard error); fitted slope {} [{}, {}]",
                o.squared_errors.len(),
                fmt3(o.slope.estimate),
                fmt3(o.slope.lo),
                fmt3(o.slope.hi)
            ),
            x_label: "N, trajectories averaged (log scale)".into(),
            y_label: "RMSE of mean gradient (log scale)".into(),
            x_scale: Scale::Log,
            log_y: true,
            y_range: Some((0.0, f64::INFINITY)),
            series: vec![
                band(o, "vs reference (95% CI)", false),
                band(o, "− ref. variance (95% CI)", true),
                line(o, "σ̂/√N"),
                dashed("reference SE σ̂/√M".into(), vec![x0, x1], vec![floor, floor]),
            ],
            // The two estimates and σ̂/√N nearly coincide: one panel each, side by side.
            panels: Some(2),
            show_title: false,
            notes: vec![],
        },
    ));
    out
}

pub(super) fn fmt3(v: f64) -> String {
    format!("{v:.3}")
}

/// The per-repetition data as CSV: `route,repetition,n,block,squared_error`.
pub fn csv(r: &GradientErrorResult) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("route,repetition,n,block,squared_error\n");
    for (name, route) in [("toy", &r.toy), ("obstacle", &r.obstacle)] {
        for (rep, rows) in route.squared_errors.iter().enumerate() {
            for (n, blocks) in route.ns.iter().zip(rows) {
                for (b, v) in route.blocks.iter().zip(blocks) {
                    let _ = writeln!(s, "{name},{rep},{n},{b},{v}");
                }
            }
        }
    }
    s
}

/// One route's slope as text: `−0.501 [−0.52, −0.48] (n = 100 repetitions, N = 1…10000)`.
pub fn slope_text(route: &RouteResult) -> String {
    format!(
        "{} [{}, {}] (95% bootstrap CI, n = {} repetitions, N = {}…{})",
        fmt3(route.slope.estimate),
        fmt3(route.slope.lo),
        fmt3(route.slope.hi),
        route.slope.n,
        route.ns.first().copied().unwrap_or(0),
        route.ns.last().copied().unwrap_or(0)
    )
}

/// The rows of a route's table: N, RMSE \[CI\], corrected RMSE \[CI\] (obstacle), σ/√N, ratio.
pub fn table_rows(route: &RouteResult) -> Vec<Vec<String>> {
    let g = |v: f64| {
        if v.is_finite() {
            format!("{v:.4e}")
        } else {
            "—".into()
        }
    };
    route
        .rmse
        .iter()
        .map(|p| {
            let mut row = vec![
                p.n.to_string(),
                format!("{} [{}, {}]", g(p.raw), g(p.raw_lo), g(p.raw_hi)),
            ];
            if route.reference_trajectories.is_some() {
                row.push(format!(
                    "{} [{}, {}]",
                    g(p.corrected),
                    g(p.corrected_lo),
                    g(p.corrected_hi)
                ));
            }
            row.push(g(p.line));
            row.push(format!("{:.3}", p.corrected / p.line));
            row
        })
        .collect()
}

/// The N whose 95% interval (reference variance removed) misses σ/√N, said in words, with the
/// exact spread of one squared error when known (toy route).
pub(super) fn coverage_note(route: &RouteResult, reps: u32) -> String {
    let missed: Vec<&RmsePoint> = route
        .rmse
        .iter()
        .filter(|p| !(p.corrected_lo <= p.line && p.line <= p.corrected_hi))
        .collect();
    if missed.is_empty() {
        return String::new();
    }
    let which = if route.reference_trajectories.is_some() {
        "(b)"
    } else {
        "(a)"
    };
    let list: Vec<String> = missed
        .iter()
        .map(|p| format!("{} ({:.3} × σ/√N)", p.n, p.corrected / p.line))
        .collect();
    let exact = match (route.squared_error_sd_n1, route.rmse.first()) {
        (Some(sd), Some(p)) if p.n == 1 => format!(
            " One squared error ‖g − ∇F‖² has the exact standard deviation {sd:.3} against its mean \
             σ² = {:.3}; the N = 1 mean over the {reps} streams is {:+.1} exact standard errors from σ².",
            route.sigma2,
            (p.raw * p.raw - route.sigma2) / (sd / f64::from(reps).sqrt())
        ),
        _ => String::new(),
    };
    format!(
        "Coverage, route {which}: σ/√N lies outside the 95% interval at {} of {} sample sizes: N = {}. \
         The squared error is right-skewed, so the t interval can undercover at small N, and the \
         N of one stream are nested (its first draws enter every N), so neighbouring N err \
         together; the slope's bootstrap resamples whole streams and keeps that dependence.{exact} ",
        missed.len(),
        route.rmse.len(),
        list.join(", ")
    )
}

/// The appendix's text for Fig. 4.2 (Markdown inline).
pub fn description(g: &GradientError, r: &GradientErrorResult) -> String {
    let (t, o) = (&r.toy, &r.obstacle);
    format!(
        "The thesis claims that the mean of N eq. 3.15 estimates approaches ∇F at the rate 1/√N. \
         Each route draws {reps} independent streams of estimates (causal form, f64, each stream \
         from its own derived seed); the RMSE at N is √(mean over the streams of ‖mean of the first \
         N estimates − reference‖²), with a 95% Student-t interval on the mean squared error mapped \
         through √. The dashed line is σ/√N, with σ² = E‖g‖² − ‖∇F‖² — not fitted, not anchored at \
         N = 1. The slope is the least-squares slope of log RMSE vs log N over every N; its 95% \
         interval is the percentile bootstrap over the streams ({boot} resamples). \
         **(a) Toy MDP** (`{mdp}`, θ = ({theta})): the reference is ∇F computed in exact rationals \
         by the exact engine's forward DP (the `gradient` of `ilopt toy eval`), with no noise; \
         σ² = {s2e} ≈ {s2:.6}, exact (E‖g‖² by enumerating every trajectory). Slope {ts}. \
         **(b) Obstacle task** under the thesis's fixed-horizon objective (T = {h} decisions, \
         absorbing ends: success 0, crash (2·v_max)² per remaining step), linear-Gaussian learner \
         (σ_π = {sigma}) over the 9 basic features at a fixed θ (a proportional pull towards the \
         goal): the reference is the mean of M = {m} independent estimates (its own seed stream), \
         σ̂² = {os2:.6e} is their sample variance (trace), and the reference's own standard error \
         σ̂/√M = {se:.4e} is drawn as a floor. Because the reference is independent of the streams, \
         E‖ḡ_N − R‖² = σ²/N + σ²/M; the band \"− ref. variance\" and the slope use \
         √(MSE − σ̂²/M) (the two bands coincide to the eye when M ≫ N). Slope {os}; by row of the gradient (the thesis's panels (a) and (b)): {blocks}. {times}\
         {n1}(Data: `gradient_error.csv`, one row per stream, N and gradient block.)",
        reps = g.repetitions,
        boot = g.bootstrap,
        mdp = g.toy.mdp,
        theta = g.toy.theta.join(", "),
        s2e = t.sigma2_exact.as_deref().unwrap_or("—"),
        s2 = t.sigma2,
        ts = slope_text(t),
        h = g.obstacle.horizon,
        sigma = g.obstacle.sigma,
        m = g.obstacle.reference_trajectories,
        os2 = o.sigma2,
        se = o.reference_variance.sqrt(),
        os = slope_text(o),
        blocks = o
            .block_slopes
            .iter()
            .map(|(b, s)| format!("{b} {} [{}, {}]", fmt3(s.estimate), fmt3(s.lo), fmt3(s.hi)))
            .collect::<Vec<_>>()
            .join(", "),
        n1 = coverage_note(t, g.repetitions) + &coverage_note(o, g.repetitions),
        times = if t.seconds > 0.0 {
            format!(
                "Run times: toy {:.1} s, obstacle {:.1} s. ",
                t.seconds, o.seconds
            )
        } else {
            "Reused from an earlier run (times in `timings/gradient-error.json`). ".into()
        },
    )
}
