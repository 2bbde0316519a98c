//! `ilopt expert vo`: the command's JSON lines against the library's answers.

use ilopt::expert::vo::vo_expert;
use ilopt::problem::KitRng;
use ilopt_cli::expert::{ExpertVoArgs, run};
use rand::SeedableRng;

#[path = "../../../tests/common/vo_cases.rs"]
mod vo_cases;
use vo_cases::{Case, random_case};

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
