//! The exact expectation of a bound row's statistic over **every** path of a short run
//! (math.md §7.3, "optional exact route for tiny K").
//!
//! On a toy MDP each step draws one trajectory prefix τ̄ from finitely many (X1,
//! [`ilopt::exact::enumerate::prefixes`]), so a run of K steps has finitely many outcome paths,
//! each with its probability Π_k p(τ̄_k; θ_k). Summing the per-path statistic times its probability
//! gives E X exactly (in ℚ) or enclosed (in intervals, where the STORM schedule's cube roots
//! enter); ∇F at every iterate is the forward DP (X2, [`ilopt::exact::forward::forward`]). Every
//! gradient estimate is the oracle's own (eq. 3.15 via the enumeration, the importance-weighted
//! old-point term via [`IlProblem::weighted_estimate`]) read through [`TableInputs::estimate`], so
//! a biased oracle moves the iterates as it would in a run.
//!
//! The same walk records the hull of every iterate θ₁, …, θ_{K+1} any path reaches: a convex set
//! that holds every iterate almost surely, on which the rows' box constants are valid.

use crate::certify::charts::prefix_terms_baselined;
use crate::certify::global_baselined::ratio_of;
use crate::inputs::TableInputs;
use ilopt::algo::ConfigNumber;
use ilopt::baseline::{Baseline, Baselined};
use ilopt::exact::enumerate::prefixes;
use ilopt::exact::forward::forward;
use ilopt::problem::{Cost, IlProblem, Weighting};
use ilopt::scalar::{BigRational, Interval, Roots, Scalar, norm_sq};
use ilopt::toy::{ToyMdp, ToyProblem, ToyTrajectory};
use nalgebra::DVector;

/// A scalar whose values can be enclosed in `f64` bounds (for the hull of the iterates).
pub trait Enclose: Scalar {
    /// `[lo, hi]` with `lo ≤ self ≤ hi`.
    fn enclosure(&self) -> [f64; 2];
}

impl Enclose for f64 {
    fn enclosure(&self) -> [f64; 2] {
        [*self, *self]
    }
}

impl Enclose for Interval {
    fn enclosure(&self) -> [f64; 2] {
        [self.inf(), self.sup()]
    }
}

impl Enclose for BigRational {
    /// The nearest `f64` is within half an ulp, so one ulp either side encloses the rational.
    fn enclosure(&self) -> [f64; 2] {
        let x = Scalar::to_f64(self);
        [x.next_down(), x.next_up()]
    }
}

/// E X over every path, with the hull of the iterates and the number of paths.
#[derive(Debug, Clone, PartialEq)]
pub struct PathMean<S> {
    /// E X (exact in ℚ, an enclosure in intervals, an approximation in `f64`).
    pub mean: S,
    /// Per coordinate, `[min, max]` over every iterate θ₁, …, θ_{K+1} of every path.
    pub hull: Vec<[f64; 2]>,
    /// Number of outcome paths (τ̄₁, …, τ̄_K).
    pub paths: u64,
}

/// Refuse a walk of more than `max_paths` paths (each step branches over the prefixes at θ₁; the
/// softmax support does not depend on θ, so the count is exact).
fn path_count<S: Scalar>(
    problem: &ToyProblem<S>,
    theta1: &[S],
    k: u64,
    max_paths: u64,
) -> Result<u64, String> {
    let n = prefixes(problem, theta1).map_err(|e| e.to_string())?.len() as u64;
    let total = u32::try_from(k)
        .ok()
        .and_then(|k| n.checked_pow(k))
        .filter(|t| *t <= max_paths);
    total.ok_or_else(|| format!("{n}^{k} paths exceed the limit of {max_paths}"))
}

fn widen(hull: &mut [[f64; 2]], theta: &[impl Enclose]) {
    for (h, t) in hull.iter_mut().zip(theta) {
        let [lo, hi] = t.enclosure();
        h[0] = h[0].min(lo);
        h[1] = h[1].max(hi);
    }
}

fn grad_norm_sq<S: Scalar>(problem: &ToyProblem<S>, theta: &[S]) -> Result<S, String> {
    Ok(norm_sq(
        &forward(problem, theta).map_err(|e| e.to_string())?.gradient,
    ))
}

/// One prefix τ̄ drawn at θ: its states and actions, p(τ̄; θ) and the estimate at θ.
struct Draw<S> {
    states: Vec<usize>,
    actions: Vec<usize>,
    prob: S,
    estimate: Vec<S>,
}

/// Every prefix at θ with the estimate the run draws there: g (eq. 3.15, the enumeration X1), or
/// with `baseline` = Some(b) the baselined g_b = g − b Σ_i ψ_i of one parameter (docs/math.md §9,
/// the engine's own baselined terms, `certify::charts::prefix_terms_baselined`). Both list the
/// prefixes in the same order, which does not depend on θ.
fn draws<S: Scalar>(
    problem: &ToyProblem<S>,
    theta: &[S],
    baseline: Option<&S>,
) -> Result<Vec<Draw<S>>, String> {
    Ok(match baseline {
        None => prefixes(problem, theta)
            .map_err(|e| e.to_string())?
            .into_iter()
            .map(|pre| Draw {
                states: pre.states,
                actions: pre.actions,
                prob: pre.prob,
                estimate: pre.estimate,
            })
            .collect(),
        Some(b) => {
            let table = problem.table(theta).map_err(|e| e.to_string())?;
            prefix_terms_baselined(problem, &table, b)?
                .into_iter()
                .map(|pre| Draw {
                    states: pre.states,
                    actions: pre.actions,
                    prob: pre.prob,
                    estimate: vec![pre.estimate],
                })
                .collect()
        }
    })
}

/// SGD with constant step η from θ₁ (Algorithm 3, eqs. 3.23–3.27): E X over every path, where
/// `X = (1/K) Σ_{k=1}^K ‖∇F(θ_k)‖²` is the statistic of eq. 3.27 and θ_{k+1} = θ_k − η ĝ_k,
/// ĝ_k = `inputs.estimate(g(θ_k, τ̄_k))`; with `baseline` = Some(b) the estimate is the baselined
/// g_b = g − b Σ_i ψ_i of one parameter (docs/math.md §9, the engine's own baselined terms,
/// `certify::charts::prefix_terms_baselined`).
///
/// # Errors
/// If there are more than `max_paths` paths, or a table cannot be built at an iterate.
pub fn sgd_mean<S: Enclose>(
    mdp: &ToyMdp,
    theta1: &[S],
    eta: &S,
    k: u64,
    inputs: &TableInputs,
    max_paths: u64,
    baseline: Option<&S>,
) -> Result<PathMean<S>, String> {
    let problem = ToyProblem::<S>::new(mdp);
    let paths = path_count(&problem, theta1, k, max_paths)?;
    let mut hull = vec![[f64::INFINITY, f64::NEG_INFINITY]; theta1.len()];
    let mut total = S::zero();
    // Depth-first over paths: (iterate index, θ_k, path probability, Σ_{i<k} ‖∇F(θ_i)‖²).
    let mut stack = vec![(1u64, theta1.to_vec(), S::one(), S::zero())];
    while let Some((i, theta, prob, acc)) = stack.pop() {
        widen(&mut hull, &theta);
        if i == k + 1 {
            total += prob * acc;
            continue;
        }
        let acc = acc + grad_norm_sq(&problem, &theta)?;
        for Draw {
            prob: pre_prob,
            estimate,
            ..
        } in draws(&problem, &theta, baseline)?
        {
            let g = inputs.estimate(estimate);
            let next: Vec<S> = theta
                .iter()
                .zip(&g)
                .map(|(t, gi)| t.clone() - eta.clone() * gi)
                .collect();
            stack.push((i + 1, next, prob.clone() * &pre_prob, acc.clone()));
        }
    }
    Ok(PathMean {
        mean: total / S::from_i64(k as i64),
        hull,
        paths,
    })
}

/// A prefix τ̄ (its states and actions) completed into a trajectory of `mdp` with the expert's
/// labels, for the oracle's weighted estimate: its last action and state enter no estimate.
pub(super) fn completed(mdp: &ToyMdp, states: &[usize], actions: &[usize]) -> ToyTrajectory {
    let mut st = states.to_vec();
    st.push(states[states.len() - 1]);
    let mut ac = actions.to_vec();
    ac.push(0);
    ToyTrajectory {
        labels: states.iter().map(|s| mdp.expert[*s]).collect(),
        states: st,
        actions: ac,
    }
}

/// The schedule (3.43) in `S`: `η_k = (1/(4L)) (7/(k+7))^{1/3}` and `a_{k+1} = (7/(k+7))^{2/3}`
/// for k = 1..K.
///
/// # Errors
/// If `S` has no cube root.
pub fn storm_schedule<S: Scalar + Roots>(l: &S, k: u64) -> Result<Vec<(S, S)>, String> {
    (1..=k)
        .map(|i| {
            let y = S::from_ratio(7, i as i64 + 7)
                .try_cbrt()
                .ok_or("the scalar has no cube root")?;
            Ok((y.clone() / (S::from_i64(4) * l), y.clone() * &y))
        })
        .collect()
}

/// IS-STORM with trajectory weights and schedule (3.43) for the constant `l` (Theorem S,
/// math.md §3.2): E X over every path, where `X = Σ_k η_k ‖∇F(θ_k)‖² / Σ_k η_k` is the statistic
/// of eq. (3.60\*), θ_{k+1} = θ_k − η_k d_k, d₁ = ĝ(θ₁, τ̄₁) and
/// `d_{k+1} = ĝ(θ_{k+1}, τ̄_{k+1}) + (1 − a_{k+1})(d_k − w ĝ(θ_k, τ̄_{k+1}))` with τ̄_{k+1} drawn at
/// θ_{k+1} and w = p(τ̄; θ_k)/p(τ̄; θ_{k+1}) (every estimate through `inputs.estimate`).
///
/// `weighting` is the old-point term's importance weight: the trajectory weight w above, or the
/// per-decision weights of row 2c.pd ([`IlProblem::weighted_estimate`], math.md §4).
///
/// With `baseline` = Some(b) the run is row 2.b's (trajectory weights only): every estimate is the baselined g_b = g − b Σ_i ψ_i
/// (one constant b for every decision, docs/math.md §9), the new point's from the engine's
/// baselined terms as in [`sgd_mean`], the old-point term w g_b(θ_k, τ̄) from the kit's
/// [`Baselined`] oracle (m = 1), as `ilopt run` computes it.
///
/// # Errors
/// As [`sgd_mean`], if `S` has no cube root, if b is not a ratio of 64-bit integers, or for a
/// baseline with per-decision weights.
#[allow(clippy::too_many_arguments)] // the run's instance, schedule, oracle and estimator
pub fn storm_mean<S: Enclose + Roots>(
    mdp: &ToyMdp,
    theta1: &[S],
    l: &S,
    k: u64,
    inputs: &TableInputs,
    max_paths: u64,
    weighting: Weighting,
    baseline: Option<&BigRational>,
) -> Result<PathMean<S>, String> {
    if baseline.is_some() && weighting != Weighting::Trajectory {
        return Err("the baselined IS-STORM walk is written for trajectory weights".into());
    }
    let mut problem = ToyProblem::<S>::new(mdp);
    let b_s = baseline.map(S::from_rational);
    let mut baselined = baseline
        .map(|b| {
            let (num, den) = ratio_of(b)?;
            let value = ConfigNumber::ratio(num, den);
            Baselined::new(ToyProblem::<S>::new(mdp), 1, &Baseline::Constant { value })
                .map_err(|e| e.to_string())
        })
        .transpose()?;
    let paths = path_count(&problem, theta1, k, max_paths)?;
    let schedule = storm_schedule(l, k)?;
    let eta_sum = schedule.iter().fold(S::zero(), |a, (e, _)| a + e);
    let mut hull = vec![[f64::INFINITY, f64::NEG_INFINITY]; theta1.len()];
    widen(&mut hull, theta1);
    let mut total = S::zero();
    let trajectory = |states: &[usize], actions: &[usize]| completed(mdp, states, actions);
    let mut cost = Cost::default();
    // Depth-first: (k, θ_k, d_k, path probability, Σ_{i<k} η_i ‖∇F(θ_i)‖²).
    let mut stack = vec![];
    for pre in draws(&problem, theta1, b_s.as_ref())? {
        let d = inputs.estimate(pre.estimate);
        stack.push((1u64, theta1.to_vec(), d, pre.prob, S::zero()));
    }
    while let Some((i, theta, d, prob, acc)) = stack.pop() {
        let (eta, _) = &schedule[(i - 1) as usize];
        let acc = acc + eta.clone() * grad_norm_sq(&problem, &theta)?;
        let next: Vec<S> = theta
            .iter()
            .zip(&d)
            .map(|(t, di)| t.clone() - eta.clone() * di)
            .collect();
        widen(&mut hull, &next);
        if i == k {
            total += prob * acc;
            continue;
        }
        let a = &schedule[(i - 1) as usize].1;
        let (old, new) = (
            DVector::from_column_slice(&theta),
            DVector::from_column_slice(&next),
        );
        for pre in draws(&problem, &next, b_s.as_ref())? {
            let g = inputs.estimate(pre.estimate);
            let traj = trajectory(&pre.states, &pre.actions);
            let wg = match &mut baselined {
                None => problem.weighted_estimate(&old, &new, &traj, weighting, &mut cost),
                Some(oracle) => oracle.weighted_estimate(
                    &old,
                    &new,
                    &vec![traj],
                    Weighting::Trajectory,
                    &mut cost,
                ),
            }
            .map_err(|e| e.to_string())?;
            let wg = inputs.estimate(wg.iter().cloned().collect());
            let keep = S::one() - a;
            let d2: Vec<S> = g
                .iter()
                .zip(d.iter().zip(&wg))
                .map(|(gi, (di, wi))| gi.clone() + keep.clone() * (di.clone() - wi))
                .collect();
            stack.push((
                i + 1,
                next.clone(),
                d2,
                prob.clone() * &pre.prob,
                acc.clone(),
            ));
        }
    }
    Ok(PathMean {
        mean: total / eta_sum,
        hull,
        paths,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::m1_tied;
    use ilopt::scalar::parse_exact;
    use ilopt::toy::PolicyKind;

    fn q(s: &str) -> BigRational {
        parse_exact(s).unwrap()
    }

    /// K = 1: X = ‖∇F(θ₁)‖², and F′(0) = −1/2 on M1 (math.md §1.4), over the 6 prefixes.
    #[test]
    fn one_sgd_step_gives_the_squared_gradient_at_the_start() {
        let m = sgd_mean(
            &m1_tied(),
            &[q("0")],
            &q("1/20"),
            1,
            &TableInputs::thesis(),
            100,
            None,
        )
        .unwrap();
        assert_eq!((m.mean, m.paths), (q("1/4"), 6));
        assert!(m.hull[0][0] < 0.0 && m.hull[0][1] > 0.0, "{:?}", m.hull);
    }

    /// K = 2: X̄ = (F′(θ₁)² + Σ_τ̄ p(τ̄; θ₁) F′(θ₁ − η g(θ₁, τ̄))²)/2, summed here directly; an
    /// oracle bias moves θ₂ and with it X̄.
    #[test]
    fn two_sgd_steps_sum_over_the_first_prefix() {
        let mdp = m1_tied();
        let p = ToyProblem::<BigRational>::new(&mdp);
        let eta = q("1/4");
        let mut second = q("0");
        for pre in prefixes(&p, &[q("0")]).unwrap() {
            let t2 = q("0") - eta.clone() * &pre.estimate[0];
            let g = forward(&p, &[t2]).unwrap().gradient;
            second += pre.prob * &g[0] * &g[0];
        }
        let want = (q("1/4") + second) / q("2");
        let got = sgd_mean(&mdp, &[q("0")], &eta, 2, &TableInputs::thesis(), 100, None).unwrap();
        assert_eq!((got.mean.clone(), got.paths), (want, 36));
        let biased = TableInputs {
            oracle_bias: Some(q("1/100")),
            ..TableInputs::thesis()
        };
        let b = sgd_mean(&mdp, &[q("0")], &eta, 2, &biased, 100, None).unwrap();
        assert_ne!(b.mean, got.mean);
        assert!(sgd_mean(&mdp, &[q("0")], &eta, 3, &TableInputs::thesis(), 100, None).is_err());
        // With a baseline b the second step draws g_b = g − bψ₁ instead: a different X̄, and
        // with b = 0 the same.
        let zero = q("0");
        let b0 = sgd_mean(
            &mdp,
            &[q("0")],
            &eta,
            2,
            &TableInputs::thesis(),
            100,
            Some(&zero),
        );
        assert_eq!(b0.unwrap().mean, got.mean);
        let eighth = q("1/8");
        let b8 = sgd_mean(
            &mdp,
            &[q("0")],
            &eta,
            2,
            &TableInputs::thesis(),
            100,
            Some(&eighth),
        );
        assert_ne!(b8.unwrap().mean, got.mean);
    }

    /// With a deterministic start and T = 2 the estimate is ∇F itself (no score term, one
    /// prefix), so IS-STORM is gradient descent with the steps η_k of (3.43): compared with that
    /// recursion written out in `f64`.
    #[test]
    fn deterministic_storm_is_gradient_descent_with_the_schedule() {
        let mdp = ToyMdp::m_family(
            q("1"),
            q("1/2"),
            q("1/2"),
            2,
            PolicyKind::TiedSoftmax,
            Some(q("1/10")),
        )
        .unwrap();
        let (l, k) = (8.0, 12u64);
        let m = storm_mean(
            &mdp,
            &[0.5f64],
            &l,
            k,
            &TableInputs::thesis(),
            10,
            Weighting::Trajectory,
            None,
        )
        .unwrap();
        let p = ToyProblem::<f64>::new(&mdp);
        let (mut theta, mut num, mut den) = (0.5f64, 0.0, 0.0);
        for i in 1..=k {
            let eta = (7.0 / (i as f64 + 7.0)).cbrt() / (4.0 * l);
            let g = forward(&p, &[theta]).unwrap().gradient[0];
            num += eta * g * g;
            den += eta;
            theta -= eta * g;
        }
        assert_eq!(m.paths, 1);
        assert!(
            (m.mean - num / den).abs() <= 1e-12 * num / den,
            "{} {}",
            m.mean,
            num / den
        );
        // In intervals the enclosure holds the same value.
        let iv = storm_mean(
            &mdp,
            &[Interval::from_rational(&q("1/2"))],
            &Interval::from_rational(&q("8")),
            k,
            &TableInputs::thesis(),
            10,
            Weighting::Trajectory,
            None,
        )
        .unwrap();
        assert!(
            iv.mean.inf() <= num / den * (1.0 + 1e-12)
                && num / den * (1.0 - 1e-12) <= iv.mean.sup()
        );
    }

    /// K = 3 with row 2.b's baseline: X̄ written out over the 6 × 6 paths that decide θ₃, with
    /// the old-point term w g_b(θ₁, τ̄₂) assembled here from the baselined terms at θ₁ and the
    /// prefix weight w = p(τ̄₂; θ₁)/p(τ̄₂; θ₂), not by the `Baselined` oracle the walk uses; and
    /// b = 0 gives the plain walk.
    #[test]
    fn a_baselined_storm_walk_matches_the_recursion_written_out() {
        let mdp = m1_tied();
        let p = ToyProblem::<f64>::new(&mdp);
        let (l, theta1, b) = (8.0f64, 0.25f64, q("1/8"));
        let bf = Scalar::to_f64(&b);
        let terms = |theta: f64| {
            let table = p.table(&[theta]).unwrap();
            prefix_terms_baselined(&p, &table, &bf).unwrap()
        };
        let grad = |theta: f64| forward(&p, &[theta]).unwrap().gradient[0];
        let sched: Vec<(f64, f64)> = (1..=3)
            .map(|i| {
                let y = (7.0 / (i as f64 + 7.0)).cbrt();
                (y / (4.0 * l), y * y)
            })
            .collect();
        let eta_sum: f64 = sched.iter().map(|s| s.0).sum();
        let mut want = 0.0;
        let at1 = terms(theta1);
        for t1 in &at1 {
            let d1 = t1.estimate;
            let theta2 = theta1 - sched[0].0 * d1;
            let at2 = terms(theta2);
            for (t2, old) in at2.iter().zip(&at1) {
                assert_eq!((&t2.states, &t2.actions), (&old.states, &old.actions));
                let w = old.prob / t2.prob;
                let d2 = t2.estimate + (1.0 - sched[0].1) * (d1 - w * old.estimate);
                let theta3 = theta2 - sched[1].0 * d2;
                let x = sched[0].0 * grad(theta1).powi(2)
                    + sched[1].0 * grad(theta2).powi(2)
                    + sched[2].0 * grad(theta3).powi(2);
                want += t1.prob * t2.prob * x / eta_sum;
            }
        }
        let walk = |baseline: Option<&BigRational>| {
            storm_mean(
                &mdp,
                &[theta1],
                &l,
                3,
                &TableInputs::thesis(),
                1000,
                Weighting::Trajectory,
                baseline,
            )
            .unwrap()
        };
        let got = walk(Some(&b));
        assert_eq!(got.paths, 216);
        assert!(
            (got.mean - want).abs() <= 1e-12 * want,
            "{} {want}",
            got.mean
        );
        let plain = walk(None).mean;
        assert!((got.mean - plain).abs() > 1e-9, "{} {plain}", got.mean);
        let zero = walk(Some(&q("0"))).mean;
        assert!((zero - plain).abs() <= 1e-12 * plain, "{zero} {plain}");
    }

    /// K = 1: X = ‖∇F(θ₁)‖² (η₁ cancels); on M1 at θ₁ = 0 the enclosure holds 1/4.
    #[test]
    fn one_storm_step_gives_the_squared_gradient_at_the_start() {
        let m = storm_mean(
            &m1_tied(),
            &[Interval::from_rational(&q("0"))],
            &Interval::from_rational(&q("5")),
            1,
            &TableInputs::thesis(),
            10,
            Weighting::Trajectory,
            None,
        )
        .unwrap();
        assert!(m.mean.inf() <= 0.25 && 0.25 <= m.mean.sup(), "{:?}", m.mean);
        assert_eq!(m.paths, 6);
    }
}
