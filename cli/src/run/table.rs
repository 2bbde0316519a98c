//! The table a person reads at the end of a run (`summary.txt`, and stderr): per seed its
//! termination, iterations, gradient calls and final metrics, then the mean over seeds. It is a
//! rendering of `summary.json` ([`render`] reads only that value), so the two cannot disagree.

use serde_json::Value;

/// The final metrics a column may show, in this order, with their header; a column is shown
/// when some seed has a value for it.
const METRICS: [(&str, &str); 4] = [
    ("score", "score"),
    ("objective", "objective"),
    ("eval_loss", "eval loss"),
    ("train_loss", "train loss"),
];

/// A metric to four significant digits: in decimal form in [1e-3, 1e5), else in exponent form.
pub fn metric(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&v.abs()) {
        let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// [`metric`], or `-` for none.
fn number(x: Option<f64>) -> String {
    x.map_or_else(|| "-".into(), metric)
}

/// The summary table of a `summary.json` value: a header line (task, policy, algorithm, budget),
/// one row per seed, and the mean of the final metrics over the seeds that have a checkpoint.
pub fn render(summary: &Value) -> String {
    let runs = summary["runs"].as_array().map_or(&[][..], Vec::as_slice);
    let metrics: Vec<(&str, &str)> = METRICS
        .iter()
        .copied()
        .filter(|(key, _)| runs.iter().any(|r| r["final"][key].is_number()))
        .collect();
    let mut rows: Vec<Vec<String>> = vec![
        ["seed", "termination", "iterations", "calls"]
            .iter()
            .map(|s| (*s).to_string())
            .chain(metrics.iter().map(|(_, h)| (*h).to_string()))
            .collect(),
    ];
    for r in runs {
        let text = |v: &Value| match v {
            Value::String(s) => s.clone(),
            Value::Null => "-".into(),
            v => v.to_string(),
        };
        let mut row = vec![
            text(&r["seed"]),
            text(&r["termination"]),
            text(&r["iterations"]),
            text(&r["cost"]["gradient_evaluations"]),
        ];
        row.extend(metrics.iter().map(|(k, _)| number(r["final"][k].as_f64())));
        rows.push(row);
    }
    let mut mean = vec![
        "mean".to_string(),
        String::new(),
        String::new(),
        String::new(),
    ];
    mean.extend(
        metrics
            .iter()
            .map(|(k, _)| number(summary["final_mean"][k].as_f64())),
    );
    rows.push(mean);
    let widths: Vec<usize> = (0..rows[0].len())
        .map(|i| rows.iter().map(|r| r[i].chars().count()).max().unwrap_or(0))
        .collect();
    let str_of = |v: &Value| v.as_str().map_or_else(|| v.to_string(), str::to_string);
    let mut out = format!(
        "{} task, {} policy, {}, budget {} gradient calls, {} seed(s)\n",
        str_of(&summary["task"]),
        str_of(&summary["policy"]),
        str_of(&summary["algorithm"]),
        summary["budget_calls"],
        runs.len()
    );
    for row in &rows {
        let cells: Vec<String> = row
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(i, (cell, &w))| {
                let pad = w - cell.chars().count();
                if i == 1 {
                    format!("{cell}{}", " ".repeat(pad))
                } else {
                    format!("{}{cell}", " ".repeat(pad))
                }
            })
            .collect();
        out.push_str(cells.join("  ").trim_end());
        out.push('\n');
    }
    out
}
