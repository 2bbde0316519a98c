//! The algorithms of the thesis, generic over the scalar, driven by one runner.
//!
//! Design (DESIGN.md, STYLE.md 5–7): each algorithm is a struct of *validated* hyper-parameters
//! plus state, with [`Algorithm::init`] and [`Algorithm::step`]. One [`runner::Runner`] owns the
//! loop, the stopping rule, the observers, the seeded [`KitRng`] and the termination reason; every
//! run records an [`config::RunConfig`] (algorithm + hyper-parameters + seed + stopping rule) that
//! [`runner::replay`] reproduces bit for bit.
//!
//! | module | what | thesis / paper |
//! |---|---|---|
//! | [`sgd`] | SGD on the IL objective | Algorithm 3 |
//! | [`storm`] | STORM (eq. 3.40, E9-corrected), schedules (3.43), Cutkosky–Orabona adaptive, explicit; IS-STORM | Alg. 4, math.md §§3–4 |
//! | [`storm_plus`] | STORM+ | Levy, Kavis, Cevher (NeurIPS 2021) |
//! | [`adam`], [`rmsprop`] | Adam, RMSProp | §2.6, eqs. 2.14–2.15 |
//! | [`o2nc`] | online-to-non-convex conversion with OGD, IL-correct sampling | Alg. 5, math.md §5 |
//! | [`printed`] | the printed Algorithm 4 (E9) and Algorithm 5 (E11): negative controls | math.md §§4–5 |
//! | [`dataset`] | datasets, the supervised inner optimiser | §2.4 |
//! | [`bc`], [`dagger`], [`rrm`], [`smile`], [`forward_training`] | dataset learners | §2.4, Alg. 1–2, eq. 3.29 |
//!
//! # Scalars
//! Algorithms are bounded by the weakest layer they need: SGD, STORM with an explicit (rational)
//! schedule, IS-STORM, the dataset learners with an SGD inner optimiser need only [`Scalar`] (so
//! they run in exact [`crate::scalar::BigRational`]); Adam, RMSProp and O2NC need [`Sqrt`]; the
//! schedule (3.43), the Cutkosky–Orabona schedule and STORM+ need cube roots ([`Roots`]).
//!
//! # Randomness
//! Randomness never depends on the scalar: algorithms draw uniforms only through
//! [`dyadic_uniform`] (a 53-bit dyadic rational built exactly in every scalar), and the problem
//! samples trajectories from the same RNG. So an interval run with the same seed follows the same
//! trajectories as the `f64` run and its iterates enclose the `f64` iterates.
//!
//! # Costs
//! Every oracle call adds to the run's [`Cost`]: trajectories and environment steps of each
//! roll-out, expert queries for the labels, and one *gradient evaluation* per per-state ∇l or
//! ∇log π (the problem counts them). A STORM step therefore costs one trajectory and two
//! estimates; a dataset learner's inner update costs one gradient evaluation per example in the
//! (mini)batch. The runner reports the cumulative cost and the wall time after every iteration.
//!
//! # Known limitations
//! * Under the direct parameterisation the score 1/π is unbounded, so large steps can leave the
//!   open simplex; the run then ends with [`runner::Termination::Failed`] (a domain error),
//!   never with a silently clipped or NaN iterate. No algorithm projects onto the simplex.
//! * Interval runs of Adam/RMSProp widen quickly once the gradients are small (the wrapping
//!   effect in `m̂/√v̂`): fine for a few iterations, not for long runs.
//! * STORM+'s constants follow the paper to the best of my recollection; see [`storm_plus`].

pub mod adam;
pub mod bc;
pub mod config;
pub mod dagger;
pub mod dataset;
pub mod fixture;
pub mod forward_training;
pub mod o2nc;
pub mod printed;
pub mod rmsprop;
pub mod rrm;
pub mod runner;
pub mod sgd;
pub mod smile;
pub mod storm;
pub mod storm_plus;

use crate::problem::{Cost, IlProblem, KitRng, OracleError};
use crate::scalar::{BigRational, Interval, Scalar, Sqrt, Undecidable, parse_exact};
use nalgebra::DVector;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::cmp::Ordering;

pub use config::{AlgorithmConfig, RunConfig};
pub use runner::{
    IterationMetrics, Observer, RunRecord, Runner, StoppingRule, Termination, replay, replay_field,
};

/// Why an algorithm could not be built or could not take a step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AlgoError {
    /// A hyper-parameter is invalid (negative or NaN step size, β ∉ [0, 1], zero budget, …).
    #[error("invalid hyper-parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter, as named in the docs and in the JSON config.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The algorithm (or the chosen schedule) needs square or cube roots, which the scalar lacks
    /// (exact rationals): build it with a [`Roots`] scalar or pick a field-only schedule.
    #[error("{algorithm} needs {operation}, which this scalar type does not provide")]
    NeedsRoots {
        /// The algorithm or schedule.
        algorithm: &'static str,
        /// The missing operation.
        operation: &'static str,
    },
    /// The gradient oracle failed.
    #[error(transparent)]
    Oracle(#[from] OracleError),
    /// Interval arithmetic could not decide a branch.
    #[error(transparent)]
    Undecidable(#[from] Undecidable),
    /// A value that must be finite is not (the run stops; nothing is silently NaN).
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// θ has the wrong length.
    #[error("θ has {got} entries, the problem needs {expected}")]
    Dimension {
        /// Entries the problem needs.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// `step` was called before `init`, or after the algorithm finished.
    #[error("algorithm state: {0}")]
    State(&'static str),
    /// A dataset learner has no data to train on.
    #[error("empty dataset")]
    EmptyDataset,
}

/// A hyper-parameter value, independent of the scalar the run uses: either a float or an exact
/// rational. Both are converted *exactly* ([`Num::exact`]) and then to the run's scalar with
/// [`Scalar::from_rational`], so a float hyper-parameter is the same number in `f64`, in exact
/// rationals and in intervals (a singleton), and a rational one like `1/3` is exact in
/// rationals, enclosed in intervals and correctly rounded in `f64`.
///
/// In JSON it is a string holding the exact value (`"1/3"`, `"3602879701896397/36028797018963968"`
/// for `0.1f64`). On input, strings are parsed exactly (`"1/3"`, `"0.05"` = 1/20, `"1e-8"`) and
/// JSON numbers are read as `f64` (`0.05` is then the float nearest 1/20).
#[derive(Debug, Clone)]
pub enum Num {
    /// A float; NaN and ±∞ are representable so that constructors can reject them by name.
    Float(f64),
    /// An exact rational.
    Exact(BigRational),
}

impl Num {
    /// The exact rational `n/d`.
    ///
    /// # Panics
    /// If `d == 0` (a programming error: callers write constants).
    pub fn ratio(n: i64, d: i64) -> Num {
        assert!(d != 0, "Num::ratio: zero denominator");
        Num::Exact(BigRational::new(n.into(), d.into()))
    }

    /// The exact value, or an error naming the parameter if it is NaN or infinite.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] for a non-finite float.
    pub fn exact(&self, name: &'static str) -> Result<BigRational, AlgoError> {
        match self {
            Num::Exact(q) => Ok(q.clone()),
            Num::Float(x) => {
                BigRational::from_float(*x).ok_or_else(|| invalid(name, "is not finite"))
            }
        }
    }

    /// The value in the scalar `S` (see the type docs).
    ///
    /// # Errors
    /// As [`Num::exact`].
    pub fn to<S: Scalar>(&self, name: &'static str) -> Result<S, AlgoError> {
        Ok(S::from_rational(&self.exact(name)?))
    }
}

impl From<f64> for Num {
    fn from(x: f64) -> Num {
        Num::Float(x)
    }
}

impl From<BigRational> for Num {
    fn from(q: BigRational) -> Num {
        Num::Exact(q)
    }
}

impl PartialEq for Num {
    /// Equal exact values (a float equals the rational it represents); NaN equals nothing.
    fn eq(&self, other: &Num) -> bool {
        match (self.exact("lhs"), other.exact("rhs")) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

impl Serialize for Num {
    fn serialize<Se: Serializer>(&self, s: Se) -> Result<Se::Ok, Se::Error> {
        match self {
            Num::Exact(q) => s.serialize_str(&q.to_string()),
            Num::Float(x) => match BigRational::from_float(*x) {
                Some(q) => s.serialize_str(&q.to_string()),
                None if x.is_nan() => s.serialize_str("NaN"),
                None if *x > 0.0 => s.serialize_str("inf"),
                None => s.serialize_str("-inf"),
            },
        }
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Num, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Text(String),
            Number(f64),
        }
        match Raw::deserialize(d)? {
            Raw::Number(x) => Ok(Num::Float(x)),
            Raw::Text(t) => match t.trim() {
                "NaN" => Ok(Num::Float(f64::NAN)),
                "inf" => Ok(Num::Float(f64::INFINITY)),
                "-inf" => Ok(Num::Float(f64::NEG_INFINITY)),
                other => parse_exact(other)
                    .map(Num::Exact)
                    .map_err(serde::de::Error::custom),
            },
        }
    }
}

/// Shorthand for [`AlgoError::InvalidParameter`].
pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> AlgoError {
    AlgoError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

/// Validate a hyper-parameter: exact value, `> 0` (`strict`) or `≥ 0`.
pub(crate) fn positive(
    n: &Num,
    name: &'static str,
    strict: bool,
) -> Result<BigRational, AlgoError> {
    let q = n.exact(name)?;
    let zero = BigRational::from_integer(0.into());
    if q < zero || (strict && q == zero) {
        return Err(invalid(
            name,
            format!("must be {} 0, got {q}", if strict { ">" } else { "≥" }),
        ));
    }
    Ok(q)
}

/// Validate a hyper-parameter in `[lo, hi]` (`open_lo`/`open_hi` exclude the endpoints).
pub(crate) fn in_range(
    n: &Num,
    name: &'static str,
    (lo, open_lo): (i64, bool),
    (hi, open_hi): (i64, bool),
) -> Result<BigRational, AlgoError> {
    let q = n.exact(name)?;
    let l = BigRational::from_integer(lo.into());
    let h = BigRational::from_integer(hi.into());
    let bad_lo = if open_lo { q <= l } else { q < l };
    let bad_hi = if open_hi { q >= h } else { q > h };
    if bad_lo || bad_hi {
        return Err(invalid(
            name,
            format!(
                "must lie in {}{lo}, {hi}{}, got {q}",
                if open_lo { "(" } else { "[" },
                if open_hi { ")" } else { "]" }
            ),
        ));
    }
    Ok(q)
}

/// What one algorithm step hands to the runner.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct StepReport<S> {
    /// The direction the step used (the oracle estimate for SGD, `d_k` for STORM, …), for the
    /// per-iteration "estimate norm" metric.
    pub estimate: Option<DVector<S>>,
    /// A loss estimate at the new or current iterate when the step has one at no extra cost
    /// (e.g. `Σ_t l(s_t, θ)` on the sampled trajectory, or the dataset loss).
    pub loss: Option<S>,
    /// The algorithm has completed its own schedule (O2NC after `M = KT` steps, forward training
    /// after `T − 1` policies).
    pub finished: bool,
    /// Where the step's gradient was evaluated when that is not the iterate (O2NC's w_n).
    pub evaluated_at: Option<DVector<S>>,
}

impl<S> StepReport<S> {
    /// A report with an estimate and optional loss, not finished.
    pub fn new(estimate: Option<DVector<S>>, loss: Option<S>) -> Self {
        StepReport {
            estimate,
            loss,
            finished: false,
            evaluated_at: None,
        }
    }
    /// Record where the gradient was evaluated.
    pub fn evaluated_at(mut self, point: DVector<S>) -> Self {
        self.evaluated_at = Some(point);
        self
    }
    /// Mark the algorithm as finished.
    pub fn finished(mut self) -> Self {
        self.finished = true;
        self
    }
}

/// What a step may use and must account to: the run's RNG and the cumulative [`Cost`].
#[derive(Debug)]
pub struct Ctx<'a> {
    /// The run's seeded RNG (owned by the runner).
    pub rng: &'a mut KitRng,
    /// The cumulative cost of the run.
    pub cost: &'a mut Cost,
}

/// An algorithm: hyper-parameters + state, initialised once and stepped by the runner
/// (STYLE.md 5). It drives the problem only through [`IlProblem`].
pub trait Algorithm<S: Scalar, P: IlProblem<S> + ?Sized> {
    /// A short stable name (`"sgd"`, `"is-storm"`, …).
    fn name(&self) -> &'static str;

    /// Reset the state and start from `theta0` (may already sample, e.g. STORM's `d_1`).
    ///
    /// # Errors
    /// [`AlgoError::Dimension`] for a θ of the wrong length; oracle failures.
    fn init(&mut self, problem: &P, theta0: DVector<S>, ctx: &mut Ctx<'_>)
    -> Result<(), AlgoError>;

    /// One iteration.
    ///
    /// # Errors
    /// Oracle failures, undecidable interval branches, non-finite values.
    fn step(&mut self, problem: &P, ctx: &mut Ctx<'_>) -> Result<StepReport<S>, AlgoError>;

    /// The current iterate (what the runner reports and returns).
    fn theta(&self) -> &DVector<S>;

    /// Further outputs (O2NC's `w̄ᵏ`, forward training's per-step policies, SMILe's mixture
    /// components). Empty by default.
    fn outputs(&self) -> Vec<DVector<S>> {
        Vec::new()
    }
}

/// Scalars with square and cube roots: what the schedule (3.43), the Cutkosky–Orabona schedule and
/// STORM+ need. Implemented for `f64`, `f32` and (rigorously, outward-rounded) for [`Interval`].
pub trait Roots: Sqrt {
    /// The real cube root `∛x`.
    fn cbrt(&self) -> Self;
}

impl Roots for f64 {
    fn cbrt(&self) -> Self {
        f64::cbrt(*self)
    }
}

impl Roots for f32 {
    fn cbrt(&self) -> Self {
        f32::cbrt(*self)
    }
}

fn point(x: f64) -> Interval {
    Interval::try_from((x, x)).unwrap_or(Interval::ENTIRE)
}

/// A float `c` with `c³ ≤ x` (`lower`) or `c³ ≥ x`, certified by interval arithmetic.
fn cbrt_bound(x: f64, lower: bool) -> f64 {
    if !x.is_finite() {
        return x;
    }
    let mut c = x.cbrt();
    for _ in 0..8 {
        let p = point(c);
        let cube = p * p * p;
        if lower && cube.sup() <= x {
            return c;
        }
        if !lower && cube.inf() >= x {
            return c;
        }
        c = if lower { c.next_down() } else { c.next_up() };
    }
    if lower {
        f64::NEG_INFINITY
    } else {
        f64::INFINITY
    }
}

impl Roots for Interval {
    /// An enclosure of `{∛x : x ∈ self}` (the cube root is increasing, so the endpoints suffice).
    fn cbrt(&self) -> Self {
        if self.is_empty() {
            return *self;
        }
        let lo = cbrt_bound(self.inf(), true);
        let hi = cbrt_bound(self.sup(), false);
        Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE)
    }
}

pub use crate::sampling::{UNIFORM_DENOMINATOR, dyadic_uniform};

/// `a·x + y`, entrywise.
pub(crate) fn axpy<S: Scalar>(a: &S, x: &DVector<S>, y: &DVector<S>) -> DVector<S> {
    x.zip_map(y, |xi, yi| a.clone() * xi + yi)
}

/// `Σ xᵢ²`.
pub(crate) fn norm_sq<S: Scalar>(x: &DVector<S>) -> S {
    x.iter().fold(S::zero(), |acc, v| acc + v.square())
}

/// `x · a`, entrywise.
pub(crate) fn scale<S: Scalar>(a: &S, x: &DVector<S>) -> DVector<S> {
    x.map(|xi| a.clone() * xi)
}

/// Error if any entry is not finite.
pub(crate) fn check_finite<S: Scalar>(x: &DVector<S>, what: &'static str) -> Result<(), AlgoError> {
    if x.iter().all(Scalar::is_finite) {
        Ok(())
    } else {
        Err(AlgoError::NonFinite(what))
    }
}

/// Error if θ has the wrong length.
pub(crate) fn check_dim<S>(expected: usize, theta: &DVector<S>) -> Result<(), AlgoError> {
    if theta.len() == expected {
        Ok(())
    } else {
        Err(AlgoError::Dimension {
            expected,
            got: theta.len(),
        })
    }
}

/// `min(1, x)` with a certain comparison.
pub(crate) fn min_one<S: Scalar>(x: S, what: &'static str) -> Result<S, AlgoError> {
    match x.certain_cmp(&S::one()) {
        Some(Ordering::Greater) => Ok(S::one()),
        Some(_) => Ok(x),
        None => Err(Undecidable { what }.into()),
    }
}

/// Which root operations the run's scalar provides, captured as function pointers when an
/// algorithm is built. This lets one algorithm type serve every scalar while its constructors
/// stay bounded by what they need: `…::new` for [`Roots`]/[`Sqrt`] scalars fills these in,
/// `…::new_field` for plain [`Scalar`]s leaves them out and rejects configurations that need them
/// with [`AlgoError::NeedsRoots`].
#[derive(Clone, Copy)]
pub struct RootOps<S> {
    /// `√x`, if the scalar has it.
    pub sqrt: Option<fn(&S) -> S>,
    /// `∛x`, if the scalar has it.
    pub cbrt: Option<fn(&S) -> S>,
}

impl<S> std::fmt::Debug for RootOps<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RootOps")
            .field("sqrt", &self.sqrt.is_some())
            .field("cbrt", &self.cbrt.is_some())
            .finish()
    }
}

impl<S: Scalar> RootOps<S> {
    /// No roots (exact rationals).
    pub fn none() -> Self {
        RootOps {
            sqrt: None,
            cbrt: None,
        }
    }
    /// Square roots only.
    pub fn sqrt_only() -> Self
    where
        S: Sqrt,
    {
        RootOps {
            sqrt: Some(<S as Sqrt>::sqrt),
            cbrt: None,
        }
    }
    /// Square and cube roots.
    pub fn all() -> Self
    where
        S: Roots,
    {
        RootOps {
            sqrt: Some(<S as Sqrt>::sqrt),
            cbrt: Some(<S as Roots>::cbrt),
        }
    }
    pub(crate) fn need_sqrt(&self, algorithm: &'static str) -> Result<fn(&S) -> S, AlgoError> {
        self.sqrt.ok_or(AlgoError::NeedsRoots {
            algorithm,
            operation: "square roots",
        })
    }
    pub(crate) fn need_cbrt(&self, algorithm: &'static str) -> Result<fn(&S) -> S, AlgoError> {
        self.cbrt.ok_or(AlgoError::NeedsRoots {
            algorithm,
            operation: "cube roots",
        })
    }
}

/// One oracle draw at `theta`: roll out π_θ, evaluate eq. 3.15 and the trajectory loss.
pub(crate) fn oracle_draw<S: Scalar, P: IlProblem<S> + ?Sized>(
    problem: &P,
    theta: &DVector<S>,
    form: crate::problem::EstimatorForm,
    ctx: &mut Ctx<'_>,
) -> Result<(P::Trajectory, DVector<S>, S), AlgoError> {
    let tau = problem.rollout(
        &crate::problem::Behaviour::Learner(theta),
        ctx.rng,
        ctx.cost,
    )?;
    let g = problem.estimate(theta, &tau, form, ctx.cost)?;
    check_finite(&g, "the gradient estimate")?;
    let loss = problem.trajectory_loss(theta, &tau)?;
    Ok((tau, g, loss))
}

/// A first-order update rule `θ ← U(θ, g)` with its own buffers (SGD, Adam, RMSProp). The outer
/// optimisers apply it to the eq. 3.15 estimate; the dataset learners apply it to the gradient of
/// the dataset loss (the supervised inner optimiser).
pub trait UpdateRule<S: Scalar>: std::fmt::Debug {
    /// Clear the buffers (step counter, moments).
    fn reset(&mut self);
    /// One update of `theta` along the gradient (estimate) `g`.
    ///
    /// # Errors
    /// [`AlgoError::NonFinite`] if the update is not finite (e.g. a zero RMSProp denominator).
    fn apply(&mut self, theta: &mut DVector<S>, g: &DVector<S>) -> Result<(), AlgoError>;
}

/// The shared step of the oracle-driven first-order methods (SGD, Adam, RMSProp): sample
/// τ ∼ p(·; θ), estimate g(θ, τ) (eq. 3.15), update θ with the rule.
pub(crate) fn first_order_step<S: Scalar, P: IlProblem<S> + ?Sized>(
    problem: &P,
    theta: &mut DVector<S>,
    rule: &mut dyn UpdateRule<S>,
    form: crate::problem::EstimatorForm,
    ctx: &mut Ctx<'_>,
) -> Result<StepReport<S>, AlgoError> {
    let (_, g, loss) = oracle_draw(problem, theta, form, ctx)?;
    rule.apply(theta, &g)?;
    check_finite(theta, "θ")?;
    Ok(StepReport::new(Some(g), Some(loss)))
}
