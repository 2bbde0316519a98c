//! Check 4: unbiasedness of the eq. 3.15 estimator (eqs. 3.16/3.18) exactly, the IS-corrected
//! old-point term (I3) exactly, and the negative controls: the printed Algorithm 4's old-point term
//! (E10), the printed Algorithm 5's sampling at θ_n instead of w_n (E11), and the printed
//! Algorithm 4 update (E9), whose mean direction is (2 − a)∇F instead of ∇F.

use crate::check::{Check, Measured, Method, Role, Verdict};
use ilopt::exact::enumerate::moments;
use ilopt::exact::forward::forward;
use ilopt::exact::importance::{unweighted_expectation, weighted_expectation};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};

type Q = BigRational;

fn max_abs_diff(a: &[Q], b: &[Q]) -> Q {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let d = x.clone() - y;
            if d < Q::zero() { -d } else { d }
        })
        .fold(Q::zero(), |m, d| if d > m { d } else { m })
}

fn row(
    id: &str,
    claim: String,
    role: Role,
    erratum: Option<&str>,
    worst: Q,
    details: String,
) -> Check {
    Check {
        id: id.into(),
        result: "Unbiasedness, eqs. 3.16/3.18".into(),
        claim,
        assumptions: vec!["finite MDP; l_t a function of (s_t, θ) only (E1)".into()],
        constants: vec![],
        bound: Some(0.0),
        measured: Some(Measured::exact(Scalar::to_f64(&worst))),
        tightness: None,
        method: Method::Exact,
        verdict: Verdict::from_bool(worst == Q::zero()),
        erratum: erratum.map(Into::into),
        role,
        details,
    }
}

/// E[g(θ, τ)] − ∇F(θ) over `(mdp, θ)` pairs, exactly; the claim holds iff every difference is 0.
pub fn estimator(cases: &[(ToyMdp, Vec<Q>)]) -> Check {
    let mut worst = Q::zero();
    for (mdp, th) in cases {
        let p = ToyProblem::<Q>::new(mdp);
        let eg = moments(&p, th).expect("evaluable").expected_estimate;
        let g = forward(&p, th).expect("evaluable").gradient;
        worst = worst.max(max_abs_diff(&eg, &g));
    }
    row(
        "4a",
        "E_{τ∼p(·;θ)}[∇f(θ, τ)] = ∇F(θ) exactly".into(),
        Role::Thesis,
        None,
        worst.clone(),
        format!("{} (MDP, θ) pairs; max |E g − ∇F| = {worst}", cases.len()),
    )
}

/// The old-point term at θ with τ ∼ p(·; θ′): IS-weighted (`Some(w)`, math.md §4) or as printed
/// (`None`, Algorithm 4 / E10). Claim: its mean is ∇F(θ).
pub fn old_point(cases: &[(ToyMdp, Vec<Q>, Vec<Q>)], weighting: Option<Weighting>) -> Check {
    let mut worst = Q::zero();
    for (mdp, th, th2) in cases {
        let p = ToyProblem::<Q>::new(mdp);
        let mean = match weighting {
            Some(w) => weighted_expectation(&p, th, th2, w).expect("evaluable"),
            None => unweighted_expectation(&p, th, th2).expect("evaluable"),
        };
        let g = forward(&p, th).expect("evaluable").gradient;
        worst = worst.max(max_abs_diff(&mean, &g));
    }
    let (id, claim, role, erratum) = match weighting {
        Some(w) => (
            if w == Weighting::Trajectory {
                "4b"
            } else {
                "4c"
            },
            format!("IS-STORM old-point term ({w:?} weights): E_{{τ∼θ′}}[w·∇f(θ, τ)] = ∇F(θ)"),
            Role::Corrected,
            Some("E10"),
        ),
        None => (
            "4d",
            "printed Algorithm 4 old-point term: E_{τ∼θ′}[∇f(θ, τ)] = ∇F(θ)".into(),
            Role::Thesis,
            Some("E10"),
        ),
    };
    row(
        id,
        claim,
        role,
        erratum,
        worst.clone(),
        format!("{} (θ, θ′) pairs; max |bias| = {worst}", cases.len()),
    )
}

/// The printed Algorithm 5 samples τ_n at θ_n but evaluates the gradient at w_n = θ_{n−1} + s_nΔ_n
/// (E11). Claim: E_{τ∼θ_n}[∇f(w_n, τ)] = ∇F(w_n), at the given (w_n, θ_n) pairs.
pub fn printed_o2nc(cases: &[(ToyMdp, Vec<Q>, Vec<Q>)]) -> Check {
    let mut c = old_point(cases, None);
    c.id = "4e".into();
    c.result = "Online-to-non-convex, Algorithm 5".into();
    c.claim = "printed Algorithm 5: E_{τ∼p(·;θ_n)}[∇f(w_n, τ)] = ∇F(w_n)".into();
    c.erratum = Some("E11".into());
    c
}

/// The printed Algorithm 4 update d_{k+1} = ∇f(θ_{k+1}, τ) + (1 − a)∇f(θ_k, τ) at θ_k = θ_{k+1} = θ:
/// its mean is (2 − a)∇F(θ), not ∇F(θ) (E9). Claim checked: mean = ∇F(θ).
pub fn printed_storm_update(mdp: &ToyMdp, theta: &[Q], a: &Q) -> Check {
    let p = ToyProblem::<Q>::new(mdp);
    let g = forward(&p, theta).expect("evaluable").gradient;
    let eg = moments(&p, theta).expect("evaluable").expected_estimate;
    let one = Q::one();
    let mean: Vec<Q> = eg
        .iter()
        .map(|x| x.clone() + (one.clone() - a) * x)
        .collect();
    let worst = max_abs_diff(&mean, &g);
    let ratio = if g.iter().all(|x| *x == Q::zero()) {
        "∇F = 0 here".to_string()
    } else {
        let j = g.iter().position(|x| *x != Q::zero()).expect("non-zero");
        format!("mean/∇F = {} (= 2 − a)", mean[j].clone() / &g[j])
    };
    let mut c = row(
        "4f",
        format!(
            "printed Algorithm 4 update (a = {a}): E[d_{{k+1}}] = ∇F(θ_{{k+1}}) when θ_k = θ_{{k+1}}"
        ),
        Role::Thesis,
        Some("E9"),
        worst,
        ratio,
    );
    c.result = "STORM, Algorithm 4 as printed".into();
    c
}
