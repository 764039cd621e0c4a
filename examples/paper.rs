//! The paper's numerical study (docs/model.md §6), read from `studies/paper.yaml`:
//! 32 bearing cases and the ideal mechanism at 300 and 600 rpm, with the vibration
//! metrics of docs/model.md §6 and a check of the paper's three findings.
//!
//! The grid, the sampling, the integrator and the analysed window all come from the
//! grid file through [`Study::load`], so the numbers printed are those
//! `studyrun studies/paper.yaml` writes into its file.
//!
//! Run: `cargo run --release --example paper` (or `... --example paper -- GRID.yaml`
//! for another grid over the same four axes).

use std::collections::BTreeMap;
use std::path::PathBuf;

use studyrun::accuracy::describe;
use studyrun::mechanism::{CaseParams, Location};
use studyrun::signal::metrics::{vibration_metrics, VibrationMetrics};
use studyrun::simulate::{simulate, CaseOutput};
use studyrun::study::Study;

/// (location, rpm, waviness amplitude in nm, ball count).
type Key = (Location, u32, u32, usize);

/// The case's position on the paper's four axes.
fn key(p: &CaseParams) -> Key {
    let amplitude = p
        .bearing
        .inner_waviness
        .harmonics
        .first()
        .map_or(0.0, |h| h.amplitude);
    (
        p.location,
        p.rpm.round() as u32,
        (amplitude * 1e9).round() as u32,
        p.bearing.ball_count,
    )
}

fn waviness_label(nm: u32) -> String {
    if nm == 0 {
        "off".to_string()
    } else {
        format!("{} µm", f64::from(nm) / 1000.0)
    }
}

/// The distinct values of one axis, ascending.
fn axis<T: Ord + Copy>(keys: &[Key], f: impl Fn(&Key) -> T) -> Vec<T> {
    let mut v: Vec<T> = keys.iter().map(f).collect();
    v.sort();
    v.dedup();
    v
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("studies/paper.yaml"));
    let study = Study::load(&path)?;
    let window = study.analysis_window();
    let (method, rtol) = describe(&study.solver.method);
    println!(
        "Paper study ({}, {} cases): {} rtol {rtol:e}, {} s at {} Hz; metrics over {} s <= t < {} s",
        path.file_name().unwrap_or_default().to_string_lossy(),
        study.cases.len(),
        method.to_uppercase(),
        study.sampling.duration,
        study.sampling.sample_rate,
        study.transient,
        study.sampling.duration
    );

    let ideal: Vec<CaseOutput> = study
        .references
        .iter()
        .map(|r| simulate(&r.params, &study.solver, &study.sampling))
        .collect::<Result<_, _>>()?;
    let mut results: BTreeMap<Key, (VibrationMetrics, CaseOutput)> = BTreeMap::new();
    let mut total_time = 0.0;
    for case in &study.cases {
        let out = simulate(&case.params, &study.solver, &study.sampling)?;
        total_time += out.wall_time;
        let m = vibration_metrics(&out, &ideal[case.reference], window.clone());
        if results.insert(key(&case.params), (m, out)).is_some() {
            return Err(format!(
                "{}: two cases at {:?}; the example needs one case per location x rpm x waviness x ball count",
                path.display(),
                key(&case.params)
            )
            .into());
        }
    }
    let keys: Vec<Key> = results.keys().copied().collect();
    let locations = axis(&keys, |k| k.0);
    let rpms = axis(&keys, |k| k.1);
    let amplitudes = axis(&keys, |k| k.2);
    let balls = axis(&keys, |k| k.3);
    if amplitudes.len() != 2
        || amplitudes[0] != 0
        || keys.len() != locations.len() * rpms.len() * 2 * balls.len()
    {
        return Err(format!(
            "{}: the findings need a full grid of location x rpm x waviness (off and one amplitude) x ball count",
            path.display()
        )
        .into());
    }
    let wavy = amplitudes[1];

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
            waviness_label(*wav),
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
    println!(
        "\ntotal integration wall time: {total_time:.2} s for {} bearing cases",
        results.len()
    );

    let metric = |k: Key| results[&k].0.slider_acceleration.rms;
    let fmt = |v: &[f64]| v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>();
    let (first, last) = (balls[0], balls[balls.len() - 1]);
    println!(
        "\nFindings (metric: RMS deviation of the slider acceleration from the ideal mechanism):"
    );
    // 1. No waviness: close to ideal; fewest balls worst, more balls closer to ideal.
    let mut f1 = true;
    for &location in &locations {
        for &rpm in &rpms {
            let v: Vec<f64> = balls
                .iter()
                .map(|&b| metric((location, rpm, 0, b)))
                .collect();
            let rel: Vec<f64> = balls
                .iter()
                .map(|&b| {
                    results[&(location, rpm, 0, b)]
                        .0
                        .slider_acceleration
                        .relative_rms()
                })
                .collect();
            let fewest_worst = v[0] >= v.iter().copied().fold(0.0, f64::max);
            let decreasing = v.windows(2).all(|w| w[1] <= w[0]);
            let close = rel.iter().all(|r| *r < 0.05);
            f1 &= fewest_worst && decreasing;
            println!(
                "  1. {location} {rpm} rpm, no waviness: RMS dev {:?} m/s² for N_b = {first}..{last} (rel. max {:.1}%); within 5% of ideal: {close}; {first} worst: {fewest_worst}; decreasing with N_b: {decreasing}",
                fmt(&v),
                100.0 * rel.iter().copied().fold(0.0, f64::max)
            );
        }
    }
    println!(
        "  => finding 1 (close to ideal, {first} balls worst, more balls closer): {}",
        verdict(f1)
    );
    // 2. Waviness makes it vibrate; 8 worst, 9 best.
    let mut f2a = true;
    let mut f2b = true;
    for &location in &locations {
        for &rpm in &rpms {
            let on: Vec<f64> = balls
                .iter()
                .map(|&b| metric((location, rpm, wavy, b)))
                .collect();
            let off: Vec<f64> = balls
                .iter()
                .map(|&b| metric((location, rpm, 0, b)))
                .collect();
            let more = on.iter().zip(&off).all(|(a, b)| a > b);
            let worst = balls[argmax(&on)];
            let best = balls[argmin(&on)];
            f2a &= more;
            f2b &= worst == 8 && best == 9;
            println!(
                "  2. {location} {rpm} rpm, waviness: RMS dev {:?} m/s²; above no-waviness for every N_b: {more}; worst N_b = {worst}, best N_b = {best}",
                fmt(&on)
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
    if locations.contains(&Location::CrankGround) && locations.contains(&Location::CrankRod) {
        for &rpm in &rpms {
            for &b in &balls {
                let (g, r) = (
                    metric((Location::CrankGround, rpm, wavy, b)),
                    metric((Location::CrankRod, rpm, wavy, b)),
                );
                total += 1;
                smaller += usize::from(r < g);
                println!(
                    "  3. {rpm} rpm, N_b = {b}, waviness: crank_ground {g:.3} vs crank_rod {r:.3} m/s²"
                );
            }
        }
    }
    println!(
        "  => finding 3 (crank_rod smaller than crank_ground): {} ({smaller} of {total} comparisons)",
        verdict(total > 0 && smaller == total)
    );
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
