//! Cost of the automatic band choice against the fast kurtogram it replaced, on the
//! paper's window (10 000 samples at 50 kHz): the whole envelope analysis of one
//! channel (`EnvelopePlan::analyse`, band choice, envelope spectrum and spectral
//! kurtosis) with `band: auto` and with `band: kurtogram`, each timed over interleaved
//! rounds of back-to-back calls; prints the median time per call and their ratio.
//!
//! Run: `cargo bench --bench band_choice -- [ROUNDS]` (default 15).

use std::f64::consts::TAU;
use std::hint::black_box;
use std::time::Instant;

use studyrun::mechanism::{CaseParams, Location};
use studyrun::signal::envelope::{BandChoice, EnvelopePlan};
use studyrun::signal::fault_frequencies::FaultFrequencies;

/// Samples of the window and sample rate (Hz) of the paper study.
const N: usize = 10_000;
const RATE: f64 = 50_000.0;
/// Calls per timed round.
const CALLS: usize = 40;

fn main() {
    let rounds: usize = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map_or(15, |a| a.parse().expect("a round count"));
    let mut params = CaseParams {
        rpm: 300.0,
        location: Location::CrankGround,
        ..CaseParams::default()
    };
    params.bearing.ball_count = 9;
    let f = FaultFrequencies::of(&params);
    let lines = [f.bpfo, f.bpfi, 2.0 * f.bsf];
    let x = signal(f.bpfo);
    let mut plan = EnvelopePlan::new(N, RATE).expect("plan");
    let mut times = [Vec::new(), Vec::new()];
    for _ in 0..rounds {
        for (t, choice) in times
            .iter_mut()
            .zip([BandChoice::Auto, BandChoice::Kurtogram])
        {
            let start = Instant::now();
            for _ in 0..CALLS {
                black_box(
                    plan.analyse(black_box(&x), choice, &lines)
                        .expect("analysis"),
                );
            }
            t.push(start.elapsed().as_secs_f64() / CALLS as f64);
        }
    }
    let [auto, kurtogram] = times.map(|mut t| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    });
    println!(
        "lines (Hz): BPFO {:.2}, BPFI {:.2}, 2·BSF {:.2}",
        lines[0], lines[1], lines[2]
    );
    println!("auto      {:.1} µs per window", auto * 1e6);
    println!("kurtogram {:.1} µs per window", kurtogram * 1e6);
    println!("ratio auto / kurtogram {:.2}", auto / kurtogram);
}

/// Impacts at `rate_hz` ringing a 6 kHz resonance (damping ratio 0.03) in a
/// deterministic pseudo-random noise of about their RMS.
fn signal(rate_hz: f64) -> Vec<f64> {
    let mut state = 1u64;
    (0..N)
        .map(|j| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let noise = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0;
            let t = (j as f64 / RATE) % (1.0 / rate_hz);
            (-0.03 * TAU * 6000.0 * t).exp() * (TAU * 6000.0 * t).sin() + 0.3 * noise
        })
        .collect()
}
