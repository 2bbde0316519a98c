//! The gradient calls a config's first step costs at least, so that a config whose first step
//! alone exceeds `run.budget_calls` is refused before anything runs (the runner completes the
//! step that reaches the budget, so such a run would spend far more than it was given).
//!
//! Only what is certain counts ([`Cost::gradient_evaluations`](ilopt::problem::Cost) counts one
//! per decision whose ∇ is taken):
//! - decisions per trajectory, as the task states them ([`RunTask::least_decisions`]): exactly
//!   `task.steps` on a fixed horizon with `after_end = "reset"`, exactly T − 1 on a toy MDP
//!   without absorbing states; otherwise at least 1 (an absorbing end or an episode may stop after
//!   the first decision), and nothing for a toy MDP with absorbing states (its first state may
//!   absorb);
//! - an oracle method (SGD, STORM, Adam, …) computes at least one estimate (eq. 3.15) before its
//!   first iterate: `trajectories_per_gradient` trajectories, one call per decision;
//! - a dataset learner (BC, DAgger, RRM, SMILe, forward training) trains once in its first step:
//!   `inner.iterations` updates of `inner.batch_size` calls each, or, full batch, of one call per
//!   example, the examples being at least `trajectories_per_iteration` × the decisions per
//!   trajectory (forward training keeps one state per trajectory).

use super::config::LoadedConfig;
use super::error::RunError;
use super::runnable::RunTask;
use ilopt::algo::AlgorithmConfig;
use ilopt::algo::dataset::InnerConfig;

/// A certain lower bound on the first step's gradient calls, with how it is made up.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FirstStep {
    /// The bound.
    pub calls: u128,
    /// Its factors in words, e.g. `run.trajectories_per_gradient × task.steps = 100000 × 500`.
    pub how: String,
}

/// The least gradient calls of the config's first step; `None` when nothing certain can be said.
pub fn first_step<T: RunTask + ?Sized>(task: &T, config: &LoadedConfig) -> Option<FirstStep> {
    let (d, d_words) = task.least_decisions()?;
    let d = u128::from(d);
    let dataset = |n: u64, inner: &InnerConfig, per_trajectory: (u128, &str)| {
        let i = u128::from(inner.iterations);
        match inner.batch_size {
            Some(b) => FirstStep {
                calls: i * u128::from(b),
                how: format!("algorithm.inner.iterations × algorithm.inner.batch_size = {i} × {b}"),
            },
            None => FirstStep {
                calls: i * u128::from(n) * per_trajectory.0,
                how: format!(
                    "algorithm.inner.iterations × algorithm.trajectories_per_iteration × {} = {i} × {n} × {} (full batch)",
                    per_trajectory.1, per_trajectory.0
                ),
            },
        }
    };
    let bound = match &config.file.algorithm {
        AlgorithmConfig::Bc(c) => dataset(c.trajectories_per_iteration, &c.inner, (d, d_words)),
        AlgorithmConfig::Dagger(c) => dataset(c.trajectories_per_iteration, &c.inner, (d, d_words)),
        AlgorithmConfig::Rrm(c) => dataset(c.trajectories_per_iteration, &c.inner, (d, d_words)),
        AlgorithmConfig::Smile(c) => dataset(c.trajectories_per_iteration, &c.inner, (d, d_words)),
        AlgorithmConfig::ForwardTraining(c) => dataset(
            c.trajectories_per_iteration,
            &c.inner,
            (d.min(1), "(1 state kept per trajectory)"),
        ),
        _ => {
            let m = config.file.run.trajectories_per_gradient as u128;
            FirstStep {
                calls: m * d,
                how: format!("run.trajectories_per_gradient × {d_words} = {m} × {d}"),
            }
        }
    };
    (bound.calls > 0).then_some(bound)
}

/// `n` for a person: exact below 10⁵, else two significant digits as `5·10⁷` or `1.2·10⁸`.
fn amount(n: u128) -> String {
    if n < 100_000 {
        return n.to_string();
    }
    let exp = n.ilog10();
    let scale = 10u128.pow(exp - 1);
    let two = (n + scale / 2) / scale; // two significant digits, rounded
    let (two, exp) = if two >= 100 {
        (two / 10, exp + 1)
    } else {
        (two, exp)
    };
    let sup: String = exp
        .to_string()
        .chars()
        .map(|c| {
            "⁰¹²³⁴⁵⁶⁷⁸⁹"
                .chars()
                .nth(c as usize - '0' as usize)
                .unwrap_or(c)
        })
        .collect();
    let mantissa = if two % 10 == 0 {
        format!("{}", two / 10)
    } else {
        format!("{}.{}", two / 10, two % 10)
    };
    let approx = if two * 10u128.pow(exp - 1) == n {
        ""
    } else {
        "≈ "
    };
    format!("{approx}{mantissa}·10{sup}")
}

/// Refuse a config whose first step alone costs more gradient calls than `run.budget_calls`.
///
/// # Errors
/// [`RunError::OverBudget`] stating the first step's cost, its factors and the budget.
pub fn check_first_step<T: RunTask + ?Sized>(
    task: &T,
    config: &LoadedConfig,
) -> Result<(), RunError> {
    let budget = config.file.run.budget_calls;
    match first_step(task, config) {
        Some(f) if f.calls > u128::from(budget) => Err(RunError::OverBudget {
            path: config.path.clone(),
            message: format!(
                "the first step alone costs at least {} = {} gradient calls, above run.budget_calls = {budget}; raise the budget or make the step smaller",
                f.how,
                amount(f.calls)
            ),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::amount;

    #[test]
    fn amounts_read_as_a_person_writes_them() {
        assert_eq!(amount(99_999), "99999");
        assert_eq!(amount(50_000_000), "5·10⁷");
        assert_eq!(amount(120_000_000), "1.2·10⁸");
        assert_eq!(amount(123_456_789), "≈ 1.2·10⁸");
        assert_eq!(amount(996_000), "≈ 1·10⁶");
        assert_eq!(amount(10u128.pow(12)), "1·10¹²");
    }
}
