//! Checks 1 and 3: the SGD bound (3.27) and the online-to-non-convex bounds (§3.4, eq. 3.71) by
//! Monte Carlo over seeded runs of the kit's own algorithms on M1 (P2'), with **exact ∇F at the
//! iterates** (forward DP in interval arithmetic, by cells: [`GradientCells`]; the *lower* end of each per-run statistic is
//! used for the decision so rounding can never raise a false alarm — math.md §7.2) and the
//! decision rule of [`crate::stats`] at a stated false-alarm probability.
//!
//! Every check takes a `claim_scale`: 1 checks the theorem; a small value checks a deliberately
//! wrong (understated) bound, which the check must flag.

mod cells;
mod o2nc;
mod sgd;

pub use cells::{CELL_WIDTH, CELL_WIDTH_2D, GradientCells, MAX_CELL_DIM};

pub use o2nc::{
    O2ncSample, O2ncVariant, o2nc, o2nc_rows, o2nc_sample, o2nc_sample_tracked, o2nc_variant,
};
pub use sgd::{sgd, sgd_row, sgd_sample, sgd_sample_on, sgd_with_control};

use crate::bounds::upper;
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::stats::{Sample, assess};
use ilopt::scalar::Interval;

/// Monte-Carlo sizes and level.
#[derive(Debug, Clone, Copy)]
pub struct McSettings {
    /// Independent seeded runs R.
    pub runs: usize,
    /// False-alarm probability of this check (after Bonferroni).
    pub alpha: f64,
}

/// (lower, midpoint) of ‖v‖² for an interval vector.
fn norm_sq_bounds(v: &[Interval]) -> (f64, f64) {
    let lo: f64 = v.iter().map(|x| x.mig() * x.mig()).sum();
    let mid: f64 = v.iter().map(|x| x.mid() * x.mid()).sum();
    (lo, mid)
}

fn inconclusive(id: &str, result: &str, claim: String, details: String) -> Check {
    Check::builder(id, result, claim, Role::Thesis)
        .details(details)
        .decided(Method::Statistical, Verdict::Inconclusive)
}

/// Per-run statistics of R runs: (rigorous lower ends, midpoints), in seed order.
pub type Runs = (Vec<f64>, Vec<f64>);

/// The claim prefix of a scaled (control) bound.
fn scale_prefix(claim_scale: f64) -> String {
    if claim_scale == 1.0 {
        String::new()
    } else {
        format!("{claim_scale}·")
    }
}

/// The measured value of a statistical row and its verdict ([`assess`]): the LCB of the lower
/// ends against `upper(bound)`, the statistic's certified maximum `statistic_max`.
fn measure(
    lows: &[f64],
    mids: &[f64],
    range: f64,
    bound: f64,
    statistic_max: f64,
    mc: McSettings,
) -> (Measured, Verdict, String) {
    let sample = Sample::new(lows, range);
    let mean_mid = mids.iter().sum::<f64>() / mids.len() as f64;
    let lcb = sample.lcb(mc.alpha);
    let verdict = assess(&sample, upper(bound), statistic_max, mc.alpha);
    let text = format!(
        "R = {}; X̄ = {mean_mid:.5}, LCB = {lcb:.5} (max of Hoeffding, empirical Bernstein, betting at α/3 each; α = {:.1e}, range [0, {range:.4}]), B = {bound:.5}; flags any B < {lcb:.5}, minimum detectable violation (power 0.8) X̄ − LCB + 0.84·SE = {:.5}; the statistic cannot exceed {statistic_max:.4}",
        mc.runs,
        mc.alpha,
        crate::stats::min_detectable(mean_mid - lcb, sample.se()),
    );
    (
        Measured::from_sample(&sample, mc.alpha).with_value(mean_mid),
        verdict,
        text,
    )
}
