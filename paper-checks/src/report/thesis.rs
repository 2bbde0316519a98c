//! The thesis's own numbers (Tables 4.1–4.4) and the errata of its chapter 3 (math.md §0), as
//! the appendix prints them beside the kit's.

/// The thesis's Table 4.1 (gradient calls, mean ± spread) and 4.2 (runtime, s).
pub const THESIS_T41: [(&str, f64, f64); 5] = [
    ("STORM", 2764.0, 1300.0),
    ("SGD", 9450.0, 2886.0),
    ("RMSProp", 6411.0, 1880.0),
    ("DAgger", 53704.0, 4233.0),
    ("Adam", 10785.0, 3460.0),
];
/// Table 4.2 (runtime in seconds).
pub const THESIS_T42: [(&str, f64); 5] = [
    ("STORM", 561.37),
    ("SGD", 786.64),
    ("RMSProp", 594.49),
    ("DAgger", 1064.589),
    ("Adam", 1734.45),
];
/// Table 4.3 (gradient calls, mean ± spread).
pub const THESIS_T43: [(&str, f64, f64); 4] = [
    ("STORM", 4_472_049.0, 11031.0),
    ("RMSProp", 1_903_548.0, 9866.0),
    ("DAgger", 31_905_600.0, 4263.0),
    ("Adam", 2_467_044.0, 11636.0),
];
/// Table 4.4 (runtime in seconds).
pub const THESIS_T44: [(&str, f64); 4] = [
    ("STORM", 8233.7),
    ("RMSProp", 3328.4),
    ("DAgger", 39340.1),
    ("Adam", 4717.6),
];

/// The errata of math.md §0: (id, where, problem, correction).
pub const ERRATA: [(&str, &str, &str, &str); 18] = [
    (
        "E1",
        "(3.2), (3.5)",
        "l_t must not depend on the sampled action a_t; otherwise (3.15) is biased",
        "define l_t on the policy output (math.md §1.2)",
    ),
    (
        "E2",
        "(3.41)",
        "\"f L-smooth implies F L-smooth\" is false in IL (the sampling law depends on θ); the estimator field is not a gradient field",
        "assume L_F-smoothness of F directly, plus (A4)",
    ),
    (
        "E3",
        "(3.44) Lemma 3.3",
        "the Δ_k term lacks η_k²",
        "4(1−a_{k+1})²L²η_k²Δ_k",
    ),
    ("E4", "(3.46), (3.47)", "f written for ∇f", "typo"),
    (
        "E5",
        "(3.54)–(3.56)",
        "L²/2 in the quadratic upper bound",
        "L/2",
    ),
    (
        "E6",
        "(3.58)",
        "both coefficients wrong; needs ηL ≤ 1/4, not ηL < 2",
        "−(η/2)(1−2Lη)Δ + (η/2)(1+2Lη)e ≤ −(η/4)Δ + (3η/4)e for Lη ≤ 1/4",
    ),
    (
        "E7",
        "after (3.58)/(3.59)",
        "\"these choices make the first term negative\" is false for k = 1..23; the telescoping is invalid as written",
        "a different potential; the same step sizes then work",
    ),
    (
        "E8",
        "(3.60)",
        "O(·) hides constants, mixes T and K",
        "explicit bound (3.60*)",
    ),
    (
        "E9",
        "Alg. 4",
        "d_{k+1} = ∇f(θ_{k+1}, τ_{k+1}) + (1−a_{k+1})∇f(θ_k, τ_{k+1})",
        "d_{k+1} = ∇f(θ_{k+1}, τ_{k+1}) + (1−a_{k+1})(d_k − ∇f(θ_k, τ_{k+1})), as (3.40)",
    ),
    (
        "E10",
        "Alg. 4 / Lemma 3.3 in IL",
        "∇f(θ_k, τ_{k+1}) with τ_{k+1} ∼ p(·; θ_{k+1}) is biased for ∇F(θ_k)",
        "importance weight w = p(τ; θ_k)/p(τ; θ_{k+1}) (IS-STORM)",
    ),
    (
        "E11",
        "Alg. 5",
        "τ_n ∼ p(τ; θ_n) while the gradient is taken at w_n",
        "τ_n ∼ p(τ; w_n)",
    ),
    ("E12", "(3.64), (3.67)", "F(θ_1)", "F(θ_0)"),
    (
        "E13",
        "Thm 3.8 proof",
        "u_n = u^{mod(n,T)+1}; \"dividing by KDT = KM\"; (3.69) bounds a sum of norms by √T σ",
        "u_n = u^{⌈n/T⌉}; divide by DM; bound ‖Σ_t X_t‖, not Σ_t ‖X_t‖",
    ),
    (
        "E14",
        "(3.72)",
        "+s_n Δ_{n'}",
        "−s_{n'} Δ_{n'} (bound unaffected)",
    ),
    (
        "E15",
        "Thm 3.1",
        "statement has ‖θ_i − θ'‖; convergence needs βε/γ < 1 (unstated); Lemma 3.2 garbled",
        "‖θ_i − θ'_i‖; math.md §6",
    ),
    (
        "E16",
        "§3.2.1 end",
        "\"‖θ_k − θ_PO‖ ≤ α⁻¹‖∇F‖ ≤ E‖∇F‖\": the last inequality is false",
        "only E‖θ_k − θ_PO‖ ≤ α⁻¹ E‖∇F(θ_k)‖",
    ),
    (
        "E17",
        "Alg. 3, 4",
        "return θ_K",
        "guarantees are for a random / best iterate, not θ_K",
    ),
    (
        "E18",
        "(3.29), (3.30) vs (3.1)",
        "sums to T vs T−1",
        "use T−1 throughout",
    ),
];
