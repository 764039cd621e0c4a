//! The throughput target's case timed the quiet way: the paper case (crank_ground,
//! 300 rpm, 9 balls, waviness 35 / 4 µm on both races, damping 300 N s/m, 0.4 s
//! at 50 kHz, DOP853 at rtol 1e-8) run N times back to back on one thread, with
//! the minimum and the median wall time and the integrator's work.
//!
//! Criterion's median of ten whole cases moves by 10 % on a shared host; the
//! minimum of 30 runs is what the code can do and moves by about 1 %, so this is
//! the figure the README's target table quotes (next to criterion's median).
//!
//! Run: `cargo bench --bench case -- [RUNS]` (default 30).

use std::hint::black_box;
use std::time::Instant;

use studyrun::bearing::RaceWaviness;
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

    let mut times = Vec::with_capacity(runs);
    let mut stats = None;
    for _ in 0..runs {
        let start = Instant::now();
        let out = simulate(black_box(&case), &settings, &sampling).expect("paper case");
        times.push(start.elapsed().as_secs_f64());
        stats = Some(out.stats);
    }
    times.sort_by(f64::total_cmp);
    let stats = stats.expect("at least one run");
    let min = times[0];
    let median = times[runs / 2];
    println!(
        "paper case ({runs} runs): min {:.2} ms, median {:.2} ms; {} RHS, {} steps, {} rejected; {:.0} ns per RHS at the min",
        min * 1e3,
        median * 1e3,
        stats.rhs_evals,
        stats.steps,
        stats.rejected,
        min / stats.rhs_evals as f64 * 1e9
    );
}
