//! Route (a): a toy MDP against its exact ∇F (rationals) and exact σ².

use super::{
    GradientError, RouteResult, ToyRoute, draw, repetition_errors, squared_error_sd, summarise,
};
use crate::error::Error;
use crate::stats::fnv1a;
use ilopt::exact::enumerate::moments;
use ilopt::exact::forward::forward;
use ilopt::problem::KitRng;
use ilopt::scalar::{BigRational, Scalar, parse_exact_list};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::DVector;

/// The toy route's exact quantities at θ: (∇F by the forward DP X2, E‖g‖² by enumeration X1,
/// σ² = E‖g‖² − ‖∇F‖²), all in exact rationals.
///
/// # Errors
/// [`Error::Experiment`] if the file, θ or the exact engine fails.
pub fn toy_exact(
    route: &ToyRoute,
) -> Result<(ToyMdp, Vec<BigRational>, BigRational, BigRational), Error> {
    let e = |x: &dyn std::fmt::Display| Error::experiment("Fig. 4.2 (toy, exact)", x);
    let mdp = ToyMdp::load(&route.mdp_path()).map_err(|x| e(&x))?;
    let theta = parse_exact_list(&route.theta.join(","))
        .map_err(|(i, x)| e(&format!("θ entry {i}: {x}")))?;
    let p = ToyProblem::<BigRational>::new(&mdp);
    let x2 = forward(&p, &theta).map_err(|x| e(&x))?;
    let x1 = moments(&p, &theta).map_err(|x| e(&x))?;
    let norm2 = x2
        .gradient
        .iter()
        .fold(<BigRational as Scalar>::zero(), |a, g| a + g.clone() * g);
    let sigma2 = x1.second_moment.clone() - norm2;
    Ok((mdp, x2.gradient, x1.second_moment, sigma2))
}

/// Route (a): the toy MDP against its exact ∇F.
///
/// # Errors
/// As [`toy_exact`], or a failing draw.
pub fn toy_route(g: &GradientError) -> Result<RouteResult, Error> {
    let start = std::time::Instant::now();
    let (mdp, grad, _m2, sigma2) = toy_exact(&g.toy)?;
    let reference: Vec<f64> = grad.iter().map(Scalar::to_f64).collect();
    let p = ToyProblem::<f64>::new(&mdp);
    let theta = DVector::from_vec(
        parse_exact_list(&g.toy.theta.join(","))
            .map_err(|(i, x)| Error::experiment("Fig. 4.2 (toy)", format!("θ entry {i}: {x}")))?
            .iter()
            .map(<f64 as Scalar>::from_rational)
            .collect::<Vec<f64>>(),
    );
    // The streams' seeds depend on the route's own settings only (not on the other route's).
    let key = format!(
        "gradient-error|toy|{}|{}|{:016x}",
        serde_json::to_string(&g.toy).unwrap_or_default(),
        g.repetitions,
        fnv1a(&std::fs::read_to_string(g.toy.mdp_path()).unwrap_or_default())
    );
    let sq = repetition_errors(
        &g.toy.ns,
        g.repetitions,
        &key,
        &[(0, reference.len())],
        &reference,
        || {
            let (mut p, theta) = (p.clone(), &theta);
            move |rng: &mut KitRng| toy_draw(&mut p, theta, rng)
        },
    )?;
    let s2 = sigma2.to_f64();
    let (rmse, slope) = summarise(&g.toy.ns, &sq, s2, 0.0, g.bootstrap, &key);
    Ok(RouteResult {
        ns: g.toy.ns.clone(),
        blocks: vec!["all".into()],
        squared_errors: sq,
        reference,
        sigma2: s2,
        sigma2_exact: Some(sigma2.to_string()),
        squared_error_sd_n1: Some(squared_error_sd(&mdp, &g.toy, &grad, &sigma2)?),
        reference_variance: 0.0,
        reference_trajectories: None,
        rmse,
        slope,
        block_slopes: vec![],
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// One eq. 3.15 estimate (causal form) on the toy MDP at θ, in f64.
///
/// # Errors
/// If the oracle fails.
pub fn toy_draw(
    p: &mut ToyProblem<f64>,
    theta: &DVector<f64>,
    rng: &mut KitRng,
) -> Result<DVector<f64>, Error> {
    draw(p, theta, rng, "Fig. 4.2 (toy)")
}
