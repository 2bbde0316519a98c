//! The experiments: one seeded run of one algorithm on one task, evaluated at checkpoints (the
//! gradient-error study of Fig. 4.2 is in [`crate::gradient_error`]).
//!
//! **Evaluation.** At every checkpoint the learned policy acts *deterministically* (the
//! linear-Gaussian mean `Wφ(s)`; the softmax's most probable action) on `eval_episodes` seeded
//! episodes. The episodes depend only on (task, seed index, episode index), so every algorithm and
//! every checkpoint of one seed meets the same episodes (common random numbers). Recorded: the
//! outcomes (obstacle: success / crash / time-out; CartPole: completed 500 steps / crash = the
//! episode terminated earlier), the mean episode reward, and the mean per-decision supervised loss
//! `l(s, θ)` on the states the deterministic policy visits (obstacle: split into the x and y
//! coordinates of the velocity).
//!
//! **Budget and checkpoints**: every run of a task gets the same budget of
//! gradient calls (per-state gradient evaluations, [`Cost`](ilopt::problem::Cost); DAgger's full-batch retraining
//! counts epochs × |D|), and is evaluated at the fixed call counts 0, `checkpoint_every`, …,
//! `budget` (at the first iterate whose cumulative calls reach each). θ₁ is the task's
//! [`Theta1`](crate::config::Theta1) (zero unless a profile says otherwise).
//!
//! **Score and sustained convergence** (one definition for every algorithm): the score of a
//! checkpoint is the obstacle task's success rate, or CartPole's mean episode reward divided by
//! 500. A run *converges* at checkpoint i when the score is ≥ `converge_score` at checkpoints
//! i, i+1, …, i+`sustain`−1 (3 by default; [`sustained`]); its "gradient calls to converge" are the
//! calls at checkpoint i, its time the training wall time up to it (evaluation excluded).
//!
//! **Failure is data** ([`RunStatus`]): a run whose ‖θ‖₂ exceeds the task's `norm_bound`, whose θ
//! is not finite, or whose step fails is *diverged* — it stops there, is never converged (even if
//! it had met the criterion before), and is counted among the failed runs.

mod records;
mod run;
mod status;
mod task_learner;

pub use records::*;
pub use run::*;
pub use status::*;
pub use task_learner::*;

pub use crate::config::TaskKind;
