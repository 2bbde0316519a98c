//! A config's oracle: the bench's problem as the `[run]` table asks for it — with its baseline
//! ([`Baselined`], eq. 3.15 with b subtracted from every loss-to-go), as the mean of m
//! trajectories ([`Batched`]), or plain for m = 1 — and computations generic over its type
//! ([`OnOracle`]). The training runs and `ilopt estimate` go through [`with_oracle`], so both
//! sample the same oracle.

use super::config::LoadedConfig;
use super::driver::baseline_message;
use super::error::RunError;
use super::task::TaskLearner;
use ilopt::baseline::{Baseline, Baselined};
use ilopt::batched::Batched;
use ilopt::problem::IlProblem;

/// A computation on a config's oracle, whatever the oracle's type.
pub trait OnOracle {
    /// What it gives.
    type Output;
    /// Carry it out on `oracle`.
    ///
    /// # Errors
    /// The computation's own.
    fn on<P: IlProblem<f64>>(self, oracle: &P) -> Result<Self::Output, RunError>;
}

/// Run `computation` on the bench's oracle with `m` trajectories per call and the config's
/// `run.baseline`: [`Baselined`] when a baseline other than `none` is set, else [`Batched`] for
/// m > 1, else the problem itself.
///
/// # Errors
/// [`RunError::Invalid`] naming `run.baseline` or `run.trajectories_per_gradient` when the
/// oracle cannot be built with them; then the computation's own.
pub fn with_oracle<C: OnOracle>(
    bench: &TaskLearner,
    config: &LoadedConfig,
    m: usize,
    computation: C,
) -> Result<C::Output, RunError> {
    let baseline = config
        .file
        .run
        .baseline
        .as_ref()
        .filter(|b| **b != Baseline::None);
    macro_rules! on {
        ($p:expr) => {
            if let Some(b) = baseline {
                let b = Baselined::<_, f64>::new($p.clone(), m, b)
                    .map_err(|e| config.invalid("run.baseline", baseline_message(e)))?;
                computation.on(&b)
            } else if m > 1 {
                let b = Batched::new($p.clone(), m)
                    .map_err(|e| config.invalid("run.trajectories_per_gradient", e))?;
                computation.on(&b)
            } else {
                computation.on($p)
            }
        };
    }
    match bench {
        TaskLearner::CartPoleSoftmax(p) => on!(p),
        TaskLearner::CartPoleLogistic(p) => on!(p),
        TaskLearner::Obstacle { problem, .. } => on!(problem),
        TaskLearner::Toy(p) => on!(p),
    }
}
