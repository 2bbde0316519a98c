//! Pick a handful of meaningful seeds for a structured target from a (large) working corpus: the
//! smallest input of each behaviour class (valid MDP of each kind and size reaching the
//! arithmetic; each error kind; active/inactive VO constraint; terminating replay; …).
//!
//! `cargo run --example pick_seeds -- TARGET WORK_DIR SEED_DIR` copies at most 16 files.

use arbitrary::{Arbitrary, Unstructured};
use ilopt::expert::vo::vo_expert;
use ilopt::scalar::BigRational;
use ilopt_fuzz::props::{self, CartpoleInput, OracleInput, VoInput};
use std::collections::BTreeMap;

fn class(target: &str, data: &[u8]) -> Option<String> {
    let mut u = Unstructured::new(data);
    match target {
        "oracle" | "differential" => {
            let input = OracleInput::arbitrary(&mut u).ok()?;
            let Some(mdp) = input.parse() else {
                return Some("rejected-mdp".into());
            };
            let (th, th_new) = input.thetas(&mdp);
            let traj = input.traj.build(mdp.states, mdp.actions, mdp.horizon);
            let out = props::run_oracle::<BigRational>(
                &mdp,
                &th,
                &th_new,
                &traj,
                input.seed,
                input.expert_weight,
            );
            let e = match &out.estimates[0] {
                Ok(_) => "ok".to_string(),
                Err(e) => format!("{e:?}").split(['(', ' ', '{']).next()?.to_string(),
            };
            let big = if mdp.states == 3 && mdp.horizon == 4 { "-big" } else { "" };
            Some(format!("{:?}-{e}{big}", mdp.policy.kind))
        }
        "vo_expert" => {
            let i = VoInput::arbitrary(&mut u).ok()?;
            Some(
                match vo_expert(i.r, i.v_o, i.v_r, i.v_des, i.lam, i.big_r) {
                    Ok(s) => format!("ok-active={}", s.active),
                    Err(e) => format!("{e:?}").split(['(', ' ', '{']).next()?.to_string(),
                },
            )
        }
        "cartpole_replay" => {
            let i = CartpoleInput::arbitrary(&mut u).ok()?;
            let finite = i.init.iter().all(|x| x.is_finite());
            let mut state = i.init;
            let mut outcome = "no-steps";
            for &a in &i.actions {
                match ilopt::env::cartpole::cartpole_step(&state, usize::from(a)) {
                    Ok((next, term)) => {
                        state = next;
                        outcome = if term { "terminated" } else { "running" };
                    }
                    Err(_) => {
                        outcome = "error";
                        break;
                    }
                }
            }
            Some(format!(
                "finite={finite}-{outcome}-long={}",
                i.actions.len() >= 16
            ))
        }
        _ => None,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (target, work, seeds) = (&args[1], &args[2], &args[3]);
    let mut files: Vec<_> = std::fs::read_dir(work)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort_by_key(|p| (std::fs::metadata(p).unwrap().len(), p.clone()));
    let mut chosen = BTreeMap::new();
    for p in files {
        let data = std::fs::read(&p).unwrap();
        if let Some(c) = class(target, &data) {
            chosen.entry(c).or_insert(data);
        }
    }
    for (i, (c, data)) in chosen.iter().take(16).enumerate() {
        let name = format!("{seeds}/{i:02}-{}", c.to_lowercase());
        std::fs::write(&name, data).unwrap();
        println!("{name}");
    }
}
