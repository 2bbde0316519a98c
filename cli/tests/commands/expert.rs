//! `ilopt expert vo`: the command's JSON lines against the library's answers.

use ilopt::expert::vo::vo_expert;
use ilopt::problem::KitRng;
use ilopt_cli::expert::{ExpertVoArgs, run};
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

/// One velocity-obstacle problem of eq. 4.1.
#[derive(Debug, Clone, Copy)]
struct Case {
    r: [f64; 2],
    v_o: [f64; 2],
    v_r: [f64; 2],
    v_des: [f64; 2],
    lam: f64,
    big_r: f64,
}

/// A random case as `tests/environments/vo_expert.rs` draws them: outside the obstacle, sometimes
/// very close to it, a quarter aimed at it (active constraint).
fn random_case(rng: &mut KitRng) -> Case {
    let big_r = rng.random_range(0.05..1.0);
    // Mostly moderate distances, sometimes very close to the obstacle (half-angle α near 90°).
    let ratio = if rng.random_bool(0.1) {
        1.0 + rng.random_range(1e-9..1e-3)
    } else {
        rng.random_range(1.0001..5.0)
    };
    let th = rng.random_range(0.0..2.0 * PI);
    let r = [big_r * ratio * th.cos(), big_r * ratio * th.sin()];
    let mut vec = |s: f64| [rng.random_range(-s..s), rng.random_range(-s..s)];
    let v_o = vec(0.5);
    let v_r = vec(1.0);
    let mut v_des = vec(1.0);
    let lam = if rng.random_bool(0.2) {
        0.0
    } else {
        rng.random_range(0.0..3.0)
    };
    // A quarter of the cases aim the unconstrained minimiser at the obstacle (active constraint).
    if rng.random_bool(0.25) {
        let s = rng.random_range(0.1..2.0);
        // x₀ = v_o + s r̂ + noise  ⇒  v_des = (1+λ)x₀ − λ v_r.
        let x0 = [
            v_o[0] + s * th.cos() + rng.random_range(-0.05..0.05),
            v_o[1] + s * th.sin() + rng.random_range(-0.05..0.05),
        ];
        v_des = [
            (1.0 + lam) * x0[0] - lam * v_r[0],
            (1.0 + lam) * x0[1] - lam * v_r[1],
        ];
    }
    Case {
        r,
        v_o,
        v_r,
        v_des,
        lam,
        big_r,
    }
}

/// `ilopt expert vo --cases FILE` round trip: random cases written as JSON lines come back, in
/// order, as the library's answers bit for bit (serde_json prints shortest round-trip floats).
#[test]
fn cli_round_trip_matches_the_library() {
    let mut rng = KitRng::seed_from_u64(71);
    let cases: Vec<Case> = (0..500).map(|_| random_case(&mut rng)).collect();
    let mut text = String::new();
    for c in &cases {
        text.push_str(
            &serde_json::json!({"r": c.r, "v_o": c.v_o, "v_r": c.v_r, "v_des": c.v_des, "lam": c.lam, "R": c.big_r})
                .to_string(),
        );
        text.push('\n');
    }
    // One case inside the obstacle, at line 501.
    text.push_str(r#"{"r":[0,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":1}"#);
    let path = std::env::temp_dir().join(format!("ilopt-vo-cli-{}.jsonl", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let mut out = Vec::new();
    run(
        &ExpertVoArgs {
            cases: path.clone(),
        },
        &mut out,
    )
    .unwrap();
    std::fs::remove_file(&path).unwrap();
    let lines: Vec<serde_json::Value> = String::from_utf8(out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), cases.len() + 1);
    for (k, (c, l)) in cases.iter().zip(&lines).enumerate() {
        let s = vo_expert(c.r, c.v_o, c.v_r, c.v_des, c.lam, c.big_r).unwrap();
        let u: [f64; 2] = serde_json::from_value(l["u"].clone()).unwrap();
        let j: f64 = serde_json::from_value(l["J"].clone()).unwrap();
        assert_eq!((u, j), (s.u, s.j), "line {}", k + 1);
    }
    let last = lines[cases.len()]["error"].as_str().unwrap();
    assert!(last.starts_with("line 501: inside the obstacle"), "{last}");
}
