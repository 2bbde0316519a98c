//! The linear-Gaussian policy (P3) whose loss is that of the *executed* velocity: the obstacle
//! task's environment clips every commanded velocity to the maximum speed `v` (thesis §4.1.1),
//! so what the agent does at a state is `c(Wφ)`, not `Wφ`.
//!
//! * Sampling, the score `∇_W log π(a|s)` and the likelihood ratio are P3's (the sampled action
//!   is the unclipped Gaussian draw; the environment clips it).
//! * The loss compares the executed mean with the expert's velocity:
//!   `c(m) = m·min(1, v/‖m‖)`, `l(s, W) = ‖c(Wφ) − π*(s)‖²`.
//! * Its gradient, with `m = Wφ`, `r = c(m) − π*(s)`: `∂l/∂m = 2 J_c(m) r`, where `J_c = I` for
//!   `‖m‖ ≤ v` and `J_c = (v/‖m‖)(I − m mᵀ/‖m‖²)` (symmetric) for `‖m‖ > v`; `∇_W l = (∂l/∂m)φᵀ`.
//!   `c` is continuous, and differentiable except on the sphere `‖m‖ = v`, where the estimator
//!   uses the inner branch.
//!
//! **Why.** P3's loss `‖Wφ − π*‖²` grows without bound in W although the executed velocity cannot
//! exceed `v`: a policy that drives at full speed (large W, clipped) is penalised for a
//! velocity it never executes, and the eq. 3.15 estimate — loss times score — has no bound,
//! so plain SGD on it can run away. Here `l ≤ (v + ‖π*(s)‖)²` for every W.

use super::linear_gaussian::{ActionVector, LinearGaussian};
use super::{LikelihoodRatio, Policy, PolicyError, check_out, check_positive, check_vec};
use crate::problem::KitRng;
use crate::scalar::{Scalar, Sqrt, certainly_less};

/// [`LinearGaussian`] with the loss of the velocity clipped to `v` (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedLimitedGaussian<S, A = Vec<S>> {
    inner: LinearGaussian<S, A>,
    v_max: S,
    v_max_sq: S,
}

impl<S: Scalar, A> SpeedLimitedGaussian<S, A> {
    /// The policy `inner` with executed velocities clipped to `v_max` (finite, certainly > 0).
    ///
    /// # Errors
    /// [`PolicyError::NonFinite`] or [`PolicyError::NotPositive`] for a bad `v_max`.
    pub fn new(inner: LinearGaussian<S, A>, v_max: S) -> Result<Self, PolicyError> {
        check_positive("v_max", &v_max)?;
        Ok(Self {
            inner,
            v_max_sq: v_max.square(),
            v_max,
        })
    }

    /// The underlying linear-Gaussian policy (sampling, score, mean).
    pub fn inner(&self) -> &LinearGaussian<S, A> {
        &self.inner
    }

    /// The speed limit `v`.
    pub fn v_max(&self) -> &S {
        &self.v_max
    }
}

impl<S: Sqrt, A: ActionVector<S>> SpeedLimitedGaussian<S, A> {
    /// The loss of [`Policy::loss_into`], the same operations without the gradient and without
    /// checking θ and φ (validated by the caller). `scratch` has `θ`'s length; its contents
    /// afterwards are unspecified.
    ///
    /// # Errors
    /// As [`Policy::loss_into`] for a bad label, an undecidable speed limit or a non-finite loss.
    pub(crate) fn loss_only_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        scratch: &mut [S],
    ) -> Result<S, PolicyError> {
        let k = self.inner.actions();
        let n = Policy::<S>::feature_dim(&self.inner);
        check_vec("label", label, k)?;
        let mut n2 = S::zero();
        for i in 0..k {
            let m = crate::scalar::dot(&theta[i * n..(i + 1) * n], phi);
            n2 += m.square();
            scratch[i * n] = m;
        }
        if !certainly_less(&self.v_max_sq, &n2, "speed limit: ‖Wφ‖ > v")? {
            return self.inner.loss_only_validated(theta, phi, label);
        }
        let s = self.v_max.clone() / n2.sqrt();
        let mut loss = S::zero();
        for (i, y) in label.iter().enumerate() {
            let r = s.clone() * &scratch[i * n] - y;
            loss += r.square();
        }
        if !loss.is_finite() {
            return Err(PolicyError::NonFinite { param: "loss" });
        }
        Ok(loss)
    }

    /// The clipped branch of [`Policy::loss_into`] (`‖m‖ > v`), the outputs `m_i` parked in the
    /// first entry of each row of `grad` and `n2 = ‖m‖²`: `c = s·m` with `s = v/‖m‖`,
    /// `r = c − π*`, `∂l/∂m = 2s(r − m (mᵀr)/‖m‖²)`, the gradient's rows written over `grad`
    /// (row i after its `m_i` is read).
    fn clipped_loss_into(
        &self,
        phi: &[S],
        label: &[S],
        n2: &S,
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        let n = phi.len();
        let two = S::from_i64(2);
        let s = self.v_max.clone() / n2.clone().sqrt();
        let mut loss = S::zero();
        let mut m_dot_r = S::zero();
        for (i, y) in label.iter().enumerate() {
            let m = &grad[i * n];
            let r = s.clone() * m - y;
            loss += r.square();
            m_dot_r += r * m;
        }
        let q = m_dot_r / n2;
        for (i, y) in label.iter().enumerate() {
            let m = grad[i * n].clone();
            let r = s.clone() * &m - y;
            let d = two.clone() * &s * (r - m * &q);
            for (g, x) in grad[i * n..(i + 1) * n].iter_mut().zip(phi) {
                *g = d.clone() * x;
            }
        }
        if !loss.is_finite() {
            return Err(PolicyError::NonFinite { param: "loss" });
        }
        Ok(loss)
    }

    /// The executed mean `c(Wφ)` (module docs).
    ///
    /// # Errors
    /// As [`LinearGaussian::mean`]; [`PolicyError::Undecidable`] if an interval `‖Wφ‖` straddles
    /// `v`.
    pub fn executed_mean(&self, theta: &[S], phi: &[S]) -> Result<Vec<S>, PolicyError> {
        let mut m = self.inner.mean(theta, phi)?;
        let n2 = crate::scalar::norm_sq(&m);
        if certainly_less(&self.v_max_sq, &n2, "speed limit: ‖Wφ‖ > v")? {
            let s = self.v_max.clone() / n2.sqrt();
            for x in &mut m {
                *x *= &s;
            }
        }
        Ok(m)
    }

    /// [`Policy::loss_score_into`] for a θ and φ the caller has checked (lengths and
    /// finiteness): the same operations after those checks, so the same values and, for such
    /// inputs, the same errors in the same order.
    ///
    /// # Errors
    /// As [`Policy::loss_score_into`].
    #[inline]
    pub(crate) fn loss_score_validated(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        action: &A,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        let k = self.inner.actions();
        let n = Policy::<S>::feature_dim(&self.inner);
        let action: &[S] = action.borrow();
        check_vec("label", label, k)?;
        check_out("grad", grad, k * n)?;
        check_vec("action", action, k)?;
        check_out("score", score, k * n)?;
        let mut n2 = S::zero();
        for i in 0..k {
            let m = crate::scalar::dot(&theta[i * n..(i + 1) * n], phi);
            n2 += m.square();
            grad[i * n] = m.clone();
            score[i * n] = m;
        }
        let loss = if certainly_less(&self.v_max_sq, &n2, "speed limit: ‖Wφ‖ > v")? {
            self.clipped_loss_into(phi, label, &n2, grad)?
        } else {
            inside_loss_into(phi, label, grad)
        };
        let sigma_sq = self.inner.sigma_sq();
        for (i, a) in action.iter().enumerate() {
            let s = (a.clone() - &score[i * n]) / sigma_sq;
            for (sc, x) in score[i * n..(i + 1) * n].iter_mut().zip(phi) {
                *sc = s.clone() * x;
            }
        }
        Ok(loss)
    }
}

impl<S: Sqrt, A: ActionVector<S>> Policy<S> for SpeedLimitedGaussian<S, A> {
    type Action = A;
    type Label = [S];

    fn param_dim(&self) -> usize {
        Policy::<S>::param_dim(&self.inner)
    }
    fn feature_dim(&self) -> usize {
        Policy::<S>::feature_dim(&self.inner)
    }

    /// P3's sample `a = Wφ + σ_π ε` (the environment clips it).
    fn sample(&self, theta: &[S], phi: &[S], rng: &mut KitRng) -> Result<A, PolicyError> {
        self.inner.sample(theta, phi, rng)
    }

    /// `l = ‖c(Wφ) − π*(s)‖²` and `∇_W l = 2 J_c r φᵀ` (module docs) without allocating: the
    /// outputs `m_i = (Wφ)_i` are parked in the first entry of each row of `grad` until the rows
    /// are written.
    fn loss_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        grad: &mut [S],
    ) -> Result<S, PolicyError> {
        let k = self.inner.actions();
        let n = Policy::<S>::feature_dim(&self.inner);
        check_vec("label", label, k)?;
        check_vec("theta", theta, k * n)?;
        check_vec("phi", phi, n)?;
        check_out("grad", grad, k * n)?;
        let mut n2 = S::zero();
        for i in 0..k {
            let m = crate::scalar::dot(&theta[i * n..(i + 1) * n], phi);
            n2 += m.square();
            grad[i * n] = m;
        }
        if certainly_less(&self.v_max_sq, &n2, "speed limit: ‖Wφ‖ > v")? {
            self.clipped_loss_into(phi, label, &n2, grad)
        } else {
            Ok(inside_loss_into(phi, label, grad))
        }
    }

    /// P3's score without allocating (the sampled action is the unclipped draw).
    fn score_into(
        &self,
        theta: &[S],
        phi: &[S],
        action: &A,
        score: &mut [S],
    ) -> Result<(), PolicyError> {
        self.inner.score_into(theta, phi, action, score)
    }

    /// Loss, gradient and score with each output `m_i = (Wφ)_i` computed once: the same numbers
    /// as [`Policy::loss_into`] then [`Policy::score_into`], which compute it two or three
    /// times. Every shape is checked first (as [`LinearGaussian`]'s does); the outputs are parked
    /// in the first entry of each row of `grad` and of `score` until the rows are written.
    fn loss_score_into(
        &self,
        theta: &[S],
        phi: &[S],
        label: &[S],
        action: &A,
        grad: &mut [S],
        score: &mut [S],
    ) -> Result<S, PolicyError> {
        let k = self.inner.actions();
        let n = Policy::<S>::feature_dim(&self.inner);
        check_vec("label", label, k)?;
        check_vec("theta", theta, k * n)?;
        check_vec("phi", phi, n)?;
        self.loss_score_validated(theta, phi, label, action, grad, score)
    }
}

/// The loss inside the limit (`‖m‖ ≤ v`), P3's: `l = ‖m − π*‖²`, `∇_W l = 2(m − π*)φᵀ`, the
/// outputs `m_i` parked in the first entry of each row of `grad` and the gradient's rows written
/// over them (the numbers of [`LinearGaussian`]'s `loss_into`, without recomputing `Wφ`).
fn inside_loss_into<S: Scalar>(phi: &[S], label: &[S], grad: &mut [S]) -> S {
    let n = phi.len();
    let mut loss = S::zero();
    for (i, y) in label.iter().enumerate() {
        let r = grad[i * n].clone() - y;
        loss += r.square();
        let two_r = S::from_i64(2) * &r;
        for (g, x) in grad[i * n..(i + 1) * n].iter_mut().zip(phi) {
            *g = two_r.clone() * x;
        }
    }
    loss
}

impl<S: Sqrt, A: ActionVector<S>> LikelihoodRatio<S> for SpeedLimitedGaussian<S, A> {
    /// P3's log-probability (sampling is unchanged).
    fn log_prob(&self, theta: &[S], phi: &[S], action: &A) -> Result<S, PolicyError> {
        self.inner.log_prob(theta, phi, action)
    }

    /// P3's ratio.
    fn log_likelihood_ratio(
        &self,
        theta: &[S],
        theta_other: &[S],
        phi: &[S],
        action: &A,
    ) -> Result<S, PolicyError> {
        self.inner
            .log_likelihood_ratio(theta, theta_other, phi, action)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::PolicyExt;
    use crate::scalar::{Dual, Interval};

    const PHI: [f64; 3] = [0.7, -1.3, 1.0];
    const LABEL: [f64; 2] = [0.06, -0.03];

    fn policy<S: Sqrt>() -> SpeedLimitedGaussian<S> {
        SpeedLimitedGaussian::new(
            LinearGaussian::new(2, 3, S::from_binary64(0.02).unwrap()).unwrap(),
            S::from_binary64(0.1).unwrap(),
        )
        .unwrap()
    }

    /// θ inside the limit (‖Wφ‖ ≈ 0.05) and far outside (‖Wφ‖ ≈ 2.1).
    const INSIDE: [f64; 6] = [0.02, 0.01, 0.03, -0.01, 0.02, 0.0];
    const OUTSIDE: [f64; 6] = [1.0, -0.5, 0.4, 0.3, 0.9, -0.2];

    /// The fused loss-and-score pass gives the numbers of the two separate calls, on both
    /// branches, in every scalar with a square root (bit for bit in `f64` and in the duals, the same
    /// enclosures for intervals); a bad action is still an error.
    macro_rules! fused_equals_separate {
        ($($name:ident: $s:ty),*) => {$(
            #[test]
            fn $name() {
                let p = policy::<$s>();
                let cast = |v: &[f64]| -> Vec<$s> {
                    v.iter().map(|x| <$s>::from_binary64(*x).unwrap()).collect()
                };
                let (phi, label) = (cast(&PHI), cast(&LABEL));
                let action = cast(&[0.05, -0.2]);
                for theta in [cast(&INSIDE), cast(&OUTSIDE)] {
                    let (mut g, mut sc) = (vec![<$s>::zero(); 6], vec![<$s>::zero(); 6]);
                    let l = p
                        .loss_score_into(&theta, &phi, &label, &action, &mut g, &mut sc)
                        .unwrap();
                    let (mut g2, mut sc2) = (vec![<$s>::zero(); 6], vec![<$s>::zero(); 6]);
                    let l2 = p.loss_into(&theta, &phi, &label, &mut g2).unwrap();
                    p.score_into(&theta, &phi, &action, &mut sc2).unwrap();
                    assert_eq!(format!("{l:?} {g:?} {sc:?}"), format!("{l2:?} {g2:?} {sc2:?}"));
                    let bad = cast(&[0.05]);
                    assert!(
                        p.loss_score_into(&theta, &phi, &label, &bad, &mut g, &mut sc)
                            .is_err()
                    );
                }
            }
        )*};
    }
    fused_equals_separate!(
        fused_equals_separate_f64: f64,
        fused_equals_separate_dual: Dual<f64>,
        fused_equals_separate_interval: Interval
    );

    #[test]
    fn inside_the_limit_it_is_p3() {
        let p = policy::<f64>();
        let (l, g) = p.loss(&INSIDE, &PHI, &LABEL).unwrap();
        let (l3, g3) = p.inner().loss(&INSIDE, &PHI, &LABEL).unwrap();
        assert_eq!(l, l3);
        assert_eq!(g, g3);
    }

    #[test]
    fn outside_it_is_the_loss_of_the_clipped_velocity_and_bounded() {
        let p = policy::<f64>();
        let (l, _) = p.loss(&OUTSIDE, &PHI, &LABEL).unwrap();
        let c = p.executed_mean(&OUTSIDE, &PHI).unwrap();
        approx::assert_abs_diff_eq!(c[0].hypot(c[1]), 0.1, epsilon = 1e-15);
        let direct = (c[0] - LABEL[0]).powi(2) + (c[1] - LABEL[1]).powi(2);
        approx::assert_abs_diff_eq!(l, direct, epsilon = 1e-15);
        // P3's loss is about 4 (‖Wφ‖ ≈ 2.1); the executed one is bounded by (v + ‖π*‖)².
        let (l3, _) = p.inner().loss(&OUTSIDE, &PHI, &LABEL).unwrap();
        assert!(l3 > 4.0);
        let bound = (0.1 + LABEL[0].hypot(LABEL[1])).powi(2);
        assert!(l <= bound);
        let huge: Vec<f64> = OUTSIDE.iter().map(|x| x * 1e6).collect();
        assert!(p.loss(&huge, &PHI, &LABEL).unwrap().0 <= bound);
    }

    /// The analytic gradient equals forward-mode dual numbers on the same formula evaluated
    /// through `executed_mean` (an independent route: no hand-written Jacobian).
    #[test]
    fn gradient_matches_dual_numbers_on_both_branches() {
        let p = policy::<f64>();
        let pd = policy::<Dual<f64>>();
        for theta in [INSIDE, OUTSIDE] {
            let (_, g) = p.loss(&theta, &PHI, &LABEL).unwrap();
            let td = Dual::variables(&theta);
            let phid: Vec<Dual<f64>> = PHI.iter().map(|x| Dual::constant(*x)).collect();
            let c = pd.executed_mean(&td, &phid).unwrap();
            let l = c.iter().zip(LABEL).fold(Dual::constant(0.0), |a, (ci, y)| {
                let r = ci.clone() - Dual::constant(y);
                a + r.clone() * r
            });
            let gd = l.gradient_padded(6);
            for (a, b) in g.iter().zip(&gd) {
                assert!(
                    approx::abs_diff_eq!(*a, *b, epsilon = 1e-13 * (1.0 + b.abs())),
                    "{g:?} vs {gd:?}"
                );
            }
        }
    }

    #[test]
    fn gradient_matches_central_differences() {
        let p = policy::<f64>();
        let (_, g) = p.loss(&OUTSIDE, &PHI, &LABEL).unwrap();
        let h = 1e-6;
        for j in 0..6 {
            let (mut a, mut b) = (OUTSIDE, OUTSIDE);
            a[j] += h;
            b[j] -= h;
            let fd = (p.loss(&a, &PHI, &LABEL).unwrap().0 - p.loss(&b, &PHI, &LABEL).unwrap().0)
                / (2.0 * h);
            assert!(
                approx::abs_diff_eq!(fd, g[j], epsilon = 1e-7),
                "{j}: {fd} vs {}",
                g[j]
            );
        }
    }

    #[test]
    fn intervals_enclose_the_f64_loss_and_refuse_to_guess_at_the_kink() {
        let p = policy::<f64>();
        let pi = policy::<Interval>();
        let iv = |x: &[f64]| {
            x.iter()
                .map(|v| <Interval as Scalar>::from_binary64(*v).unwrap())
                .collect::<Vec<_>>()
        };
        for theta in [INSIDE, OUTSIDE] {
            let (l, g) = p.loss(&theta, &PHI, &LABEL).unwrap();
            let (li, gi) = pi.loss(&iv(&theta), &iv(&PHI), &iv(&LABEL)).unwrap();
            assert!(li.contains(l), "{li:?} ∌ {l}");
            for (a, b) in gi.iter().zip(&g) {
                assert!(a.contains(*b));
            }
        }
        // θ such that ‖Wφ‖ = v exactly up to a wide interval: undecidable, not a guess.
        let wide: Vec<Interval> = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]
            .iter()
            .map(|&v| Interval::try_from((v - 0.05, v + 0.05)).unwrap())
            .collect();
        let phi1 = iv(&[1.0, 0.0, 0.0]);
        assert!(matches!(
            pi.loss(&wide, &phi1, &iv(&LABEL)),
            Err(PolicyError::Undecidable(_))
        ));
    }

    #[test]
    fn the_score_and_sampling_are_p3s_and_bad_limits_are_refused() {
        let p = policy::<f64>();
        let a = vec![0.3, -0.2];
        assert_eq!(
            p.score(&OUTSIDE, &PHI, &a).unwrap(),
            p.inner().score(&OUTSIDE, &PHI, &a).unwrap()
        );
        let inner = LinearGaussian::new(2, 3, 0.02).unwrap();
        assert!(matches!(
            SpeedLimitedGaussian::new(inner.clone(), 0.0),
            Err(PolicyError::NotPositive { param: "v_max", .. })
        ));
        assert!(matches!(
            SpeedLimitedGaussian::new(inner, f64::NAN),
            Err(PolicyError::NonFinite { param: "v_max" })
        ));
    }
}
