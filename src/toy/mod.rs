//! Toy MDPs: finite problems small enough to enumerate every trajectory, so that F(θ), ∇F(θ) and
//! E[∇f(θ, τ)] are computed exactly (math.md §1; file format `docs/formats/toy-mdp.md`), also
//! under the two fixed-horizon termination semantics of math.md §8 ([`Termination`]).

pub mod estimator;
mod format;
pub mod policy;
mod problem;
pub mod table;

pub use format::{MAX_ACTIONS, MAX_HORIZON, MAX_STATES, Termination, ToyError, ToyMdp};
pub use policy::{PolicyKind, PolicySpec};
pub use problem::{ToyExample, ToyProblem, ToyTrajectory};
pub use table::PolicyTable;
