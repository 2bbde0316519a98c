//! The PPO expert's greedy action in any real scalar, with an exact-decision `f64` pre-test.

use super::*;

/// The PPO expert's greedy action in the scalar `S`, the actor's weights converted once
/// ([`PpoExpert::greedy_in`]): the roll-outs label every visited state with it.
///
/// [`PpoGreedy::action`] performs the operations of [`PpoExpert::action_in`] in the same order
/// (so its action is the same, bit for bit in `f64`), streaming the hidden layer into the two
/// logits instead of storing it. In `f64` a cheaper test comes first: the logits' difference
/// `D = Σᵢ (W₂)₁ᵢ uᵢ − (W₂)₀ᵢ uᵢ + (b₂)₁ − (b₂)₀` evaluated with a rational approximation of tanh
/// ([`fast_tanh`], absolute error below [`FAST_TANH_ERROR`]). When |D̃| exceeds a bound on its
/// distance from the exact forward pass's difference (the approximation's error, the rounding of
/// both passes; [`PpoGreedy`]'s `margin`) the exact pass's comparison `z₁ > z₀` has the sign of
/// D̃, and that is the action; otherwise, or for a non-finite activation, the exact pass decides
/// (and reports errors as [`PpoExpert::action_in`] does). The labels are therefore those of the
/// exact pass; only the work differs.
#[derive(Debug, Clone)]
pub struct PpoGreedy<S> {
    /// The actor's weights in `S` ([`Mlp`] layout: `W₁ | b₁ | W₂ | b₂`).
    pub(super) weights: Vec<S>,
    /// Hidden units.
    pub(super) hidden: usize,
    /// The `f64` filter, only when `S` is `f64`.
    pub(super) filter: Option<MarginFilter>,
}

/// The `f64` pre-test of [`PpoGreedy`]: W₁ by columns (unit stride), the differences of W₂'s two
/// rows and of b₂, and the margin beyond which the approximate difference decides.
#[derive(Debug, Clone)]
pub(super) struct MarginFilter {
    /// Column j of W₁ (`hidden` entries each).
    pub(super) w1: [Vec<f64>; OBSERVATION_DIM],
    pub(super) b1: Vec<f64>,
    /// (W₂)₁ᵢ − (W₂)₀ᵢ.
    pub(super) dw: Vec<f64>,
    /// (b₂)₁ − (b₂)₀.
    pub(super) db: f64,
    pub(super) margin: f64,
}

/// An upper bound on `|fast_tanh(x) − tanh(x)|` for every finite x (the approximation's measured
/// error, below 10⁻⁶ on a fine grid, with a factor of ten to spare; `tests` checks it).
pub const FAST_TANH_ERROR: f64 = 1e-5;

/// tanh by a rational minimax approximation `x·p(x²)/q(x²)` on [−7.9, 7.9], clamped outside
/// (Eigen's single-precision `ptanh` coefficients, evaluated in `f64`): branch-free, so a loop of
/// it vectorises. Absolute error below [`FAST_TANH_ERROR`]; not for results, only for the
/// pre-test of [`PpoGreedy`].
#[inline(always)]
pub fn fast_tanh(x: f64) -> f64 {
    const CLAMP: f64 = 7.905_311_107_635_498;
    const A: [f64; 7] = [
        4.893_524_558_917_86e-3,
        6.372_619_288_754_36e-4,
        1.485_722_357_179_79e-5,
        5.122_297_090_371_14e-8,
        -8.604_671_522_137_35e-11,
        2.000_187_904_824_77e-13,
        -2.760_768_477_423_55e-16,
    ];
    const B: [f64; 4] = [
        4.893_525_185_543_85e-3,
        2.268_434_632_439e-3,
        1.185_347_056_866_54e-4,
        1.198_258_394_667_02e-6,
    ];
    let x = x.clamp(-CLAMP, CLAMP);
    let x2 = x * x;
    let p = A[6];
    let p = p.mul_add(x2, A[5]);
    let p = p.mul_add(x2, A[4]);
    let p = p.mul_add(x2, A[3]);
    let p = p.mul_add(x2, A[2]);
    let p = p.mul_add(x2, A[1]);
    let p = p.mul_add(x2, A[0]) * x;
    let q = B[3];
    let q = q.mul_add(x2, B[2]);
    let q = q.mul_add(x2, B[1]);
    let q = q.mul_add(x2, B[0]);
    // 1/q in single precision (relative error ≤ 2⁻²³ with q's own rounding to f32: ≤ 1.2·10⁻⁷
    // on |p/q| ≤ 1), eight lanes per division instead of four.
    #[allow(clippy::cast_possible_truncation)] // q ∈ [4.9·10⁻³, 1] on the clamped range
    let r = f64::from(1.0 / (q as f32));
    p * r
}

impl<S: Real> PpoGreedy<S> {
    pub(super) fn new(e: &PpoExpert) -> Result<Self, PpoError> {
        let weights = e
            .actor
            .iter()
            .map(|&w| from_f64_exact::<S>(w, "actor"))
            .collect::<Result<Vec<S>, _>>()
            .map_err(PpoError::Act)?;
        let hidden = e.hidden();
        // The filter is sound only when the exact pass runs in `f64` itself.
        let filter = (std::any::type_name::<S>() == std::any::type_name::<f64>())
            .then(|| MarginFilter::new(&e.actor, hidden));
        Ok(Self {
            weights,
            hidden,
            filter,
        })
    }

    /// The greedy action at `state`: [`PpoExpert::action_in`]'s result.
    ///
    /// # Errors
    /// As [`PpoExpert::action_in`].
    #[inline]
    pub fn action(&self, state: &[S; OBSERVATION_DIM]) -> Result<usize, PpoError> {
        if let Some(f) = &self.filter
            && let Some(a) = f.decide(&[
                state[0].to_f64(),
                state[1].to_f64(),
                state[2].to_f64(),
                state[3].to_f64(),
            ])
        {
            return Ok(a);
        }
        self.exact(state)
    }

    /// The forward pass of [`Mlp::forward`] and the comparison of [`PpoExpert::action_in`], with
    /// each hidden unit added into the two logits as soon as it is computed (the same operations,
    /// in the same order, as the stored-layer pass).
    pub(super) fn exact(&self, state: &[S; OBSERVATION_DIM]) -> Result<usize, PpoError> {
        if !state.iter().fold(true, |ok, x| ok & x.is_finite()) {
            return Err(PpoError::Act(PolicyError::NonFinite { param: "phi" }));
        }
        let h = self.hidden;
        let (w1, rest) = self.weights.split_at(h * OBSERVATION_DIM);
        let (b1, rest) = rest.split_at(h);
        let (w2, b2) = rest.split_at(ACTIONS * h);
        let (mut z0, mut z1) = (S::zero(), S::zero());
        for i in 0..h {
            let row = &w1[i * OBSERVATION_DIM..(i + 1) * OBSERVATION_DIM];
            let a = crate::scalar::dot(row, state) + &b1[i];
            let u = crate::policy::tanh(&a).map_err(PpoError::Act)?;
            z0 += w2[i].clone() * &u;
            z1 += w2[h + i].clone() * &u;
        }
        let z0 = z0 + &b2[0];
        let z1 = z1 + &b2[1];
        match z1.certain_cmp(&z0) {
            Some(Ordering::Greater) => Ok(1),
            Some(_) => Ok(0),
            None => Err(PpoError::Act(PolicyError::Undecidable(Undecidable {
                what: "PPO expert: order of the two logits",
            }))),
        }
    }
}

impl MarginFilter {
    pub(super) fn new(actor: &[f64], h: usize) -> Self {
        let (w1, rest) = actor.split_at(h * OBSERVATION_DIM);
        let (b1, rest) = rest.split_at(h);
        let (w2, b2) = rest.split_at(ACTIONS * h);
        let dw: Vec<f64> = (0..h).map(|i| w2[h + i] - w2[i]).collect();
        let db = b2[1] - b2[0];
        // |D̃ − (ẑ₁ − ẑ₀)| is at most: the approximation's error and the exact tanh's (a few
        // units in the last place of |u| ≤ 1, taken as 10⁻¹⁴) times Σ|Δwᵢ|, plus the rounding of
        // the three sums of h + 1 terms each (γ_{h+2} times the sums of their terms' magnitudes,
        // |u| ≤ 1 + FAST_TANH_ERROR), and of Δw and Δb themselves. Doubled, with a factor of 4 on
        // the rounding terms, to spare.
        let u = f64::EPSILON / 2.0;
        let terms = (h + 2) as f64;
        let sum_abs_dw: f64 = dw.iter().map(|d| d.abs()).sum();
        let sum_abs_w2: f64 = w2.iter().chain(b2).map(|w| w.abs()).sum();
        let rounding = 4.0
            * terms
            * u
            * (sum_abs_w2 + 2.0 * (sum_abs_dw + db.abs()))
            * (1.0 + FAST_TANH_ERROR);
        let margin = 2.0 * (sum_abs_dw * (FAST_TANH_ERROR + 1e-14) + rounding);
        Self {
            w1: std::array::from_fn(|j| (0..h).map(|i| w1[i * OBSERVATION_DIM + j]).collect()),
            b1: b1.to_vec(),
            dw,
            db,
            margin,
        }
    }

    /// The action when the approximate logit difference decides it, else `None`.
    ///
    /// The hidden units are taken [`LANES`] at a time into as many partial sums (added at the
    /// end), so that the loop runs in vector registers; the margin's rounding term bounds any
    /// order of summation (γ of the number of terms times the sum of their magnitudes), so the
    /// order does not matter to the decision's soundness.
    #[inline]
    pub(super) fn decide(&self, s: &[f64; OBSERVATION_DIM]) -> Option<usize> {
        let [c0, c1, c2, c3] = &self.w1;
        let n = self.b1.len();
        let (c0, c1, c2, c3, b1, dw) = (
            &c0[..n],
            &c1[..n],
            &c2[..n],
            &c3[..n],
            &self.b1[..n],
            &self.dw[..n],
        );
        // One hidden unit: the exact pass's pre-activation, operation for operation (`dot` from
        // 0, then b₁), and its term of the logit difference.
        #[inline(always)]
        fn unit(c: [f64; 4], b: f64, dw: f64, s: &[f64; OBSERVATION_DIM]) -> (bool, f64) {
            let a = 0.0 + c[0] * s[0] + c[1] * s[1] + c[2] * s[2] + c[3] * s[3] + b;
            (a.is_finite(), dw * fast_tanh(a))
        }
        let mut acc = [0.0f64; LANES];
        let mut finite = [true; LANES];
        let chunks = c0
            .chunks_exact(LANES)
            .zip(c1.chunks_exact(LANES))
            .zip(c2.chunks_exact(LANES))
            .zip(c3.chunks_exact(LANES))
            .zip(b1.chunks_exact(LANES))
            .zip(dw.chunks_exact(LANES));
        for (((((k0, k1), k2), k3), kb), kd) in chunks {
            for l in 0..LANES {
                let (f, t) = unit([k0[l], k1[l], k2[l], k3[l]], kb[l], kd[l], s);
                finite[l] &= f;
                acc[l] += t;
            }
        }
        let full = n - n % LANES;
        let mut tail_finite = true;
        let mut tail = 0.0;
        for i in full..n {
            let (f, t) = unit([c0[i], c1[i], c2[i], c3[i]], b1[i], dw[i], s);
            tail_finite &= f;
            tail += t;
        }
        let finite = finite.iter().all(|&f| f) & tail_finite;
        let d = acc.iter().sum::<f64>() + tail + self.db;
        (finite && d.abs() > self.margin).then_some(usize::from(d > 0.0))
    }
}

/// Hidden units per step of [`MarginFilter::decide`]'s loop: two AVX2 registers of `f64`.
const LANES: usize = 8;

#[cfg(test)]
mod greedy_tests {
    use super::*;

    /// The approximation's error on a grid of spacing 10⁻⁶ over [−12, 12] stays below 10⁻⁶;
    /// between grid points it can grow by at most the spacing times the error's slope (≤ 2), so
    /// [`FAST_TANH_ERROR`] = 10⁻⁵ bounds it everywhere (beyond ±12 both sides are within 10⁻⁹ of
    /// ±1 and the clamped value).
    #[test]
    pub(super) fn fast_tanh_error_is_below_its_bound() {
        let n = 24_000_000;
        let mut worst = 0.0f64;
        for k in 0..=n {
            let x = -12.0 + 24.0 * f64::from(k) / f64::from(n);
            let exact = crate::policy::tanh(&x).unwrap();
            worst = worst.max((fast_tanh(x) - exact).abs());
        }
        assert!(worst < 1e-6, "worst error {worst:e}");
        approx::assert_abs_diff_eq!(fast_tanh(1e300), 1.0, epsilon = 1e-6);
        approx::assert_abs_diff_eq!(fast_tanh(-1e300), -1.0, epsilon = 1e-6);
    }

    /// The greedy labeller gives `action_in`'s action (and the filter decides most states).
    #[test]
    pub(super) fn greedy_matches_the_exact_forward_pass() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json");
        let e = PpoExpert::load(&path).unwrap();
        let g = e.greedy_in::<f64>().unwrap();
        let f = g.filter.as_ref().expect("the f64 filter");
        let mut rng = KitRng::seed_from_u64(7);
        let mut decided = 0;
        let n = 200_000;
        for k in 0..n {
            // States around the balance point and far from it, and some on the decision boundary's
            // scale (tiny).
            let scale = [1e-6, 0.05, 0.5, 3.0][k % 4];
            let s: [f64; 4] = std::array::from_fn(|_| scale * (2.0 * rng.random::<f64>() - 1.0));
            let want = e.action_in(&s).unwrap();
            assert_eq!(g.action(&s).unwrap(), want, "state {s:?}");
            assert_eq!(e.action(&s).unwrap(), want);
            if let Some(a) = f.decide(&s) {
                assert_eq!(a, want);
                decided += 1;
            }
        }
        assert!(decided > n / 2, "the filter decided only {decided} of {n}");
        let bad = [f64::NAN, 0.0, 0.0, 0.0];
        assert_eq!(
            g.action(&bad).unwrap_err().to_string(),
            e.action_in(&bad).unwrap_err().to_string()
        );
        // Another scalar: no filter, the exact pass.
        let dual = e.greedy_in::<crate::scalar::Dual<f64>>().unwrap();
        assert!(dual.filter.is_none());
        for k in 0..100 {
            let s: [f64; 4] = std::array::from_fn(|j| 0.01 * (k as f64 - 50.0) * (j as f64 + 1.0));
            let sd = s.map(|x| crate::scalar::Dual::<f64>::from_binary64(x).unwrap());
            assert_eq!(dual.action(&sd).unwrap(), e.action_in(&s).unwrap());
        }
    }
}
