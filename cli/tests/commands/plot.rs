//! `ilopt plot`: two small runs drawn overlaid and in panels (one mean line and one band per
//! run, in the run's fixed colour), one seed without a band, diverged runs marked, PNG output,
//! and one named error per bad input.

use crate::ROOT;
use crate::support::{Scratch, ilopt};
use std::path::{Path, PathBuf};

/// A toy run of `algorithm` (TOML lines) over `seeds` into `dir/name`: 300 calls, a checkpoint
/// every 30 (11 checkpoints).
fn toy_run(dir: &Path, name: &str, algorithm: &str, seeds: &str, extra_run: &str) -> PathBuf {
    let mdp = format!("{ROOT}/examples/toy/three-state.json").replace('\\', "/");
    let config = format!(
        "[task]\nname = \"toy\"\nmdp = \"{mdp}\"\n\n[algorithm]\n{algorithm}\n\n[run]\nbudget_calls = 300\nseeds = {seeds}\ntheta0 = [1, 1, 1, 1, 1, 1]\n{extra_run}\n\n[evaluation]\nevery_calls = 30\n"
    );
    let cfg = dir.join(format!("{name}.toml"));
    std::fs::write(&cfg, config).unwrap();
    let out = dir.join(name);
    let (code, _, stderr) = ilopt(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    out
}

const SGD: &str =
    "algorithm = \"sgd\"\nform = \"causal\"\nstep = { kind = \"constant\", eta = 0.2 }";
const ADAM: &str = "algorithm = \"adam\"\nform = \"causal\"\nalpha = 0.05\nbeta1 = 0.9\nbeta2 = 0.999\nepsilon = 1e-8";
const BC: &str = "algorithm = \"bc\"\ntrajectories_per_iteration = 1\nretrain = \"warm-start\"\ninner = { iterations = 5, rule = { rule = \"sgd\", step = { kind = \"constant\", eta = 0.1 } } }";

/// An SVG element's attribute (`element` as [`elements`] gives it, from the space after the tag).
fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let start = element.find(&format!(" {name}=\""))? + name.len() + 3;
    element[start..].split('"').next()
}

/// The elements `<tag …>` of an SVG: their attributes, each after a space.
fn elements<'a>(svg: &'a str, tag: &str) -> Vec<&'a str> {
    let open = format!("<{tag}");
    svg.split(&open)
        .skip(1)
        .filter(|e| e.starts_with(' '))
        .filter_map(|e| e.split('>').next())
        .collect()
}

/// Per colour (`#RRGGBB`): the mean lines (solid, 2 px, at least 8 points: the markers'
/// outlines have at most 5) and the band fills (translucent polygons).
fn lines_and_bands(svg: &str, color: &str) -> (usize, usize) {
    let lines = elements(svg, "polyline")
        .into_iter()
        .filter(|e| {
            attr(e, "stroke") == Some(color)
                && attr(e, "stroke-width") == Some("2")
                && attr(e, "opacity") == Some("1")
                && attr(e, "points").is_some_and(|p| p.split_whitespace().count() >= 8)
        })
        .count();
    let bands = elements(svg, "polygon")
        .into_iter()
        .filter(|e| {
            attr(e, "fill") == Some(color)
                && attr(e, "opacity").is_some_and(|o| o.parse::<f64>().is_ok_and(|o| o < 0.5))
        })
        .count();
    (lines, bands)
}

/// The text of every `<text>` element.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| t.split_once('>'))
        .filter_map(|(_, rest)| rest.split_once("</text>"))
        .map(|(text, _)| text.trim().to_string())
        .collect()
}

/// The first two colours of `ilopt_plot::by_position`: Okabe–Ito blue and vermillion.
const FIRST: &str = "#0072B2";
const SECOND: &str = "#D55E00";

#[test]
fn two_runs_overlaid_and_in_panels_draw_one_line_and_one_band_each() {
    let s = Scratch::new("two");
    let sgd = toy_run(s.path(), "sgd", SGD, "[1, 2, 3]", "");
    let adam = toy_run(s.path(), "adam", ADAM, "[1, 2, 3]", "");
    for layout in ["overlay", "panels"] {
        let out = s.path().join(format!("{layout}.svg"));
        let (code, stdout, stderr) = ilopt(&[
            "plot",
            sgd.to_str().unwrap(),
            adam.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--layout",
            layout,
            "--labels",
            "SGD (η = 0.2),Adam",
            "--title",
            "Two toy runs",
        ]);
        assert_eq!(code, 0, "{stderr}");
        let summary: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(summary["metric"], "objective", "the toy task's default");
        assert_eq!(summary["runs"][1]["label"], "Adam");
        assert_eq!(summary["runs"][0]["checkpoints"], 11);
        let svg = std::fs::read_to_string(&out).unwrap();
        for color in [FIRST, SECOND] {
            assert_eq!(lines_and_bands(&svg, color), (1, 1), "{layout}, {color}");
        }
        let t = texts(&svg);
        assert!(t.iter().any(|x| x == "Two toy runs"), "{layout}: title");
        assert!(t.iter().any(|x| x == "SGD (η = 0.2)"), "{layout}: label");
        let notes = t.join(" ");
        assert!(notes.contains("95% Student-t interval"), "{notes}");
        assert!(
            notes.contains("clamped to the range of objective [0, ∞)"),
            "{notes}"
        );
    }
    // The first run keeps its colour when the second changes.
    let out = s.path().join("swapped.svg");
    let (code, _, stderr) = ilopt(&[
        "plot",
        sgd.to_str().unwrap(),
        sgd.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--x",
        "iterations",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(&out).unwrap();
    assert_eq!(lines_and_bands(&svg, FIRST), (1, 1));
    assert_eq!(lines_and_bands(&svg, SECOND), (1, 1));
    // Two directories of the same name are told apart by their paths.
    assert!(texts(&svg).iter().any(|t| t.ends_with("sgd")));
}

#[test]
fn one_seed_has_no_band_and_diverged_seeds_are_marked() {
    let s = Scratch::new("seeds");
    let one = toy_run(s.path(), "one", SGD, "[5]", "");
    // η = 10⁴ leaves ‖θ‖ ≤ 2·10⁴ within two steps: both seeds diverge after their checkpoint at 0.
    let huge = SGD.replace("eta = 0.2", "eta = 1e4");
    let wild = toy_run(s.path(), "wild", &huge, "[7, 8]", "norm_bound = 2e4");
    let out = s.path().join("f.svg");
    let (code, stdout, stderr) = ilopt(&[
        "plot",
        one.to_str().unwrap(),
        wild.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--metric",
        "objective",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(summary["runs"][1]["diverged"], 2);
    let svg = std::fs::read_to_string(&out).unwrap();
    assert_eq!(lines_and_bands(&svg, FIRST), (1, 0), "one seed: no band");
    let t = texts(&svg);
    assert!(t.iter().any(|x| x == "wild (diverged 2/2)"), "{t:?}");
    let notes = t.join(" ");
    assert!(notes.contains("one seed, no band: one"), "{notes}");
    assert!(notes.contains("× marks a diverged run"), "{notes}");
    // Each diverged seed's cross: two white halo strokes and two coloured strokes.
    let crosses = elements(&svg, "polyline")
        .into_iter()
        .filter(|e| attr(e, "stroke") == Some(SECOND) && attr(e, "stroke-width") == Some("3"))
        .count();
    assert_eq!(crosses, 2 * 2, "two crosses");
}

#[test]
fn a_png_is_rendered_from_the_svg() {
    let s = Scratch::new("png");
    let run = toy_run(s.path(), "sgd", SGD, "[1, 2]", "");
    let out = s.path().join("f.PNG");
    let (code, _, stderr) = ilopt(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let bytes = std::fs::read(&out).unwrap();
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "a PNG file");
}

#[test]
fn bad_inputs_get_one_named_error_each() {
    let s = Scratch::new("errors");
    let sgd = toy_run(s.path(), "sgd", SGD, "[1, 2]", "");
    let bc = toy_run(s.path(), "bc", BC, "[1, 2]", "");
    let no_seeds = s.path().join("no-seeds");
    std::fs::create_dir_all(&no_seeds).unwrap();
    std::fs::copy(sgd.join("config.toml"), no_seeds.join("config.toml")).unwrap();
    let one_missing = s.path().join("one-missing");
    std::fs::create_dir_all(&one_missing).unwrap();
    for f in ["config.toml", "seed-1.csv", "seed-1.json"] {
        std::fs::copy(sgd.join(f), one_missing.join(f)).unwrap();
    }
    let cartpole = s.path().join("cartpole");
    std::fs::create_dir_all(&cartpole).unwrap();
    std::fs::write(
        cartpole.join("config.toml"),
        "[task]\nname = \"cartpole\"\n[algorithm]\nalgorithm = \"sgd\"\nform = \"causal\"\nstep = { kind = \"constant\", eta = 0.1 }\n[run]\nbudget_calls = 10\nseeds = [1]\n",
    )
    .unwrap();
    for f in ["seed-1.csv", "seed-1.json"] {
        std::fs::copy(sgd.join(f), cartpole.join(f)).unwrap();
    }
    let bad_cell = s.path().join("bad-cell");
    std::fs::create_dir_all(&bad_cell).unwrap();
    for f in ["config.toml", "seed-1.json", "seed-2.json", "seed-2.csv"] {
        std::fs::copy(sgd.join(f), bad_cell.join(f)).unwrap();
    }
    let csv = std::fs::read_to_string(sgd.join("seed-1.csv")).unwrap();
    std::fs::write(bad_cell.join("seed-1.csv"), csv.replacen(",1.5", ",x", 1)).unwrap();

    let p = |d: &Path| d.to_str().unwrap().to_string();
    let svg = p(&s.path().join("f.svg"));
    let nowhere = p(&s.path().join("nowhere"));
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (
            vec![nowhere.clone(), "--out".into(), svg.clone()],
            vec![nowhere.as_str(), "no such directory"],
        ),
        (
            vec![p(s.path()), "--out".into(), svg.clone()],
            vec!["no config.toml"],
        ),
        (
            vec![p(&no_seeds), "--out".into(), svg.clone()],
            vec!["no-seeds", "no seed files", "[1, 2]"],
        ),
        (
            vec![p(&one_missing), "--out".into(), svg.clone()],
            vec!["seed-2.csv", "missing"],
        ),
        (
            vec![p(&bad_cell), "--out".into(), svg.clone()],
            vec![
                "seed-1.csv",
                "line 2",
                "`objective` = \"x\" is not a number",
            ],
        ),
        (
            vec![
                p(&sgd),
                "--out".into(),
                svg.clone(),
                "--metric".into(),
                "score".into(),
            ],
            vec![
                "no `score` values",
                "toy run records train_loss, gradient_norm, objective",
            ],
        ),
        (
            vec![
                p(&sgd),
                p(&bc),
                "--out".into(),
                svg.clone(),
                "--x".into(),
                "iterations".into(),
            ],
            vec!["mixed x axes", "bc", "use --x calls"],
        ),
        (
            vec![p(&sgd), p(&cartpole), "--out".into(), svg.clone()],
            vec!["mixed tasks", "toy", "cartpole"],
        ),
        (
            vec![p(&sgd), "--out".into(), p(&s.path().join("f.pdf"))],
            vec!["f.pdf", "must end in .svg or .png"],
        ),
        (
            vec![
                p(&sgd),
                p(&bc),
                "--out".into(),
                svg.clone(),
                "--labels".into(),
                "a".into(),
            ],
            vec!["--labels gives 1 labels for 2 run directories"],
        ),
        (
            vec![
                p(&sgd),
                "--out".into(),
                p(&s.path().join("no/such/dir/f.svg")),
            ],
            vec!["no/such/dir/f.svg", "cannot write the figure"],
        ),
    ];
    for (args, wanted) in cases {
        let mut all = vec!["plot"];
        all.extend(args.iter().map(String::as_str));
        let (code, stdout, stderr) = ilopt(&all);
        assert_eq!(code, 1, "{args:?}: {stdout}{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        for w in wanted {
            assert!(stderr.contains(w), "{args:?}: {w:?} not in {stderr}");
        }
    }
    assert!(
        !s.path().join("f.svg").exists(),
        "no figure for a refused input"
    );
    // The same runs with --x calls draw together.
    let (code, _, stderr) = ilopt(&["plot", &p(&sgd), &p(&bc), "--out", &svg]);
    assert_eq!(code, 0, "{stderr}");
}
