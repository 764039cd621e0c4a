//! The throughput target's case timed the quiet way: the paper case (crank_ground,
//! 300 rpm, 9 balls, waviness 35 / 4 µm on both races, damping 300 N s/m, 0.4 s
//! at 50 kHz, DOP853 at rtol 1e-8) run N times back to back on one thread, with
//! the minimum and the median wall time and the integrator's work.
//!
//! Criterion's median of ten whole cases moves by 10 % on a shared host; the
//! minimum of 30 runs is what the code can do and moves by about 1 %, so this is
//! the figure the README's target table quotes (next to criterion's median).
//!
//! With `--defects` the same case also runs with a flat 1 mm × 20 µm defect at 0 rad
//! on the outer race, the inner race and ball 0 (docs/model.md §2.9), the four
//! scenes interleaved run by run so that a busy host slows them alike, and each
//! defect's minimum is given as a ratio to the defect-free one.
//!
//! Run: `cargo bench --bench case -- [RUNS] [--defects]` (default 30).

use std::hint::black_box;
use std::time::Instant;

use studyrun::bearing::{Defect, DefectProfile, DefectRace, RaceWaviness};
use studyrun::mechanism::{CaseParams, Location};
use studyrun::simulate::{simulate, Sampling};
use studyrun::solve::{Method, SolverSettings};

fn main() {
    let runs: usize = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(|a| a.parse().expect("RUNS must be a positive whole number"))
        .unwrap_or(30)
        .max(1);
    let defects = std::env::args().any(|a| a == "--defects");
    let mut case = CaseParams {
        location: Location::CrankGround,
        ..CaseParams::default()
    };
    case.bearing.inner_waviness = RaceWaviness::single(35, 4e-6);
    case.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    let sampling = Sampling {
        duration: 0.4,
        sample_rate: 50_000.0,
    };
    let settings = SolverSettings::new(Method::DEFAULT);

    let mut scenes = vec![("paper case".to_string(), case.clone())];
    if defects {
        for race in DefectRace::ALL {
            let mut c = case.clone();
            c.bearing.defects = vec![Defect {
                race,
                angle: 0.0,
                width: 1e-3,
                depth: 20e-6,
                profile: DefectProfile::Flat,
            }];
            scenes.push((format!("{race} defect"), c));
        }
    }
    let mut times = vec![Vec::with_capacity(runs); scenes.len()];
    let mut stats = vec![None; scenes.len()];
    for _ in 0..runs {
        for (k, (_, case)) in scenes.iter().enumerate() {
            let start = Instant::now();
            let out = simulate(black_box(case), &settings, &sampling).expect("paper case");
            times[k].push(start.elapsed().as_secs_f64());
            stats[k] = Some(out.stats);
        }
    }
    for t in &mut times {
        t.sort_by(f64::total_cmp);
    }
    let base = times[0][0];
    for (k, ((name, _), stats)) in scenes.iter().zip(stats).enumerate() {
        let stats = stats.expect("at least one run");
        let (min, median) = (times[k][0], times[k][runs / 2]);
        let ratio = if k == 0 {
            String::new()
        } else {
            format!("; {:.2}x the paper case's min", min / base)
        };
        println!(
            "{name} ({runs} runs): min {:.2} ms, median {:.2} ms; {} RHS, {} steps, {} rejected, {} events; {:.0} ns per RHS at the min{ratio}",
            min * 1e3,
            median * 1e3,
            stats.rhs_evals,
            stats.steps,
            stats.rejected,
            stats.events,
            min / stats.rhs_evals as f64 * 1e9
        );
    }
}
