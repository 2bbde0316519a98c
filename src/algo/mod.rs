//! The algorithms of the thesis, generic over the scalar, driven by one runner.
//!
//! Design (conventions.md 5–7): each algorithm is a struct of *validated* hyper-parameters
//! plus state, with [`Algorithm::init`] and [`Algorithm::step`]. One [`runner::Runner`] owns the
//! loop, the stopping rule, the observers, the seeded [`crate::problem::KitRng`] and the termination reason; every
//! run records an [`config::RunConfig`] (algorithm + hyper-parameters + seed + stopping rule) that
//! [`runner::replay`] reproduces bit for bit.
//!
//! | module | what | thesis / paper |
//! |---|---|---|
//! | [`first_order`] | the shell of SGD, Adam and RMSProp: an update rule applied to the eq. 3.15 estimate | Algorithm 3, §2.6 |
//! | [`sgd`] | SGD on the IL objective | Algorithm 3 |
//! | [`storm`] | STORM (eq. 3.40, E9-corrected), schedules (3.43), Cutkosky–Orabona adaptive, explicit; IS-STORM | Alg. 4, math.md §§3–4 |
//! | [`storm_stability`] | when STORM's linearised direction recursion amplifies: ρ((1 − a)(I − ηA)), η*(a) | math.md §10 |
//! | [`storm_plus`] | STORM+ | Levy, Kavis, Cevher (NeurIPS 2021) |
//! | [`adam`], [`rmsprop`] | Adam, RMSProp | §2.6, eqs. 2.14–2.15 |
//! | [`o2nc`] | online-to-non-convex conversion with OGD, IL-correct sampling | Alg. 5, math.md §5 |
//! | [`as_printed`] | the printed Algorithm 4 (E9) and Algorithm 5 (E11): negative controls | math.md §§4–5 |
//! | [`dataset`] | datasets, the supervised inner optimiser | §2.4 |
//! | [`learner`] | the shell of the dataset learners: shared state plus a per-algorithm data schedule | §2.4 |
//! | [`bc`], [`dagger`], [`rrm`], [`smile`], [`forward_training`] | dataset learners | §2.4, Alg. 1–2, eq. 3.29 |
//!
//! # Scalars
//! Every algorithm has one constructor, bounded by [`crate::scalar::Scalar`]. What needs roots —
//! Adam, RMSProp, O2NC and SGD with η₀/√k (square roots); the schedule (3.43), the
//! Cutkosky–Orabona schedule and STORM+ (cube roots) — asks the scalar's
//! [`crate::scalar::Roots`] capability when it is built and fails with
//! [`AlgoError::NeedsRoots`] in a scalar without roots (exact
//! [`crate::scalar::BigRational`]). SGD with constant or inverse-time steps, STORM / IS-STORM
//! with `constant` or `explicit` schedules and the dataset learners with an SGD inner optimiser
//! use field operations only, so they run exactly in rationals.
//!
//! # Randomness
//! Randomness never depends on the scalar: algorithms draw uniforms only through
//! [`dyadic_uniform`](crate::sampling::dyadic_uniform) (a 53-bit dyadic rational built exactly in every scalar), and the problem
//! samples trajectories from the same RNG. So an interval run with the same seed follows the same
//! trajectories as the `f64` run and its iterates enclose the `f64` iterates.
//!
//! # Costs
//! Every oracle call adds to the run's [`crate::problem::Cost`]: trajectories and environment steps of each
//! roll-out, expert queries for the labels, and one *gradient evaluation* per per-state ∇l or
//! ∇log π (the problem counts them). A STORM step therefore costs one trajectory and two
//! estimates; a dataset learner's inner update costs one gradient evaluation per example in the
//! (mini)batch. The runner reports the cumulative cost and the wall time after every iteration.
//!
//! # Known limitations
//! * Under the direct parameterisation the score 1/π is unbounded, so large steps can leave the
//!   open simplex; the run then ends with [`Termination::Diverged`] (a domain error),
//!   never with a silently clipped or NaN iterate. No algorithm projects onto the simplex.
//! * Interval runs of Adam/RMSProp widen quickly once the gradients are small (the wrapping
//!   effect in `m̂/√v̂`): fine for a few iterations, not for long runs.
//! * STORM+'s constants are those of [`storm_plus`]'s module docs; the run is checked against
//!   the same recursion, not against the authors' released code.

pub mod adam;
mod algorithm;
pub mod as_printed;
pub mod bc;
pub mod config;
pub mod dagger;
pub mod dataset;
mod error;
pub mod first_order;
pub mod forward_training;
pub mod learner;
pub mod o2nc;
pub mod observer;
mod parameter_range;
mod prefetch;
pub mod records;
pub mod rmsprop;
mod roots;
pub mod rrm;
pub mod runner;
pub mod sgd;
pub mod smile;
pub mod storm;
pub mod storm_plus;
pub mod storm_stability;
pub mod termination;
mod vector;

pub use crate::scalar::ConfigNumber;
pub use algorithm::{Algorithm, StepContext, StepReport};
pub use config::{AlgorithmConfig, RunConfig};
pub use error::AlgoError;
pub use first_order::{FirstOrder, UpdateRule};
pub use learner::{DataSchedule, DatasetLearner};
pub use observer::{
    CheckpointObserver, IterationMetrics, NormBound, Observer, Progress, Schedule, norm_of,
};
pub use runner::{MAX_FREE_STEPS, RunFailure, RunRecord, Runner, StoppingRule, replay};
pub use termination::{Divergence, RecordedTermination, Termination};

pub(crate) use algorithm::oracle_draw;
pub(crate) use error::{check_dim, check_finite, invalid, min_one};
pub(crate) use parameter_range::{in_range, positive};
pub(crate) use roots::{cbrt, require_roots, sqrt};
pub(crate) use vector::{axpy, norm_sq, scale};
