//! The PPO expert's greedy action in any real scalar, with an exact-decision `f64` pre-test.

use super::*;

/// The PPO expert's greedy action in the scalar `S`, the actor's weights converted once
/// ([`PpoExpert::greedy_in`]): the roll-outs label every visited state with it.
///
/// [`PpoGreedy::action`] performs the operations of [`PpoExpert::action_in`] in the same order
/// (so its action is the same, bit for bit in `f64`), streaming the hidden layer into the two
/// logits instead of storing it. In `f64` a cheaper test comes first: the logits' difference
/// `D = Σᵢ (W₂)₁ᵢ uᵢ − (W₂)₀ᵢ uᵢ + (b₂)₁ − (b₂)₀` evaluated in single precision with a rational
/// approximation of tanh ([`fast_tanh_f32`], absolute error below [`FAST_TANH_F32_ERROR`]). When
/// |D̃| exceeds a bound on its distance from the exact forward pass's difference (the
/// approximation's error, the single-precision pre-activations' and sums' rounding, the exact
/// pass's own rounding; [`PpoGreedy`]'s filter) the exact pass's comparison `z₁ > z₀` has the
/// sign of D̃, and that is the action; otherwise, or for a non-finite activation, the exact pass
/// decides (and reports errors as [`PpoExpert::action_in`] does). The labels are therefore those
/// of the exact pass; only the work differs.
#[derive(Debug, Clone)]
pub struct PpoGreedy<S> {
    /// The actor's weights in `S` ([`Mlp`] layout: `W₁ | b₁ | W₂ | b₂`).
    pub(super) weights: Vec<S>,
    /// Hidden units.
    pub(super) hidden: usize,
    /// The single-precision filter, only when `S` is `f64`.
    pub(super) filter: Option<Box<MarginFilter>>,
}

/// The single-precision pre-test of [`PpoGreedy`]: W₁ by columns (unit stride), b₁, the
/// differences of W₂'s two rows, all rounded to `f32`; the difference of b₂; and the margin
/// beyond which the approximate difference decides, `margin + slope · (Σⱼ Kⱼ |sⱼ| + K_b)`
/// (the last term bounds the pre-activations' rounding at the state s).
#[derive(Debug, Clone)]
pub(super) struct MarginFilter {
    /// Column j of W₁ (`hidden` entries each).
    pub(super) w1: [Vec<f32>; OBSERVATION_DIM],
    pub(super) b1: Vec<f32>,
    /// (W₂)₁ᵢ − (W₂)₀ᵢ.
    pub(super) dw: Vec<f32>,
    /// (b₂)₁ − (b₂)₀.
    pub(super) db: f64,
    /// The state-independent part of the margin.
    pub(super) margin: f64,
    /// Kⱼ = Σᵢ |Δwᵢ| |(W₁)ᵢⱼ|.
    pub(super) k: [f64; OBSERVATION_DIM],
    /// K_b = Σᵢ |Δwᵢ| |(b₁)ᵢ|.
    pub(super) kb: f64,
    /// The relative rounding of a pre-activation (single precision, inputs rounded, and the
    /// exact pass's double precision), doubled as the rest of the margin is.
    pub(super) slope: f64,
}

/// An upper bound on `|fast_tanh_f32(x) − tanh(x)|` for every `f32` x (the approximation's
/// error in single precision, below 10⁻⁶ on every `f32` input, with a factor of ten to spare;
/// `tests` checks it input by input).
pub const FAST_TANH_F32_ERROR: f64 = 1e-5;

/// tanh by a rational minimax approximation `x·p(x²)/q(x²)` on [−7.9, 7.9], clamped outside,
/// in single precision (Eigen's `ptanh` for `float`, the same coefficients): branch-free, so a
/// loop of it runs eight lanes to a vector register. Absolute error below
/// [`FAST_TANH_F32_ERROR`]; not for results, only for the pre-test of [`PpoGreedy`]. Odd: the
/// value at −x is exactly the negated value at x.
#[inline(always)]
pub fn fast_tanh_f32(x: f32) -> f32 {
    const CLAMP: f32 = 7.905_311;
    const A: [f32; 7] = [
        4.893_524_6e-3,
        6.372_619_5e-4,
        1.485_722_4e-5,
        5.122_297e-8,
        -8.604_672e-11,
        2.000_188e-13,
        -2.760_768_5e-16,
    ];
    const B: [f32; 4] = [4.893_525e-3, 2.268_434_6e-3, 1.185_347e-4, 1.198_258_4e-6];
    let x = x.clamp(-CLAMP, CLAMP);
    let x2 = x * x;
    // Estrin's scheme: pairs of coefficients first, then powers x⁴ and x⁸, so that the chain of
    // dependent operations is four deep instead of Horner's seven.
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    let p01 = A[1].mul_add(x2, A[0]);
    let p23 = A[3].mul_add(x2, A[2]);
    let p45 = A[5].mul_add(x2, A[4]);
    let p03 = p23.mul_add(x4, p01);
    let p46 = A[6].mul_add(x4, p45);
    let p = p46.mul_add(x8, p03) * x;
    let q01 = B[1].mul_add(x2, B[0]);
    let q23 = B[3].mul_add(x2, B[2]);
    let q = q23.mul_add(x4, q01);
    p / q
}

/// γₙ = n·u/(1 − n·u): the relative error bound of n roundings to unit roundoff u.
fn gamma(n: usize, u: f64) -> f64 {
    let nu = n as f64 * u;
    nu / (1.0 - nu)
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
        let filter = S::IS_BINARY64.then(|| Box::new(MarginFilter::new(&e.actor, hidden)));
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
        let (u32r, u64r) = (f64::from(f32::EPSILON) / 2.0, f64::EPSILON / 2.0);
        let e = FAST_TANH_F32_ERROR;
        let sum_abs_dw: f64 = dw.iter().map(|d| d.abs()).sum();
        let sum_abs_w2: f64 = w2.iter().chain(b2).map(|w| w.abs()).sum();
        // |D̃ − (ẑ₁ − ẑ₀)| is at most the sum of:
        // * Σ|Δwᵢ| |ũᵢ − ûᵢ|, with |ũᵢ − ûᵢ| ≤ the approximation's error, the exact tanh's
        //   (a few units in the last place of |u| ≤ 1: 10⁻¹⁴), the absolute rounding of f32
        //   subnormals (10⁻³⁰, far above it), and |ãᵢ − âᵢ| since tanh is 1-Lipschitz: the
        //   pre-activation's rounding, γ₈ in f32 (state and weights rounded to f32, five terms
        //   summed) plus γ₅ in f64 (the exact pass) times Σⱼ |(W₁)ᵢⱼ||sⱼ| + |(b₁)ᵢ|; with the
        //   weights |Δwᵢ| that is slope · (Σⱼ Kⱼ|sⱼ| + K_b);
        // * the single-precision sum of the terms Δw̃ᵢ ũᵢ: Δwᵢ rounded, the product rounded and
        //   `ceil(h / LANES)` terms summed per lane, γ_{k+2} in f32 times Σ|Δwᵢ|(1 + e); the lanes
        //   then summed in f64 with Δb (10⁻¹⁴ of the magnitudes);
        // * the exact pass's own rounding: its three
        //   sums of h + 1 terms each and Δw, Δb themselves, γ_{h+2} with a factor of 4.
        // Doubled, to spare.
        let per_lane = h.div_ceil(LANES);
        let rounding =
            4.0 * (h + 2) as f64 * u64r * (sum_abs_w2 + 2.0 * (sum_abs_dw + db.abs())) * (1.0 + e);
        let summing = gamma(per_lane + 2, u32r) * sum_abs_dw * (1.0 + e)
            + 1e-14 * (sum_abs_dw * (1.0 + e) + db.abs());
        let margin = 2.0 * (sum_abs_dw * (e + 1e-14 + 1e-30) + summing + rounding);
        let slope = 2.0 * (gamma(8, u32r) + gamma(5, u64r));
        #[allow(clippy::cast_possible_truncation)]
        // rounding to f32 is the point; the margin bounds it
        let to32 = |x: f64| x as f32;
        Self {
            w1: std::array::from_fn(|j| {
                (0..h).map(|i| to32(w1[i * OBSERVATION_DIM + j])).collect()
            }),
            b1: b1.iter().map(|&b| to32(b)).collect(),
            dw: dw.iter().map(|&d| to32(d)).collect(),
            db,
            margin,
            k: std::array::from_fn(|j| {
                (0..h)
                    .map(|i| dw[i].abs() * w1[i * OBSERVATION_DIM + j].abs())
                    .sum()
            }),
            kb: dw.iter().zip(b1).map(|(d, b)| d.abs() * b.abs()).sum(),
            slope,
        }
    }

    /// The margin at the state s: beyond it the approximate difference decides.
    fn margin_at(&self, s: &[f64; OBSERVATION_DIM]) -> f64 {
        let spread: f64 = self.k.iter().zip(s).map(|(k, x)| k * x.abs()).sum();
        self.margin + self.slope * (spread + self.kb)
    }

    /// The action when the approximate logit difference decides it, else `None`.
    ///
    /// The hidden units are taken [`LANES`] at a time into as many single-precision partial
    /// sums, added at the end in `f64`, so that the loop runs in one vector register; the
    /// margin bounds the rounding of that order of summation.
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
        #[allow(clippy::cast_possible_truncation)] // bounded by the margin; ±∞ fails `finite`
        let s32 = s.map(|x| x as f32);
        // One hidden unit's term of the logit difference. `a − a` is 0 for a finite
        // pre-activation and NaN otherwise (where the clamped tanh alone would stay finite), so
        // a non-finite one makes D̃ NaN, which decides nothing. (The margin at such a state,
        // beyond 10³⁰, would not let D̃ decide either: this is a second guard, at one subtraction
        // per unit instead of a lane-wise flag.)
        #[inline(always)]
        fn unit(c: [f32; 4], b: f32, dw: f32, s: &[f32; OBSERVATION_DIM]) -> f32 {
            let a = b + c[0] * s[0] + c[1] * s[1] + c[2] * s[2] + c[3] * s[3];
            #[allow(clippy::eq_op)] // a − a is the finiteness test, on purpose
            let nan_unless_finite = a - a;
            dw * fast_tanh_f32(a) + nan_unless_finite
        }
        let mut acc = [0.0f32; LANES];
        let chunks = c0
            .chunks_exact(LANES)
            .zip(c1.chunks_exact(LANES))
            .zip(c2.chunks_exact(LANES))
            .zip(c3.chunks_exact(LANES))
            .zip(b1.chunks_exact(LANES))
            .zip(dw.chunks_exact(LANES));
        for (((((k0, k1), k2), k3), kb), kd) in chunks {
            for l in 0..LANES {
                acc[l] += unit([k0[l], k1[l], k2[l], k3[l]], kb[l], kd[l], &s32);
            }
        }
        let full = n - n % LANES;
        let mut tail = 0.0f64;
        for i in full..n {
            tail += f64::from(unit([c0[i], c1[i], c2[i], c3[i]], b1[i], dw[i], &s32));
        }
        let finite = s.iter().all(|x| x.is_finite());
        let d = acc.iter().map(|&x| f64::from(x)).sum::<f64>() + tail + self.db;
        (finite && d.abs() > self.margin_at(s)).then_some(usize::from(d > 0.0))
    }
}

/// Hidden units per step of [`MarginFilter::decide`]'s loop: one AVX2 register of `f32`.
const LANES: usize = 8;

#[cfg(test)]
mod greedy_tests {
    use super::*;

    /// The single-precision approximation's error, input by input: every positive `f32` from
    /// 2⁻²⁰ up to the clamp and a little beyond (the function is odd, exactly, so the negative
    /// inputs mirror these), against the `f64` tanh (itself within 10⁻¹⁵). Below 2⁻²⁰, x² < 2⁻⁴⁰
    /// leaves p(x²)/q(x²) within a few roundings of A₀/B₀ ≈ 1, so |x·p/q| ≤ 1.01·|x| (plus
    /// 10⁻⁴⁰ for the subnormals' absolute rounding; sampled inputs check it), and |tanh x| ≤ |x|:
    /// the error is below 2.01·2⁻²⁰ < 2·10⁻⁶. Beyond the clamp
    /// C the value is the one at C, and tanh moves by less than 1 − tanh(C) < 3·10⁻⁷ there.
    #[test]
    pub(super) fn fast_tanh_f32_error_is_below_its_bound() {
        let exact = |x: f32| f64::from(x).tanh();
        let error = |x: f32| (f64::from(fast_tanh_f32(x)) - exact(x)).abs();
        let from = (2.0f32).powi(-20).to_bits();
        let to = 8.0f32.to_bits();
        let mut worst = 0.0f64;
        for bits in from..=to {
            worst = worst.max(error(f32::from_bits(bits)));
        }
        assert!(worst < 1e-6, "worst error {worst:e} on [2⁻²⁰, 8]");
        // Odd, bit for bit, and the small inputs' ratio.
        for bits in (0..=to).step_by(997) {
            let x = f32::from_bits(bits);
            assert_eq!(fast_tanh_f32(-x).to_bits(), (-fast_tanh_f32(x)).to_bits());
            if x < (2.0f32).powi(-20) {
                let bound = 1.01 * f64::from(x) + 1e-40;
                assert!(f64::from(fast_tanh_f32(x)).abs() <= bound, "at {x:e}");
            }
        }
        assert!(1.0 - exact(7.905_311) < 3e-7);
        for x in [8.5f32, 100.0, 3e38, f32::INFINITY] {
            assert_eq!(fast_tanh_f32(x), fast_tanh_f32(7.905_311));
            assert!(error(x) < 1e-6 + 3e-7);
        }
    }

    /// The committed CartPole expert (`experts/cartpole-ppo.json`).
    fn committed_expert() -> PpoExpert {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experts/cartpole-ppo.json");
        PpoExpert::load(&path).unwrap()
    }

    /// States on either side of the exact pass's decision boundary, within 2⁻⁶⁰ of it along random
    /// segments (bisection), and how many of them `f` decides against the exact pass.
    fn boundary_errors(e: &PpoExpert, f: &MarginFilter) -> (usize, usize) {
        let mut rng = KitRng::seed_from_u64(11);
        let (mut near, mut wrong) = (0, 0);
        let mut draw = || -> [f64; 4] {
            std::array::from_fn(|j| [0.5, 1.0, 0.1, 1.0][j] * (2.0 * rng.random::<f64>() - 1.0))
        };
        for _ in 0..4_000 {
            let (mut lo, mut hi) = (draw(), draw());
            let side = e.action_in(&lo).unwrap();
            if side == e.action_in(&hi).unwrap() {
                continue;
            }
            for _ in 0..60 {
                let mid: [f64; 4] = std::array::from_fn(|j| 0.5 * (lo[j] + hi[j]));
                if e.action_in(&mid).unwrap() == side {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            for s in [lo, hi] {
                near += 1;
                wrong += usize::from(f.decide(&s).is_some_and(|a| a != e.action_in(&s).unwrap()));
            }
        }
        (near, wrong)
    }

    /// The margin is sound where it is tight: no state next to the decision boundary is decided
    /// against the exact pass. The check has power: the same filter without its margin decides
    /// some of those states wrongly.
    #[test]
    pub(super) fn the_filter_never_decides_against_the_exact_pass_near_the_boundary() {
        let e = committed_expert();
        let g = e.greedy_in::<f64>().unwrap();
        let f = g.filter.as_ref().expect("the f64 filter");
        let (near, wrong) = boundary_errors(&e, f);
        assert!(near > 1000, "only {near} boundary states");
        assert_eq!(
            wrong, 0,
            "{wrong} of {near} boundary states decided wrongly"
        );
        let mut bare = f.clone();
        bare.margin = 0.0;
        bare.slope = 0.0;
        let (_, wrong) = boundary_errors(&e, &bare);
        assert!(
            wrong > 0,
            "without a margin no boundary state was decided wrongly"
        );
    }

    /// The greedy labeller gives `action_in`'s action (and the filter decides most states).
    #[test]
    pub(super) fn greedy_matches_the_exact_forward_pass() {
        let e = committed_expert();
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
        // Finite states whose single-precision pre-activations overflow (or whose entries do):
        // the filter decides nothing, the exact pass gives the action.
        for s in [
            [1e39, 0.0, 0.0, 0.0],
            [0.0, -1e39, 0.0, 0.0],
            [0.0, 0.0, 3e38, -3e38],
            [1e30, 1e30, -1e30, 1e30],
        ] {
            assert!(f.decide(&s).is_none(), "state {s:?}");
            assert_eq!(g.action(&s).unwrap(), e.action_in(&s).unwrap());
        }
        let bad = [f64::NAN, 0.0, 0.0, 0.0];
        assert_eq!(
            g.action(&bad).unwrap_err().to_string(),
            e.action_in(&bad).unwrap_err().to_string()
        );
        // Another scalar: no filter, the exact pass (`f32` too: the filter's bound is for a
        // binary64 exact pass).
        let dual = e.greedy_in::<crate::scalar::Dual<f64>>().unwrap();
        assert!(dual.filter.is_none());
        assert!(e.greedy_in::<f32>().unwrap().filter.is_none());
        for k in 0..100 {
            let s: [f64; 4] = std::array::from_fn(|j| 0.01 * (k as f64 - 50.0) * (j as f64 + 1.0));
            let sd = s.map(|x| crate::scalar::Dual::<f64>::from_binary64(x).unwrap());
            assert_eq!(dual.action(&sd).unwrap(), e.action_in(&s).unwrap());
        }
    }
}
