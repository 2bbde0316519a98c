//! Online-to-non-convex conversion (Algorithm 5; Cutkosky, Mehta, Orabona, ICML 2023) with online
//! gradient descent as the online learner, the parameters of math.md §5 and the **IL-correct
//! sampling** τ_n ∼ p(·; w_n) (erratum E11; the printed sampling at θ_n is
//! [`crate::algo::as_printed`]'s negative control).
//!
//! Inputs: budget N ≥ 4, δ > 0, G > 0 (G² ≥ sup_θ E‖g‖²), Δ₀ > 0 (Δ₀ ≥ F(θ₀) − F*). Then
//! `T = min(⌈(GNδ/Δ₀)^{2/3}⌉, ⌊N/2⌋)`, `K = ⌊N/T⌋`, `M = KT`, `D = δ/T`, `η = D/(G√T)`
//! (T, K, D computed exactly in rationals). For n = (k−1)T + t, one runner step each:
//!
//! ```text
//! t = 1: Δ ← 0 (restart)
//! Δ_n = Δ;  θ_n = θ_{n−1} + Δ_n;  s_n ∼ U[0,1];  w_n = θ_{n−1} + s_n Δ_n
//! τ_n ∼ p(·; w_n);  g_n = g(w_n, τ_n);  Δ ← Π_{‖·‖≤D}(Δ_n − η g_n),  Π(x) = x·min(1, D/‖x‖)
//! ```
//!
//! Outputs ([`Algorithm::outputs`]): `w̄ᵏ = (1/T) Σ_t w_{(k−1)T+t}`, k = 1..K. The run finishes
//! after M steps. `s_n` is a dyadic uniform ([`crate::sampling::dyadic_uniform`]).

use super::{
    AlgoError, Algorithm, ConfigNumber, StepContext, StepReport, axpy, check_dim, check_finite,
    invalid, norm_sq, positive, require_roots, scale, sqrt,
};
use crate::problem::{Behaviour, EstimatorForm, IlProblem};
use crate::sampling::dyadic_uniform;
use crate::scalar::{BigRational, Scalar};
use nalgebra::DVector;
use num_bigint::BigInt;
use num_traits::ToPrimitive;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;

/// O2NC, as named in [`AlgoError::NeedsRoots`].
const O2NC: &str = "O2NC (projection and η = D/(G√T))";

/// O2NC configuration (math.md §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct O2ncConfig {
    /// Budget N ≥ 4 (gradient-oracle calls).
    pub budget: u64,
    /// δ > 0.
    pub delta: ConfigNumber,
    /// G > 0 with G² ≥ sup_θ E_{τ∼θ}‖g(θ, τ)‖².
    pub g: ConfigNumber,
    /// Δ₀ > 0 with Δ₀ ≥ F(θ₀) − F*.
    pub delta0: ConfigNumber,
    /// Which form of eq. 3.15.
    pub form: EstimatorForm,
}

/// The derived parameters T, K, M, D of math.md §5 (exact).
#[derive(Debug, Clone, PartialEq)]
pub struct O2ncParameters {
    /// Block length T.
    pub t: u64,
    /// Number of blocks K.
    pub k: u64,
    /// Steps M = KT.
    pub m: u64,
    /// Radius D = δ/T.
    pub d: BigRational,
}

impl O2ncConfig {
    /// Validate and derive T, K, M, D exactly: `T = min(⌈x^{2/3}⌉, ⌊N/2⌋)` with x = GNδ/Δ₀, where
    /// ⌈x^{2/3}⌉ is the least integer t with t³ ≥ x².
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] for N < 4 or non-positive δ, G, Δ₀.
    pub fn parameters(&self) -> Result<O2ncParameters, AlgoError> {
        if self.budget < 4 {
            return Err(invalid(
                "budget",
                format!("must be at least 4, got {}", self.budget),
            ));
        }
        let delta = positive(&self.delta, "delta", true)?;
        let g = positive(&self.g, "g", true)?;
        let delta0 = positive(&self.delta0, "delta0", true)?;
        let n = BigRational::from_integer(BigInt::from(self.budget));
        let x = &g * &n * &delta / &delta0;
        let x2 = &x * &x;
        let cap = self.budget / 2;
        let cube = |t: u64| BigRational::from_integer(BigInt::from(t).pow(3));
        let t = if cube(cap) < x2 {
            cap
        } else {
            // Start from the float estimate and correct exactly.
            let est = ToPrimitive::to_f64(&x)
                .unwrap_or(0.0)
                .powf(2.0 / 3.0)
                .ceil();
            let mut t = if est.is_finite() && est >= 0.0 {
                (est as u64).min(cap)
            } else {
                cap
            };
            while t > 0 && cube(t - 1) >= x2 {
                t -= 1;
            }
            while cube(t) < x2 {
                t += 1;
            }
            t.max(1)
        };
        let k = self.budget / t;
        Ok(O2ncParameters {
            t,
            k,
            m: k * t,
            d: delta / BigRational::from_integer(BigInt::from(t)),
        })
    }
}

/// Where τ_n is sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SamplePoint {
    /// τ_n ∼ p(·; w_n) (IL-correct).
    W,
    /// τ_n ∼ p(·; θ_n) (Algorithm 5 as printed, E11).
    Theta,
}

/// Online-to-non-convex conversion with OGD.
#[derive(Debug, Clone)]
pub struct O2nc<S> {
    params: O2ncParameters,
    radius: S,
    eta: S,
    form: EstimatorForm,
    sampling: SamplePoint,
    theta: DVector<S>,
    delta: DVector<S>,
    w_sum: DVector<S>,
    n: u64,
    last_w: Option<DVector<S>>,
    outputs: Vec<DVector<S>>,
}

impl<S: Scalar> O2nc<S> {
    /// The current iterate (as [`Algorithm::theta`], without naming the problem type).
    pub fn theta(&self) -> &DVector<S> {
        &self.theta
    }

    /// Validate and build (IL-correct sampling at w_n).
    ///
    /// # Errors
    /// As [`O2ncConfig::parameters`]; [`AlgoError::NeedsRoots`] for a scalar without square
    /// roots.
    pub fn new(config: &O2ncConfig) -> Result<Self, AlgoError> {
        Self::with_sampling(config, SamplePoint::W)
    }

    pub(crate) fn with_sampling(
        config: &O2ncConfig,
        sampling: SamplePoint,
    ) -> Result<Self, AlgoError> {
        let params = config.parameters()?;
        let radius = S::from_rational(&params.d);
        let g = S::from_rational(&config.g.exact("g")?);
        require_roots::<S>(O2NC, "square roots")?;
        let eta = radius.clone() / (g * sqrt(&S::from_i64(params.t as i64), O2NC)?);
        Ok(O2nc {
            params,
            radius,
            eta,
            form: config.form,
            sampling,
            theta: DVector::from_vec(Vec::new()),
            delta: DVector::from_vec(Vec::new()),
            w_sum: DVector::from_vec(Vec::new()),
            n: 0,
            last_w: None,
            outputs: Vec::new(),
        })
    }

    /// The derived T, K, M, D.
    pub fn parameters(&self) -> &O2ncParameters {
        &self.params
    }

    /// The OGD step size η = D/(G√T).
    pub fn ogd_step(&self) -> &S {
        &self.eta
    }

    /// The last sampled point w_n.
    pub fn last_w(&self) -> Option<&DVector<S>> {
        self.last_w.as_ref()
    }

    /// Π_{‖·‖≤D}(x) = x·min(1, D/‖x‖), decided by comparing ‖x‖² with D².
    fn project(&self, x: DVector<S>) -> Result<DVector<S>, AlgoError> {
        let n2 = norm_sq(&x);
        match n2.certain_cmp(&self.radius.square()) {
            Some(Ordering::Greater) => {
                let f = self.radius.clone() / sqrt(&n2, O2NC)?;
                Ok(scale(&f, &x))
            }
            Some(_) => Ok(x),
            None => Err(crate::scalar::Undecidable {
                what: "O2NC projection ‖x‖ ≤ D",
            }
            .into()),
        }
    }
}

impl<S: Scalar, P: IlProblem<S> + ?Sized> Algorithm<S, P> for O2nc<S> {
    fn name(&self) -> &'static str {
        match self.sampling {
            SamplePoint::W => "o2nc",
            SamplePoint::Theta => "printed-algorithm-5",
        }
    }

    fn init(
        &mut self,
        problem: &mut P,
        theta0: DVector<S>,
        _: &mut StepContext<'_>,
    ) -> Result<(), AlgoError> {
        check_dim(problem.dim(), &theta0)?;
        let zero = DVector::from_element(theta0.len(), S::zero());
        self.delta = zero.clone();
        self.w_sum = zero;
        self.theta = theta0;
        self.n = 0;
        self.last_w = None;
        self.outputs.clear();
        Ok(())
    }

    fn step(
        &mut self,
        problem: &mut P,
        ctx: &mut StepContext<'_>,
    ) -> Result<StepReport<S>, AlgoError> {
        if self.n >= self.params.m {
            return Err(AlgoError::State("O2NC has used its M = KT steps"));
        }
        self.n += 1;
        let t = (self.n - 1) % self.params.t + 1;
        if t == 1 {
            self.delta.iter_mut().for_each(|x| *x = S::zero());
            self.w_sum.iter_mut().for_each(|x| *x = S::zero());
        }
        let delta_n = self.delta.clone();
        let theta_n = &self.theta + &delta_n;
        let s: S = dyadic_uniform(ctx.rng);
        let w_n = axpy(&s, &delta_n, &self.theta);
        check_finite(&w_n, "w_n")?;
        let at = match self.sampling {
            SamplePoint::W => &w_n,
            SamplePoint::Theta => &theta_n,
        };
        let tau = problem.rollout(&Behaviour::Learner(at), ctx.rng, ctx.cost)?;
        let g = problem.estimate(&w_n, &tau, self.form, ctx.cost)?;
        check_finite(&g, "the gradient estimate")?;
        self.delta = self.project(axpy(&-self.eta.clone(), &g, &delta_n))?;
        self.w_sum += &w_n;
        if t == self.params.t {
            let inv = S::one() / S::from_i64(self.params.t as i64);
            self.outputs.push(scale(&inv, &self.w_sum));
        }
        let loss = if self.sampling == SamplePoint::W {
            Some(problem.trajectory_loss(&w_n, &tau)?)
        } else {
            None
        };
        self.theta = theta_n;
        self.last_w = Some(w_n.clone());
        let report = StepReport::new(Some(g), loss).evaluated_at(w_n);
        Ok(if self.n == self.params.m {
            report.finished()
        } else {
            report
        })
    }

    fn theta(&self) -> &DVector<S> {
        &self.theta
    }

    fn outputs(&self) -> Vec<DVector<S>> {
        self.outputs.clone()
    }
}
