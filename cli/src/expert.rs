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
//! and its objective, from [`ilopt::expert::vo::vo_expert`] (double cone, `v = 0` feasible) — or
//! `{"error":"line N: …"}` when the case has no solution (e.g. `line 3: inside the obstacle: …`)
//! or line `N` (1-based, counting every line of the input) is malformed: bad JSON or UTF-8 (with
//! the column), a missing or unknown field, or a field of the wrong shape, named (`field v_des:
//! expected 2 numbers, got 3`). A bad case never stops the batch; the command then exits with
//! status 1 after writing every line, and says on stderr how many cases failed.
//!
//! `--cases -` reads the cases from standard input.
//!
//! # Errors
//! An unreadable input or a failed write is an [`ExpertCliError`] (the command fails).

use ilopt::expert::vo::vo_expert;
use serde::Serialize;
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
    /// JSON-lines file of cases {"r","v_o","v_r","v_des","lam","R"}; `-` reads standard input.
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
#[derive(Debug, Clone)]
struct Case {
    r: [f64; 2],
    v_o: [f64; 2],
    v_r: [f64; 2],
    v_des: [f64; 2],
    lam: f64,
    big_r: f64,
}

/// The fields of a case, in the order of the format.
const FIELDS: [&str; 6] = ["r", "v_o", "v_r", "v_des", "lam", "R"];

/// A JSON error's message without serde's own "at line 1 column C" (the input line is one JSON
/// document, so only the column is news), with the column.
fn json_error(e: &serde_json::Error) -> String {
    let text = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let msg = text.strip_suffix(&suffix).unwrap_or(&text);
    format!("column {}: {msg}", e.column())
}

/// Check a parsed line field by field, naming the first field that is missing, unknown or of
/// the wrong shape.
fn case_of(v: &serde_json::Value) -> Result<Case, String> {
    let obj = v.as_object().ok_or_else(|| {
        "expected a JSON object {\"r\", \"v_o\", \"v_r\", \"v_des\", \"lam\", \"R\"}".to_string()
    })?;
    if let Some(k) = obj.keys().find(|k| !FIELDS.contains(&k.as_str())) {
        return Err(format!(
            "unknown field `{k}` (expected r, v_o, v_r, v_des, lam, R)"
        ));
    }
    let get = |k: &str| obj.get(k).ok_or_else(|| format!("missing field `{k}`"));
    let vector = |k: &str| -> Result<[f64; 2], String> {
        let a = get(k)?
            .as_array()
            .ok_or_else(|| format!("field `{k}`: expected a vector of 2 numbers"))?;
        if a.len() != 2 {
            return Err(format!("field `{k}`: expected 2 numbers, got {}", a.len()));
        }
        let x = |i: usize| {
            a[i].as_f64()
                .ok_or_else(|| format!("field `{k}`[{i}]: expected a number, got {}", a[i]))
        };
        Ok([x(0)?, x(1)?])
    };
    let number = |k: &str| -> Result<f64, String> {
        let v = get(k)?;
        v.as_f64()
            .ok_or_else(|| format!("field `{k}`: expected a number, got {v}"))
    };
    Ok(Case {
        r: vector("r")?,
        v_o: vector("v_o")?,
        v_r: vector("v_r")?,
        v_des: vector("v_des")?,
        lam: number("lam")?,
        big_r: number("R")?,
    })
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
    let out = serde_json::from_slice::<serde_json::Value>(line)
        .map_err(|e| json_error(&e))
        .and_then(|v| case_of(&v))
        .map_err(|e| format!("line {number}: malformed case: {e}"))
        .and_then(|c| {
            vo_expert(c.r, c.v_o, c.v_r, c.v_des, c.lam, c.big_r)
                .map(|s| Solved { u: s.u, j: s.j })
                .map_err(|e| format!("line {number}: {e}"))
        });
    Some(out)
}

/// What a batch did: cases solved and cases that failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Summary {
    /// Cases with a solution.
    pub solved: usize,
    /// Cases with an error line.
    pub failed: usize,
}

/// Runs `ilopt expert vo`: reads the cases (a file, or standard input for `-`) and writes one
/// JSON line per case to `out` (module docs for the format).
///
/// # Errors
/// [`ExpertCliError::Read`] if the input cannot be read, [`ExpertCliError::Write`] if `out` fails.
pub fn run(args: &ExpertVoArgs, out: &mut impl Write) -> Result<Summary, ExpertCliError> {
    let read_error = |source| ExpertCliError::Read {
        path: args.cases.clone(),
        source,
    };
    let bytes = if args.cases.as_os_str() == "-" {
        let mut b = Vec::new();
        std::io::Read::read_to_end(&mut std::io::stdin().lock(), &mut b).map_err(read_error)?;
        b
    } else {
        std::fs::read(&args.cases).map_err(read_error)?
    };
    let mut summary = Summary::default();
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let json = match solve_line(i + 1, line) {
            None => continue,
            Some(Ok(s)) => {
                summary.solved += 1;
                serde_json::to_string(&s)
            }
            Some(Err(error)) => {
                summary.failed += 1;
                serde_json::to_string(&Failed { error })
            }
        }
        .map_err(std::io::Error::other)?;
        writeln!(out, "{json}")?;
    }
    out.flush()?;
    Ok(summary)
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
        let summary = run(
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
        let failed = lines.iter().filter(|l| l.get("error").is_some()).count();
        assert_eq!(summary.failed, failed);
        assert_eq!(summary.solved, lines.len() - failed);
        lines
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
        assert_eq!(
            run_on(r#"{"r":[1,0],"v_o":[0,0],"v_r":[0,0],"v_des":["a",0],"lam":0,"R":0.5}"#)[0]["error"],
            "line 1: malformed case: field `v_des`[0]: expected a number, got \"a\""
        );
        let u = out[0]["u"].as_array().unwrap();
        approx::assert_abs_diff_eq!(u[0].as_f64().unwrap(), 0.75, epsilon = 1e-15);
        approx::assert_abs_diff_eq!(u[1].as_f64().unwrap(), 3f64.sqrt() / 4.0, epsilon = 1e-15);
        approx::assert_abs_diff_eq!(out[0]["J"].as_f64().unwrap(), 0.25, epsilon = 1e-15);
        let err = |k: usize| out[k]["error"].as_str().unwrap().to_owned();
        assert!(
            err(1).starts_with("line 2: inside the obstacle"),
            "{}",
            err(1)
        );
        assert_eq!(
            err(2),
            "line 4: malformed case: field `v_des`: expected 2 numbers, got 3"
        );
        assert_eq!(err(3), "line 5: malformed case: missing field `R`");
        // One line number: serde's "at line 1 column 2" is replaced by the column alone.
        assert!(
            err(4).starts_with("line 6: malformed case: column 2: ") && !err(4).contains("line 1"),
            "{}",
            err(4)
        );
        assert!(
            err(5).starts_with("line 7: malformed case: unknown field `x`"),
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
