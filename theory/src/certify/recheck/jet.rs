//! Hand-written differentiation for the second route: a second-order multivariate jet ([`Jet`])
//! and truncated Taylor series in one variable, in any scalar (written apart from the kit's dual
//! numbers, so the second route shares no derivative code with the first).

use ilopt::scalar::Scalar;

/// A second-order jet in `d` variables: value, gradient and Hessian (row-major).
#[derive(Debug, Clone)]
pub struct Jet<S> {
    pub(super) v: S,
    pub(super) g: Vec<S>,
    pub(super) h: Vec<S>,
}

impl<S: Scalar> Jet<S> {
    pub(super) fn constant(v: S, d: usize) -> Self {
        Self {
            v,
            g: vec![S::zero(); d],
            h: vec![S::zero(); d * d],
        }
    }
    /// A function of the single variable θ_o with derivatives (f, f′, f″).
    pub(super) fn along(f: S, f1: S, f2: S, o: usize, d: usize) -> Self {
        let mut j = Self::constant(f, d);
        if d > 0 {
            j.g[o] = f1;
            j.h[o * d + o] = f2;
        }
        j
    }
    pub(super) fn d(&self) -> usize {
        self.g.len()
    }
    pub(super) fn zip(&self, o: &Self, f: impl Fn(&S, &S) -> S) -> Self {
        Self {
            v: f(&self.v, &o.v),
            g: self.g.iter().zip(&o.g).map(|(a, b)| f(a, b)).collect(),
            h: self.h.iter().zip(&o.h).map(|(a, b)| f(a, b)).collect(),
        }
    }
    pub(super) fn add(&self, o: &Self) -> Self {
        self.zip(o, |a, b| a.clone() + b)
    }
    pub(super) fn sub(&self, o: &Self) -> Self {
        self.zip(o, |a, b| a.clone() - b)
    }
    /// (fg)′ = f′g + fg′, (fg)″ = f″g + f′g′ᵀ + g′f′ᵀ + fg″.
    pub(super) fn mul(&self, o: &Self) -> Self {
        let d = self.d();
        let mut r = Self::constant(self.v.product(&o.v), d);
        for i in 0..d {
            r.g[i] = self.g[i].product(&o.v) + self.v.product(&o.g[i]);
            for j in 0..d {
                let k = i * d + j;
                r.h[k] = self.h[k].product(&o.v)
                    + self.g[i].product(&o.g[j])
                    + self.g[j].product(&o.g[i])
                    + self.v.product(&o.h[k]);
            }
        }
        r
    }
    /// (1/f)′ = −f′/f², (1/f)″ = 2f′f′ᵀ/f³ − f″/f².
    pub(super) fn recip(&self) -> Self {
        let d = self.d();
        let r = S::one() / &self.v;
        let r2 = r.product(&r);
        let r3 = r2.product(&r);
        let mut out = Self::constant(r, d);
        for i in 0..d {
            out.g[i] = -(self.g[i].product(&r2));
            for j in 0..d {
                let k = i * d + j;
                out.h[k] = S::from_i64(2) * &self.g[i] * &self.g[j] * &r3 - self.h[k].product(&r2);
            }
        }
        out
    }
    pub(super) fn div(&self, o: &Self) -> Self {
        self.mul(&o.recip())
    }
    pub(super) fn scale(&self, k: &S) -> Self {
        Self {
            v: self.v.product(k),
            g: self.g.iter().map(|x| x.product(k)).collect(),
            h: self.h.iter().map(|x| x.product(k)).collect(),
        }
    }
}

/// Truncated Taylor series (coefficients f⁽ᵏ⁾/k!, k = 0..=3) in one variable.
pub(super) type Series<S> = [S; 4];

pub(super) fn s_mul<S: Scalar>(a: &Series<S>, b: &Series<S>) -> Series<S> {
    std::array::from_fn(|k| (0..=k).fold(S::zero(), |acc, i| acc + a[i].product(&b[k - i])))
}

/// a/b by the recurrence c_k = (a_k − Σ_{i<k} c_i b_{k−i}) / b_0.
pub(super) fn s_div<S: Scalar>(a: &Series<S>, b: &Series<S>) -> Series<S> {
    let mut c: Series<S> = std::array::from_fn(|_| S::zero());
    for k in 0..4 {
        let mut t = a[k].clone();
        for i in 0..k {
            t -= c[i].product(&b[k - i]);
        }
        c[k] = t / &b[0];
    }
    c
}
