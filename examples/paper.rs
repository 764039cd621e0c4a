//! The paper's numerical study (docs/model.md §6): 32 bearing cases and the ideal
//! mechanism at 300 and 600 rpm, with the vibration metrics of docs/model.md §6 and a
//! check of the paper's three findings.
//!
//! Run: `cargo run --release --example paper`

use std::collections::BTreeMap;

use studyrun::bearing::RaceWaviness;
use studyrun::mechanism::{CaseParams, Location};
use studyrun::signal::metrics::{default_window_start, vibration_metrics, VibrationMetrics};
use studyrun::simulate::{simulate, CaseOutput, Sampling};
use studyrun::solve::{Method, SolverSettings};

const BALLS: [usize; 4] = [8, 9, 10, 11];
const RPMS: [f64; 2] = [300.0, 600.0];
const LOCATIONS: [Location; 2] = [Location::CrankGround, Location::CrankRod];

type Key = (Location, u32, bool, usize);

fn case(location: Location, rpm: f64, waviness: bool, balls: usize) -> CaseParams {
    let mut c = CaseParams {
        location,
        rpm,
        ..CaseParams::default()
    };
    c.bearing.ball_count = balls;
    if waviness {
        c.bearing.inner_waviness = RaceWaviness::single(35, 4e-6);
        c.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    }
    c
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sampling = Sampling {
        duration: 0.4,
        sample_rate: 50_000.0,
    };
    let solver = SolverSettings::new(Method::DEFAULT);
    // One window for every case, as `studyrun studies/paper.yaml` uses (a common
    // window keeps one frequency grid): from one revolution at the slowest speed.
    let t_from = default_window_start(300.0);
    let window = sampling.analysis_window(t_from);
    println!(
        "Paper study: DOP853 rtol 1e-8, {} s at {} Hz; metrics over {t_from} s <= t < {} s",
        sampling.duration, sampling.sample_rate, sampling.duration
    );

    let mut ideal: BTreeMap<u32, CaseOutput> = BTreeMap::new();
    for rpm in RPMS {
        ideal.insert(
            rpm as u32,
            simulate(&case(Location::Ideal, rpm, false, 9), &solver, &sampling)?,
        );
    }
    let mut results: BTreeMap<Key, (VibrationMetrics, CaseOutput)> = BTreeMap::new();
    let mut total_time = 0.0;
    for location in LOCATIONS {
        for rpm in RPMS {
            for waviness in [false, true] {
                for balls in BALLS {
                    let out = simulate(&case(location, rpm, waviness, balls), &solver, &sampling)?;
                    total_time += out.wall_time;
                    let m = vibration_metrics(&out, &ideal[&(rpm as u32)], window.clone());
                    results.insert((location, rpm as u32, waviness, balls), (m, out));
                }
            }
        }
    }

    println!();
    println!("| location | rpm | waviness | N_b | slider acc RMS dev (m/s²) | rel. | crank moment RMS dev (N m) | rel. | bearing force RMS dev (N) | rel. | max F (N) | steps | RHS evals | wall (s) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for ((loc, rpm, wav, nb), (m, out)) in &results {
        let max_f = out
            .channel("bearing_force")
            .unwrap()
            .iter()
            .copied()
            .fold(0.0, f64::max);
        println!(
            "| {loc} | {rpm} | {} | {nb} | {:.3} | {:.1}% | {:.4} | {:.1}% | {:.2} | {:.1}% | {:.1} | {} | {} | {:.2} |",
            if *wav { "4 µm" } else { "off" },
            m.slider_acceleration.rms,
            100.0 * m.slider_acceleration.relative_rms(),
            m.crank_moment.rms,
            100.0 * m.crank_moment.relative_rms(),
            m.bearing_force.rms,
            100.0 * m.bearing_force.relative_rms(),
            max_f,
            out.stats.steps,
            out.stats.rhs_evals,
            out.wall_time
        );
    }
    println!("\ntotal integration wall time: {total_time:.2} s for 32 bearing cases");

    let metric = |k: Key| results[&k].0.slider_acceleration.rms;
    println!(
        "\nFindings (metric: RMS deviation of the slider acceleration from the ideal mechanism):"
    );
    // 1. No waviness: close to ideal; 8 balls worst, more balls closer to ideal.
    let mut f1 = true;
    for location in LOCATIONS {
        for rpm in RPMS.map(|r| r as u32) {
            let v: Vec<f64> = BALLS
                .iter()
                .map(|&b| metric((location, rpm, false, b)))
                .collect();
            let rel: Vec<f64> = BALLS
                .iter()
                .map(|&b| {
                    results[&(location, rpm, false, b)]
                        .0
                        .slider_acceleration
                        .relative_rms()
                })
                .collect();
            let eight_worst = v[0] >= v.iter().copied().fold(0.0, f64::max);
            let decreasing = v.windows(2).all(|w| w[1] <= w[0]);
            let close = rel.iter().all(|r| *r < 0.05);
            f1 &= eight_worst && decreasing;
            println!(
                "  1. {location} {rpm} rpm, no waviness: RMS dev {:?} m/s² for N_b = 8..11 (rel. max {:.1}%); within 5% of ideal: {close}; 8 worst: {eight_worst}; decreasing with N_b: {decreasing}",
                v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>(),
                100.0 * rel.iter().copied().fold(0.0, f64::max)
            );
        }
    }
    println!(
        "  => finding 1 (close to ideal, 8 balls worst, more balls closer): {}",
        verdict(f1)
    );
    // 2. Waviness makes it vibrate; 8 worst, 9 best.
    let mut f2a = true;
    let mut f2b = true;
    for location in LOCATIONS {
        for rpm in RPMS.map(|r| r as u32) {
            let on: Vec<f64> = BALLS
                .iter()
                .map(|&b| metric((location, rpm, true, b)))
                .collect();
            let off: Vec<f64> = BALLS
                .iter()
                .map(|&b| metric((location, rpm, false, b)))
                .collect();
            let more = on.iter().zip(&off).all(|(a, b)| a > b);
            let worst = BALLS[argmax(&on)];
            let best = BALLS[argmin(&on)];
            f2a &= more;
            f2b &= worst == 8 && best == 9;
            println!(
                "  2. {location} {rpm} rpm, waviness: RMS dev {:?} m/s²; above no-waviness for every N_b: {more}; worst N_b = {worst}, best N_b = {best}",
                on.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>()
            );
        }
    }
    println!(
        "  => finding 2a (waviness makes the mechanism vibrate): {}",
        verdict(f2a)
    );
    println!(
        "  => finding 2b (8 balls worst, 9 best, at both speeds and locations): {}",
        verdict(f2b)
    );
    // 3. crank_rod vibrates less than crank_ground.
    let mut smaller = 0;
    let mut total = 0;
    for rpm in RPMS.map(|r| r as u32) {
        for b in BALLS {
            let (g, r) = (
                metric((Location::CrankGround, rpm, true, b)),
                metric((Location::CrankRod, rpm, true, b)),
            );
            total += 1;
            smaller += usize::from(r < g);
            println!(
                "  3. {rpm} rpm, N_b = {b}, waviness: crank_ground {g:.3} vs crank_rod {r:.3} m/s²"
            );
        }
    }
    println!("  => finding 3 (crank_rod smaller than crank_ground): {} ({smaller} of {total} comparisons)", verdict(smaller == total));
    Ok(())
}

fn verdict(ok: bool) -> &'static str {
    if ok {
        "CONFIRMED"
    } else {
        "NOT CONFIRMED"
    }
}

fn argmax(v: &[f64]) -> usize {
    (0..v.len()).max_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap()
}

fn argmin(v: &[f64]) -> usize {
    (0..v.len()).min_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap()
}
