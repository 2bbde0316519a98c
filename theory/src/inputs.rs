//! The table's inputs as one value: the bound formulas it compares against, the certified
//! constants it plugs in, and the gradient oracle whose expectations its exact rows compute.
//!
//! The rows read these through [`TableInputs`] rather than calling [`crate::bounds`] or using a
//! certified constant directly, so that the perturbation test (`theory/tests/checks/perturbation.rs`)
//! can hand the table a deliberately wrong input — a constant halved, a factor dropped from a
//! bound's formula, a small bias on every gradient estimate — and assert that at least one row's
//! verdict turns. [`TableInputs::thesis`] is the table as it is run: the formulas of
//! [`crate::bounds`], the constants as certified, the oracle unbiased.

use crate::bounds::{self, O2ncParams};
use crate::certify::box_constants::ToyConstants;
use crate::certify::global::GlobalConstants;
use crate::record::constant::Constant;
use ilopt::scalar::{BigRational, Scalar};

/// The bound formulas the table compares its measurements with (each a function of its constants,
/// as in [`crate::bounds`]).
#[derive(Debug, Clone, Copy)]
pub struct Formulas {
    /// Eq. 3.27, [`bounds::sgd_constant`]: `(L, η, σ², B_F, K) ↦ Lησ² + 2B_F/(ηK)`.
    pub sgd_constant: fn(f64, f64, f64, f64, u64) -> f64,
    /// Eqs. 3.25/3.26, [`bounds::sgd_weighted`]: `(L, η₁..η_K, σ², B_F) ↦ (2B_F + Lσ²Σ η_k²)/Σ η_k`.
    pub sgd_weighted: fn(f64, &[f64], f64, f64) -> f64,
    /// Eq. (3.60\*) middle expression, [`bounds::storm_fixed`]: `(L, σ², B_F, K)`.
    pub storm_fixed: fn(f64, f64, f64, u64) -> f64,
    /// Thm 3.8 at the theorem level, [`bounds::o2nc_theorem`]: `(Δ₀, δ, G, σ, T/K/M)`.
    pub o2nc_theorem: fn(f64, f64, f64, f64, O2ncParams) -> f64,
    /// Corollary (3.71), [`bounds::o2nc_corollary`]: `(Δ₀, δ, G, N)`.
    pub o2nc_corollary: fn(f64, f64, f64, u64) -> f64,
}

impl Formulas {
    /// The formulas of [`crate::bounds`].
    pub const THESIS: Formulas = Formulas {
        sgd_constant: bounds::sgd_constant,
        sgd_weighted: bounds::sgd_weighted,
        storm_fixed: bounds::storm_fixed,
        o2nc_theorem: bounds::o2nc_theorem,
        o2nc_corollary: bounds::o2nc_corollary,
    };
}

/// A certified constant of the toy checks (math.md §7.1), by the name the proofs give it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConstantKind {
    /// B_F ≥ F(θ₁) − F*.
    BF,
    /// L_F, the smoothness constant of F (S1)/(A1).
    LF,
    /// L̃ of (A4), the mean-square smoothness of the (importance-weighted) old-point term.
    LTilde,
    /// σ² ≥ sup Var_θ(g) (S2)/(A3).
    Sigma2,
    /// G² ≥ sup E‖g‖².
    G2,
    /// G_F ≥ sup ‖∇F‖.
    GF,
    /// G_∞ ≥ sup ‖g(θ, τ)‖.
    GInf,
}

/// The table's inputs (see the module's documentation).
#[derive(Debug, Clone)]
pub struct TableInputs {
    /// The bound formulas.
    pub formulas: Formulas,
    /// One certified constant multiplied by a factor (`None`: every constant as certified).
    pub constant_scale: Option<(ConstantKind, BigRational)>,
    /// A bias added to every coordinate of every gradient estimate the exact rows take an
    /// expectation of (`None`: the oracle of eq. 3.15 as it is).
    pub oracle_bias: Option<BigRational>,
}

impl Default for TableInputs {
    fn default() -> Self {
        Self::thesis()
    }
}

impl TableInputs {
    /// The table as it is run: [`Formulas::THESIS`], certified constants, unbiased oracle.
    pub fn thesis() -> TableInputs {
        TableInputs {
            formulas: Formulas::THESIS,
            constant_scale: None,
            oracle_bias: None,
        }
    }

    /// A certified constant's value as the rows must use it (scaled if this input says so).
    pub fn constant<S: Scalar>(&self, kind: ConstantKind, certified: S) -> S {
        match &self.constant_scale {
            Some((k, factor)) if *k == kind => certified * S::from_rational(factor),
            _ => certified,
        }
    }

    /// [`TableInputs::constant`] for an `f64` constant (the product is rounded to nearest: a
    /// perturbed constant is a deliberate error, not a bound that must stay rigorous).
    pub fn constant_f64(&self, kind: ConstantKind, certified: f64) -> f64 {
        self.constant(kind, certified)
    }

    /// A certified constant record as the rows must use it: value (and its exact form) scaled if
    /// this input names `kind`; the certificate is kept, so a re-check of the scaled value against
    /// it (row 8) sees the error.
    pub fn constant_record(&self, kind: ConstantKind, c: &Constant) -> Constant {
        let mut out = c.clone();
        if let Some((k, factor)) = &self.constant_scale
            && *k == kind
        {
            out.value = c.value * factor.to_f64();
            out.rational =
                BigRational::from_float(out.value).map_or_else(|| "inf".into(), |q| q.to_string());
        }
        out
    }

    /// Box constants as the rows must use them ([`TableInputs::constant_record`] on each).
    pub fn toy_constants(&self, k: &ToyConstants) -> ToyConstants {
        use ConstantKind::*;
        ToyConstants {
            b_f: self.constant_record(BF, &k.b_f),
            l_f: self.constant_record(LF, &k.l_f),
            sigma2: self.constant_record(Sigma2, &k.sigma2),
            g2: self.constant_record(G2, &k.g2),
            g_f: self.constant_record(GF, &k.g_f),
            g_inf: self.constant_record(GInf, &k.g_inf),
            mdp: k.mdp.clone(),
        }
    }

    /// Global constants as the rows must use them ([`TableInputs::constant_record`] on each; L̃
    /// for both weightings).
    pub fn global_constants(&self, g: &GlobalConstants) -> GlobalConstants {
        use ConstantKind::*;
        GlobalConstants {
            b_f: self.constant_record(BF, &g.b_f),
            l_f: self.constant_record(LF, &g.l_f),
            l_tilde: self.constant_record(LTilde, &g.l_tilde),
            l_tilde_pd: self.constant_record(LTilde, &g.l_tilde_pd),
            sigma2: self.constant_record(Sigma2, &g.sigma2),
            g_f: self.constant_record(GF, &g.g_f),
            g_inf: self.constant_record(GInf, &g.g_inf),
            mdp: g.mdp.clone(),
        }
    }

    /// A gradient estimate as the rows must see it: `g + b·1` under an oracle bias b, else `g`.
    pub fn estimate<S: Scalar>(&self, mut g: Vec<S>) -> Vec<S> {
        if let Some(b) = &self.oracle_bias {
            let b = S::from_rational(b);
            for gi in &mut g {
                *gi += &b;
            }
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ilopt::scalar::parse_exact;

    #[test]
    fn the_thesis_inputs_change_nothing() {
        let t = TableInputs::thesis();
        let x = parse_exact("7/3").unwrap();
        assert_eq!(t.constant(ConstantKind::LF, x.clone()), x);
        assert_eq!(t.estimate(vec![x.clone()]), vec![x]);
        assert_eq!(
            (t.formulas.storm_fixed)(2.0, 3.0, 0.5, 100),
            bounds::storm_fixed(2.0, 3.0, 0.5, 100)
        );
    }

    #[test]
    fn a_perturbation_changes_only_what_it_names() {
        let half = parse_exact("1/2").unwrap();
        let t = TableInputs {
            constant_scale: Some((ConstantKind::Sigma2, half.clone())),
            oracle_bias: Some(parse_exact("1/1000").unwrap()),
            ..TableInputs::thesis()
        };
        let x = parse_exact("3").unwrap();
        assert_eq!(
            t.constant(ConstantKind::Sigma2, x.clone()),
            parse_exact("3/2").unwrap()
        );
        assert_eq!(t.constant(ConstantKind::LF, x.clone()), x);
        assert_eq!(
            t.estimate(vec![parse_exact("1").unwrap()]),
            vec![parse_exact("1001/1000").unwrap()]
        );
        assert_eq!(t.constant_f64(ConstantKind::Sigma2, 3.0), 1.5);
    }
}
