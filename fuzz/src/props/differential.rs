//! The differential property: exact rationals, intervals and `f64` agree on the same oracle call
//! (the interval contains the rational; the float is within the tolerance policy of it).

use super::oracle::{OracleInput, check_oracle_outputs, run_oracle};
use ilopt::problem::OracleError;
use ilopt::scalar::{BigRational, Interval, Scalar, interval_contains_rational};
use nalgebra::DVector;

/// Errors that depend only on the *shape* of the input, never on the arithmetic: every scalar
/// must agree on them.
fn structural(e: &OracleError) -> Option<&'static str> {
    match e {
        OracleError::Dimension { .. } => Some("dimension"),
        OracleError::Trajectory(_) => Some("trajectory"),
        OracleError::Behaviour(_) => Some("behaviour"),
        _ => None,
    }
}

fn same_structure<A, B>(x: &Result<A, OracleError>, y: &Result<B, OracleError>, what: &str) {
    let kx = x.as_ref().err().and_then(structural);
    let ky = y.as_ref().err().and_then(structural);
    if kx.is_some() || ky.is_some() {
        assert_eq!(kx, ky, "{what}: structural errors differ");
    }
}

/// The kit's tolerance policy on one value: the exact value in the enclosure, the `f64` value in
/// the enclosure (src/tolerance.rs).
fn agree(q: &BigRational, i: &Interval, f: Option<&f64>, what: &str) {
    assert!(
        interval_contains_rational(*i, q),
        "{what}: exact {q} not in the interval {i:?}"
    );
    if let Some(f) = f {
        assert!(
            f.is_finite() && i.contains(*f),
            "{what}: f64 {f:e} not in the interval {i:?} (exact {q})"
        );
    }
}

fn agree_vec(
    q: &Result<DVector<BigRational>, OracleError>,
    i: &Result<DVector<Interval>, OracleError>,
    f: &Result<DVector<f64>, OracleError>,
    what: &str,
) {
    same_structure(q, i, what);
    same_structure(q, f, what);
    if let (Ok(q), Ok(i)) = (q, i) {
        assert_eq!(q.len(), i.len());
        for k in 0..q.len() {
            let fk = f.as_ref().ok().map(|f| &f[k]);
            agree(&q[k], &i[k], fk, &format!("{what}[{k}]"));
        }
    }
}

/// Target `differential`: the same oracle input in `f64`, [`Interval`] and [`BigRational`]. Where
/// the exact and the interval computation both succeed, the exact value lies in the enclosure and
/// so does the `f64` value (when it succeeds too); errors caused by the input's shape are the same
/// in every arithmetic; an interval roll-out that succeeds is the exact roll-out.
pub fn check_differential(input: &OracleInput) {
    let Some(mdp) = input.parse() else { return };
    let (th, th_new) = input.thetas(&mdp);
    let traj = input.traj.build(mdp.states, mdp.actions, mdp.horizon);
    let (seed, w) = (input.seed, input.expert_weight);
    let f = run_oracle::<f64>(&mdp, &th, &th_new, &traj, seed, w);
    let i = run_oracle::<Interval>(&mdp, &th, &th_new, &traj, seed, w);
    let q = run_oracle::<BigRational>(&mdp, &th, &th_new, &traj, seed, w);
    check_oracle_outputs(&mdp, &f);
    check_oracle_outputs(&mdp, &q);
    for k in 0..2 {
        agree_vec(
            &q.estimates[k],
            &i.estimates[k],
            &f.estimates[k],
            &format!("estimate {k}"),
        );
        agree_vec(
            &q.weighted[k],
            &i.weighted[k],
            &f.weighted[k],
            &format!("weighted {k}"),
        );
    }
    same_structure(&q.loss, &i.loss, "loss");
    same_structure(&q.loss, &f.loss, "loss");
    if let (Ok(ql), Ok(il)) = (&q.loss, &i.loss) {
        agree(ql, il, f.loss.as_ref().ok(), "trajectory_loss");
    }
    for (k, ((qs, is), fs)) in q
        .supervised
        .iter()
        .zip(&i.supervised)
        .zip(&f.supervised)
        .enumerate()
    {
        same_structure(qs, is, "supervised");
        same_structure(qs, fs, "supervised");
        if let (Ok((ql, qg)), Ok((il, ig))) = (qs, is) {
            let fv = fs.as_ref().ok();
            agree(ql, il, fv.map(|x| &x.0), &format!("supervised {k} loss"));
            agree_vec(
                &Ok(qg.clone()),
                &Ok(ig.clone()),
                &fv.map(|x| x.1.clone()).ok_or(OracleError::NonFinite("f64")),
                &format!("supervised {k} gradient"),
            );
        }
    }
    for k in 0..3 {
        same_structure(&q.rollouts[k], &i.rollouts[k], "rollout");
        same_structure(&q.rollouts[k], &f.rollouts[k], "rollout");
        if let (Ok(qt), Ok(it)) = (&q.rollouts[k], &i.rollouts[k]) {
            assert_eq!(qt, it, "rollout {k}: the interval run decided differently");
        }
    }
}
