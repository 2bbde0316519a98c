//! The appendix's rendering: the kit-vs-thesis speed-up table, the figures' clamping and tick
//! labels, and the theorem-check section built from check records, on hand-made numbers.

use ilopt_plot::{Figure, Marker, Scale, Series, Style, fmt_tick, style_for};
use paper_checks::config::TheorySize;
use paper_checks::experiment::{SeedTiming, TaskKind};
use paper_checks::pipeline::TheoryCache;
use paper_checks::report::blocks::{self, Block, Table};
use paper_checks::report::speedup::{
    SpeedupRow, TimeBasis, kit_time, speedup_cells, speedup_row, speedup_total,
};
use paper_checks::report::theory;
use paper_checks::results::ConfigTiming;
use paper_checks::results::TheoryTable;
use paper_checks::storage::{read_json, to_json, write_atomic};

fn timing(train: &[f64], converge: &[Option<f64>]) -> ConfigTiming {
    ConfigTiming {
        task: TaskKind::Obstacle,
        label: "STORM".into(),
        runs: train
            .iter()
            .zip(converge)
            .enumerate()
            .map(|(i, (t, c))| SeedTiming {
                seed: i as u64,
                seed_index: Some(i as u32),
                train_seconds: *t,
                evaluation_seconds: 0.0,
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
        x_scale: Scale::Linear,
        log_y,
        y_range: range,
        series: vec![s],
        panels: None,
        show_title: false,
        notes: vec![],
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
        x_scale: Scale::Linear,
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
        panels: None,
        show_title: false,
        notes: vec![],
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
        // On one plot and in small multiples alike.
        for panels in [None, Some(2)] {
            let mut f = figure_of(labels);
            f.panels = panels;
            let svg = f.to_svg().expect("draws");
            assert!(
                svg.to_uppercase().contains(&format!("STROKE=\"{storm}\"")),
                "STORM not in {storm} in {labels:?} ({panels:?})"
            );
        }
    }
    for panels in [None, Some(2)] {
        let mut f = figure_of(&["SGD", "Adam", "RMSProp", "DAgger"]);
        f.panels = panels;
        let without = f.to_svg().expect("draws").to_uppercase();
        assert!(
            !without.contains(&storm),
            "STORM's colour used without STORM ({panels:?})"
        );
    }
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

fn constant(
    name: &str,
    value: f64,
    provenance: ilopt_theory::constants::Provenance,
    how: &str,
) -> ilopt_theory::constants::Constant {
    ilopt_theory::constants::Constant {
        name: name.into(),
        value,
        rational: String::new(),
        provenance,
        how: how.into(),
        certificate: None,
        charts: vec![],
        attained: None,
    }
}

/// A thesis row with an erratum and a negative control that its check detects, sharing a
/// constant.
fn two_checks() -> Vec<ilopt_theory::check::Check> {
    use ilopt_theory::check::{Check, Measured, Method, Role, Verdict};
    use ilopt_theory::constants::Provenance;
    let lf = constant(
        "L_F",
        2.029554,
        Provenance::Rigorous,
        "interval branch-and-bound (727 boxes)",
    );
    let thesis = Check {
        id: "1a".into(),
        result: "(3.41)".into(),
        claim: "F smooth".into(),
        assumptions: vec![],
        constants: vec![
            lf.clone(),
            constant("B_F", 0.5, Provenance::Exact, "F(θ₁) − inf F over |θ| ≤ 1"),
        ],
        bound: Some(2.0),
        measured: Some(Measured::exact(1.0)),
        tightness: Some(0.5),
        method: Method::Rigorous,
        verdict: Verdict::Holds,
        erratum: Some("E2".into()),
        role: Role::Thesis,
        refuted_by_erratum: false,
        details: "first".into(),
    };
    let control = Check {
        id: "1a.control".into(),
        result: "(3.41)".into(),
        claim: "a bound a quarter of the true one".into(),
        assumptions: vec![],
        constants: vec![lf],
        bound: Some(0.5),
        measured: Some(Measured {
            value: 1.0,
            lcb: Some(0.75),
            ucb: None,
            runs: Some(100),
            alpha: Some(0.01),
            null_hypothesis: None,
            se: Some(0.1),
            resolution: None,
        }),
        tightness: None,
        method: Method::Statistical,
        verdict: Verdict::Fails,
        erratum: None,
        role: Role::NegativeControl,
        refuted_by_erratum: false,
        details: "second | x".into(),
    };
    vec![thesis, control]
}

fn tables(blocks: &[Block]) -> Vec<&Table> {
    blocks
        .iter()
        .filter_map(|b| match b {
            Block::Table(t) => Some(t),
            _ => None,
        })
        .collect()
}

#[test]
fn the_theory_section_is_rendered_from_the_check_records() {
    let checks = two_checks();
    let b = theory::blocks(
        &TheoryTable::Checks(checks.clone()),
        TheorySize::Quick,
        "tab:t",
    );
    let t = tables(&b);
    // The check table split in two, then the constants.
    assert_eq!(t.len(), 3, "{b:?}");
    assert_eq!(t[0].label, "tab:t-1-claims");
    assert_eq!(
        t[0].header,
        ["#", "result", "claim", "role", "verdict", "erratum"]
    );
    assert_eq!(
        t[0].rows,
        [
            ["1a", "(3.41)", "F smooth", "thesis", "**holds**", "E2"],
            [
                "1a.control",
                "(3.41)",
                "a bound a quarter of the true one",
                "negative control",
                "**fails**",
                "—"
            ],
        ]
    );
    assert_eq!(t[1].label, "tab:t-1-numbers");
    assert_eq!(
        t[1].rows,
        [
            [
                "1a",
                "rigorous",
                "2.000",
                "1.000",
                "—",
                "0.5000",
                "**holds**"
            ],
            [
                "1a.control",
                "statistical",
                "0.5000",
                "1.000 (0.7500)",
                "0.3342",
                "—",
                "**fails**"
            ],
        ]
    );
    // The power of the statistical row, the controls and the status.
    assert!(b.contains(&Block::List(vec![
        "**1a.control** (negative control): B = 0.5000, flags B < 0.7500, minimum detectable \
         violation 0.3342 → **fails**"
            .into()
    ])));
    assert!(b.contains(&Block::Para(
        "Uninformative or inconclusive rows (no evidence either way; not a failure of the status): none. Thesis claims refuted by their errata (expected to fail): none. Negative controls: 1a.control detected.".into()
    )));
    // Two rows alone are not the table's α family: the status names the claims not emitted.
    assert!(b.iter().any(|x| matches!(x, Block::Para(p)
        if p.starts_with("**Status: FAILS — α-family claim(s) not emitted: 1, 1b,"))));
    // Each constant once, with the checks using it; the details refer to it.
    let k = t[2];
    assert_eq!(k.label, "tab:t-constants");
    assert_eq!(
        k.rows,
        [
            [
                "K1",
                "L_F",
                "2.029554",
                "rigorous upper bound",
                "interval branch-and-bound (727 boxes)",
                "1a, 1a.control"
            ],
            [
                "K2",
                "B_F",
                "0.500000",
                "exact",
                "F(θ₁) − inf F over |θ| ≤ 1",
                "1a"
            ],
        ]
    );
    assert_eq!(
        b.last(),
        Some(&Block::List(vec![
            "**1a** first. Constants: K1, K2 (table of constants).".into(),
            "**1a.control** second \\| x. Constants: K1 (table of constants).".into(),
        ]))
    );
    let md = blocks::markdown(&b);
    assert_eq!(
        md.matches("interval branch-and-bound (727 boxes)").count(),
        1,
        "{md}"
    );
    // The errata table's column: the checks of each erratum.
    let by = theory::checks_by_erratum(&checks);
    assert_eq!(by.len(), 1);
    assert_eq!(by["E2"], ["1a"]);
}

#[test]
fn an_undetected_control_fails_the_status_and_no_table_is_a_note() {
    let mut checks = two_checks();
    checks[1].verdict = ilopt_theory::check::Verdict::Holds;
    let b = theory::blocks(&TheoryTable::Checks(checks), TheorySize::Quick, "tab:t");
    assert!(b.contains(&Block::Para(
        "Uninformative or inconclusive rows (no evidence either way; not a failure of the status): none. Thesis claims refuted by their errata (expected to fail): none. Negative controls: 1a.control NOT detected.".into()
    )));
    // The status names the undetected control (and, for these two rows alone, the α family's
    // claims that were not emitted).
    assert!(b.iter().any(|x| matches!(x, Block::Para(p)
        if p.starts_with("**Status: FAILS — negative control(s) not detected: 1a.control;")
            && p.contains("α-family claim(s) not emitted"))));
    let none = theory::blocks(&TheoryTable::NotRun, TheorySize::None, "tab:t");
    assert_eq!(none.len(), 1);
    assert!(matches!(&none[0], Block::Para(p) if p.starts_with("*Not run")));
    assert!(theory::checks_by_erratum(TheoryTable::NotRun.checks()).is_empty());
}

#[test]
fn the_theory_cache_round_trips_the_check_records() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let file = dir.path().join("theory.json");
    let cache = TheoryCache {
        key_hash: "0123456789abcdef".into(),
        checks: two_checks(),
    };
    write_atomic(&file, &to_json("theory cache", &cache).expect("serialises")).expect("writes");
    let back: TheoryCache = read_json(&file).expect("reads back");
    assert_eq!(back, cache);
    // The renderings of the records read back are those of the records computed.
    assert_eq!(
        ilopt_theory::report::markdown(&back.checks),
        ilopt_theory::report::markdown(&cache.checks)
    );
    // A cache of another shape (no records) is a miss, not an error.
    std::fs::write(&file, "{\"key_hash\": \"x\", \"markdown\": \"| # |\"}").expect("writes");
    assert!(read_json::<TheoryCache>(&file).is_none());
}

/// Fig. 4.9's situation: most algorithms sit on the cap, a few fall to 0, a reference line.
fn capped_panels() -> Figure {
    let x: Vec<f64> = (0..11).map(|k| f64::from(k) * 0.2).collect();
    let mut series: Vec<Series> = ALGORITHMS
        .iter()
        .enumerate()
        .map(|(a, label)| {
            let mut s = Series::new(*label);
            s.x.clone_from(&x);
            s.mean = x
                .iter()
                .map(|t| {
                    if a % 3 == 0 {
                        100.0 * (-3.0 * t).exp()
                    } else {
                        100.0
                    }
                })
                .collect();
            s.lo = s.mean.iter().map(|m| m - 15.0).collect();
            s.hi = s.mean.iter().map(|m| m + 15.0).collect();
            s
        })
        .collect();
    let mut reference = Series::new("Expert (PPO) (ref.)");
    reference.x = vec![0.0, 2.0];
    reference.mean = vec![0.0, 0.0];
    reference.lo.clone_from(&reference.mean);
    reference.hi.clone_from(&reference.mean);
    reference.reference = true;
    series.push(reference);
    Figure {
        title: "t".into(),
        x_label: "gradient calls (millions, cumulative)".into(),
        y_label: "resets before a full episode (count)".into(),
        x_scale: Scale::Linear,
        log_y: false,
        y_range: Some((0.0, 100.0)),
        series,
        panels: Some(3),
        show_title: false,
        notes: vec![],
    }
}

/// The text of every `<text>` element of an SVG written by plotters.
fn svg_texts(svg: &str) -> Vec<&str> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| t.split_once('>'))
        .filter_map(|(_, rest)| rest.split_once("</text>"))
        .map(|(text, _)| text.trim())
        .collect()
}

#[test]
fn small_multiples_draw_one_titled_panel_per_algorithm() {
    // PAPER_CHECKS_FIGURE_DIR keeps the files for a look; a temporary directory otherwise.
    let tmp = tempfile::tempdir().expect("temp dir");
    let dir = std::env::var_os("PAPER_CHECKS_FIGURE_DIR")
        .map_or_else(|| tmp.path().to_path_buf(), std::path::PathBuf::from);
    std::fs::create_dir_all(&dir).expect("figure dir");
    let svg_path = dir.join("small-multiples.svg");
    let svg = capped_panels().to_svg().expect("draws");
    let png = ilopt_plot::render_png(&svg).expect("renders");
    assert!(png.starts_with(b"\x89PNG"), "a PNG");
    std::fs::write(&svg_path, &svg).expect("writes the SVG");
    std::fs::write(dir.join("small-multiples.png"), &png).expect("writes the PNG");
    let texts = svg_texts(&svg);
    // One title per algorithm (titles may wrap: the words appear in order, once), the
    // reference line in the legend only, each axis described once.
    for label in ALGORITHMS {
        let hits = texts.iter().filter(|t| **t == label).count();
        let wrapped = texts
            .windows(2)
            .filter(|w| format!("{} {}", w[0], w[1]) == label)
            .count();
        assert_eq!(hits + wrapped, 1, "{label}: {texts:?}");
    }
    assert_eq!(
        texts
            .iter()
            .filter(|t| **t == "Expert (PPO) (ref.)")
            .count(),
        1
    );
    assert_eq!(
        texts
            .iter()
            .filter(|t| **t == "gradient calls (millions, cumulative)")
            .count(),
        1
    );
    assert_eq!(
        texts
            .iter()
            .filter(|t| **t == "resets before a full episode (count)")
            .count(),
        1
    );
    // Every panel draws the reference line: one dashed polyline pair per panel at least.
    let grey = hex(&style_for("Expert (PPO) (ref.)"));
    assert!(
        svg.to_uppercase()
            .matches(&format!("STROKE=\"{grey}\""))
            .count()
            >= ALGORITHMS.len()
    );
}

#[test]
fn small_multiples_without_a_drawn_algorithm_still_draw() {
    let mut f = capped_panels();
    f.series.retain(|s| s.reference);
    assert!(f.to_svg().expect("draws").contains("Expert (PPO) (ref.)"));
    f.series.clear();
    f.to_svg().expect("draws");
}

/// Two sections with figures, the figures of the first also used by the second.
fn sections_with_figures() -> Vec<Block> {
    let heading = |text: &str| Block::Heading {
        level: 2,
        text: text.into(),
    };
    let figure = |name: &str, caption: &str| Block::Figure {
        path: format!("figures/{name}.png"),
        caption: caption.into(),
    };
    let text = "Text of the section, long enough to fill a few lines of the page. ".repeat(12);
    vec![
        heading("Fig. 4.2: gradient error"),
        Block::Para(text.clone()),
        figure(
            "fig4-2b-gradient-error-obstacle",
            "Fig. 4.2 (b): obstacle task",
        ),
        Block::Para(text.clone()),
        heading("CartPole"),
        Block::Para(text.clone()),
        figure("fig4-9-crashes", "Fig. 4.9: CartPole, resets"),
        figure("fig4-2b-gradient-error-obstacle", "Fig. 4.10: again"),
        Block::Para(text),
        heading("After the figures"),
    ]
}

#[test]
fn latex_figures_float_but_stay_in_their_section() {
    // PAPER_CHECKS_LATEX_DIR keeps the documents (to build with pdflatex); a temporary
    // directory otherwise.
    let tmp = tempfile::tempdir().expect("temp dir");
    let dir = std::env::var_os("PAPER_CHECKS_LATEX_DIR")
        .map_or_else(|| tmp.path().to_path_buf(), std::path::PathBuf::from);
    std::fs::create_dir_all(&dir).expect("latex dir");
    paper_checks::report::document::write_documents(&sections_with_figures(), &dir)
        .expect("writes");
    let tex = std::fs::read_to_string(dir.join("appendix.tex")).expect("reads");
    assert_eq!(tex.matches("\\begin{figure}[htbp]").count(), 3, "{tex}");
    assert!(!tex.contains("[H]"), "{tex}");
    // A barrier before every heading, defined (unless the preamble did) before the first.
    assert_eq!(
        tex.matches("\\FloatBarrier\n\\subsection*").count(),
        3,
        "{tex}"
    );
    let defined = tex
        .find("\\providecommand{\\FloatBarrier}")
        .expect("defined");
    assert!(defined < tex.find("\\FloatBarrier\n").expect("used"));
    let standalone = std::fs::read_to_string(dir.join("appendix-standalone.tex")).expect("reads");
    assert!(!standalone.contains("float,"), "{standalone}");
    assert!(standalone.contains("\\input{appendix}"));
}

/// A curve with diverged runs says so in its panel title and draws a cross where each stopped;
/// the figure's note explains the cross.
#[test]
fn diverged_runs_are_marked_in_titles_and_with_crosses() {
    let mut f = capped_panels();
    f.series[1].runs = 3;
    f.series[1].diverged = 2;
    f.series[1].diverged_at = vec![(0.4, 100.0), (2.0, 150.0)];
    let crosses = f.diverged_points();
    assert_eq!(
        crosses[1],
        vec![(0.4, 100.0), (2.0, 100.0)],
        "clamped to the range"
    );
    assert!(crosses[0].is_empty());
    let svg = f.to_svg().expect("draws");
    let label = format!("{} (diverged 2/3)", ALGORITHMS[1]);
    let texts = svg_texts(&svg);
    assert!(texts.iter().any(|t| t.contains(&label)), "{texts:?}");
    assert!(
        texts.iter().any(|t| t.contains("× marks a diverged run")),
        "{texts:?}"
    );
    // Without diverged runs: neither the label nor the note.
    let plain = capped_panels().to_svg().expect("draws");
    assert!(!plain.contains("diverged"));
    // One plot with a legend: the legend entry carries the count.
    let mut single = capped_panels();
    single.panels = None;
    single.series[0].runs = 4;
    single.series[0].diverged = 1;
    single.series[0].diverged_at = vec![(1.0, 50.0)];
    let svg = single.to_svg().expect("draws");
    assert!(
        svg_texts(&svg)
            .iter()
            .any(|t| t.contains(&format!("{} (diverged 1/4)", ALGORITHMS[0]))),
        "{svg}"
    );
}
