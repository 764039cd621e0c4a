//! The envelope chain on the MFPT bearing recordings (`../shared/data/mfpt`, never part
//! of the repository): per file and per band choice, the band demodulated, the band
//! energies around BPFO, BPFI and 2·BSF in its squared-envelope spectrum, and which
//! is largest against the file's label. Each whole recording (146 484 samples, 3 s at
//! 48 828 Hz) is analysed as one window.
//!
//! Run: `cargo run --release --example mfpt_bands [fixed-low-Hz fixed-high-Hz ...]`.

use std::path::{Path, PathBuf};

use studyrun::recordings::read::{read_samples, Selector};
use studyrun::signal::band_choice::usable_bandwidth;
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
    let mut choices = vec![("kurtog", BandChoice::Kurtogram), ("auto", BandChoice::Auto)];
    for pair in args.chunks(2) {
        let band = Band {
            low: pair[0],
            high: pair[1],
        };
        choices.push(("fixed", BandChoice::Fixed(band)));
    }
    for (name, choice) in choices {
        let named = files(&dir)
            .iter()
            .filter(|(path, label)| report(path, label, name, choice))
            .count();
        println!("{name} {}: labelled fault largest in {named} of 14\n", choice.describe());
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

/// Prints one file's line and returns whether the labelled line is the largest.
fn report(path: &Path, label: &str, name: &str, choice: BandChoice) -> bool {
    let mut x = read_samples(path, &Selector::Variable("bearing.gs".into()))
        .expect("readable recording")
        .values;
    x.truncate(window());
    let mut plan = EnvelopePlan::new(x.len(), RATE).expect("plan");
    let lines = LINES.map(|(_, f)| f);
    let env = plan.analyse(&x, choice, &lines).expect("analysis");
    let freqs = frequencies(x.len(), RATE);
    let energies = LINES.map(|(_, f)| band_energy(&env.spectrum, &freqs, f));
    let best = (0..3)
        .max_by(|&a, &b| energies[a].total_cmp(&energies[b]))
        .map(|i| LINES[i].0)
        .unwrap_or("none");
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    println!(
        "{name:6} {stem:24} usable {:6.0} band {:6.0}..{:6.0} Hz  bpfo {:.3e} bpfi {:.3e} 2bsf {:.3e}  \
         largest {best:4} label {label} {}",
        usable(&x),
        env.band.low,
        env.band.high,
        energies[0],
        energies[1],
        energies[2],
        if best == label { "ok" } else { "WRONG" }
    );
    best == label
}

/// The usable bandwidth of `x` (Hz, [`usable_bandwidth`]).
fn usable(x: &[f64]) -> f64 {
    let fft = realfft::RealFftPlanner::<f64>::new().plan_fft_forward(x.len());
    let mut input = x.to_vec();
    let mut spectrum = fft.make_output_vec();
    fft.process(&mut input, &mut spectrum).expect("FFT");
    usable_bandwidth(&spectrum, 0.5 * RATE)
}
