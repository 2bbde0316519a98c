//! **Negative controls**: the thesis's Algorithms 4 and 5 *as printed*, so that the theory checks
//! can show what goes wrong with them. Do not use them as optimisers.
//!
//! * [`printed_algorithm_4`]: Algorithm 4's printed update (erratum E9)
//!   `d_{k+1} = g(θ_{k+1}, τ_{k+1}) + (1 − a_{k+1}) g(θ_k, τ_{k+1})` — it drops `d_k` and flips
//!   the sign of the correction, so its mean direction is ≈ (2 − a)∇F and it does not track the
//!   gradient (math.md §4). Any [`StormSchedule`] can be used;
//!   the printed one is `adaptive`.
//! * [`printed_algorithm_5`]: Algorithm 5 sampling τ_n ∼ p(·; θ_n) while the gradient is taken at
//!   w_n (erratum E11), which makes E[g(w_n, τ_n)] ≠ ∇F(w_n).

use super::AlgoError;
use super::o2nc::{O2nc, O2ncConfig, SamplePoint};
use super::storm::{Correction, Storm, StormSchedule, Update};
use crate::problem::EstimatorForm;
use crate::scalar::Scalar;
use serde::{Deserialize, Serialize};

/// Configuration of the printed Algorithm 4 (no importance weights, E9 update).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PrintedAlgorithm4Config {
    /// Step sizes and momenta (the thesis prints `adaptive`).
    pub schedule: StormSchedule,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

fn storm_config(c: &PrintedAlgorithm4Config) -> super::storm::StormConfig {
    super::storm::StormConfig {
        schedule: c.schedule.clone(),
        correction: Correction::Unweighted,
        form: c.form,
    }
}

/// Algorithm 4 as printed (E9). Its name is `"printed-algorithm-4"`.
///
/// # Errors
/// As [`Storm::new`].
pub fn printed_algorithm_4<S: Scalar>(c: &PrintedAlgorithm4Config) -> Result<Storm<S>, AlgoError> {
    Storm::with_update(&storm_config(c), Update::PrintedE9)
}

/// Algorithm 5 as printed (E11): sampling at θ_n. Its name is `"printed-algorithm-5"`.
///
/// # Errors
/// As [`O2nc::new`].
pub fn printed_algorithm_5<S: Scalar>(c: &O2ncConfig) -> Result<O2nc<S>, AlgoError> {
    O2nc::with_sampling(c, SamplePoint::Theta)
}
