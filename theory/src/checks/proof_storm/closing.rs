//! The closing algebra of Theorem S (math.md §3.2) for schedule (3.43): the bound the telescoped
//! potential gives, assembled from step 3's coefficients in ℚ with rational enclosures of the
//! cube roots, against the closed form the table uses (`storm_fixed`, eq. (3.60\*) middle).
//!
//! Summing step 3 over k = 1..K, with Φ₁ ≤ F(θ₁) + λ₀σ² (E‖ε₁‖² ≤ σ²) and Φ_{K+1} ≥ F*:
//! `Σ_k η_k Δ_k ≤ 2[B_F + λ₀σ² + Σ_k 2λ_k a_{k+1}²σ²]`, divided by Σ_k η_k. For (3.43),
//! η_k = y_k/(4L), a_{k+1} = y_k², y_k = (7/(k+7))^{1/3}, so λ₀ = 1/(2L) (y₀ = 1) and
//! λ_k a_{k+1}² = y_k³/(2L) = 7/(2L(k+7)) are rational: the numerator is exact and only
//! Σ_k y_k needs enclosures.

use super::potential::{lambda, noise};
use crate::certify::global::GlobalConstants;
use crate::inputs::{ConstantKind, TableInputs};
use crate::record::check::{Check, Measured, Method, Role, Verdict};
use crate::schedule::cbrt_enclosure;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar};
use num_bigint::BigInt;

type Q = BigRational;

/// Bits of each cube root's rational enclosure: K = 3·10⁴ roots of width 2⁻⁶⁴ each leave the
/// sum's enclosure far inside the comparison's relative 10⁻¹².
const ROOT_BITS: u32 = 64;

/// λ_k a_{k+1}² for schedule (3.43) at step k: a²/(8L²η) with a = y², η = y/(4L), i.e.
/// y³/(2L) = 7/(2L(k+7)) (k = 0 gives 1/(2L)).
pub fn schedule_lambda_a2(l: &Q, k: u64) -> Q {
    Q::from_ratio(7, k as i64 + 7) / (Q::from_integer(2.into()) * l)
}

/// Σ_{k=1}^K λ_k a_{k+1}² for schedule (3.43) = (7/(2L))(H_{K+7} − H_7), exactly: the sum of
/// [`schedule_lambda_a2`] over k, by linearity.
pub fn schedule_lambda_a2_sum(l: &Q, k_max: u64) -> Q {
    schedule_lambda_a2(l, 0) * Q::from_integer(7.into()) * harmonic_tail(k_max)
}

/// H_{K+7} − H_7 = Σ_{k=1}^K 1/(k+7), exactly, by binary splitting (the fractions are combined
/// unreduced and reduced once, so the cost is a few large products instead of K reductions of a
/// growing denominator).
pub fn harmonic_tail(k_max: u64) -> Q {
    /// Σ_{n=a}^{b−1} 1/n as an unreduced (numerator, denominator), a < b.
    fn split(a: u64, b: u64) -> (BigInt, BigInt) {
        if b - a == 1 {
            return (BigInt::from(1u8), BigInt::from(a));
        }
        let m = a + (b - a) / 2;
        let ((p1, q1), (p2, q2)) = (split(a, m), split(m, b));
        (p1 * &q2 + p2 * &q1, q1 * q2)
    }
    if k_max == 0 {
        return Q::zero();
    }
    let (p, q) = split(8, k_max + 8);
    Q::new(p, q)
}

/// Rational bounds lo ≤ Σ_{k=1}^K (7/(k+7))^{1/3} ≤ hi. A pure function of K, computed once
/// per K and process (the table asks for the same K under every perturbation).
pub fn schedule_sum(k_max: u64) -> (Q, Q) {
    static DONE: std::sync::OnceLock<std::sync::Mutex<std::collections::HashMap<u64, (Q, Q)>>> =
        std::sync::OnceLock::new();
    let done = DONE.get_or_init(Default::default);
    if let Some(sum) = done.lock().map_or(None, |m| m.get(&k_max).cloned()) {
        return sum;
    }
    let sum = schedule_sum_uncached(k_max);
    if let Ok(mut m) = done.lock() {
        m.insert(k_max, sum.clone());
    }
    sum
}

fn schedule_sum_uncached(k_max: u64) -> (Q, Q) {
    let (mut lo, mut hi) = (Q::zero(), Q::zero());
    for k in 1..=k_max {
        let (l, h) = cbrt_enclosure(&Q::from_ratio(7, k as i64 + 7), ROOT_BITS);
        lo += l;
        hi += h;
    }
    (lo, hi)
}

/// The numerator 2[B_F + λ₀σ² + Σ_{k=1}^K 2λ_k a_{k+1}²σ²] of Theorem S for (3.43), exactly.
pub fn numerator(l: &Q, sigma2: &Q, b_f: &Q, k_max: u64) -> Q {
    let eta0 = Q::one() / (Q::from_integer(4.into()) * l);
    // Σ_k noise(λ_k a², σ²) = noise(Σ_k λ_k a², σ²): the noise term is linear in λ_k a².
    let total =
        b_f.clone() + lambda(l, &eta0) * sigma2 + noise(&schedule_lambda_a2_sum(l, k_max), sigma2);
    Q::from_integer(2.into()) * total
}

/// An enclosure [lo, hi] of Theorem S's bound Σ_k η_k Δ_k / Σ_k η_k ≤ N / Σ_k η_k for (3.43),
/// Σ_k η_k = Σ_k y_k/(4L), given the sum's enclosure.
pub fn bound(l: &Q, sigma2: &Q, b_f: &Q, k_max: u64, sum: &(Q, Q)) -> (Q, Q) {
    let n = numerator(l, sigma2, b_f, k_max) * Q::from_integer(4.into()) * l;
    (n.clone() / &sum.1, n / &sum.0)
}

/// How a floating-point value f compares with an exact value enclosed by [lo, hi] (0 < lo):
/// `Some(true)` if |f − B| ≤ tol·B for every B in the enclosure, `Some(false)` if for none,
/// `None` otherwise.
pub fn agrees(f: &Q, enclosure: &(Q, Q), tol: &Q) -> Option<bool> {
    let (lo, hi) = enclosure;
    let within = |b: &Q| {
        let diff = f.clone() - b;
        let diff = if diff < Q::zero() { -diff } else { diff };
        diff <= tol.clone() * b
    };
    if within(lo) && within(hi) {
        Some(true)
    } else if *f > hi.clone() * (Q::one() + tol) || *f < lo.clone() * (Q::one() - tol) {
        Some(false)
    } else {
        None
    }
}

/// Row 2c.close: for L = max(L_F, L̃) of each weighting (the L of rows 2c and 2c.pd), σ² and
/// B_F, all as the inputs give them, Theorem S's bound assembled from step 3 at K = `k_max`
/// agrees with `inputs.formulas.storm_fixed(L, σ², B_F, K)` to a relative 10⁻¹² (the closed
/// form's own `f64` rounding).
pub fn row(inputs: &TableInputs, g: &GlobalConstants, k_max: u64) -> Check {
    let sigma2 = inputs.constant_f64(ConstantKind::Sigma2, g.sigma2.value);
    let b_f = inputs.constant_f64(ConstantKind::BF, g.b_f.value);
    let l_f = inputs.constant_f64(ConstantKind::LF, g.l_f.value);
    let tol = Q::from_float(1e-12).unwrap_or_else(Q::zero);
    let sum = schedule_sum(k_max);
    let mut verdict = Verdict::Holds;
    let mut details = vec![];
    let mut worst = 0.0f64;
    let mut closed_forms = vec![];
    for (w, l_tilde) in [
        (Weighting::Trajectory, g.l_tilde.value),
        (Weighting::PerDecision, g.l_tilde_pd.value),
    ] {
        let l = l_f.max(inputs.constant_f64(ConstantKind::LTilde, l_tilde));
        let f = (inputs.formulas.storm_fixed)(l, sigma2, b_f, k_max);
        let exact = [l, sigma2, b_f, f].map(Q::from_float);
        let [Some(lq), Some(sq), Some(bq), Some(fq)] = exact else {
            verdict = Verdict::Inconclusive;
            details.push(format!(
                "{}: a non-finite value among L = {l}, σ² = {sigma2}, B_F = {b_f}, storm_fixed = {f}",
                super::states::weighting_name(w)
            ));
            continue;
        };
        let enc = bound(&lq, &sq, &bq, k_max, &sum);
        let mid = (enc.0.clone() + &enc.1) / Q::from_integer(2.into());
        let rel = ((fq.clone() - &mid) / &mid).to_f64();
        worst = if rel.abs() > worst.abs() { rel } else { worst };
        closed_forms.push(f);
        let this = agrees(&fq, &enc, &tol);
        verdict = match (verdict, this) {
            (Verdict::Fails, _) | (_, Some(false)) => Verdict::Fails,
            (Verdict::Inconclusive, _) | (_, None) => Verdict::Inconclusive,
            _ => Verdict::Holds,
        };
        details.push(format!(
            "{} weights, L = {l}: assembled bound ∈ [{:.15e}, {:.15e}] (width {:.1e}), storm_fixed = {f:.15e}, relative difference {rel:.2e}",
            super::states::weighting_name(w),
            enc.0.to_f64(),
            enc.1.to_f64(),
            (enc.1.clone() - &enc.0).to_f64()
        ));
    }
    Check::builder(
        "2c.close",
        super::RESULT,
        format!(
            "Theorem S's bound assembled from step 3 and telescoped, 2[B_F + λ₀σ² + Σ_k 2λ_k a_{{k+1}}²σ²]/Σ_k η_k with schedule (3.43) at K = {k_max}, equals the closed form storm_fixed(L, σ², B_F, K) = 4[2LB_F + σ²(1 + 14(H_{{K+7}} − H_7))]/Σ_k (7/(k+7))^{{1/3}} to a relative 10⁻¹²"
        ),
        Role::Corrected,
    )
    .assumptions([
        "Φ₁ ≤ F(θ₁) + λ₀σ² (E‖ε₁‖² ≤ σ²), Φ_{K+1} ≥ F*, B_F ≥ F(θ₁) − F*",
        "numerator exact in ℚ; Σ_k (7/(k+7))^{1/3} enclosed by rational cube-root bounds (64 bits each)",
    ])
    .constants(
        g.summary()
            .into_iter()
            .filter(|c| ["B_F", "σ²", "L_F", "L̃", "L̃_PD"].contains(&c.name.as_str()))
            .collect(),
    )
    .maybe_bound(closed_forms.first().copied())
    .measured(Measured::exact(worst))
    .erratum("E7, E8")
    .details(format!(
        "{}; σ² = {sigma2}, B_F = {b_f}, L_F = {l_f} as the inputs give them",
        details.join("; ")
    ))
    .decided(Method::Rigorous, verdict)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::bounds::storm_fixed;

    /// (3.60*)'s middle expression with the factor 14 dropped (a wrong closed form).
    pub(crate) fn without_14(l: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
        let denom: f64 = (1..=k).map(|i| (7.0 / (i as f64 + 7.0)).cbrt()).sum();
        let h = crate::bounds::harmonic(k + 7) - crate::bounds::harmonic(7);
        4.0 * (2.0 * l * b_f + sigma2 * (1.0 + h)) / denom
    }

    /// The schedule's product equals λ(L, η)·a² at a rational y (the same identity the closing
    /// uses with y irrational): y = 1/2, L = 3.
    #[test]
    fn the_schedule_product_is_lambda_times_a_squared() {
        let (l, y) = (Q::from_integer(3.into()), Q::from_ratio(1, 2));
        let eta = y.clone() / (Q::from_integer(4.into()) * &l);
        let a = y.square();
        let direct = lambda(&l, &eta) * a.square();
        assert_eq!(
            direct,
            y.clone() * &y * &y / (Q::from_integer(2.into()) * &l)
        );
        // At k = 49, y³ = 7/56 = 1/8, i.e. y = 1/2.
        assert_eq!(schedule_lambda_a2(&l, 49), direct);
    }

    /// The binary-split sum is the sum of the per-step products (and of 1/(k+7)).
    #[test]
    fn the_summed_products_are_the_sum_of_the_products() {
        let l = Q::from_ratio(13, 3);
        for k_max in [0u64, 1, 2, 7, 50] {
            let direct = (1..=k_max).fold(Q::zero(), |acc, k| acc + schedule_lambda_a2(&l, k));
            assert_eq!(schedule_lambda_a2_sum(&l, k_max), direct, "K = {k_max}");
            let h = (1..=k_max).fold(Q::zero(), |acc, k| acc + Q::from_ratio(1, k as i64 + 7));
            assert_eq!(harmonic_tail(k_max), h);
        }
    }

    /// The assembled bound agrees with the closed form of (3.60*) and not with one that drops
    /// the 14 or halves the σ² term.
    #[test]
    fn the_closing_matches_the_closed_form() {
        let q = |x: f64| Q::from_float(x).unwrap();
        let (l, s2, bf, k) = (4.4, 2.8, 0.5, 300);
        let sum = schedule_sum(k);
        let enc = bound(&q(l), &q(s2), &q(bf), k, &sum);
        let tol = q(1e-12);
        assert!(enc.0 <= enc.1);
        assert_eq!(
            agrees(&q(storm_fixed(l, s2, bf, k)), &enc, &tol),
            Some(true)
        );
        assert_eq!(
            agrees(&q(without_14(l, s2, bf, k)), &enc, &tol),
            Some(false)
        );
        assert_eq!(
            agrees(&q(storm_fixed(l, s2 / 2.0, bf, k)), &enc, &tol),
            Some(false)
        );
    }
}
