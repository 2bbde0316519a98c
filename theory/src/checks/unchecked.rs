//! The thesis's statements and errata the table does not check, each with the reason: printed
//! under the table so that a reader sees what the table is silent about.

/// A statement (or erratum) without a row, and why no row can check it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unchecked {
    /// The statement, by equation, lemma or erratum number.
    pub statement: &'static str,
    /// Why no row checks it.
    pub reason: &'static str,
}

/// Every statement of chapter 3 and erratum of docs/math.md without a row.
pub const UNCHECKED: &[Unchecked] = &[
    Unchecked {
        statement: "E4 ((3.46), (3.47): f written for ∇f)",
        reason: "a typo in notation; no number depends on it",
    },
    Unchecked {
        statement: "(3.60) as printed (E8)",
        reason: "an O(·) statement with hidden constants over a mix of T and K: no finite run can \
                 refute it; the explicit (3.60*) is checked instead (rows 2c, its proof steps and \
                 their closing algebra)",
    },
    Unchecked {
        statement: "Lemma 3.2",
        reason: "garbled as printed (E15): no single reading is a statement to check; the \
                 contraction it is used for is checked in its corrected form (rows 5b–5d)",
    },
    Unchecked {
        statement: "Theorem 3.1 in its ε, β, γ form",
        reason: "ε, β and γ (the sensitivity, smoothness and strong-convexity constants of the \
                 performative-prediction argument) are not defined for a finite-horizon IL \
                 objective with a learned state distribution; the table checks the form they \
                 enter through, the contraction modulus κ = εβ/γ, exactly on three instances \
                 (rows 5a–5e)",
    },
    Unchecked {
        statement: "E16 (end of Sec. 3.2.1: α⁻¹‖∇F(θ_k)‖ ≤ E‖∇F(θ_k)‖)",
        reason: "needs an α-strongly convex F, which no toy objective of the kit is; the printed \
                 step compares a random variable with its mean, so it can hold only for \
                 degenerate laws — the corrected statement (in expectation) follows from strong \
                 convexity directly",
    },
    Unchecked {
        statement: "E17 (Algorithms 3 and 4 return θ_K)",
        reason: "the proofs bound an average (equivalently a random or the best) iterate and say \
                 nothing about θ_K; the table's bound rows measure the averaged quantity the \
                 proofs bound, which is the guarantee the algorithms have",
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_says_why() {
        assert!(!UNCHECKED.is_empty());
        for u in UNCHECKED {
            assert!(!u.statement.is_empty() && u.reason.len() > 20, "{u:?}");
        }
    }
}
