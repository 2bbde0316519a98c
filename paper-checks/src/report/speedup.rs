//! The kit's training wall time next to the thesis's runtimes (Tables 4.2 and 4.4) as ratios
//! thesis / kit, with the machine that measured the kit's times.
//!
//! Wall times depend on the machine, so the appendix compares them only as speed-ups and says on
//! what the kit ran ([`Machine`]); the thesis does not describe its machine.

use super::aggregate::{ci, num};
use crate::provenance::Machine;
use crate::results::{ConfigTiming, ConfigWithTiming};
use crate::stats::Interval;

/// What a kit wall time measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeBasis {
    /// Training wall time up to the convergence checkpoint, over the seeds that converged.
    ToConverge {
        /// Seeds that converged.
        converged: usize,
        /// Seeds.
        seeds: usize,
    },
    /// Training wall time of the whole run (no seed converged), over all seeds.
    WholeRun {
        /// Seeds.
        seeds: usize,
    },
}

impl TimeBasis {
    /// Short description for a table cell.
    pub fn text(self) -> String {
        match self {
            TimeBasis::ToConverge { converged, seeds } => {
                format!("to converge ({converged}/{seeds} seeds)")
            }
            TimeBasis::WholeRun { seeds } => format!("— (0/{seeds} converged)"),
        }
    }
}

/// One algorithm's kit time next to the thesis's.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedupRow {
    /// Algorithm.
    pub label: String,
    /// The kit's mean training wall time in seconds (with its interval) and what it measures;
    /// `None` when no timing file exists (results reused from an older run).
    pub kit: Option<(Interval, TimeBasis)>,
    /// The thesis's runtime in seconds, if the thesis reports this algorithm.
    pub thesis_seconds: Option<f64>,
}

/// `thesis / kit` when both are finite and positive.
pub fn ratio(thesis_seconds: f64, kit_seconds: f64) -> Option<f64> {
    (thesis_seconds.is_finite()
        && kit_seconds.is_finite()
        && thesis_seconds > 0.0
        && kit_seconds > 0.0)
        .then(|| thesis_seconds / kit_seconds)
}

impl SpeedupRow {
    /// The speed-up `thesis seconds / kit mean seconds`, if both exist.
    pub fn ratio(&self) -> Option<f64> {
        let kit = self.kit.as_ref()?;
        if !matches!(kit.1, TimeBasis::ToConverge { .. }) {
            return None;
        }
        ratio(self.thesis_seconds?, kit.0.mean)
    }
}

/// The kit's time of one configuration: the mean training wall time to converge over the seeds
/// that converged (as Tables 4.1/4.3 average gradient calls), or the whole run's when no seed
/// converged.
pub fn kit_time(t: &ConfigTiming) -> (Interval, TimeBasis) {
    let conv: Vec<f64> = t.runs.iter().filter_map(|r| r.converge_seconds).collect();
    let seeds = t.runs.len();
    if conv.is_empty() {
        // No ratio for a method that did not converge (the row shows "—").
        (
            super::aggregate::seconds(&[]),
            TimeBasis::WholeRun { seeds },
        )
    } else {
        (
            super::aggregate::seconds(&conv),
            TimeBasis::ToConverge {
                converged: conv.len(),
                seeds,
            },
        )
    }
}

/// One algorithm's row.
pub fn speedup_row(
    label: &str,
    timing: Option<&ConfigTiming>,
    thesis: &[(&str, f64)],
) -> SpeedupRow {
    SpeedupRow {
        label: label.to_string(),
        kit: timing.map(kit_time),
        thesis_seconds: thesis.iter().find(|t| t.0 == label).map(|t| t.1),
    }
}

/// The rows of one task (every algorithm except BC, which the thesis's tables omit).
pub fn speedup_rows(set: &[ConfigWithTiming], thesis: &[(&str, f64)]) -> Vec<SpeedupRow> {
    set.iter()
        .filter(|c| c.0.label != "BC")
        .map(|(c, t)| speedup_row(&c.label, t.as_ref(), thesis))
        .collect()
}

/// Sums over the rows that have both a kit time and a thesis time: (kit seconds, thesis
/// seconds, thesis / kit, rows summed).
pub fn speedup_total(rows: &[SpeedupRow]) -> (f64, f64, Option<f64>, usize) {
    let both: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.ratio().is_some())
        .filter_map(|r| Some((r.kit.as_ref()?.0.mean, r.thesis_seconds?)))
        .collect();
    let kit: f64 = both.iter().map(|b| b.0).sum();
    let thesis: f64 = both.iter().map(|b| b.1).sum();
    (kit, thesis, ratio(thesis, kit), both.len())
}

/// A speed-up as `1234×` (four significant digits), or `—`.
pub fn times(r: Option<f64>) -> String {
    r.map_or("—".into(), |r| format!("{}×", num(r)))
}

/// The table's cells for one task: a row per algorithm, then the total row.
pub fn speedup_cells(table: &str, rows: &[SpeedupRow]) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                table.to_string(),
                r.label.clone(),
                r.kit.as_ref().map_or("—".into(), |k| ci(&k.0)),
                r.kit
                    .as_ref()
                    .map_or("no timing file".into(), |k| k.1.text()),
                r.thesis_seconds.map_or("—".into(), num),
                times(r.ratio()),
            ]
        })
        .collect();
    let (kit, thesis, ratio, n) = speedup_total(rows);
    out.push(vec![
        table.to_string(),
        format!("total ({n} algorithms with both times)"),
        if n > 0 { num(kit) } else { "—".into() },
        "sum of the means".into(),
        if n > 0 { num(thesis) } else { "—".into() },
        times(ratio),
    ]);
    out
}

/// The sentence describing the machine, for the paragraph above the table.
pub fn machine_sentence(m: &Machine) -> String {
    let unknown = || "unknown".to_string();
    format!(
        "The kit's times were measured on: CPU {}; {} logical cores ({} available to the process); \
         {} rayon threads (the seeds of a configuration, and configurations, run in parallel, so \
         each run's wall time includes sharing the cores); {}; {}; `{}` build; report written {} (configurations reused from an earlier run keep \
         the wall times measured then).",
        m.cpu.clone().unwrap_or_else(unknown),
        m.logical_cpus.map_or_else(unknown, |n| n.to_string()),
        m.available_cpus.map_or_else(unknown, |n| n.to_string()),
        m.rayon_threads,
        m.os,
        m.rustc.clone().unwrap_or_else(|| "rustc unknown".into()),
        m.build_profile,
        m.date_utc
    )
}

/// The paragraph above the table.
pub fn speedup_intro(m: &Machine) -> String {
    format!(
        "Speed-up = thesis seconds / kit mean seconds. The kit's time is the mean training wall \
         time per run (evaluation excluded) to the sustained-convergence checkpoint over the \
         seeds that converged (diverged runs never count); a method none of whose runs converged \
         shows \"—\", not a ratio. BC, absent from the thesis's \
         tables, is left out; totals sum the algorithms that have both times. {} The thesis does not describe \
         the machine its runtimes were measured on, so each ratio compares machines as well as \
         implementations (and runs of different lengths).",
        machine_sentence(m)
    )
}

/// Column headers of the table.
pub const SPEEDUP_HEAD: [&str; 6] = [
    "table",
    "algorithm",
    "kit: mean seconds",
    "kit time is",
    "thesis: seconds",
    "speed-up (thesis / kit)",
];
