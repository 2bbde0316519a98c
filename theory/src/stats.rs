//! Decisions with a stated false-alarm probability (math.md §7.3).
//!
//! R i.i.d. runs give X_r ∈ [0, b]; H₀ is the theorem, E X ≤ B. A violation is flagged only when a
//! *lower confidence bound* on E X exceeds B, so P_{H₀}(flag) ≤ α:
//! * Hoeffding: `LCB = X̄ − b √(ln(1/α)/(2R))`;
//! * empirical Bernstein (Maurer & Pontil 2009, Thm 4): `LCB = X̄ − √(2V ln(2/α)/R) − 7b ln(2/α)/(3(R−1))`.
//!
//! The kit uses the larger (sharper) of the two at level α/2 each (a union bound keeps the level α).
//! Student-t is reported for orientation only. Suites split α by Bonferroni.

use serde::Serialize;

/// Summary of R runs of a per-run statistic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// R.
    pub runs: usize,
    /// X̄.
    pub mean: f64,
    /// Unbiased sample variance.
    pub variance: f64,
    /// The a-priori range bound b (X ∈ [0, b]).
    pub range: f64,
}

impl Sample {
    /// Summarise `xs` (each in [0, b]).
    ///
    /// # Panics
    /// If fewer than two runs are given (a programming error of the caller).
    pub fn new(xs: &[f64], range: f64) -> Self {
        assert!(xs.len() >= 2, "need at least two runs");
        let r = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / r;
        let variance = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r - 1.0);
        Self {
            runs: xs.len(),
            mean,
            variance,
            range,
        }
    }

    /// Hoeffding lower confidence bound at level α.
    pub fn hoeffding_lcb(&self, alpha: f64) -> f64 {
        self.mean - self.range * ((1.0 / alpha).ln() / (2.0 * self.runs as f64)).sqrt()
    }

    /// Empirical-Bernstein lower confidence bound at level α (Maurer & Pontil 2009, Thm 4).
    pub fn bernstein_lcb(&self, alpha: f64) -> f64 {
        let r = self.runs as f64;
        let l = (2.0 / alpha).ln();
        self.mean - (2.0 * self.variance * l / r).sqrt() - 7.0 * self.range * l / (3.0 * (r - 1.0))
    }

    /// The decision rule's LCB: the larger of Hoeffding and empirical Bernstein at α/2 each.
    pub fn lcb(&self, alpha: f64) -> f64 {
        self.hoeffding_lcb(alpha / 2.0)
            .max(self.bernstein_lcb(alpha / 2.0))
    }

    /// The matching upper confidence bound (same construction mirrored), for reporting.
    pub fn ucb(&self, alpha: f64) -> f64 {
        let r = self.runs as f64;
        let h = self.mean + self.range * ((2.0 / alpha).ln() / (2.0 * r)).sqrt();
        let l = (4.0 / alpha).ln();
        let b = self.mean
            + (2.0 * self.variance * l / r).sqrt()
            + 7.0 * self.range * l / (3.0 * (r - 1.0));
        h.min(b)
    }
}

/// Outcome of testing H₀: E X ≤ B.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decision {
    /// LCB ≤ B: no evidence against the bound.
    Consistent,
    /// LCB > B: the bound is violated with confidence 1 − α.
    Violated,
}

/// Test H₀: E X ≤ `bound` at level α.
pub fn decide(sample: &Sample, bound: f64, alpha: f64) -> Decision {
    if sample.lcb(alpha) > bound {
        Decision::Violated
    } else {
        Decision::Consistent
    }
}

/// Bonferroni: the per-check level for m checks at family level α.
pub fn bonferroni(alpha: f64, m: usize) -> f64 {
    alpha / m.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_a_clear_violation_and_not_a_clear_compliance() {
        let xs: Vec<f64> = (0..400)
            .map(|i| 0.5 + 0.1 * ((i % 7) as f64 / 7.0))
            .collect();
        let s = Sample::new(&xs, 1.0);
        assert_eq!(decide(&s, 0.3, 1e-3), Decision::Violated);
        assert_eq!(decide(&s, 0.6, 1e-3), Decision::Consistent);
        assert!(s.lcb(1e-3) < s.mean && s.mean < s.ucb(1e-3));
    }

    /// The false-alarm rate under H₀ (E X = B exactly) stays below α (simulated, seeded).
    #[test]
    fn false_alarm_rate_is_below_alpha() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let (alpha, trials) = (0.05, 2000);
        let mut alarms = 0;
        for _ in 0..trials {
            // Bernoulli(0.3) has mean 0.3 = B.
            let xs: Vec<f64> = (0..50)
                .map(|_| f64::from(u8::from(rng.random::<f64>() < 0.3)))
                .collect();
            if decide(&Sample::new(&xs, 1.0), 0.3, alpha) == Decision::Violated {
                alarms += 1;
            }
        }
        assert!(f64::from(alarms) / f64::from(trials) <= alpha, "{alarms}");
    }
}
