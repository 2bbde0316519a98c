//! STORM for IL: the update of eq. 3.40 (Cutkosky & Orabona, *Momentum-Based Variance Reduction
//! in Non-Convex SGD*, NeurIPS 2019), i.e. Algorithm 4 with erratum E9 corrected:
//!
//! ```text
//! d₁ = g(θ₁, τ₁),            θ_{k+1} = θ_k − η_k d_k,           τ_{k+1} ∼ p(·; θ_{k+1}),
//! d_{k+1} = g(θ_{k+1}, τ_{k+1}) + (1 − a_{k+1}) (d_k − g̃_k)
//! ```
//!
//! where the old-point term `g̃_k` is
//! * [`Correction::Unweighted`]: `g(θ_k, τ_{k+1})` — eq. 3.40 verbatim; in IL it is biased for
//!   ∇F(θ_k) because τ_{k+1} was drawn at θ_{k+1} (erratum E10);
//! * [`Correction::Trajectory`] / [`Correction::PerDecision`]: **IS-STORM**, math.md §4,
//!   `w_{k+1} g(θ_k, τ_{k+1})` with the likelihood ratio p(τ; θ_k)/p(τ; θ_{k+1}) on the whole
//!   estimate or per decision — exactly unbiased (identity I3), as in SRVR-PG / IS-MBPG.
//!
//! Schedules ([`StormSchedule`]):
//! * `thesis`: eq. 3.43, `η_k = (1/4L)(7/(k+7))^{1/3}`, `a_{k+1} = 16L²η_k² = (7/(k+7))^{2/3}`
//!   (needs cube roots);
//! * `adaptive`: Algorithm 4 as printed = Cutkosky–Orabona Algorithm 1 (math.md §3.3),
//!   `η_k = k'/(w + Σ_{i≤k} G_i²)^{1/3}`, `a_{k+1} = min(1, c η_k²)`, `G_i = ‖g(θ_i, τ_i)‖`
//!   (needs cube roots; the clip at 1 is the released code's, the thesis has none);
//! * `constant` and `explicit`: given η_k and a_{k+1} (field operations only, so STORM runs in
//!   exact rationals).
//!
//! The new-point estimate uses the configured [`EstimatorForm`]; the importance-weighted
//! old-point estimate is whatever [`IlProblem::weighted_estimate`] computes (the causal form in
//! the toy engine). Both are unbiased, so mixing them keeps the recursion's mean right.

use super::{
    AlgoError, Algorithm, ConfigNumber, StepContext, StepReport, axpy, cbrt, check_dim,
    check_finite, invalid, min_one, norm_sq, oracle_draw, positive, require_roots,
};
use crate::problem::{Behaviour, EstimatorForm, IlProblem, Weighting};
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// The STORM step sizes η_k and momenta a_{k+1}.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum StormSchedule {
    /// `η_k = eta`, `a_{k+1} = a` for all k.
    Constant {
        /// η > 0.
        eta: ConfigNumber,
        /// a ∈ [0, 1].
        a: ConfigNumber,
    },
    /// `η_k = eta[k−1]`, `a_{k+1} = a[k−1]`; the last entry repeats.
    Explicit {
        /// Step sizes, each > 0 (non-empty).
        eta: Vec<ConfigNumber>,
        /// Momenta, each in [0, 1] (non-empty).
        a: Vec<ConfigNumber>,
    },
    /// Eq. 3.43 with smoothness constant `l` (L = max(L_F, L̃) per math.md §3.2).
    Thesis {
        /// L > 0.
        l: ConfigNumber,
    },
    /// Algorithm 4's adaptive schedule (Cutkosky–Orabona): `k'`, `w`, `c`.
    Adaptive {
        /// k' > 0.
        k: ConfigNumber,
        /// w > 0.
        w: ConfigNumber,
        /// c ≥ 0.
        c: ConfigNumber,
    },
}

impl StormSchedule {
    /// `η_k = eta`, `a_{k+1} = a`.
    pub fn constant(eta: impl Into<ConfigNumber>, a: impl Into<ConfigNumber>) -> Self {
        StormSchedule::Constant {
            eta: eta.into(),
            a: a.into(),
        }
    }

    /// The adaptive schedule with the constants of Cutkosky & Orabona's Theorem 1 (math.md §3.3)
    /// for a free parameter `b > 0`, gradient bound `G` and smoothness `L`:
    /// `k' = bG^{2/3}/L`, `c = L²(28 + 1/(7b³))`,
    /// `w = G² max((4b)³, 2, (28b + 1/(7b²))³/64)`.
    /// The values are computed in `f64` (they involve G^{2/3}) and stored as floats, so the
    /// schedule is the same number in every scalar.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming `b`, `g` or `l` if not finite and > 0.
    pub fn cutkosky_orabona(b: f64, g: f64, l: f64) -> Result<Self, AlgoError> {
        for (name, x) in [("b", b), ("g", g), ("l", l)] {
            if !(x.is_finite() && x > 0.0) {
                return Err(invalid(name, format!("must be finite and > 0, got {x}")));
            }
        }
        let k = b * g.powf(2.0 / 3.0) / l;
        let c = l * l * (28.0 + 1.0 / (7.0 * b.powi(3)));
        let w = g
            * g
            * (4.0 * b)
                .powi(3)
                .max(2.0)
                .max((28.0 * b + 1.0 / (7.0 * b * b)).powi(3) / 64.0);
        Ok(StormSchedule::Adaptive {
            k: ConfigNumber::Float(k),
            w: ConfigNumber::Float(w),
            c: ConfigNumber::Float(c),
        })
    }
}

/// The old-point term of STORM (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Correction {
    /// `g(θ_k, τ_{k+1})`: eq. 3.40 verbatim (biased in IL, E10).
    Unweighted,
    /// IS-STORM with whole-trajectory weights.
    Trajectory,
    /// IS-STORM with per-decision weights.
    PerDecision,
}

impl Correction {
    fn weighting(self) -> Option<Weighting> {
        match self {
            Correction::Unweighted => None,
            Correction::Trajectory => Some(Weighting::Trajectory),
            Correction::PerDecision => Some(Weighting::PerDecision),
        }
    }
}

/// STORM / IS-STORM configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StormConfig {
    /// Step sizes and momenta.
    pub schedule: StormSchedule,
    /// The old-point term.
    pub correction: Correction,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

/// The schedule (3.43), as named in [`AlgoError::NeedsRoots`].
const THESIS_SCHEDULE: &str = "the STORM schedule (3.43)";
/// The Cutkosky–Orabona schedule, as named in [`AlgoError::NeedsRoots`].
const ADAPTIVE_SCHEDULE: &str = "the adaptive STORM schedule";

#[derive(Debug, Clone)]
enum Sched<S> {
    Lists(Vec<S>, Vec<S>),
    Thesis { quarter_inv_l: S },
    Adaptive { k: S, c: S, acc: S, w: S },
}

/// A validated STORM schedule in the run's scalar.
#[derive(Debug, Clone)]
pub(crate) struct Schedule<S>(Sched<S>);

impl<S: Scalar> Schedule<S> {
    /// Validate the schedule and build it in `S`.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter; [`AlgoError::NeedsRoots`] for the
    /// schedules with cube roots when `S` has none.
    pub(crate) fn new(s: &StormSchedule) -> Result<Self, AlgoError> {
        let momentum = |n: &ConfigNumber| super::in_range(n, "a", (0, false), (1, false));
        Ok(Schedule(match s {
            StormSchedule::Constant { eta, a } => Sched::Lists(
                vec![S::from_rational(&positive(eta, "eta", true)?)],
                vec![S::from_rational(&momentum(a)?)],
            ),
            StormSchedule::Explicit { eta, a } => {
                if eta.is_empty() {
                    return Err(invalid("eta", "the explicit list is empty"));
                }
                if a.is_empty() {
                    return Err(invalid("a", "the explicit list is empty"));
                }
                Sched::Lists(
                    eta.iter()
                        .map(|e| positive(e, "eta", true).map(|q| S::from_rational(&q)))
                        .collect::<Result<_, _>>()?,
                    a.iter()
                        .map(|x| momentum(x).map(|q| S::from_rational(&q)))
                        .collect::<Result<_, _>>()?,
                )
            }
            StormSchedule::Thesis { l } => {
                let l = positive(l, "l", true)?;
                require_roots::<S>(THESIS_SCHEDULE, "cube roots")?;
                Sched::Thesis {
                    quarter_inv_l: S::one() / (S::from_i64(4) * S::from_rational(&l)),
                }
            }
            StormSchedule::Adaptive { k, w, c } => {
                let w = S::from_rational(&positive(w, "w", true)?);
                let k = S::from_rational(&positive(k, "k", true)?);
                let c = S::from_rational(&positive(c, "c", false)?);
                require_roots::<S>(ADAPTIVE_SCHEDULE, "cube roots")?;
                Sched::Adaptive {
                    k,
                    c,
                    acc: w.clone(),
                    w,
                }
            }
        }))
    }

    pub(crate) fn reset(&mut self) {
        if let Sched::Adaptive { acc, w, .. } = &mut self.0 {
            *acc = w.clone();
        }
    }

    /// Record `G_i² = ‖g(θ_i, τ_i)‖²` (adaptive schedule only).
    pub(crate) fn observe(&mut self, g_norm_sq: &S) {
        if let Sched::Adaptive { acc, .. } = &mut self.0 {
            *acc += g_norm_sq;
        }
    }

    /// `(η_k, a_{k+1})` for 1-based k.
    pub(crate) fn next(&self, k: u64) -> Result<(S, S), AlgoError> {
        let i = (k - 1) as usize;
        Ok(match &self.0 {
            Sched::Lists(eta, a) => (
                eta[i.min(eta.len() - 1)].clone(),
                a[i.min(a.len() - 1)].clone(),
            ),
            Sched::Thesis { quarter_inv_l } => {
                let r = cbrt(&S::from_ratio(7, k as i64 + 7), THESIS_SCHEDULE)?;
                (quarter_inv_l.clone() * &r, r.square())
            }
            Sched::Adaptive { k: kp, c, acc, .. } => {
                let eta = kp.clone() / cbrt(acc, ADAPTIVE_SCHEDULE)?;
                let a = min_one(c.clone() * eta.square(), "a = min(1, cη²)")?;
                (eta, a)
            }
        })
    }
}

/// Which update the recursion uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Update {
    /// Eq. 3.40 (E9-corrected Algorithm 4).
    Corrected,
    /// Algorithm 4 as printed: `d_{k+1} = g(θ_{k+1}, τ_{k+1}) + (1 − a)g(θ_k, τ_{k+1})` (E9).
    PrintedE9,
}

/// STORM / IS-STORM (and, built by [`crate::algo::as_printed`], the printed Algorithm 4).
#[derive(Debug, Clone)]
pub struct Storm<S> {
    schedule: Schedule<S>,
    correction: Correction,
    form: EstimatorForm,
    update: Update,
    name: &'static str,
    theta: DVector<S>,
    d: Option<DVector<S>>,
    k: u64,
    last: Option<(S, S)>,
}

impl<S: Scalar> Storm<S> {
    /// The current iterate (as [`Algorithm::theta`], without naming the problem type).
    pub fn theta(&self) -> &DVector<S> {
        &self.theta
    }

    /// STORM (eq. 3.40) or IS-STORM, by `config.correction`. Every schedule runs in a scalar
    /// with roots; in one without (exact rationals) the `constant` and `explicit` schedules run
    /// and the cube-root schedules are rejected.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] naming the parameter (η ≤ 0, a ∉ [0, 1], L ≤ 0, …);
    /// [`AlgoError::NeedsRoots`] for the schedule (3.43) or the adaptive schedule without cube
    /// roots.
    pub fn new(config: &StormConfig) -> Result<Self, AlgoError> {
        Self::with_update(config, Update::Corrected)
    }

    pub(crate) fn with_update(config: &StormConfig, update: Update) -> Result<Self, AlgoError> {
        let name = match (update, config.correction) {
            (Update::PrintedE9, _) => "printed-algorithm-4",
            (_, Correction::Unweighted) => "storm",
            (_, _) => "is-storm",
        };
        Ok(Storm {
            schedule: Schedule::new(&config.schedule)?,
            correction: config.correction,
            form: config.form,
            update,
            name,
            theta: DVector::from_vec(Vec::new()),
            d: None,
            k: 0,
            last: None,
        })
    }

    /// The current direction `d_k` (after `init`).
    pub fn direction(&self) -> Option<&DVector<S>> {
        self.d.as_ref()
    }

    /// The `(η_k, a_{k+1})` used by the last step.
    pub fn last_schedule(&self) -> Option<&(S, S)> {
        self.last.as_ref()
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for Storm<S> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        ctx: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        self.schedule.reset();
        let (_, g, _) = oracle_draw(problem, &theta0, self.form, ctx)?;
        self.schedule.observe(&norm_sq(&g));
        self.d = Some(g);
        self.theta = theta0;
        self.k = 0;
        self.last = None;
        Ok(())
    }

    fn step(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        let d = self
            .d
            .take()
            .ok_or(AlgoError::State("STORM stepped before init"))?;
        self.k += 1;
        let (eta, a) = self.schedule.next(self.k)?;
        let new = axpy(&-eta.clone(), &d, &self.theta);
        check_finite(&new, "θ")?;
        let tau = problem.rollout(&Behaviour::Learner(&new), ctx.rng, ctx.cost)?;
        let (g_new, loss) = problem.estimate_with_loss(&new, &tau, self.form, ctx.cost)?;
        let g_old = match (self.update, self.correction.weighting()) {
            (Update::Corrected, Some(w)) => {
                problem.weighted_estimate(&self.theta, &new, &tau, w, ctx.cost)?
            }
            _ => problem.estimate(&self.theta, &tau, self.form, ctx.cost)?,
        };
        let one_minus_a = S::one() - &a;
        let d_next = match self.update {
            Update::Corrected => axpy(&one_minus_a, &(d - g_old), &g_new),
            Update::PrintedE9 => axpy(&one_minus_a, &g_old, &g_new),
        };
        check_finite(&d_next, "the STORM direction d")?;
        self.schedule.observe(&norm_sq(&g_new));
        self.theta = new;
        self.d = Some(d_next.clone());
        self.last = Some((eta, a));
        Ok(StepReport::new(Some(d_next), Some(loss)))
    }

    fn theta(&self) -> &DVector<S> {
        &self.theta
    }
}
