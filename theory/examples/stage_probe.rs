//! Run one stage of the theorem table alone, for profiling and before/after comparisons.
use ilopt::scalar::BigRational;
use ilopt_theory::certify::box_constants::{compute, tied_softmax_g_inf_closed_form};
use ilopt_theory::checks::baselined_storm::choose;
use ilopt_theory::checks::constants::toy_row;
use ilopt_theory::checks::{second_toy, statistical};
use ilopt_theory::input_rows::{Certified, with_perturbations};
use ilopt_theory::protocol::m1_tied;
use ilopt_theory::protocol::{FAMILY_ALPHA, Profile, STATISTICAL_CLAIMS};
use ilopt_theory::report::markdown;
use ilopt_theory::stats::bonferroni;
use ilopt_theory::suite::{global_constants, global_sizes};

/// This process's user CPU seconds so far (Linux: `/proc/self/stat`, clock ticks of 1/100 s).
fn user_cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |x| x.1);
    let ticks: f64 = after
        .split_whitespace()
        .nth(11)
        .and_then(|x| x.parse().ok())
        .unwrap_or(f64::NAN);
    ticks / 100.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("second-sgd");
    let n: usize = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(100);
    match which {
        "second-sgd" => {
            let mut s = second_toy::sizes(true).sgd;
            s.runs = n;
            let m2 = second_toy::m2_two_groups();
            let out = second_toy::sgd_sample(&m2, &second_toy::domain(), &[0.0, 0.0], s).unwrap();
            println!("{out:?}");
        }
        "second-consts" => {
            let s = second_toy::sizes(true);
            let m2 = second_toy::m2_two_groups();
            let dom = second_toy::domain();
            let zero = BigRational::from_integer(0.into());
            let k = compute(&m2, &[zero.clone(), zero], None, &dom, s.tol, s.max_boxes).unwrap();
            println!("{}", markdown(&[toy_row(&k, "x", &dom, s.coverage, "8c")]));
        }
        "second-parts" => {
            use ilopt_theory::certify::box_constants as bc;
            let s = second_toy::sizes(true);
            let m2 = second_toy::m2_two_groups();
            let dom = second_toy::domain();
            let one = BigRational::from_integer(1.into());
            let zero = BigRational::from_integer(0.into());
            let t = std::time::Instant::now();
            let lap = |what: &str| eprintln!("{what}: {:.1} s", t.elapsed().as_secs_f64());
            let k = bc::ToyConstants {
                b_f: bc::b_f(&m2, &[zero.clone(), zero.clone()], None).unwrap(),
                l_f: {
                    let c = bc::l_f(&m2, &dom, s.tol, s.max_boxes).unwrap();
                    lap("l_f");
                    c
                },
                sigma2: {
                    let c = bc::sigma2(&m2, &one, &dom, s.tol, s.max_boxes).unwrap();
                    lap("sigma2");
                    c
                },
                g2: {
                    let c = bc::sigma2(&m2, &zero, &dom, s.tol, s.max_boxes).unwrap();
                    lap("g2");
                    c
                },
                g_f: {
                    let c = bc::gradient_norm(&m2, &dom, s.tol, s.max_boxes).unwrap();
                    lap("g_f");
                    c
                },
                g_inf: {
                    let c = bc::estimator_bound(&m2, &dom, s.tol, s.max_boxes).unwrap();
                    lap("g_inf");
                    c
                },
                mdp: m2.clone(),
            };
            for c in k.all() {
                eprintln!(
                    "{} {} boxes {:?}",
                    c.name,
                    c.value,
                    c.certificate.as_ref().map(|x| x.certificate.len())
                );
            }
            for (name, r) in k.recheck(&dom, s.coverage) {
                lap(&format!("recheck {name} passed {}", r.passed()));
            }
        }
        "second-recheck" => {
            // The second toy's constants and their re-check at the full tolerance and coverage
            // with a box budget of n per constant.
            let s = second_toy::sizes(true);
            let m2 = second_toy::m2_two_groups();
            let dom = second_toy::domain();
            let zero = BigRational::from_integer(0.into());
            let k = compute(&m2, &[zero.clone(), zero], None, &dom, s.tol, n).unwrap();
            let u = user_cpu();
            for (name, r) in k.recheck(&dom, s.coverage) {
                println!("{name}: {r:?}");
            }
            eprintln!("recheck user CPU: {:.2} s", user_cpu() - u);
            println!("{}", markdown(&[toy_row(&k, "x", &dom, s.coverage, "8c")]));
        }
        "second" => {
            let rows = second_toy::rows(second_toy::sizes(true)).unwrap();
            println!("{}", markdown(&rows));
        }
        "schedule" => {
            // Rows 2a and 2b (schedule 3.43, erratum E7) up to k = n.
            let u = user_cpu();
            let rows = ilopt_theory::checks::schedule::rows(n as u64);
            eprintln!("schedule rows user CPU: {:.2} s", user_cpu() - u);
            println!("{}", markdown(&rows));
        }
        "global" => {
            let m1 = m1_tied();
            let g = global_constants(&m1, Profile::Full.sizes()).unwrap();
            println!("{g:?}");
        }
        "global-quick" => {
            // The "global constants" stage of the quick profile.
            let m1 = m1_tied();
            let u = user_cpu();
            let g = global_constants(&m1, Profile::Quick.sizes()).unwrap();
            eprintln!("global constants user CPU: {:.2} s", user_cpu() - u);
            println!("{g:?}");
        }
        "choose-2b" => {
            // The "rows 2.b (constants)" stage of the quick profile.
            let m1 = m1_tied();
            let u = user_cpu();
            let c = choose(&m1, global_sizes(Profile::Quick.sizes())).unwrap();
            eprintln!("rows 2.b constants user CPU: {:.2} s", user_cpu() - u);
            println!("{:?} {:?}", c.grid, c.b_star);
            println!("{:?} {:?}", c.constants.sigma2, c.constants.l_tilde);
        }
        "storm" => {
            let m1 = m1_tied();
            let mut s = Profile::Full.sizes();
            let g = global_constants(&m1, Profile::Quick.sizes()).unwrap();
            s.storm_runs = n;
            let alpha = bonferroni(FAMILY_ALPHA, STATISTICAL_CLAIMS);
            let u = user_cpu();
            let rows = statistical::storm_rows(&m1, &g, s, alpha);
            eprintln!("storm rows user CPU: {:.2} s", user_cpu() - u);
            println!("{}", markdown(&rows));
        }
        "inputs" => {
            // The "input-reading rows and their perturbations" stage of the quick profile.
            let m1 = m1_tied();
            let s = Profile::Quick.sizes();
            let r = 1000.0 * 0.05 * tied_softmax_g_inf_closed_form(3, 0.5);
            let domain = vec![[-r, r]];
            let zero = BigRational::from_integer(0.into());
            let f_inf = BigRational::new(7.into(), 8.into());
            let k = compute(
                &m1,
                std::slice::from_ref(&zero),
                Some(&f_inf),
                &domain,
                s.bnb_tol,
                200_000,
            )
            .unwrap();
            let g = global_constants(&m1, s).unwrap();
            let certified = Certified {
                profile: Profile::Quick,
                m1,
                theta1: vec![zero],
                f_inf,
                k,
                g,
                domain,
            };
            let u = user_cpu();
            let t = std::time::Instant::now();
            let rows = with_perturbations(&certified).unwrap();
            eprintln!(
                "input-reading rows and their perturbations: {:.1} s wall, {:.2} s user CPU",
                t.elapsed().as_secs_f64(),
                user_cpu() - u
            );
            println!("{}", markdown(&rows));
        }
        _ => panic!("unknown"),
    }
}
