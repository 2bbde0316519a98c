//! Rows 3b.s1 and 3b.s1.printed: (3.64)/(3.65) with E12, F(θ_n) − F(θ_{n−1}) =
//! ∫₀¹⟨∇F(θ_{n−1} + sΔ_n), Δ_n⟩ds at every step of the recorded runs, summed to F(θ_M) − F(θ_0),
//! the integral enclosed by the mean-value form; and row 3b.s1.d0, the bound F(θ_0) − F(θ_M) ≤ Δ₀
//! that (3.66) takes from it.

use super::path::delta0_of;
use super::{Evaluated, RESULT};
use crate::certify::box_constants::ToyConstants;
use crate::checks::proof_step::StepSlack;
use crate::inputs::TableInputs;
use crate::record::check::{Check, Method, Role};
use ilopt::exact::forward::forward;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar, enclose_rational};
use ilopt::toy::{ToyMdp, ToyProblem};

type Q = BigRational;

/// `lo ≤ x ≤ hi` for the ends of an enclosure, decided exactly in ℚ.
fn within(s: &mut StepSlack, x: &Q, iv: Interval) -> Result<(), String> {
    let end = |e: f64| Q::from_float(e).ok_or_else(|| format!("unbounded enclosure {iv:?}"));
    s.exact(&end(iv.inf())?, x);
    s.exact(x, &end(iv.sup())?);
    Ok(())
}

/// The engine in the two arithmetics the segment integrals need.
pub struct SegmentEngine {
    point: ToyProblem<Interval>,
    jet: ToyProblem<Dual<Interval>>,
}

impl SegmentEngine {
    /// For the problem `mdp`.
    pub fn new(mdp: &ToyMdp) -> Self {
        SegmentEngine {
            point: ToyProblem::new(mdp),
            jet: ToyProblem::new(mdp),
        }
    }

    /// An enclosure of ∫₀¹ F′(θ + sΔ) Δ ds (the right side of (3.65), one parameter), by the
    /// mean-value form on J sub-segments: with h = Δ/J, centre c_j and hull X_j of the j-th,
    /// ∫_{X_j} F′ = h F′(c_j) + ∫ (F′(x) − F′(c_j)) dx and |∫ (F′(x) − F′(c_j)) dx| ≤
    /// mag F″(X_j) h²/4; F′(c_j) by the forward DP (X2) in intervals, F″(X_j) by X2 in
    /// `Dual<Interval>`.
    ///
    /// # Errors
    /// If the engine cannot enclose F′ or F″ on a sub-segment.
    pub fn integral(&self, theta: &Q, step: &Q, pieces: usize) -> Result<Interval, String> {
        if step.is_certainly_zero() {
            return Ok(Interval::zero());
        }
        let j = pieces.max(1) as i64;
        let at = |num: i64, den: i64| theta.clone() + step.clone() * Q::new(num.into(), den.into());
        let h = enclose_rational(&(step.clone() / Q::from_integer(j.into())));
        let quarter_h2 = h.sqr() / Interval::from_i64(4);
        let mut acc = Interval::zero();
        for i in 0..j {
            let centre = enclose_rational(&at(2 * i + 1, 2 * j));
            let hull = enclose_rational(&at(i, j)).convex_hull(enclose_rational(&at(i + 1, j)));
            let slope = forward(&self.point, &[centre])
                .map_err(|e| e.to_string())?
                .gradient[0];
            let curvature = forward(&self.jet, &Dual::variables(&[hull]))
                .map_err(|e| e.to_string())?
                .gradient
                .swap_remove(0)
                .into_parts(1)
                .1[0];
            let m = curvature.mag();
            let bend = Interval::try_from((-m, m)).map_err(|e| format!("|F″| ≤ {m}: {e:?}"))?;
            acc += h * slope + bend * quarter_h2;
        }
        Ok(acc)
    }
}

/// Rows 3b.s1 (E12: F(θ_0)) and 3b.s1.printed (F(θ_1)).
pub fn telescoping(mdp: &ToyMdp, ev: &Evaluated, pieces: usize) -> Result<Vec<Check>, String> {
    let engine = SegmentEngine::new(mdp);
    let (t, kb) = (ev.runs.params.t as usize, ev.runs.params.k as usize);
    let (mut steps, mut printed) = (StepSlack::new(), StepSlack::new());
    let (mut worst_width, mut moved) = (0.0f64, 0usize);
    for (r, path) in ev.runs.paths.iter().enumerate() {
        let f = &ev.objective[r];
        let m = path.w.len();
        let mut integrals = Vec::with_capacity(m);
        for n in 1..=m {
            let step = path.step(n);
            let iv = engine.integral(&path.theta[n - 1], &step, pieces)?;
            // A step with Δ_n = 0 (each block's first) is 0 = 0: not counted as a point.
            if !step.is_certainly_zero() {
                worst_width = worst_width.max(iv.wid());
                within(&mut steps, &(f[n].clone() - &f[n - 1]), iv)?;
            }
            integrals.push(iv);
        }
        let sum = |from: usize, to: usize| {
            integrals[from - 1..to]
                .iter()
                .fold(Interval::zero(), |a, b| a + *b)
        };
        within(&mut steps, &(f[m].clone() - &f[0]), sum(1, m))?;
        // The printed version on the run (θ'_0 = θ_0: OGD's Δ_1 = 0, so θ_1 = θ_0) and on every
        // block entered after its first step, n = n₀..kT with n₀ = (k−1)T + 2 (a learner whose
        // first step Δ'_1 = Δ_{n₀} is nonzero): F(θ_{kT}) − F(θ'_1) = F(θ_{kT}) − F(θ_{n₀})
        // against Σ_{n=n₀}^{kT} ∫⟨∇F, Δ_n⟩.
        within(&mut printed, &(f[m].clone() - &f[1]), sum(1, m))?;
        for b in 1..=kb {
            let n0 = (b - 1) * t + 2;
            if n0 > b * t {
                continue;
            }
            moved += usize::from(!path.step(n0).is_certainly_zero());
            within(&mut printed, &(f[b * t].clone() - &f[n0]), sum(n0, b * t))?;
        }
    }
    let claim = |start: &str| {
        format!(
            "F(θ_n) − F(θ_{{n−1}}) = ∫₀¹⟨∇F(θ_{{n−1}} + sΔ_n), Δ_n⟩ds at every step and F(θ_M) − {start} = Σ_n of them on every run"
        )
    };
    let basis = format!(
        "{}; the exact F(θ_n) − F(θ_{{n−1}}) in ℚ must lie in an enclosure of the integral (mean-value form on {pieces} sub-segments, ∇F and ∇²F by X2 in intervals; widest enclosure {worst_width:.3e}); each step with Δ_n ≠ 0, run or window is two points (lower end, upper end)",
        ev.describe()
    );
    let s1 = steps
        .row("3b.s1", RESULT, claim("F(θ_0)"), Role::Corrected)
        .assumptions(["F well-behaved (3.61): F is C¹ on the toy"])
        .erratum("E12")
        .details(format!("{}; {basis}", steps.summary()))
        .decided(Method::Rigorous, steps.verdict());
    let p1 = printed
        .row(
            "3b.s1.printed",
            RESULT,
            "(3.64) as printed: F(θ_M) − F(θ_1) = Σ_{n=1}^M ∫₀¹⟨∇F(θ_{n−1} + sΔ_n), Δ_n⟩ds, on each run and each window of a block entered after its first step",
            Role::Thesis,
        )
        .erratum("E12")
        .refuted_by_erratum()
        .details(format!(
            "{}; on each run it agrees (OGD restarts at Δ_1 = 0, so θ_1 = θ_0); on the {moved} windows with a nonzero first step it drops F(θ'_1) − F(θ'_0); {basis}",
            printed.summary()
        ))
        .decided(Method::Rigorous, printed.verdict());
    Ok(vec![s1, p1])
}

/// Row 3b.s1.d0: the first term of (3.66), F(θ_0) − E F(θ_M) ≤ F(θ_0) − F* ≤ Δ₀, on every run:
/// F(θ_0) − F(θ_M) ≤ Δ₀ exactly, Δ₀ = B_F read through `inputs`.
///
/// # Errors
/// If the certified B_F is not finite.
pub fn descent(inputs: &TableInputs, k: &ToyConstants, ev: &Evaluated) -> Result<Check, String> {
    let delta0 = delta0_of(inputs, k)?;
    let mut s = StepSlack::new();
    for f in &ev.objective {
        let last = f.last().ok_or("a run without iterates")?;
        s.exact(&(f[0].clone() - last), &delta0);
    }
    Ok(s.row(
        "3b.s1.d0",
        RESULT,
        "(3.66), first term: F(θ_0) − F(θ_M) ≤ F(θ_0) − F* ≤ Δ₀ on every run",
        Role::Thesis,
    )
    .constants(vec![k.b_f.clone()])
    .details(format!(
        "{}; Δ₀ = B_F = {}; F by X2 in ℚ at the exact f64 iterates; {}",
        s.summary(),
        delta0,
        ev.describe()
    ))
    .decided(Method::Exact, s.verdict()))
}
