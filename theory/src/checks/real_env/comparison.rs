//! The statistic of check 6: per-coordinate z-scores of an estimator against the reference, the
//! Bonferroni critical value and the minimum detectable bias (normal approximation).

use nalgebra::DVector;

use super::mean_var;
use super::reference::Reference;
use crate::stats::normal_upper_quantile;

/// Φ⁻¹(0.8), the table's stated power ([`crate::stats::POWER`]): the minimum detectable bias is
/// the bias flagged with probability ≥ 0.8.
pub use crate::stats::POWER_Z;

/// An estimator's samples against the reference, per coordinate.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Trajectories N.
    pub n: usize,
    /// ḡ_j.
    pub mean: Vec<f64>,
    /// ḡ_j − ref_j, the estimated bias.
    pub bias: Vec<f64>,
    /// `√(s_g²/N + s_ref²/N′)`: the estimator's and the reference's noise.
    pub se: Vec<f64>,
    /// The reference's share of it, `s_ref/√N′`.
    pub se_reference: Vec<f64>,
    /// `z_j = bias_j / se_j`.
    pub z: Vec<f64>,
    /// `(z_crit + z_{0.8})·se_j`.
    pub mdb: Vec<f64>,
    /// `Φ⁻¹(1 − α/(2d))`.
    pub z_crit: f64,
    /// `max_j |z_j|` with the first N/16, N/4 and N samples (the 1/√N behaviour).
    pub trend: Vec<(usize, f64)>,
}

impl Comparison {
    /// `max_j |z_j|` and its coordinate.
    pub fn worst(&self) -> (f64, usize) {
        self.z
            .iter()
            .enumerate()
            .map(|(j, z)| (z.abs(), j))
            .fold((f64::NEG_INFINITY, 0), |a, b| if b.0 > a.0 { b } else { a })
    }
    /// Flagged at the row's α.
    pub fn flagged(&self) -> bool {
        self.worst().0 > self.z_crit
    }
    /// Whether `other`'s measured bias is at least this row's MDB on some coordinate.
    pub fn detects(&self, other: &Comparison) -> bool {
        other.bias.iter().zip(&self.mdb).any(|(b, m)| b.abs() >= *m)
    }
}

/// Compare samples with the reference at false-alarm probability α.
pub fn compare(samples: &[DVector<f64>], r: &Reference, alpha: f64) -> Comparison {
    let n = samples.len();
    let d = r.mean.len();
    let z_crit = normal_upper_quantile(alpha / (2.0 * d as f64));
    let cols: Vec<Vec<f64>> = (0..d)
        .map(|j| samples.iter().map(|g| g[j]).collect())
        .collect();
    let stats = |m: usize| -> Vec<(f64, f64)> {
        cols.iter()
            .zip(&r.se)
            .map(|(c, sr)| {
                let (gm, gv) = mean_var(&c[..m]);
                (gm, (gv / m as f64 + sr * sr).sqrt())
            })
            .collect()
    };
    let full = stats(n);
    let bias: Vec<f64> = full.iter().zip(&r.mean).map(|(s, rm)| s.0 - rm).collect();
    let se: Vec<f64> = full.iter().map(|s| s.1).collect();
    let trend = [16usize, 4, 1]
        .into_iter()
        .map(|k| {
            let m = (n / k).max(2);
            let w = stats(m)
                .iter()
                .zip(&r.mean)
                .map(|(s, rm)| ((s.0 - rm) / s.1).abs())
                .fold(0.0f64, f64::max);
            (m, w)
        })
        .collect();
    Comparison {
        n,
        mean: full.iter().map(|s| s.0).collect(),
        z: bias.iter().zip(&se).map(|(b, s)| b / s).collect(),
        mdb: se
            .iter()
            .map(|s| crate::stats::min_detectable(z_crit * s, *s))
            .collect(),
        bias,
        se,
        se_reference: r.se.clone(),
        z_crit,
        trend,
    }
}

/// The variance reduction of a baselined estimator, per trajectory: `tr Var(g) / tr Var(g_b)`
/// from `plain` samples (one trajectory each) and `baselined` samples (each the mean of `m`
/// trajectories, so `Var(g_b) = m·Var(sample)`), with its interval at level 1 − `alpha` (`reps`
/// bootstrap resamples of both sets, seeded): the total of [`super::variance::reduction`].
/// Returns (ratio, lower, upper).
pub fn variance_ratio(
    plain: &[DVector<f64>],
    baselined: &[DVector<f64>],
    m: usize,
    reps: usize,
    seed: u64,
    alpha: f64,
) -> (f64, f64, f64) {
    let t = super::variance::reduction(plain, baselined, m, reps, seed, alpha).total;
    (t.value, t.lo, t.hi)
}

#[cfg(test)]
mod tests {
    use super::{normal_upper_quantile, variance_ratio};

    #[test]
    fn normal_quantiles() {
        assert!((normal_upper_quantile(0.025) - 1.959_964).abs() < 1e-5);
        assert!((normal_upper_quantile(0.005) - 2.575_829).abs() < 1e-5);
        assert!((normal_upper_quantile(1e-6) - 4.753_424).abs() < 1e-4);
        assert!((normal_upper_quantile(0.2) - super::POWER_Z).abs() < 1e-5);
    }

    /// Samples ±a (one trajectory each) against ±b (means of m): the ratio is a²/(m·b²)
    /// exactly, and its interval contains it.
    #[test]
    fn variance_ratio_is_the_per_trajectory_ratio() {
        use nalgebra::DVector;
        let plain: Vec<DVector<f64>> = (0..200)
            .map(|i| DVector::from_vec(vec![if i % 2 == 0 { 4.0 } else { -4.0 }, 0.0]))
            .collect();
        let baselined: Vec<DVector<f64>> = (0..100)
            .map(|i| DVector::from_vec(vec![if i % 2 == 0 { 0.5 } else { -0.5 }, 0.0]))
            .collect();
        let (r, lo, hi) = variance_ratio(&plain, &baselined, 16, 200, 1, 0.05);
        // s² of ±a over an even n is a²·n/(n − 1).
        let expect = (16.0 * 200.0 / 199.0) / (16.0 * 0.25 * 100.0 / 99.0);
        assert!((r - expect).abs() < 1e-12, "{r} vs {expect}");
        assert!(lo <= r && r <= hi, "[{lo}, {hi}] misses {r}");
    }
}
