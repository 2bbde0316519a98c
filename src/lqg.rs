//! The linear-quadratic-Gaussian toy of math.md §1.3: a continuous imitation-learning problem
//! whose objective and expected gradient estimate are **polynomials** in the policy's weights, so
//! the unbiasedness claim E[∇f] = ∇F (eqs. 3.14–3.16) becomes an exact matrix identity in ℚ.
//!
//! Dynamics `s_{t+1} = As_t + Ba_t + ω_t`, `ω_t ∼ N(0, Q)`, `s_1 ∼ N(0, Σ₁)`; learner
//! `a_t ∼ N(Ws_t, σ_π² I_m)` (P3 with φ(s) = s, [`LinearGaussian`]); linear expert `π*(s) = Ks`;
//! loss on the output (erratum E1) `l_t = ‖Ws_t − Ks_t‖² = s_tᵀHs_t`. With
//! `M = A + BW`, `H = (W − K)ᵀ(W − K)`, `P_t = E[s_t s_tᵀ]`:
//!
//! * covariance recursion: `P_1 = Σ₁`, `P_{t+1} = M P_t Mᵀ + σ_π² BBᵀ + Q`;
//! * objective: `F(W) = Σ_{t=1}^{T−1} tr(H P_t)` ([`LqgSystem::objective`]);
//! * expected estimate of eq. 3.15, by Isserlis' theorem
//!   (`Cov(s_t, ε_i) = M^{t−i−1}Bσ_π`, `Cov(s_t, s_i) = M^{t−i}P_i`, `ε_i ⊥ s_i`, all zero-mean):
//!   `E[g] = Σ_{t=1}^{T−1} [2(W − K)P_t + Σ_{i=1}^{t−1} 2Bᵀ(M^{t−i−1})ᵀ H M^{t−i} P_i]`
//!   ([`LqgSystem::expected_estimate`]); the double sum is `Σ E[l_t ∇log π_i]`;
//! * ∇F by forward-mode [`Dual`] numbers through the recursion ([`LqgSystem::gradient`]): an
//!   independent route that uses no score formula.
//!
//! A non-zero mean of s₁ would add Isserlis terms; the toy keeps it zero. Matrices are nalgebra
//! [`DMatrix`]es over any [`Scalar`]; the arithmetic is written here because nalgebra's own products
//! need `num_traits::Zero`, which intervals (inari's type, so the kit cannot add it) do not
//! implement.

use crate::oracle::EstimatorKernel;
use crate::policy::{LinearGaussian, Policy, PolicyError, check_vec_scalar};
use crate::problem::KitRng;
use crate::sampling::standard_normal;
use crate::scalar::{Dual, Scalar, Sqrt};
use nalgebra::DMatrix;
use std::cmp::Ordering;

/// Why an LQG system could not be built or evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LqgError {
    /// A matrix has the wrong shape.
    #[error("`{param}` is {got_rows}×{got_cols}, expected {rows}×{cols}")]
    Shape {
        /// The offending parameter.
        param: &'static str,
        /// Rows expected.
        rows: usize,
        /// Columns expected.
        cols: usize,
        /// Rows given.
        got_rows: usize,
        /// Columns given.
        got_cols: usize,
    },
    /// A dimension is zero.
    #[error("`{param}` must be at least 1")]
    EmptyDimension {
        /// The offending parameter.
        param: &'static str,
    },
    /// A value is NaN, ±∞ or an unbounded interval.
    #[error("`{param}` contains a non-finite value")]
    NonFinite {
        /// The offending parameter.
        param: &'static str,
    },
    /// σ_π² is not certainly > 0.
    #[error("`{param}` must be certainly positive, got {value}")]
    NotPositive {
        /// The offending parameter.
        param: &'static str,
        /// Its (lossy) value.
        value: f64,
    },
    /// The horizon is below 2 (no loss would be paid after a decision).
    #[error("`horizon` must be at least 2, got {0}")]
    Horizon(usize),
    /// A covariance matrix is certainly not symmetric.
    #[error("`{param}` must be symmetric (a covariance)")]
    Asymmetric {
        /// The offending parameter.
        param: &'static str,
    },
    /// Sampling needs a Cholesky factor, and this covariance is not certainly positive definite.
    #[error("`{param}` must be certainly positive definite to sample from it")]
    NotPositiveDefinite {
        /// The offending parameter.
        param: &'static str,
    },
    /// The policy rejected an input.
    #[error(transparent)]
    Policy(#[from] PolicyError),
}

/// An LQG imitation problem (math.md §1.3), validated. `n` = state dimension, `m` = action
/// dimension.
#[derive(Debug, Clone, PartialEq)]
pub struct LqgSystem<S: Scalar> {
    a: DMatrix<S>,
    b: DMatrix<S>,
    q: DMatrix<S>,
    sigma1: DMatrix<S>,
    k: DMatrix<S>,
    sigma_pi_sq: S,
    horizon: usize,
}

/// One simulated trajectory: states `s_1..s_T` and actions `a_1..a_{T−1}`.
#[derive(Debug, Clone, PartialEq)]
pub struct LqgTrajectory<S> {
    /// `s_1, …, s_T` (each of length n).
    pub states: Vec<Vec<S>>,
    /// `a_1, …, a_{T−1}` (each of length m).
    pub actions: Vec<Vec<S>>,
}

fn check_shape<S: Scalar>(
    param: &'static str,
    x: &DMatrix<S>,
    rows: usize,
    cols: usize,
) -> Result<(), LqgError> {
    if x.nrows() != rows || x.ncols() != cols {
        return Err(LqgError::Shape {
            param,
            rows,
            cols,
            got_rows: x.nrows(),
            got_cols: x.ncols(),
        });
    }
    if !x.iter().all(Scalar::is_finite) {
        return Err(LqgError::NonFinite { param });
    }
    Ok(())
}

fn check_symmetric<S: Scalar>(param: &'static str, x: &DMatrix<S>) -> Result<(), LqgError> {
    for i in 0..x.nrows() {
        for j in 0..i {
            if matches!(
                x[(i, j)].certain_cmp(&x[(j, i)]),
                Some(Ordering::Less | Ordering::Greater)
            ) {
                return Err(LqgError::Asymmetric { param });
            }
        }
    }
    Ok(())
}

/// `AB` for any scalar.
fn mm<S: Scalar>(a: &DMatrix<S>, b: &DMatrix<S>) -> DMatrix<S> {
    DMatrix::from_fn(a.nrows(), b.ncols(), |i, j| {
        (0..a.ncols()).fold(S::zero(), |acc, k| acc + a[(i, k)].clone() * &b[(k, j)])
    })
}

fn zip<S: Scalar>(a: &DMatrix<S>, b: &DMatrix<S>, f: impl Fn(&S, &S) -> S) -> DMatrix<S> {
    DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| f(&a[(i, j)], &b[(i, j)]))
}

fn add<S: Scalar>(a: &DMatrix<S>, b: &DMatrix<S>) -> DMatrix<S> {
    zip(a, b, |x, y| x.clone() + y)
}

fn scale<S: Scalar>(c: &S, a: &DMatrix<S>) -> DMatrix<S> {
    a.map(|x| c.clone() * &x)
}

fn zeros<S: Scalar>(rows: usize, cols: usize) -> DMatrix<S> {
    DMatrix::from_fn(rows, cols, |_, _| S::zero())
}

fn identity<S: Scalar>(n: usize) -> DMatrix<S> {
    DMatrix::from_fn(n, n, |i, j| if i == j { S::one() } else { S::zero() })
}

fn trace<S: Scalar>(a: &DMatrix<S>) -> S {
    (0..a.nrows().min(a.ncols())).fold(S::zero(), |acc, i| acc + &a[(i, i)])
}

/// The policy parameter vector of a weight matrix: `θ[i·n + j] = W_ij` (the row-major layout of
/// [`LinearGaussian`]).
pub fn theta_of<S: Scalar>(w: &DMatrix<S>) -> Vec<S> {
    (0..w.nrows())
        .flat_map(|i| (0..w.ncols()).map(move |j| w[(i, j)].clone()))
        .collect()
}

/// The `rows × cols` weight matrix of a row-major parameter vector (inverse of [`theta_of`]).
///
/// # Errors
/// [`LqgError::Shape`] if `theta.len() ≠ rows·cols`.
pub fn matrix_of<S: Scalar>(theta: &[S], rows: usize, cols: usize) -> Result<DMatrix<S>, LqgError> {
    if theta.len() != rows * cols {
        return Err(LqgError::Shape {
            param: "theta",
            rows: rows * cols,
            cols: 1,
            got_rows: theta.len(),
            got_cols: 1,
        });
    }
    Ok(DMatrix::from_row_slice(rows, cols, theta))
}

/// The lower Cholesky factor `L` with `LLᵀ = x`, when every pivot is certainly positive.
fn cholesky<S: Sqrt>(param: &'static str, x: &DMatrix<S>) -> Result<DMatrix<S>, LqgError> {
    let n = x.nrows();
    let mut l = zeros::<S>(n, n);
    for j in 0..n {
        let pivot = (0..j).fold(x[(j, j)].clone(), |acc, k| acc - l[(j, k)].square());
        if !pivot.is_certainly_positive() {
            return Err(LqgError::NotPositiveDefinite { param });
        }
        let d = pivot.sqrt();
        for i in j + 1..n {
            let v = (0..j).fold(x[(i, j)].clone(), |acc, k| {
                acc - l[(i, k)].clone() * &l[(j, k)]
            });
            l[(i, j)] = v / &d;
        }
        l[(j, j)] = d;
    }
    Ok(l)
}

impl<S: Scalar> LqgSystem<S> {
    /// A validated system. Shapes: `A` n×n, `B` n×m, `Q` and `Σ₁` n×n symmetric, `K` m×n;
    /// `σ_π² > 0` certainly; `horizon = T ≥ 2`; every entry finite.
    ///
    /// Positive semi-definiteness of `Q` and `Σ₁` is what makes them covariances; the exact
    /// identities hold for any symmetric data, and sampling ([`LqgSystem::simulator`]) checks
    /// positive definiteness.
    ///
    /// # Errors
    /// [`LqgError`] naming the first offending parameter.
    pub fn new(
        a: DMatrix<S>,
        b: DMatrix<S>,
        q: DMatrix<S>,
        sigma1: DMatrix<S>,
        k: DMatrix<S>,
        sigma_pi_sq: S,
        horizon: usize,
    ) -> Result<Self, LqgError> {
        let n = a.nrows();
        let m = b.ncols();
        if n == 0 {
            return Err(LqgError::EmptyDimension { param: "a" });
        }
        if m == 0 {
            return Err(LqgError::EmptyDimension { param: "b" });
        }
        check_shape("a", &a, n, n)?;
        check_shape("b", &b, n, m)?;
        check_shape("q", &q, n, n)?;
        check_shape("sigma1", &sigma1, n, n)?;
        check_shape("k", &k, m, n)?;
        check_symmetric("q", &q)?;
        check_symmetric("sigma1", &sigma1)?;
        if !sigma_pi_sq.is_finite() {
            return Err(LqgError::NonFinite {
                param: "sigma_pi_sq",
            });
        }
        if !sigma_pi_sq.is_certainly_positive() {
            return Err(LqgError::NotPositive {
                param: "sigma_pi_sq",
                value: sigma_pi_sq.to_f64(),
            });
        }
        if horizon < 2 {
            return Err(LqgError::Horizon(horizon));
        }
        Ok(Self {
            a,
            b,
            q,
            sigma1,
            k,
            sigma_pi_sq,
            horizon,
        })
    }

    /// State dimension n.
    pub fn state_dim(&self) -> usize {
        self.a.nrows()
    }
    /// Action dimension m.
    pub fn action_dim(&self) -> usize {
        self.b.ncols()
    }
    /// Horizon T (losses at t = 1..T−1).
    pub fn horizon(&self) -> usize {
        self.horizon
    }
    /// σ_π².
    pub fn sigma_pi_sq(&self) -> &S {
        &self.sigma_pi_sq
    }
    /// The expert gain K (m×n).
    pub fn expert_gain(&self) -> &DMatrix<S> {
        &self.k
    }

    /// The dynamics matrix A (n×n).
    pub fn a(&self) -> &DMatrix<S> {
        &self.a
    }
    /// The input matrix B (n×m).
    pub fn b(&self) -> &DMatrix<S> {
        &self.b
    }
    /// The process-noise covariance Q (n×n).
    pub fn q(&self) -> &DMatrix<S> {
        &self.q
    }
    /// The initial-state covariance Σ₁ (n×n).
    pub fn sigma1(&self) -> &DMatrix<S> {
        &self.sigma1
    }

    /// The same system in another scalar type, every entry converted by `f` (e.g.
    /// `Interval::from_rational`, `|x| x.to_f64()`), validated again.
    ///
    /// # Errors
    /// As [`LqgSystem::new`] (e.g. a rational too large for `f64` becomes non-finite).
    pub fn try_map<T: Scalar>(&self, f: impl Fn(&S) -> T) -> Result<LqgSystem<T>, LqgError> {
        let l = self.lift(f);
        LqgSystem::new(l.a, l.b, l.q, l.sigma1, l.k, l.sigma_pi_sq, l.horizon)
    }

    fn check_w(&self, w: &DMatrix<S>) -> Result<(), LqgError> {
        check_shape("w", w, self.action_dim(), self.state_dim())
    }

    /// The same system with every entry mapped by `f` (used to lift the data into dual numbers).
    fn lift<T: Scalar>(&self, f: impl Fn(&S) -> T) -> LqgSystem<T> {
        LqgSystem {
            a: self.a.map(|x| f(&x)),
            b: self.b.map(|x| f(&x)),
            q: self.q.map(|x| f(&x)),
            sigma1: self.sigma1.map(|x| f(&x)),
            k: self.k.map(|x| f(&x)),
            sigma_pi_sq: f(&self.sigma_pi_sq),
            horizon: self.horizon,
        }
    }

    /// `M = A + BW`.
    fn closed_loop(&self, w: &DMatrix<S>) -> DMatrix<S> {
        add(&self.a, &mm(&self.b, w))
    }

    /// `H = (W − K)ᵀ(W − K)` and `W − K`.
    fn loss_matrix(&self, w: &DMatrix<S>) -> (DMatrix<S>, DMatrix<S>) {
        let e = zip(w, &self.k, |x, y| x.clone() - y);
        (mm(&e.transpose(), &e), e)
    }

    /// The state covariances `P_1, …, P_{T−1}`: `P_1 = Σ₁`, `P_{t+1} = M P_t Mᵀ + σ_π² BBᵀ + Q`
    /// (math.md §1.3).
    ///
    /// # Errors
    /// [`LqgError::Shape`] / [`LqgError::NonFinite`] for a bad W (m×n).
    pub fn covariances(&self, w: &DMatrix<S>) -> Result<Vec<DMatrix<S>>, LqgError> {
        self.check_w(w)?;
        let m = self.closed_loop(w);
        let mt = m.transpose();
        let drive = add(
            &scale(&self.sigma_pi_sq, &mm(&self.b, &self.b.transpose())),
            &self.q,
        );
        let mut p = vec![self.sigma1.clone()];
        for _ in 1..self.horizon - 1 {
            let last = p.last().expect("P_1 is present");
            p.push(add(&mm(&mm(&m, last), &mt), &drive));
        }
        Ok(p)
    }

    /// `F(W) = Σ_{t=1}^{T−1} tr(H P_t)`, `H = (W − K)ᵀ(W − K)` (math.md §1.3).
    ///
    /// # Errors
    /// As [`LqgSystem::covariances`].
    pub fn objective(&self, w: &DMatrix<S>) -> Result<S, LqgError> {
        let p = self.covariances(w)?;
        let (h, _) = self.loss_matrix(w);
        Ok(p.iter().fold(S::zero(), |acc, pt| acc + trace(&mm(&h, pt))))
    }

    /// The expectation of the eq. 3.15 estimator in closed form (Isserlis, math.md §1.3):
    /// `E[g] = Σ_{t=1}^{T−1} [2(W − K)P_t + Σ_{i=1}^{t−1} 2Bᵀ(M^{t−i−1})ᵀ H M^{t−i} P_i]`, an m×n
    /// matrix in the layout of W.
    ///
    /// # Errors
    /// As [`LqgSystem::covariances`].
    pub fn expected_estimate(&self, w: &DMatrix<S>) -> Result<DMatrix<S>, LqgError> {
        let p = self.covariances(w)?;
        let m = self.closed_loop(w);
        let (h, e) = self.loss_matrix(w);
        let two = S::from_i64(2);
        let steps = self.horizon - 1;
        // M⁰, M¹, …, M^{T−2}.
        let mut powers = vec![identity::<S>(self.state_dim())];
        for d in 1..steps {
            powers.push(mm(&powers[d - 1], &m));
        }
        let bt = self.b.transpose();
        let mut g = zeros::<S>(self.action_dim(), self.state_dim());
        for t in 0..steps {
            g = add(&g, &scale(&two, &mm(&e, &p[t])));
            for i in 0..t {
                let d = t - i;
                let term = mm(
                    &mm(&mm(&bt, &powers[d - 1].transpose()), &h),
                    &mm(&powers[d], &p[i]),
                );
                g = add(&g, &scale(&two, &term));
            }
        }
        Ok(g)
    }

    /// `∇_W F` by forward-mode dual numbers through the covariance recursion (no score formula;
    /// the independent route of math.md §1.3's \[CHECK\]), an m×n matrix in the layout of W.
    ///
    /// # Errors
    /// As [`LqgSystem::covariances`].
    pub fn gradient(&self, w: &DMatrix<S>) -> Result<DMatrix<S>, LqgError> {
        self.check_w(w)?;
        let (m, n) = (self.action_dim(), self.state_dim());
        let vars = Dual::variables(&theta_of(w));
        let wd = DMatrix::from_row_slice(m, n, &vars);
        let lifted = self.lift(|x| Dual::constant(x.clone()));
        let f = lifted.objective(&wd)?;
        let g = f.gradient_padded(m * n);
        Ok(DMatrix::from_row_slice(m, n, &g))
    }

    /// The eq. 3.15 estimate on one trajectory, with the policy's own loss gradient and score
    /// (φ(s) = s, label π*(s) = Ks): `g = Σ_{t=1}^{T−1} [∇l_t + l_t Σ_{i<t} ∇log π(a_i|s_i)]`,
    /// returned with the trajectory loss `Σ_t l_t` (an unbiased estimate of F(W)). The sum is the
    /// task problems' own: the policy's [`EstimatorKernel::causal_sum_validated`] after θ and the
    /// states are checked here.
    ///
    /// The policy's σ_π² should equal the system's for `E[g]` to be
    /// [`LqgSystem::expected_estimate`].
    ///
    /// # Errors
    /// [`LqgError::Shape`] for a trajectory with fewer than T − 1 states or actions;
    /// [`LqgError::Policy`] for a policy, θ, state or action of the wrong shape, or a non-finite θ
    /// or state.
    pub fn estimate(
        &self,
        policy: &LinearGaussian<S>,
        theta: &[S],
        trajectory: &LqgTrajectory<S>,
    ) -> Result<(S, Vec<S>), LqgError> {
        let steps = self.horizon - 1;
        let short = |param, rows, got_rows, first: Option<&Vec<S>>, cols| LqgError::Shape {
            param,
            rows,
            cols,
            got_rows,
            got_cols: first.map_or(0, Vec::len),
        };
        if trajectory.states.len() < steps {
            let t = &trajectory.states;
            return Err(short(
                "trajectory",
                steps,
                t.len(),
                t.first(),
                self.state_dim(),
            ));
        }
        if trajectory.actions.len() < steps {
            let a = &trajectory.actions;
            return Err(short(
                "actions",
                steps,
                a.len(),
                a.first(),
                self.action_dim(),
            ));
        }
        check_vec_scalar("theta", theta, policy.param_dim())?;
        let states = &trajectory.states[..steps];
        let mut features = Vec::with_capacity(steps * self.state_dim());
        let mut labels = Vec::with_capacity(steps);
        for s in states {
            check_vec_scalar("state", s, policy.feature_dim())?;
            features.extend_from_slice(s);
            labels.push(self.expert(s)?);
        }
        let mut g = vec![S::zero(); policy.param_dim()];
        let mut total = S::zero();
        policy.causal_sum_validated(
            theta,
            &features,
            None,
            &labels,
            &trajectory.actions[..steps],
            None,
            &mut g,
            Some(&mut total),
            &mut Vec::new(),
        )?;
        Ok((total, g))
    }

    /// The expert's action `π*(s) = Ks`.
    ///
    /// # Errors
    /// [`LqgError::Policy`] with [`PolicyError::Shape`] for a state of the wrong length.
    pub fn expert(&self, s: &[S]) -> Result<Vec<S>, LqgError> {
        if s.len() != self.state_dim() {
            return Err(PolicyError::Shape {
                param: "state",
                expected: self.state_dim(),
                got: s.len(),
            }
            .into());
        }
        Ok((0..self.action_dim())
            .map(|i| (0..s.len()).fold(S::zero(), |acc, j| acc + self.k[(i, j)].clone() * &s[j]))
            .collect())
    }
}

/// Samples trajectories of an [`LqgSystem`] (holds the Cholesky factors of Σ₁ and Q).
#[derive(Debug, Clone)]
pub struct LqgSimulator<'a, S: Scalar> {
    system: &'a LqgSystem<S>,
    chol_sigma1: DMatrix<S>,
    chol_q: DMatrix<S>,
}

impl<S: Sqrt> LqgSystem<S> {
    /// A simulator: needs Σ₁ and Q certainly positive definite (Cholesky factors).
    ///
    /// # Errors
    /// [`LqgError::NotPositiveDefinite`] naming the covariance.
    pub fn simulator(&self) -> Result<LqgSimulator<'_, S>, LqgError> {
        Ok(LqgSimulator {
            system: self,
            chol_sigma1: cholesky("sigma1", &self.sigma1)?,
            chol_q: cholesky("q", &self.q)?,
        })
    }
}

impl<S: Sqrt> LqgSimulator<'_, S> {
    fn gaussian(l: &DMatrix<S>, rng: &mut KitRng) -> Vec<S> {
        let z: Vec<S> = (0..l.ncols()).map(|_| standard_normal::<S>(rng)).collect();
        (0..l.nrows())
            .map(|i| (0..=i).fold(S::zero(), |acc, j| acc + l[(i, j)].clone() * &z[j]))
            .collect()
    }

    /// Roll out `policy` at θ for T steps: `s_1 = L₁z`, `a_t ∼ policy`, `s_{t+1} = As_t + Ba_t + L_Q z_t`
    /// (z standard normal f64 draws converted exactly, so one seed gives one path in every scalar).
    ///
    /// # Errors
    /// [`LqgError::Policy`] for a policy or θ of the wrong shape.
    pub fn rollout(
        &self,
        policy: &LinearGaussian<S>,
        theta: &[S],
        rng: &mut KitRng,
    ) -> Result<LqgTrajectory<S>, LqgError> {
        let sys = self.system;
        let (n, m) = (sys.state_dim(), sys.action_dim());
        if policy.actions() != m || policy.feature_dim() != n {
            return Err(PolicyError::Shape {
                param: "policy",
                expected: m * n,
                got: policy.param_dim(),
            }
            .into());
        }
        let mut states = vec![Self::gaussian(&self.chol_sigma1, rng)];
        let mut actions = Vec::with_capacity(sys.horizon - 1);
        for t in 0..sys.horizon - 1 {
            let s = &states[t];
            let a = policy.sample(theta, s, rng)?;
            let noise = Self::gaussian(&self.chol_q, rng);
            let next: Vec<S> = (0..n)
                .map(|i| {
                    let ax = (0..n).fold(S::zero(), |acc, j| acc + sys.a[(i, j)].clone() * &s[j]);
                    let bu = (0..m).fold(S::zero(), |acc, j| acc + sys.b[(i, j)].clone() * &a[j]);
                    ax + bu + &noise[i]
                })
                .collect();
            actions.push(a);
            states.push(next);
        }
        Ok(LqgTrajectory { states, actions })
    }
}
