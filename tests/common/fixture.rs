//! A small self-contained [`IlProblem`]: the aliased two-state family M(μ_A, p₀, p₁, T) of
//! math.md §6 under the direct parameterisation P1, written independently of the toy-MDP module so
//! that the algorithms can be tested and cross-checked against `ilopt::toy`. A test fixture,
//! declared once by the algorithms test crate (`tests/algorithms/main.rs`).
//!
//! States A (= 0), B (= 1); actions 0, 1; expert a*(A) = 1, a*(B) = 0; μ = (μ_A, 1 − μ_A);
//! action 1 leads to A w.p. p₁, action 0 w.p. p₀, whatever the state. The learner cannot see the
//! state: θ = (p) with π_θ(1) = p, p ∈ (0, 1). Brier loss l(A) = 2(1 − p)², l(B) = 2p².
//! Closed forms (math.md §6): `F(p) = A₂p² + A₁p + A₀`, RRM map `G(p) = (μ_A + (T−2)(p₀ + Δp))/(T−1)`.
//!
//! Sampling uses one dyadic uniform ([`ilopt::sampling::dyadic_uniform`]) per decision, compared with
//! [`Scalar::certain_cmp`], so every scalar follows the same trajectory for the same seed.

#![allow(dead_code)]

use ilopt::algo::AlgoError;
use ilopt::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use ilopt::sampling::UNIFORM_DENOMINATOR;
use ilopt::scalar::{BigRational, Scalar, Undecidable};
use nalgebra::DVector;
use rand::RngCore;
use std::cmp::Ordering;

/// [`AlgoError::InvalidParameter`] for `name`.
fn invalid(name: &'static str, reason: impl Into<String>) -> AlgoError {
    AlgoError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

/// The M-family problem of math.md §6 with the direct parameterisation.
#[derive(Debug, Clone, PartialEq)]
pub struct AliasedTwoState {
    mu_a: BigRational,
    p0: BigRational,
    p1: BigRational,
    horizon: usize,
}

/// A trajectory of [`AliasedTwoState`]: states `s_1..s_T` (0 = A, 1 = B) and actions
/// `a_1..a_{T−1}`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TwoStateTrajectory {
    /// Visited states, length T.
    pub states: Vec<u8>,
    /// Actions taken, length T − 1.
    pub actions: Vec<u8>,
}

fn q(n: i64, d: i64) -> BigRational {
    BigRational::new(n.into(), d.into())
}

impl AliasedTwoState {
    /// M(μ_A, p₀, p₁, T).
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] if a probability is outside [0, 1] or `horizon < 2`.
    pub fn new(
        mu_a: BigRational,
        p0: BigRational,
        p1: BigRational,
        horizon: usize,
    ) -> Result<Self, AlgoError> {
        for (name, v) in [("mu_a", &mu_a), ("p0", &p0), ("p1", &p1)] {
            if *v < q(0, 1) || *v > q(1, 1) {
                return Err(invalid(name, format!("must lie in [0, 1], got {v}")));
            }
        }
        if horizon < 2 {
            return Err(invalid("horizon", "must be at least 2"));
        }
        Ok(AliasedTwoState {
            mu_a,
            p0,
            p1,
            horizon,
        })
    }

    /// M1 = M(1/2, 1/2, 1, 3): `F(p) = 2p² − 3p + 2`, p_PO = 3/4, p_PS = 2/3, κ = 1/4.
    pub fn m1() -> Self {
        AliasedTwoState {
            mu_a: q(1, 2),
            p0: q(1, 2),
            p1: q(1, 1),
            horizon: 3,
        }
    }

    /// The horizon T.
    pub fn horizon(&self) -> usize {
        self.horizon
    }

    fn coefficients(&self) -> (BigRational, BigRational, BigRational) {
        let t = BigRational::from_integer((self.horizon as i64).into());
        let one = q(1, 1);
        let two = q(2, 1);
        let four = q(4, 1);
        let d = &self.p1 - &self.p0;
        let a2 = &two * (&t - &one) - &four * (&t - &two) * &d;
        let base = &self.mu_a + (&t - &two) * &self.p0;
        let a1 = &two * (&t - &two) * &d - &four * &base;
        let a0 = &two * &base;
        (a2, a1, a0)
    }

    /// The exact objective `F(p) = A₂p² + A₁p + A₀` (math.md §6).
    pub fn objective<S: Scalar>(&self, p: &S) -> S {
        let (a2, a1, a0) = self.coefficients();
        S::from_rational(&a2) * p.square() + S::from_rational(&a1) * p + S::from_rational(&a0)
    }

    /// The exact derivative `F'(p) = 2A₂p + A₁`.
    pub fn derivative<S: Scalar>(&self, p: &S) -> S {
        let (a2, a1, _) = self.coefficients();
        S::from_rational(&(q(2, 1) * a2)) * p + S::from_rational(&a1)
    }

    /// The exact RRM map of eq. 3.29 (population), `G(p) = (μ_A + (T−2)(p₀ + Δp))/(T−1)`.
    pub fn rrm_map<S: Scalar>(&self, p: &S) -> S {
        let t = self.horizon as i64;
        let d = S::from_rational(&(&self.p1 - &self.p0));
        let qp = S::from_rational(&self.p0) + d * p;
        (S::from_rational(&self.mu_a) + S::from_i64(t - 2) * qp) / S::from_i64(t - 1)
    }

    /// `p_PO = −A₁/(2A₂)` (valid when A₂ > 0 and the vertex lies in (0, 1)).
    pub fn p_po(&self) -> BigRational {
        let (a2, a1, _) = self.coefficients();
        -a1 / (q(2, 1) * a2)
    }

    /// `p_PS = (μ_A + (T−2)p₀)/((T−1) − (T−2)Δ)`.
    pub fn p_ps(&self) -> BigRational {
        let t = BigRational::from_integer((self.horizon as i64).into());
        let two = q(2, 1);
        (&self.mu_a + (&t - &two) * &self.p0)
            / ((&t - q(1, 1)) - (&t - &two) * (&self.p1 - &self.p0))
    }

    /// The RRM contraction modulus `κ = (T−2)Δ/(T−1)`.
    pub fn kappa(&self) -> BigRational {
        let t = self.horizon as i64;
        (&self.p1 - &self.p0) * q(t - 2, t - 1)
    }

    fn p<'a, S: Scalar>(&self, theta: &'a DVector<S>) -> Result<&'a S, OracleError> {
        if theta.len() != 1 {
            return Err(OracleError::Dimension {
                expected: 1,
                got: theta.len(),
            });
        }
        let p = &theta[0];
        if !p.is_finite() {
            return Err(OracleError::NonFinite("θ"));
        }
        if !(p.is_certainly_positive() && S::one().certain_cmp(p) == Some(Ordering::Greater)) {
            return Err(OracleError::Domain(format!(
                "the direct parameterisation needs p ∈ (0, 1) certainly, got {:?}",
                p
            )));
        }
        Ok(p)
    }

    /// π_θ(a).
    fn pi<S: Scalar>(p: &S, a: u8) -> S {
        if a == 1 { p.clone() } else { S::one() - p }
    }

    /// ψ = ∇log π_θ(a).
    fn score<S: Scalar>(p: &S, a: u8) -> S {
        if a == 1 {
            S::one() / p
        } else {
            -(S::one() / (S::one() - p))
        }
    }

    /// l(s, θ) and ∇l(s, θ) for the Brier loss.
    fn loss<S: Scalar>(p: &S, s: u8) -> (S, S) {
        let two = S::from_i64(2);
        let four = S::from_i64(4);
        if s == 0 {
            let r = S::one() - p;
            (two * r.square(), -(four * r))
        } else {
            (two * p.square(), four * p)
        }
    }

    fn check(&self, tau: &TwoStateTrajectory) -> Result<(), OracleError> {
        if tau.states.len() != self.horizon
            || tau.actions.len() + 1 != self.horizon
            || tau.states.iter().chain(&tau.actions).any(|&x| x > 1)
        {
            return Err(OracleError::Trajectory(
                "not a trajectory of this problem".into(),
            ));
        }
        Ok(())
    }

    /// Per-step terms `∇l_t + l_t Σ_{i<t} ψ_i` (causal) at θ, each with the prefix weight
    /// `Π_{i<t} π_old/π_new` if requested.
    fn terms<S: Scalar>(
        &self,
        p: &S,
        tau: &TwoStateTrajectory,
        form: EstimatorForm,
        new_p: Option<&S>,
        weighting: Option<Weighting>,
    ) -> Result<S, OracleError> {
        let n = self.horizon - 1;
        let mut total = S::zero();
        let mut psi_sum = S::zero();
        let mut prefix_w = S::one();
        let mut all_psi = S::zero();
        let mut all_loss = S::zero();
        for t in 0..n {
            let (l, dl) = Self::loss(p, tau.states[t]);
            match form {
                EstimatorForm::Causal => {
                    let term = dl + l * &psi_sum;
                    total += match weighting {
                        Some(Weighting::PerDecision) => prefix_w.clone() * term,
                        _ => term,
                    };
                }
                EstimatorForm::Full => {
                    total += dl;
                    all_loss += l;
                }
            }
            if t + 1 < n {
                let a = tau.actions[t];
                psi_sum += Self::score(p, a);
                all_psi += Self::score(p, a);
                if let Some(np) = new_p {
                    let den = Self::pi(np, a);
                    if den.is_certainly_zero() {
                        return Err(OracleError::ZeroProbability("π_new"));
                    }
                    prefix_w *= Self::pi(p, a) / den;
                }
            }
        }
        if form == EstimatorForm::Full {
            total += all_loss * all_psi;
            if weighting == Some(Weighting::PerDecision) {
                // The per-decision split is defined on the causal form; for the full form the
                // whole-trajectory weight is used (still unbiased).
                total *= prefix_w.clone();
            }
        }
        if weighting == Some(Weighting::Trajectory) {
            total *= prefix_w;
        }
        Ok(total)
    }

    fn gradient_evaluations(&self) -> u64 {
        // T−1 loss gradients and T−2 scores.
        2 * self.horizon as u64 - 3
    }
}

fn uniform_index(rng: &mut KitRng) -> i64 {
    (rng.next_u64() >> 11) as i64
}

/// `u < x` for the dyadic `u = k/2⁵³`, certain or an error.
fn below<S: Scalar>(k: i64, x: &S, what: &'static str) -> Result<bool, OracleError> {
    match S::from_ratio(k, UNIFORM_DENOMINATOR).certain_cmp(x) {
        Some(o) => Ok(o == Ordering::Less),
        None => Err(Undecidable { what }.into()),
    }
}

impl<S: Scalar> IlProblem<S> for AliasedTwoState {
    type Trajectory = TwoStateTrajectory;
    /// A state (0 = A, 1 = B); its expert label is `1 − state`.
    type Labelled = u8;

    fn dim(&self) -> usize {
        1
    }

    fn rollout(
        &mut self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<TwoStateTrajectory, OracleError> {
        // Validate the behaviour's parameters first.
        match behaviour {
            Behaviour::Learner(th) => {
                self.p(th)?;
            }
            Behaviour::Expert => {}
            Behaviour::Mixture {
                expert_weight,
                learners,
            } => {
                let total: f64 = expert_weight + learners.iter().map(|(w, _)| w).sum::<f64>();
                if !(0.0..=1.0).contains(expert_weight)
                    || learners.iter().any(|(w, _)| !(0.0..=1.0).contains(w))
                    || (total - 1.0).abs() > 1e-9
                {
                    return Err(OracleError::Behaviour(
                        "weights must be in [0, 1] and sum to 1".into(),
                    ));
                }
                for (_, th) in learners {
                    self.p(th)?;
                }
            }
            Behaviour::NonStationary(per_step) => {
                for th in per_step.iter().flatten() {
                    self.p(th)?;
                }
            }
            #[allow(unreachable_patterns)]
            _ => return Err(OracleError::Behaviour("unsupported behaviour".into())),
        }
        let exact = |x: &BigRational| S::from_rational(x);
        let mut states = Vec::with_capacity(self.horizon);
        let mut actions = Vec::with_capacity(self.horizon - 1);
        let u = uniform_index(rng);
        let mut s: u8 = if below(u, &exact(&self.mu_a), "initial state")? {
            0
        } else {
            1
        };
        states.push(s);
        for t in 0..self.horizon - 1 {
            // Who acts: None = expert, Some(p) = a learner with π(1) = p.
            let actor: Option<&S> = match behaviour {
                Behaviour::Learner(th) => Some(&th[0]),
                Behaviour::Expert => None,
                Behaviour::Mixture {
                    expert_weight,
                    learners,
                } => {
                    let v = uniform_index(rng) as f64 / UNIFORM_DENOMINATOR as f64;
                    if v < *expert_weight {
                        None
                    } else {
                        let mut acc = *expert_weight;
                        let mut chosen = learners.last().map(|(_, th)| &th[0]);
                        for (w, th) in learners {
                            acc += w;
                            if v < acc {
                                chosen = Some(&th[0]);
                                break;
                            }
                        }
                        chosen
                    }
                }
                Behaviour::NonStationary(per_step) => {
                    per_step.get(t).copied().flatten().map(|th| &th[0])
                }
                #[allow(unreachable_patterns)]
                _ => None,
            };
            let a: u8 = match actor {
                None => 1 - s,
                Some(p) => u8::from(below(uniform_index(rng), p, "action sampling")?),
            };
            let to_a = if a == 1 { &self.p1 } else { &self.p0 };
            s = if below(uniform_index(rng), &exact(to_a), "transition")? {
                0
            } else {
                1
            };
            actions.push(a);
            states.push(s);
        }
        cost.trajectories += 1;
        cost.env_steps += (self.horizon - 1) as u64;
        cost.expert_queries += (self.horizon - 1) as u64;
        Ok(TwoStateTrajectory { states, actions })
    }

    fn estimate(
        &mut self,
        theta: &DVector<S>,
        trajectory: &TwoStateTrajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let p = self.p(theta)?;
        self.check(trajectory)?;
        let g = self.terms(p, trajectory, form, None, None)?;
        cost.gradient_evaluations += self.gradient_evaluations();
        Ok(DVector::from_element(1, g))
    }

    fn weighted_estimate(
        &mut self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &TwoStateTrajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        let p = self.p(theta_old)?;
        let np = self.p(theta_new)?;
        self.check(trajectory)?;
        let g = self.terms(
            p,
            trajectory,
            EstimatorForm::Causal,
            Some(np),
            Some(weighting),
        )?;
        cost.gradient_evaluations += self.gradient_evaluations();
        Ok(DVector::from_element(1, g))
    }

    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &TwoStateTrajectory,
    ) -> Result<S, OracleError> {
        let p = self.p(theta)?;
        self.check(trajectory)?;
        Ok(trajectory.states[..self.horizon - 1]
            .iter()
            .fold(S::zero(), |acc, &s| acc + Self::loss(p, s).0))
    }

    fn labelled_states(&self, trajectory: &TwoStateTrajectory) -> Vec<u8> {
        trajectory.states[..trajectory.states.len().saturating_sub(1)].to_vec()
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &u8,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError> {
        for len in [theta.len(), grad.len()] {
            if len != 1 {
                return Err(OracleError::Dimension {
                    expected: 1,
                    got: len,
                });
            }
        }
        // The supervised loss is a polynomial: it is defined for every real p, so training may
        // pass through p ∉ (0, 1) (only roll-outs need a probability).
        if *example > 1 {
            return Err(OracleError::Trajectory("state out of range".into()));
        }
        let (l, dl) = Self::loss(&theta[0], *example);
        cost.gradient_evaluations += 1;
        grad[0] = dl;
        Ok(l)
    }
}
