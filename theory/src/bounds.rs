//! The thesis's convergence bounds as functions of their constants (math.md §§2, 3, 5).
//!
//! Each function states the theorem, its assumptions and where the constants come from. The bounds
//! are short closed forms evaluated in `f64`; [`upper`] inflates a computed bound by a relative
//! 10⁻¹² so that rounding in its evaluation (at most a few dozen operations of relative error
//! 2⁻⁵³ each, plus libm's < 1 ulp for `ln`/`cbrt`/`sqrt`) can only make the bound *larger*: a check
//! that compares a measurement against `upper(B)` can never flag a violation caused by rounding.

use serde::{Deserialize, Serialize};

/// `b · (1 + 10⁻¹²)` (for b ≥ 0): a safe upper bound on a bound evaluated in floating point.
pub fn upper(b: f64) -> f64 {
    b * (1.0 + 1e-12)
}

/// **Theorem SGD, eq. 3.27** (math.md §2). Assumptions: (S1) F is L-smooth on a convex set holding
/// every iterate, F* > −∞; (S2) E g = ∇F and E‖g‖² ≤ σ² + c‖∇F‖²; (S3) fresh τ_k ∼ p(·; θ_k) and
/// constant η ≤ 1/(Lc). With B_F ≥ F(θ_1) − F*:
/// `(1/K) Σ_k E‖∇F(θ_k)‖² ≤ Lησ² + 2B_F/(ηK)`.
pub fn sgd_constant(l: f64, eta: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    l * eta * sigma2 + 2.0 * b_f / (eta * k as f64)
}

/// **Eqs. 3.25/3.26** for deterministic steps η_k ≤ 1/(Lc):
/// `Σ_k η_k E‖∇F(θ_k)‖² ≤ 2B_F + Lσ² Σ_k η_k²`; returned divided by Σ_k η_k, i.e. a bound on the
/// η-weighted average of E‖∇F(θ_k)‖².
pub fn sgd_weighted(l: f64, etas: &[f64], sigma2: f64, b_f: f64) -> f64 {
    let s1: f64 = etas.iter().sum();
    let s2: f64 = etas.iter().map(|e| e * e).sum();
    (2.0 * b_f + l * sigma2 * s2) / s1
}

/// The side condition of eq. 3.23: η ≤ 1/(Lc) (no constraint when c = 0).
pub fn sgd_step_admissible(l: f64, c: f64, eta: f64) -> bool {
    eta > 0.0 && (c == 0.0 || eta * l * c <= 1.0)
}

/// Harmonic number H_n.
pub fn harmonic(n: u64) -> f64 {
    (1..=n).map(|i| 1.0 / i as f64).sum()
}

/// The STORM schedule (3.43): η_k = (1/(4L)) (7/(k+7))^{1/3}, a_{k+1} = 16L²η_k² = (7/(k+7))^{2/3}.
pub fn storm_schedule(l: f64, k: u64) -> (f64, f64) {
    let y = (7.0 / (k as f64 + 7.0)).cbrt();
    (y / (4.0 * l), y * y)
}

/// **Theorem S / eq. (3.60\*)**, middle expression (math.md §3.2): for IS-STORM with schedule (3.43),
/// under (A1)–(A4), with L = max(L_F, L̃), σ² ≥ sup Var, B_F ≥ F(θ_1) − F*:
/// `Σ_k η_k Δ_k / Σ_k η_k ≤ 4[2LB_F + σ²(1 + 14(H_{K+7} − H_7))] / Σ_{k=1}^K (7/(k+7))^{1/3}`.
pub fn storm_fixed(l: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    let denom: f64 = (1..=k).map(|i| (7.0 / (i as f64 + 7.0)).cbrt()).sum();
    let h = harmonic(k + 7) - harmonic(7);
    4.0 * (2.0 * l * b_f + sigma2 * (1.0 + 14.0 * h)) / denom
}

/// The right-hand, closed-form expression of (3.60\*):
/// `4(K+7)^{1/3}[2LB_F + σ²(1 + 14 ln((K+7)/7))] / (7^{1/3} K)`.
pub fn storm_fixed_closed(l: f64, sigma2: f64, b_f: f64, k: u64) -> f64 {
    let kf = k as f64;
    4.0 * (kf + 7.0).cbrt() * (2.0 * l * b_f + sigma2 * (1.0 + 14.0 * ((kf + 7.0) / 7.0).ln()))
        / (7f64.cbrt() * kf)
}

/// Parameters of the adaptive (Cutkosky–Orabona) schedule of Algorithm 4 (math.md §3.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CutkoskyOrabona {
    /// k′ = bG^{2/3}/L.
    pub k_prime: f64,
    /// c = L²(28 + 1/(7b³)).
    pub c: f64,
    /// w = G² max((4b)³, 2, (28b + 1/(7b²))³/64).
    pub w: f64,
}

/// The parameters of Cutkosky & Orabona (2019) Theorem 1 for a free b > 0.
pub fn cutkosky_orabona_params(l: f64, g: f64, b: f64) -> CutkoskyOrabona {
    CutkoskyOrabona {
        k_prime: b * g.powf(2.0 / 3.0) / l,
        c: l * l * (28.0 + 1.0 / (7.0 * b.powi(3))),
        w: g * g
            * (4.0 * b)
                .powi(3)
                .max(2.0)
                .max((28.0 * b + 1.0 / (7.0 * b * b)).powi(3) / 64.0),
    }
}

/// **Cutkosky–Orabona Theorem 1** (math.md §3.3; secondary check for IL):
/// `E[(1/K) Σ_k ‖∇F(θ_k)‖] ≤ (w^{1/6}√(2M) + 2M^{3/4})/√K + 2σ^{1/3}/K^{1/3}`,
/// `M = 8B_F/k′ + w^{1/3}σ²/(4L²k′²) + k′²c² ln(K+2)/(2L²)`.
pub fn cutkosky_orabona(l: f64, sigma2: f64, b_f: f64, p: CutkoskyOrabona, k: u64) -> f64 {
    let kf = k as f64;
    let m = 8.0 * b_f / p.k_prime
        + p.w.cbrt() * sigma2 / (4.0 * l * l * p.k_prime * p.k_prime)
        + p.k_prime * p.k_prime * p.c * p.c * (kf + 2.0).ln() / (2.0 * l * l);
    (p.w.powf(1.0 / 6.0) * (2.0 * m).sqrt() + 2.0 * m.powf(0.75)) / kf.sqrt()
        + 2.0 * sigma2.sqrt().cbrt() / kf.cbrt()
}

/// The online-to-non-convex parameters of math.md §5 for budget N, radius δ, G, Δ₀.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct O2ncParams {
    /// Block length T = min(⌈(GNδ/Δ₀)^{2/3}⌉, ⌊N/2⌋).
    pub t: u64,
    /// Number of blocks K = ⌊N/T⌋.
    pub k: u64,
    /// M = KT gradient evaluations.
    pub m: u64,
}

/// T, K, M of math.md §5 (N ≥ 4).
pub fn o2nc_params(n: u64, delta: f64, g: f64, delta0: f64) -> O2ncParams {
    let t = ((g * n as f64 * delta / delta0).powf(2.0 / 3.0).ceil() as u64).clamp(1, n / 2);
    let k = n / t;
    O2ncParams { t, k, m: k * t }
}

/// **Theorem-level O2NC bound** (Cutkosky–Mehta–Orabona 2023, math.md §5) with the realised T, K,
/// D = δ/T, M: `E[(1/K) Σ_k ‖(1/T) Σ_t ∇F(w^k_t)‖] ≤ Δ₀/(DM) + G/√T + σ/√T`.
pub fn o2nc_theorem(delta0: f64, delta: f64, g: f64, sigma: f64, p: O2ncParams) -> f64 {
    let d = delta / p.t as f64;
    let t = (p.t as f64).sqrt();
    delta0 / (d * p.m as f64) + g / t + sigma / t
}

/// **Corollary, eq. 3.71**: `2Δ₀/(δN) + max(5G^{2/3}Δ₀^{1/3}/(Nδ)^{1/3}, 6G/√N)`.
pub fn o2nc_corollary(delta0: f64, delta: f64, g: f64, n: u64) -> f64 {
    let nf = n as f64;
    2.0 * delta0 / (delta * nf)
        + (5.0 * g.powf(2.0 / 3.0) * delta0.cbrt() / (nf * delta).cbrt()).max(6.0 * g / nf.sqrt())
}

/// The thesis's intermediate line before (3.71): `2TΔ₀/(δN) + 3G/√T`.
pub fn o2nc_intermediate(delta0: f64, delta: f64, g: f64, n: u64, t: u64) -> f64 {
    2.0 * t as f64 * delta0 / (delta * n as f64) + 3.0 * g / (t as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (3.28): with η = ε²/(2σ²L) and K = 8σ²LB_F/ε⁴, the right side of (3.27) squared is ε².
    #[test]
    fn eq_3_28_is_consistent_with_3_27() {
        let (l, s2, bf, eps): (f64, f64, f64, f64) = (2.0, 3.0, 0.5, 0.25);
        let eta = eps * eps / (2.0 * s2 * l);
        let k = 8.0 * s2 * l * bf / eps.powi(4);
        assert_eq!(k, k.round());
        let b = sgd_constant(l, eta, s2, bf, k as u64);
        assert!((b - eps * eps).abs() < 1e-15, "{b}");
    }

    /// (3.60*): the closed form dominates the harmonic-number form (H_{K+7} − H_7 ≤ ln((K+7)/7) and
    /// Σ (7/(k+7))^{1/3} ≥ 7^{1/3} K/(K+7)^{1/3}).
    #[test]
    fn storm_closed_form_dominates() {
        for k in [1u64, 2, 10, 100, 1000, 100_000] {
            assert!(storm_fixed(4.4, 2.8, 0.5, k) <= storm_fixed_closed(4.4, 2.8, 0.5, k));
        }
    }

    #[test]
    fn o2nc_parameters() {
        let p = o2nc_params(1000, 0.1, 1.0, 1.0);
        // (1·1000·0.1)^{2/3} = 21.54 → T = 22, K = 45, M = 990.
        assert_eq!(
            p,
            O2ncParams {
                t: 22,
                k: 45,
                m: 990
            }
        );
        let p = o2nc_params(10, 100.0, 10.0, 0.01);
        assert_eq!(p.t, 5, "capped at ⌊N/2⌋");
    }
}
