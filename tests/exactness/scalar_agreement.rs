//! One test body for every scalar type (conventions.md 10): the exact engine and the oracle's estimates
//! computed in `f64`, `f32`, intervals, rationals and duals agree with the exact rational values
//! under the kit's tolerance policy (`ilopt::tolerance`): rationals equal, intervals contain the
//! exact value, f64 lies inside the interval run of the same code.

use crate::common::{example, q};
use ilopt::exact::backward::backward;
use ilopt::exact::enumerate::moments;
use ilopt::exact::forward::forward;
use ilopt::exact::importance::weighted_expectation;
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Dual, Interval, Scalar};
use ilopt::tolerance::{Agreement, all_agree};
use ilopt::toy::{ToyMdp, ToyProblem};

/// Every quantity the engine computes at θ (and θ′ for the IS identity), flattened.
fn quantities<S: Scalar>(mdp: &ToyMdp, theta: &[BigRational], theta2: &[BigRational]) -> Vec<S> {
    let p = ToyProblem::<S>::new(mdp);
    let th: Vec<S> = theta.iter().map(S::from_rational).collect();
    let th2: Vec<S> = theta2.iter().map(S::from_rational).collect();
    let x1 = moments(&p, &th).unwrap();
    let x2 = forward(&p, &th).unwrap();
    let x3 = backward(&p, &th).unwrap();
    let is = weighted_expectation(&p, &th, &th2, Weighting::PerDecision).unwrap();
    let mut out = vec![
        x1.objective,
        x1.second_moment,
        x1.variance,
        x2.objective,
        x3.0,
    ];
    out.extend(x1.expected_estimate);
    out.extend(x1.expected_full);
    out.extend(x2.gradient);
    out.extend(x3.1);
    out.extend(is);
    out
}

fn cases() -> Vec<(ToyMdp, Vec<BigRational>, Vec<BigRational>)> {
    let v = |xs: &[&str]| xs.iter().map(|x| q(x)).collect::<Vec<_>>();
    vec![
        (example("m1-tied.json"), v(&["0"]), v(&["1"])),
        (example("m1-tied.json"), v(&["1/3"]), v(&["-2/7"])),
        (
            example("m1-softmax.json"),
            v(&["1/10", "-3"]),
            v(&["2", "1/3"]),
        ),
        (example("m1-direct.json"), v(&["1/3"]), v(&["1/5"])),
        (
            example("three-state.json"),
            v(&["1/2", "-1", "0.1", "3", "2/3", "-5/4"]),
            v(&["0", "1", "1", "0", "-1/3", "2"]),
        ),
        // Termination (math.md §8): reset and absorbing semantics.
        (example("terminal-reset.json"), v(&["1/3"]), v(&["1/5"])),
        (example("terminal-absorb.json"), v(&["2/7"]), v(&["0.9"])),
    ]
}

fn agrees_everywhere<S: Agreement>() {
    for (mdp, theta, theta2) in cases() {
        let exact = quantities::<BigRational>(&mdp, &theta, &theta2);
        let enclosure = quantities::<Interval>(&mdp, &theta, &theta2);
        let got = quantities::<S>(&mdp, &theta, &theta2);
        assert!(
            all_agree(&got, &exact, &enclosure),
            "{}: {got:?} disagrees with exact {exact:?} / enclosure {enclosure:?}",
            std::any::type_name::<S>()
        );
        // The interval run is a genuine enclosure: it contains the exact values.
        assert!(all_agree(&enclosure, &exact, &enclosure));
    }
}

macro_rules! for_each_scalar {
    ($body:ident: $($name:ident => $t:ty),+ $(,)?) => {
        $( #[test] fn $name() { $body::<$t>(); } )+
    };
}

for_each_scalar!(agrees_everywhere:
    exact_rational => BigRational,
    interval => Interval,
    float64 => f64,
    float32 => f32,
    dual_float64 => Dual<f64>,
    dual_rational => Dual<BigRational>,
);
