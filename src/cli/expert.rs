//! `ilopt expert vo --cases FILE`: solve eq. 4.1 (the velocity-obstacle expert, thesis §4.1.2) for a
//! batch of cases.
//!
//! # Input
//! `FILE` is JSON lines; each non-blank line is one case
//! `{"r":[x,y],"v_o":[x,y],"v_r":[x,y],"v_des":[x,y],"lam":L,"R":R}` (all six fields required,
//! vectors of exactly two numbers, no other fields). Whitespace-only lines are skipped and produce
//! no output (so a trailing newline is harmless); a trailing `\r` is ignored.
//!
//! # Output
//! One JSON line per case, in input order: `{"u":[x,y],"J":J}` — the global minimiser of eq. 4.1
//! and its objective, from [`crate::expert::vo::vo_expert`] (double cone, `v = 0` feasible) — or
//! `{"error":"line N: …"}` when the case has no solution (e.g. `line 3: inside the obstacle: …`)
//! or line `N` (1-based, counting every line of the file) is malformed (bad JSON or UTF-8, a
//! missing or unknown field, a vector of the wrong length). A bad case never stops the batch.
//!
//! # Errors
//! An unreadable file or a failed write is an [`ExpertCliError`] (the command fails).

use crate::expert::vo::vo_expert;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::PathBuf;
use thiserror::Error;

/// Arguments of `ilopt expert vo`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Parser)]
#[command(
    name = "vo",
    about = "Solve the velocity-obstacle expert QP of eq. 4.1 for a batch of cases"
)]
pub struct ExpertVoArgs {
    /// JSON-lines file of cases {"r","v_o","v_r","v_des","lam","R"}.
    #[arg(long, value_name = "FILE")]
    pub cases: PathBuf,
}

/// Errors of `ilopt expert vo` that stop the command (a bad case does not: it is an output line).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ExpertCliError {
    /// The cases file cannot be read.
    #[error("cannot read cases file {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Writing the output failed.
    #[error("cannot write output: {0}")]
    Write(#[from] std::io::Error),
}

/// One case of the input.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    r: [f64; 2],
    v_o: [f64; 2],
    v_r: [f64; 2],
    v_des: [f64; 2],
    lam: f64,
    #[serde(rename = "R")]
    big_r: f64,
}

#[derive(Serialize)]
struct Solved {
    u: [f64; 2],
    #[serde(rename = "J")]
    j: f64,
}

#[derive(Serialize)]
struct Failed {
    error: String,
}

/// The output line for one input line (`None` for a blank line).
fn solve_line(number: usize, line: &[u8]) -> Option<Result<Solved, String>> {
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    if line.iter().all(u8::is_ascii_whitespace) {
        return None;
    }
    let out = match serde_json::from_slice::<Case>(line) {
        Err(e) => Err(format!("line {number}: malformed case: {e}")),
        Ok(c) => vo_expert(c.r, c.v_o, c.v_r, c.v_des, c.lam, c.big_r)
            .map(|s| Solved { u: s.u, j: s.j })
            .map_err(|e| format!("line {number}: {e}")),
    };
    Some(out)
}

/// Runs `ilopt expert vo`: reads the cases file and writes one JSON line per case to `out`
/// (module docs for the format).
///
/// # Errors
/// [`ExpertCliError::Read`] if the file cannot be read, [`ExpertCliError::Write`] if `out` fails.
pub fn run(args: &ExpertVoArgs, out: &mut impl Write) -> Result<(), ExpertCliError> {
    let bytes = std::fs::read(&args.cases).map_err(|source| ExpertCliError::Read {
        path: args.cases.clone(),
        source,
    })?;
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let json = match solve_line(i + 1, line) {
            None => continue,
            Some(Ok(s)) => serde_json::to_string(&s),
            Some(Err(error)) => serde_json::to_string(&Failed { error }),
        }
        .map_err(std::io::Error::other)?;
        writeln!(out, "{json}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[test]
    fn parses_cases_flag() {
        let a = ExpertVoArgs::try_parse_from(["vo", "--cases", "x.jsonl"]).unwrap();
        assert_eq!(a.cases, PathBuf::from("x.jsonl"));
        assert!(ExpertVoArgs::try_parse_from(["vo"]).is_err());
        assert!(ExpertVoArgs::try_parse_from(["vo", "x.jsonl"]).is_err());
        assert!(ExpertVoArgs::try_parse_from(["vo", "--cases"]).is_err());
    }

    fn run_on(content: &str) -> Vec<serde_json::Value> {
        let dir = std::env::temp_dir().join(format!(
            "ilopt-expert-cli-{}-{}",
            std::process::id(),
            content.len()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!(
            "{:x}.jsonl",
            content.bytes().map(u64::from).sum::<u64>()
        ));
        std::fs::write(&path, content).unwrap();
        let mut out = Vec::new();
        run(
            &ExpertVoArgs {
                cases: path.clone(),
            },
            &mut out,
        )
        .unwrap();
        std::fs::remove_file(&path).unwrap();
        String::from_utf8(out)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    }

    #[test]
    fn solves_and_reports_errors_in_order() {
        let content = concat!(
            // Dead ahead (hand-computed in vo.rs): J = 1/4, u = (3/4, √3/4).
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":0.5}"#,
            "\n",
            r#"{"r":[0.1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":0.5}"#,
            "\n\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0,2],"lam":0,"R":0.5}"#,
            "\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0}"#,
            "\r\n",
            "not json\n",
            r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":0,"R":0.5,"x":1}"#,
            "\n",
            r#"{"r":[0,3],"v_o":[0,0],"v_r":[0,0],"v_des":[1,0],"lam":-1,"R":1}"#,
            "\n",
        );
        let out = run_on(content);
        assert_eq!(out.len(), 7, "{out:?}");
        let u = out[0]["u"].as_array().unwrap();
        assert!((u[0].as_f64().unwrap() - 0.75).abs() < 1e-15);
        assert!((u[1].as_f64().unwrap() - 3f64.sqrt() / 4.0).abs() < 1e-15);
        assert!((out[0]["J"].as_f64().unwrap() - 0.25).abs() < 1e-15);
        let err = |k: usize| out[k]["error"].as_str().unwrap().to_owned();
        assert!(
            err(1).starts_with("line 2: inside the obstacle"),
            "{}",
            err(1)
        );
        assert!(err(2).starts_with("line 4: malformed"), "{}", err(2));
        assert!(
            err(3).starts_with("line 5: malformed") && err(3).contains("R"),
            "{}",
            err(3)
        );
        assert!(err(4).starts_with("line 6: malformed"), "{}", err(4));
        assert!(
            err(5).starts_with("line 7: malformed") && err(5).contains('x'),
            "{}",
            err(5)
        );
        assert!(err(6).starts_with("line 8: λ must be ≥ 0"), "{}", err(6));
    }

    #[test]
    fn unreadable_file_is_an_error() {
        let args = ExpertVoArgs {
            cases: PathBuf::from("/nonexistent/ilopt/cases.jsonl"),
        };
        assert!(matches!(
            run(&args, &mut Vec::new()),
            Err(ExpertCliError::Read { .. })
        ));
    }
}
