//! How the cost of one case grows with simulated duration and with ball count.
//!
//! Run: `cargo bench --bench scaling`. Prints two tables measured in this one run
//! (best of 3 wall times per row, one thread):
//!
//! - duration 0.1, 0.2, 0.4, 0.8 s of the paper case: wall time, RHS evaluations,
//!   and both relative to the 0.1 s row (linear growth keeps `time / duration` flat);
//! - ball count 8, 16, 32, 64 at 0.2 s: wall time, RHS evaluations, and nanoseconds
//!   per RHS evaluation per ball (flat when the kernel dominates and scales linearly).

use std::time::Instant;

use studyrun::bearing::RaceWaviness;
use studyrun::mechanism::{CaseParams, Location};
use studyrun::simulate::{simulate, CaseOutput, Sampling};
use studyrun::solve::{Method, SolverSettings};

fn paper_case(balls: usize) -> CaseParams {
    let mut c = CaseParams {
        location: Location::CrankGround,
        ..CaseParams::default()
    };
    c.bearing.ball_count = balls;
    c.bearing.inner_waviness = RaceWaviness::single(35, 4e-6);
    c.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    c
}

/// Best-of-3 wall time (s) and the output of one case.
fn best_of_3(case: &CaseParams, duration: f64) -> (f64, CaseOutput) {
    let settings = SolverSettings::new(Method::DEFAULT);
    let sampling = Sampling {
        duration,
        sample_rate: 50_000.0,
    };
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..3 {
        let start = Instant::now();
        let o = simulate(case, &settings, &sampling).expect("case runs");
        best = best.min(start.elapsed().as_secs_f64());
        out = Some(o);
    }
    (best, out.expect("three runs"))
}

fn main() {
    // `cargo bench` passes `--bench`; there is nothing to filter.
    println!("## Cost against simulated duration (crank_ground, 300 rpm, 9 balls, waviness, the default DOP853 1e-8)\n");
    println!("| duration (s) | wall (ms) | RHS | wall / wall(0.1 s) | RHS / RHS(0.1 s) |");
    println!("|---|---|---|---|---|");
    let mut first = None;
    for duration in [0.1, 0.2, 0.4, 0.8] {
        let (wall, out) = best_of_3(&paper_case(9), duration);
        let rhs = out.stats.rhs_evals as f64;
        let (w0, r0) = *first.get_or_insert((wall, rhs));
        println!(
            "| {duration} | {:.2} | {rhs} | {:.2} | {:.2} |",
            1e3 * wall,
            wall / w0,
            rhs / r0
        );
    }
    println!("\n## Cost against ball count (0.2 s)\n");
    println!("| balls | wall (ms) | RHS | ns per RHS | ns per RHS per ball |");
    println!("|---|---|---|---|---|");
    for balls in [8usize, 16, 32, 64] {
        let (wall, out) = best_of_3(&paper_case(balls), 0.2);
        let per_rhs = 1e9 * wall / out.stats.rhs_evals as f64;
        println!(
            "| {balls} | {:.2} | {} | {per_rhs:.0} | {:.1} |",
            1e3 * wall,
            out.stats.rhs_evals,
            per_rhs / balls as f64
        );
    }
}
