//! The envelope chain on the MFPT bearing recordings (`../shared/data/mfpt`, never part
//! of the repository): per file and per band choice, the band demodulated, the band
//! energies around BPFO, BPFI and 2·BSF in its squared-envelope spectrum, and which
//! is largest against the file's label, as a Markdown table (docs/validation.md). Each
//! recording is analysed as one window: all of it (146 484 samples, 3 s at 48 828 Hz),
//! or its first `MFPT_WINDOW` samples. The choices are `kurtogram`, `auto`, any fixed
//! bands given as pairs of edges in Hz, and with `MFPT_REJECTED=1` two rejected
//! criteria over `auto`'s admissible bands: the largest complex-envelope kurtosis, and
//! the largest kurtosis of the envelope spectrum up to 3.5 times the largest line (a
//! protrugram-like criterion).
//!
//! Run: `cargo run --release --example mfpt_bands [LOW HIGH ...]`.

use std::path::{Path, PathBuf};

use studyrun::recordings::read::{read_samples, Selector};
use studyrun::signal::band_choice::{admissible, usable_bandwidth};
use studyrun::signal::envelope::{Band, BandChoice, EnvelopePlan};
use studyrun::signal::indicators::band_energy;
use studyrun::signal::spectrum::frequencies;

/// The recordings' sample rate (Hz).
const RATE: f64 = 48_828.0;
/// BPFO, BPFI and 2·BSF at the 25 Hz shaft speed (Hz), from the data set's README.
const LINES: [(&str, f64); 3] = [("bpfo", 81.125), ("bpfi", 118.875), ("2bsf", 127.82)];

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mfpt");
    if !dir.is_dir() {
        println!("SKIPPED: /work/shared/data/mfpt absent");
        return;
    }
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("band edges in Hz"))
        .collect();
    let mut choices = vec![BandChoice::Kurtogram, BandChoice::Auto];
    choices.extend(args.chunks(2).map(|pair| {
        BandChoice::Fixed(Band {
            low: pair[0],
            high: pair[1],
        })
    }));
    println!("| file | usable (Hz) | band (Hz) | BPFO : BPFI : 2·BSF | named |");
    println!("|---|---|---|---|---|");
    let mut named = vec![0; choices.len()];
    for (path, label) in files(&dir) {
        let mut x = read_samples(&path, &Selector::Variable("bearing.gs".into()))
            .expect("readable recording")
            .values;
        x.truncate(window());
        for (count, &choice) in named.iter_mut().zip(&choices) {
            *count += usize::from(report(&path, &x, label, choice));
        }
        if std::env::var("MFPT_REJECTED").is_ok() {
            for (name, envelope_spectrum) in [("kurtosis", false), ("spectrum kurtosis", true)] {
                let band = rejected(&x, envelope_spectrum);
                print!("{name}: ");
                report(&path, &x, label, BandChoice::Fixed(band));
            }
        }
    }
    for (count, choice) in named.iter().zip(&choices) {
        println!(
            "{}: labelled fault largest in {count} of 14",
            choice.describe()
        );
    }
}

/// Samples analysed from the start of each recording: `MFPT_WINDOW` or all of it.
fn window() -> usize {
    std::env::var("MFPT_WINDOW").map_or(usize::MAX, |v| v.parse().expect("a sample count"))
}

/// The 14 files with their labels (`bpfo` outer race, `bpfi` inner race).
fn files(dir: &Path) -> Vec<(PathBuf, &'static str)> {
    let mut out = Vec::new();
    for (prefix, label) in [("InnerRaceFault", "bpfi"), ("OuterRaceFault", "bpfo")] {
        for load in 1..=7 {
            out.push((dir.join(format!("{prefix}_vload_{load}.mat")), label));
        }
    }
    out
}

/// Prints one file's row for `choice` (the band energies over the largest of the
/// three) and returns whether the labelled line is the largest.
fn report(path: &Path, x: &[f64], label: &str, choice: BandChoice) -> bool {
    let mut plan = EnvelopePlan::new(x.len(), RATE).expect("plan");
    let lines = LINES.map(|(_, f)| f);
    let env = plan.analyse(x, choice, &lines).expect("analysis");
    let freqs = frequencies(x.len(), RATE);
    let energies = LINES.map(|(_, f)| band_energy(&env.spectrum, &freqs, f));
    let best = (0..3)
        .max_by(|&a, &b| energies[a].total_cmp(&energies[b]))
        .expect("three lines");
    let ratios = energies.map(|e| e / energies[best]);
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = LINES[best].0;
    println!(
        "| {stem} ({}) | {:.0} | {:.0}–{:.0} | {:.3} : {:.3} : {:.3} | {name}{} |",
        choice.describe(),
        usable(x),
        env.band.low,
        env.band.high,
        ratios[0],
        ratios[1],
        ratios[2],
        if name == label { "" } else { " (wrong)" }
    );
    name == label
}

/// The band a rejected criterion chooses among `auto`'s admissible bands: the largest
/// complex-envelope kurtosis, or with `envelope_spectrum` the largest kurtosis
/// `<A⁴>/<A²>²` of the envelope spectrum's amplitudes `A_k` over `1 ≤ k ≤ 3.5 f_max/Δf`.
fn rejected(x: &[f64], envelope_spectrum: bool) -> Band {
    let lines = LINES.map(|(_, f)| f);
    let usable = usable(x);
    let mut plan = EnvelopePlan::new(x.len(), RATE).expect("plan");
    let top = (3.5 * lines[2] * x.len() as f64 / RATE) as usize;
    let bands: Vec<Band> = plan.bands().iter().map(|b| b.1).collect();
    let mut best = (Band::NONE, f64::NEG_INFINITY);
    for band in bands.into_iter().filter(|&b| admissible(b, usable, &lines)) {
        let env = plan
            .analyse(x, BandChoice::Fixed(band), &lines)
            .expect("analysis");
        let score = if envelope_spectrum {
            let a = &env.spectrum[1..=top];
            let m2 = a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64;
            let m4 = a.iter().map(|v| v.powi(4)).sum::<f64>() / a.len() as f64;
            m4 / (m2 * m2)
        } else {
            env.band_kurtosis
        };
        if score > best.1 {
            best = (band, score);
        }
    }
    best.0
}

/// The usable bandwidth of `x` (Hz, [`usable_bandwidth`]).
fn usable(x: &[f64]) -> f64 {
    let fft = realfft::RealFftPlanner::<f64>::new().plan_fft_forward(x.len());
    let mut input = x.to_vec();
    let mut spectrum = fft.make_output_vec();
    fft.process(&mut input, &mut spectrum).expect("FFT");
    usable_bandwidth(&spectrum, 0.5 * RATE)
}
