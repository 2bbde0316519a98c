//! A config's oracle: the task's problem as the `[run]` table asks for it — with its baseline
//! ([`Baselined`], eq. 3.15 with b subtracted from every loss-to-go), as the mean of m
//! trajectories ([`Batched`]), or plain for m = 1 — and computations generic over its type
//! ([`OnOracle`]). The training runs and `ilopt estimate` go through [`with_oracle`], so both
//! sample the same oracle.

use super::config::LoadedConfig;
use super::error::RunError;
use super::runnable::RunTask;
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
    fn on<P: IlProblem<f64>>(self, oracle: &mut P) -> Result<Self::Output, RunError>;
}

/// Run `computation` on the task's oracle with `m` trajectories per call and the config's
/// `run.baseline`: [`Baselined`] when a baseline other than `none` is set, else [`Batched`] for
/// m > 1, else the problem itself.
///
/// # Errors
/// [`RunError::Invalid`] naming `run.baseline` or `run.trajectories_per_gradient` when the
/// oracle cannot be built with them; then the computation's own.
pub fn with_oracle<T: RunTask + ?Sized, C: OnOracle>(
    task: &T,
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
    let p = task.problem();
    if let Some(b) = baseline {
        let mut b = Baselined::<_, f64>::new(p.clone(), m, b)
            .map_err(|e| config.invalid("run.baseline", baseline_message(e)))?;
        computation.on(&mut b)
    } else if m > 1 {
        let mut b = Batched::new(p.clone(), m)
            .map_err(|e| config.invalid("run.trajectories_per_gradient", e))?;
        computation.on(&mut b)
    } else {
        computation.on(&mut p.clone())
    }
}

/// An oracle's error about its baseline without the "baseline: " its message starts with (the
/// key `run.baseline` already says it); any other error as it is.
pub(super) fn baseline_message(e: ilopt::problem::OracleError) -> String {
    match e {
        ilopt::problem::OracleError::Baseline(m) => m,
        e => e.to_string(),
    }
}
