//! The band of a curve over seeds: the mean with its 95% Student-t interval
//! `mean ± t_{0.975,n−1}·s/√n` ([`Summary`]), the interval the figures shade and the appendix's
//! tables print for quantities of unbounded range.

/// The 0.975 quantile of Student's t with `df` degrees of freedom (NaN for `df = 0`), from
/// statrs' inverse CDF.
pub fn t975(df: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    if df == 0 {
        return f64::NAN;
    }
    StudentsT::new(0.0, 1.0, df as f64).map_or(f64::NAN, |t| t.inverse_cdf(0.975))
}

/// A sample summary: n, mean and the 95% Student-t interval `mean ± t_{0.975,n−1}·s/√n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Sample size.
    pub n: usize,
    /// Mean (NaN for n = 0).
    pub mean: f64,
    /// Half-width of the 95% t interval (NaN for n < 2).
    pub half_width: f64,
}

impl Summary {
    /// Summarise a sample.
    pub fn of(xs: &[f64]) -> Self {
        let n = xs.len();
        if n == 0 {
            return Summary {
                n,
                mean: f64::NAN,
                half_width: f64::NAN,
            };
        }
        let mean = xs.iter().sum::<f64>() / n as f64;
        let half_width = if n < 2 {
            f64::NAN
        } else {
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            t975(n - 1) * (var / n as f64).sqrt()
        };
        Summary {
            n,
            mean,
            half_width,
        }
    }
    /// Lower end of the interval.
    pub fn lo(&self) -> f64 {
        self.mean - self.half_width
    }
    /// Upper end of the interval.
    pub fn hi(&self) -> f64 {
        self.mean + self.half_width
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_interval_of_a_known_sample() {
        // df = 2 has the closed form t_p = (2p − 1)·√(2 / (4p(1 − p))); s = 1, n = 3.
        let p = 0.975f64;
        let t2 = (2.0 * p - 1.0) * (2.0 / (4.0 * p * (1.0 - p))).sqrt();
        let s = Summary::of(&[1.0, 2.0, 3.0]);
        assert_eq!(s.mean, 2.0);
        assert!(
            (s.half_width - t2 / 3f64.sqrt()).abs() < 1e-9,
            "{}",
            s.half_width
        );
        assert!(Summary::of(&[4.0]).half_width.is_nan());
        assert!(Summary::of(&[]).mean.is_nan());
    }

    #[test]
    fn t_quantiles_against_closed_forms_and_the_printed_table() {
        // df = 1 is Cauchy: t_p = tan(π(p − 1/2)).
        let t1 = (std::f64::consts::PI * 0.475).tan();
        assert!((t975(1) - t1).abs() < 1e-9 * t1, "{}", t975(1));
        // Printed tables (3 decimals): df 10, 30, 120.
        for (df, printed) in [(10, 2.228), (30, 2.042), (120, 1.980)] {
            assert!((t975(df) - printed).abs() < 5e-4, "df {df}: {}", t975(df));
        }
        assert!(t975(0).is_nan());
    }
}
