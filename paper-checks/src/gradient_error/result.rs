//! What a route of Fig. 4.2 measured: the RMSE per N with its interval, the fitted slope with its
//! bootstrap interval, and the reference's own error.

use serde::{Deserialize, Serialize};

/// A slope with its 95% interval: what claim O1 reads.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlopeCi {
    /// Least-squares slope of log RMSE vs log N on all repetitions.
    pub estimate: f64,
    /// 2.5% bootstrap percentile.
    pub lo: f64,
    /// 97.5% bootstrap percentile.
    pub hi: f64,
    /// Repetitions (the units resampled).
    pub n: usize,
}

impl SlopeCi {
    /// The rule suggested for O1: the interval contains −1/2 and excludes 0.
    pub fn consistent_with_inverse_sqrt(&self) -> bool {
        self.lo <= -0.5 && -0.5 <= self.hi && self.hi < 0.0
    }
}

/// One route's data and summaries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RouteResult {
    /// The sample sizes.
    pub ns: Vec<u64>,
    /// Names of the gradient blocks whose squared errors are recorded (obstacle: x-row, y-row;
    /// toy: the whole gradient).
    pub blocks: Vec<String>,
    /// Per repetition, per N, per block: ‖block of (ḡ_N − reference)‖².
    pub squared_errors: Vec<Vec<Vec<f64>>>,
    /// The reference (∇F exactly, rounded to f64; or the M-trajectory mean).
    pub reference: Vec<f64>,
    /// σ² = E‖g‖² − ‖∇F‖² (exact, rounded; or estimated from the reference's estimates).
    pub sigma2: f64,
    /// σ² exactly, as a fraction (toy route only).
    pub sigma2_exact: Option<String>,
    /// Variance of the reference's error, E‖R − ∇F‖² (0 for the exact reference; σ̂²/M).
    pub reference_variance: f64,
    /// The exact standard deviation of ‖g − ∇F‖² (one estimate's squared error: the spread of
    /// the N = 1 column), toy route only.
    pub squared_error_sd_n1: Option<f64>,
    /// Trajectories behind the reference (None: exact).
    pub reference_trajectories: Option<u64>,
    /// RMSE(N) per N, with the reference's variance subtracted from the MSE, and its 95% interval.
    pub rmse: Vec<RmsePoint>,
    /// The fitted slope.
    pub slope: SlopeCi,
    /// Per gradient block (obstacle: the x and y rows, the thesis's panels (a) and (b)): its name
    /// and the slope of its own RMSE (σ² and the reference variance of that block).
    pub block_slopes: Vec<(String, SlopeCi)>,
    /// Wall time of the route in seconds (0 when reused; kept out of the deterministic data,
    /// written to `timings/gradient-error.json`).
    #[serde(skip)]
    pub seconds: f64,
}

/// RMSE at one N.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RmsePoint {
    /// N.
    pub n: u64,
    /// √(mean squared error against the reference), uncorrected.
    pub raw: f64,
    /// √ of its 95% interval's ends (lower end clamped at 0).
    pub raw_lo: f64,
    /// Upper end.
    pub raw_hi: f64,
    /// √(MSE − reference variance) (= raw for the exact reference).
    pub corrected: f64,
    /// Interval of the corrected value.
    pub corrected_lo: f64,
    /// Upper end.
    pub corrected_hi: f64,
    /// σ/√N.
    pub line: f64,
}

/// Both routes: the Fig. 4.2 data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GradientErrorResult {
    /// Reuse key.
    pub key_hash: String,
    /// Route (a).
    pub toy: RouteResult,
    /// Route (b).
    pub obstacle: RouteResult,
}
