//! Prints the numbers of math.md §10: STORM's mean linearisation exactly on toy MDPs and measured
//! on the two tasks of the quick profile, at θ = 0 and at a DAgger solution.
//!
//! `cargo run --release -p paper-checks --example storm_stability -- [toy] [obstacle] [cartpole]
//! [--trajectories N] [--batches B]` (default: all three parts, N = 256, B = 8).

use ilopt::algo::storm_stability::{eigenvalues, mean_radius, second_moment_radius, threshold};
use ilopt::exact::storm_jacobian::{Matrix, hessian, unweighted, weighted};
use ilopt::problem::Weighting;
use ilopt::scalar::{BigRational, Scalar, parse_exact};
use ilopt::toy::{ToyMdp, ToyProblem};
use nalgebra::{Complex, DMatrix, DVector};
use paper_checks::config::{Profile, committed_text};
use paper_checks::experiment::TaskKind;
use paper_checks::storm_stability::{
    Measurement, Options, Spectrum, Stat, bench_of, dagger_solution, measure_bench,
};
use std::path::Path;

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let mut parts = Vec::new();
    let mut opts = Options::default();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut number = |name: &str| -> Result<usize, String> {
            args.next()
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| format!("{name} needs a positive integer"))
        };
        match a.as_str() {
            "--trajectories" => opts.trajectories = number("--trajectories")?,
            "--batches" => opts.batches = number("--batches")?,
            "toy" | "obstacle" | "cartpole" => parts.push(a),
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    if parts.is_empty() {
        parts = vec!["toy".into(), "obstacle".into(), "cartpole".into()];
    }
    for part in &parts {
        match part.as_str() {
            "toy" => toy()?,
            "obstacle" => task(TaskKind::Obstacle, &opts)?,
            _ => task(TaskKind::Cartpole, &opts)?,
        }
    }
    Ok(())
}

fn f64s(m: &Matrix<BigRational>) -> DMatrix<f64> {
    let d = m.len();
    DMatrix::from_fn(m.first().map_or(0, Vec::len), d, |i, j| m[i][j].to_f64())
}

fn show(m: &Matrix<BigRational>) -> String {
    let rows: Vec<String> = m
        .iter()
        .map(|r| {
            r.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect();
    format!("[{}]", rows.join("; "))
}

fn eig_list(l: &[Complex<f64>]) -> String {
    let v: Vec<String> = l
        .iter()
        .map(|z| {
            if z.im == 0.0 {
                format!("{:.4}", z.re)
            } else {
                format!("{:.4}{:+.4}i", z.re, z.im)
            }
        })
        .collect();
    v.join(", ")
}

/// The exact part: E[J], C, ∇²F on three toy MDPs, the thresholds and radii from them.
fn toy() -> Result<(), String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/toy");
    let cases: [(&str, &[&[&str]]); 3] = [
        ("m1-tied.json", &[&["-1"], &["0"], &["1/2"], &["2"]]),
        ("m2-tied-two-groups.json", &[&["0", "0"], &["1/2", "-1"]]),
        (
            "three-state.json",
            &[&["1/2", "-1", "1", "1/3", "-1/2", "2"]],
        ),
    ];
    println!("# Exact (toy MDPs, rationals; eigenvalues in f64 from the exact matrices)\n");
    for (file, thetas) in cases {
        let mdp = ToyMdp::load(&dir.join(file)).map_err(|e| e.to_string())?;
        let p = ToyProblem::<BigRational>::new(&mdp);
        for xs in thetas {
            let th: Vec<BigRational> = xs
                .iter()
                .map(|x| parse_exact(x).map_err(|e| e.to_string()))
                .collect::<Result<_, _>>()?;
            let u = unweighted(&p, &th).map_err(|e| e.to_string())?;
            let h = hessian(&p, &th).map_err(|e| e.to_string())?;
            let w = weighted(&p, &th, Weighting::PerDecision).map_err(|e| e.to_string())?;
            let (ju, jh) = (f64s(&u.mean_jacobian), f64s(&h));
            let (lu, lh) = (
                eigenvalues(&ju).map_err(|e| e.to_string())?,
                eigenvalues(&jh).map_err(|e| e.to_string())?,
            );
            println!("## {file} at θ = {xs:?}");
            if th.len() <= 2 {
                println!("E[J] = {}", show(&u.mean_jacobian));
                println!("C = {}", show(&u.covariance));
                println!("∇²F = {}", show(&h));
            }
            println!(
                "E[J] + C == ∇²F: {}; E[J̃] (per-decision) == ∇²F: {}",
                sum(&u.mean_jacobian, &u.covariance) == h,
                w == h
            );
            println!("eig E[J] = {}; eig ∇²F = {}", eig_list(&lu), eig_list(&lh));
            let kron = f64s(&u.second_moment);
            for a in [0.1, 0.5, 0.9] {
                let (tu, th_) = (
                    threshold(&lu, a).map_err(|e| e.to_string())?,
                    threshold(&lh, a).map_err(|e| e.to_string())?,
                );
                let mut line = format!("a = {a}: η*(E[J]) = {tu:.4}, η*(∇²F) = {th_:.4};");
                for eta in [0.1, 0.5, 1.0, 2.0] {
                    let r = |l: &[Complex<f64>]| mean_radius(l, eta, a).unwrap_or(f64::NAN);
                    let r2 = second_moment_radius(&ju, &kron, eta, a).unwrap_or(f64::NAN);
                    line += &format!(
                        " η = {eta}: ρ_u = {:.4}, ρ_IS = {:.4}, ρ₂_u = {:.4};",
                        r(&lu),
                        r(&lh),
                        r2
                    );
                }
                println!("{line}");
            }
            println!();
        }
    }
    Ok(())
}

fn sum(a: &Matrix<BigRational>, b: &Matrix<BigRational>) -> Matrix<BigRational> {
    a.iter()
        .zip(b)
        .map(|(r, s)| r.iter().zip(s).map(|(x, y)| x.clone() + y).collect())
        .collect()
}

fn stat(s: Stat) -> String {
    format!("{:.4e} ± {:.1e}", s.value, s.stderr)
}

fn spectrum(name: &str, s: &Spectrum, m: &Measurement) {
    println!(
        "{name}: Re λ ∈ [{}, {}], max |Im λ| = {}; sym part λ ∈ [{}, {}]; ‖A−Aᵀ‖/‖A+Aᵀ‖ = {}",
        stat(s.min_re),
        stat(s.max_re),
        stat(s.max_im),
        stat(s.sym_min),
        stat(s.sym_max),
        stat(s.asymmetry)
    );
    for (i, a) in m.options.momenta.iter().enumerate() {
        let mut line = format!("  a = {a}: η* = {}; ρ:", stat(s.thresholds[i]));
        for (j, eta) in m.options.etas.iter().enumerate() {
            line += &format!(" {eta:.0e}→{:.3}", s.radii[i][j].value);
        }
        println!("{line}");
    }
}

fn task(kind: TaskKind, opts: &Options) -> Result<(), String> {
    let text = committed_text("quick").ok_or("no quick profile")?;
    let profile = Profile::from_toml(text, Path::new("quick")).map_err(|e| e.to_string())?;
    let bench = bench_of(&profile, kind).map_err(|e| e.to_string())?;
    println!(
        "# {} (quick profile, objective {}, d = {}, N = {}, B = {}, IS weighting {:?})\n",
        kind.name(),
        bench
            .horizon()
            .map_or_else(|| "of the MDP's file".into(), |h| h.label()),
        bench.dim(),
        opts.trajectories,
        opts.batches,
        opts.weighting
    );
    let start = std::time::Instant::now();
    let (dagger, iterations) =
        dagger_solution(&profile, kind, &bench, 1).map_err(|e| e.to_string())?;
    println!(
        "DAgger: {iterations} iterations to the budget ({:.0} s), ‖θ‖ = {:.4}\n",
        start.elapsed().as_secs_f64(),
        dagger.norm()
    );
    for (name, theta) in [("θ = 0", DVector::zeros(bench.dim())), ("DAgger θ", dagger)] {
        let m = measure_bench(&bench, &theta, opts).map_err(|e| e.to_string())?;
        println!("## {name} ({:.0} s)", m.seconds);
        println!("‖E[J̃] − E[J]‖/‖E[J̃]‖ = {}", stat(m.covariance_share));
        spectrum("E[J] (unweighted)", &m.unweighted, &m);
        spectrum("E[J̃] (IS, ≈ ∇²F)", &m.weighted, &m);
        for (name, x) in [
            ("unweighted J_τ", &m.unweighted_direction),
            ("weighted J̃_τ", &m.weighted_direction),
        ] {
            let th: Vec<String> = m
                .options
                .momenta
                .iter()
                .zip(&x.thresholds)
                .map(|(a, t)| format!("a = {a}: {}", stat(*t)))
                .collect();
            println!(
                "second moment along v ({name}): vᵀE[·]v = {}, E‖·v‖² = {}; one-step growth of E‖d‖² for η above {}",
                stat(x.rayleigh),
                stat(x.mean_square),
                th.join(", ")
            );
        }
        println!();
    }
    Ok(())
}
