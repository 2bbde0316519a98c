//! Seeded runs of the kit's IL-correct Algorithm 5 on a one-parameter toy, recorded exactly: the
//! f64 iterates θ_n, evaluation points w_n and estimates g_n of every step, each converted to the
//! rational it is ([`Scalar::from_binary64`]), with the run's own OGD step η and radius D.

use super::StepSizes;
use crate::certify::box_constants::ToyConstants;
use crate::inputs::{ConstantKind, TableInputs};
use ilopt::algo::config::{AlgorithmConfig, RunConfig};
use ilopt::algo::o2nc::{O2nc, O2ncConfig, O2ncParameters};
use ilopt::algo::{ConfigNumber, IterationMetrics, Runner, StoppingRule, Termination};
use ilopt::problem::EstimatorForm;
use ilopt::scalar::{BigRational, Scalar};
use ilopt::toy::{ToyMdp, ToyProblem};
use std::cell::RefCell;

type Q = BigRational;

/// One run of Algorithm 5 (math.md §5), exactly as the f64 run visited it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPath {
    /// The run's seed.
    pub seed: u64,
    /// θ_0, θ_1, …, θ_M.
    pub theta: Vec<Q>,
    /// w_1, …, w_M (`w[n − 1]` is w_n).
    pub w: Vec<Q>,
    /// g_1, …, g_M as the oracle returned them (`g[n − 1]` is g_n = g(w_n, τ_n)).
    pub g: Vec<Q>,
}

impl RunPath {
    /// Δ_n = θ_n − θ_{n−1} (n = 1..M), exactly from the recorded iterates.
    pub fn step(&self, n: usize) -> Q {
        self.theta[n].clone() - &self.theta[n - 1]
    }
}

/// The runs of the proof-step rows with the parameters they ran with.
#[derive(Debug, Clone, PartialEq)]
pub struct Runs {
    /// The recorded runs.
    pub paths: Vec<RunPath>,
    /// T, K, M and D = δ/T (exact) of math.md §5.
    pub params: O2ncParameters,
    /// The OGD step η the runs used (the f64 value, exactly).
    pub eta: Q,
    /// The projection radius the runs used (D rounded to f64, exactly).
    pub radius: Q,
    /// G as configured (f64): √G² rounded up.
    pub g: f64,
    /// Δ₀ as configured (exact).
    pub delta0: Q,
    /// δ (exact).
    pub delta: Q,
}

/// G for Algorithm 5 and the bounds: √G² (G² through `inputs`) rounded up to an f64.
pub fn g_of(inputs: &TableInputs, k: &ToyConstants) -> f64 {
    inputs
        .constant_f64(ConstantKind::G2, k.g2.value)
        .sqrt()
        .next_up()
}

/// Δ₀ = B_F (through `inputs`) exactly.
///
/// # Errors
/// If the certified value is not finite.
pub fn delta0_of(inputs: &TableInputs, k: &ToyConstants) -> Result<Q, String> {
    let b = Q::from_float(k.b_f.value).ok_or("B_F is not finite")?;
    Ok(inputs.constant(ConstantKind::BF, b))
}

/// Run Algorithm 5 (IL-correct, causal estimator) `sizes.runs` times (seeds 0, 1, …) from
/// θ₀ = `sizes.theta0` with budget N, radius δ and the hyper-parameters G, Δ₀ read through
/// `inputs`, and record every step exactly. Every visited θ_n and w_n must lie in `domain` (the
/// box the certified constants hold on).
///
/// # Errors
/// A message naming the run for a failed run, a problem with other than one parameter, or an
/// iterate outside `domain`.
pub fn record(
    inputs: &TableInputs,
    mdp: &ToyMdp,
    k: &ToyConstants,
    domain: &[[f64; 2]],
    sizes: &StepSizes,
) -> Result<Runs, String> {
    if mdp.policy.dim() != 1 || domain.len() != 1 {
        return Err(format!(
            "the O2NC proof-step rows need a one-parameter problem (u^k = −D sign(Σ_t ∇F(w_t)) exactly); this one has {}",
            mdp.policy.dim()
        ));
    }
    if sizes.delta.1 == 0 {
        return Err("δ = n/0".into());
    }
    let delta = Q::new(sizes.delta.0.into(), sizes.delta.1.into());
    let g = g_of(inputs, k);
    let delta0 = delta0_of(inputs, k)?;
    let config = O2ncConfig {
        budget: sizes.budget,
        delta: ConfigNumber::Exact(delta.clone()),
        g: ConfigNumber::Float(g),
        delta0: ConfigNumber::Exact(delta0.clone()),
        form: EstimatorForm::Causal,
    };
    let algo = O2nc::<f64>::new(&config).map_err(|e| e.to_string())?;
    let params = algo.parameters().clone();
    let exact = |x: f64| Q::from_binary64(x).ok_or_else(|| format!("non-finite value {x}"));
    let eta = exact(*algo.ogd_step())?;
    let radius = exact(<f64 as Scalar>::from_rational(&params.d))?;
    let mut pf = ToyProblem::<f64>::new(mdp);
    let [lo, hi] = domain[0];
    let mut paths = Vec::with_capacity(sizes.runs);
    for seed in 0..sizes.runs as u64 {
        let cfg = RunConfig {
            algorithm: AlgorithmConfig::O2nc(config.clone()),
            theta0: vec![ConfigNumber::Float(sizes.theta0)],
            seed,
            stop: StoppingRule::iterations(params.m + 1),
        };
        // (θ_n, w_n, g_n) per step; θ_0 from the observation after `init`.
        let theta0 = RefCell::new(None::<f64>);
        let steps = RefCell::new(Vec::<(f64, f64, f64)>::with_capacity(params.m as usize));
        let observer = |m: &IterationMetrics<f64>| match (&m.evaluated_at, &m.estimate) {
            (Some(w), Some(g)) => steps.borrow_mut().push((m.theta[0], w[0], g[0])),
            _ if m.iteration == 0 => *theta0.borrow_mut() = Some(m.theta[0]),
            _ => {}
        };
        let rec = Runner::new(cfg.stop.clone())
            .and_then(|runner| {
                runner
                    .keep_history(false)
                    .with_observer(observer)
                    .run_config(&cfg, &mut pf)
            })
            .map_err(|e| format!("run {seed}: {e}"))?;
        if let Termination::Diverged(_) = rec.termination {
            return Err(format!("run {seed}: {}", rec.termination));
        }
        let steps = steps.into_inner();
        let theta0 = theta0.into_inner().ok_or(format!("run {seed}: no θ₀"))?;
        if steps.len() != params.m as usize {
            return Err(format!(
                "run {seed}: {} steps recorded, expected M = {}",
                steps.len(),
                params.m
            ));
        }
        let outside = std::iter::once(theta0)
            .chain(steps.iter().flat_map(|s| [s.0, s.1]))
            .find(|x| !(lo..=hi).contains(x));
        if let Some(x) = outside {
            return Err(format!(
                "run {seed}: the iterate {x} leaves the constants' domain [{lo}, {hi}]"
            ));
        }
        let mut theta = vec![exact(theta0)?];
        let (mut w, mut gs) = (vec![], vec![]);
        for (t, wn, gn) in steps {
            theta.push(exact(t)?);
            w.push(exact(wn)?);
            gs.push(exact(gn)?);
        }
        paths.push(RunPath {
            seed,
            theta,
            w,
            g: gs,
        });
    }
    Ok(Runs {
        paths,
        params,
        eta,
        radius,
        g,
        delta0,
        delta,
    })
}
