//! # ilopt — imitation learning as stochastic optimisation, checked
//!
//! A research kit for the thesis *Momentum-Based Variance Reduced Algorithms for Imitation
//! Learning*: the unbiased gradient oracle of eq. 3.15 ([`oracle`]) on toy MDPs ([`toy`]) and on
//! the thesis's tasks ([`task`]: CartPole and the obstacle task, with their experts), the
//! algorithms built on it ([`algo`]: SGD, STORM, IS-STORM, STORM+, Adam, RMSProp, the
//! online-to-non-convex conversion, and the dataset learners BC, DAgger, RRM, SMILe, forward
//! training), and the exact engine ([`exact`]) that computes F, ∇F and the estimator's moments on
//! toy MDPs in rational arithmetic.
//!
//! Everything numeric is generic over [`scalar::Scalar`], so the same code runs in `f64`/`f32`,
//! exact rationals, interval arithmetic, and dual numbers over any of them. The repository's
//! `docs/architecture.md` maps the modules and the data flow of one iteration; `docs/math.md`
//! states the mathematics the doc comments cite as "math.md §N".
//!
//! ## Exact numbers and enclosures
//!
//! ```
//! use ilopt::scalar::{BigRational, Interval, Scalar};
//!
//! let third = BigRational::from_ratio(1, 3);
//! assert_eq!(third.clone() + third.clone() + third, <BigRational as Scalar>::one());
//! let enclosure = Interval::from_ratio(1, 3); // contains the real number 1/3
//! assert!(enclosure.inf() <= 1.0 / 3.0 && 1.0 / 3.0 <= enclosure.sup());
//! ```
//!
//! ## The estimator is unbiased, proved on a toy MDP
//!
//! Enumeration (X1) gives the expectation of the eq. 3.15 estimate, the forward recursion (X2)
//! gives ∇F; in rationals they are compared with `==`:
//!
//! ```
//! use ilopt::exact::{enumerate::moments, forward::forward};
//! use ilopt::scalar::{BigRational, Scalar};
//! use ilopt::toy::{ToyMdp, ToyProblem};
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/toy/m1-tied.json");
//! let mdp = ToyMdp::load(std::path::Path::new(path))?;
//! let problem = ToyProblem::<BigRational>::new(&mdp);
//! let theta = [BigRational::from_ratio(1, 3)];
//! let by_enumeration = moments(&problem, &theta)?;
//! let by_recursion = forward(&problem, &theta)?;
//! assert_eq!(by_enumeration.objective, by_recursion.objective);
//! assert_eq!(by_enumeration.expected_estimate, by_recursion.gradient);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Running an algorithm
//!
//! A [`algo::RunConfig`] (also readable from JSON) builds any algorithm for any scalar; the run is
//! seeded, so an interval run follows the `f64` run's trajectories and encloses its iterate:
//!
//! ```
//! use ilopt::algo::config::AlgorithmConfig;
//! use ilopt::algo::sgd::{SgdConfig, SgdStep};
//! use ilopt::algo::{ConfigNumber, RunConfig, RunRecord, StoppingRule, replay};
//! use ilopt::problem::EstimatorForm;
//! use ilopt::scalar::Interval;
//! use ilopt::toy::{ToyMdp, ToyProblem};
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/toy/m1-direct.json");
//! let mdp = ToyMdp::load(std::path::Path::new(path))?;
//! let config = RunConfig {
//!     algorithm: AlgorithmConfig::Sgd(SgdConfig {
//!         step: SgdStep::constant(ConfigNumber::ratio(1, 20)),
//!         form: EstimatorForm::Causal,
//!     }),
//!     theta0: vec![ConfigNumber::ratio(1, 2)],
//!     seed: 7,
//!     stop: StoppingRule::iterations(25),
//! };
//! let fast: RunRecord<f64> = replay(&config, &mut ToyProblem::<f64>::new(&mdp))?;
//! let rigorous: RunRecord<Interval> = replay(&config, &mut ToyProblem::<Interval>::new(&mdp))?;
//! let (x, enclosure) = (fast.theta[0], rigorous.theta[0]);
//! assert!(enclosure.inf() <= x && x <= enclosure.sup());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]
// One exception, allowed where it stands: a cache hint in `algo::prefetch`.
#![deny(unsafe_code)]
// Index loops over states and actions mirror the equations they implement (math.md §1.4).
#![allow(clippy::needless_range_loop)]

pub mod algo;
pub mod baseline;
pub mod batched;
pub mod env;
pub mod evaluate;
pub mod exact;
/// Experts that label states (thesis ch. 4): the CartPole LQR controller and the velocity-obstacle
/// expert of eq. 4.1.
pub mod expert;
pub mod lqg;
pub mod oracle;
pub mod policy;
pub mod problem;
pub mod sampling;
pub mod scalar;
pub mod seeding;
pub mod task;
pub mod tolerance;
pub mod toy;
