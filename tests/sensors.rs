//! `sensors:` end to end: the stored noise-free series is the transducer's response
//! to the stored channel, the noise has the requested SNR over the analysed window,
//! the series are bit-identical for any `-j`, shard split and resume, a study
//! without sensors stores nothing of them and the rest bit for bit, and bad sensors
//! are refused by field.

use std::path::Path;

use studyrun::output::StudyReader;
use studyrun::signal::sensor::Transducer;
use studyrun::simulate::CHANNELS;
use studyrun::study::Study;

const BASE: &str = "name: sens\nduration: 0.1\nsample_rate: 10000\ntransient: \"0.02 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  rpm: [600]\n";

const SENSORS: &str = "sensors:\n  - {name: acc, channel: bearing_force_y, natural_frequency: \"2 kHz\", damping_ratio: 0.05, noise: {snr_db: 10, seed: 7}}\n  - {name: moment, channel: crank_moment, natural_frequency: 1500, damping_ratio: 0.7}\n  - {name: quiet, channel: bearing_force_y, natural_frequency: 3000, damping_ratio: 0.2, noise: {snr_db: -3}}\n";

/// (name, channel, f_n, ζ, requested SNR) of [`SENSORS`].
const EXPECTED: [(&str, &str, f64, f64, Option<f64>); 3] = [
    ("acc", "bearing_force_y", 2000.0, 0.05, Some(10.0)),
    ("moment", "crank_moment", 1500.0, 0.7, None),
    ("quiet", "bearing_force_y", 3000.0, 0.2, Some(-3.0)),
];

fn run(dir: &Path, name: &str, text: &str, args: &[&str]) -> StudyReader {
    let grid = dir.join(format!("{name}.yaml"));
    std::fs::write(&grid, text).unwrap();
    let out = dir.join(format!("{name}.h5"));
    let mut all = vec![grid.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"];
    all.extend(args);
    crate::common::studyrun_ok(dir, &all);
    StudyReader::open(&out).unwrap()
}

fn series<'a>(reader: &StudyReader, case: &'a studyrun::output::CaseData, name: &str) -> &'a [f64] {
    let k = reader
        .layout()
        .series
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no series {name}"));
    &case.series[k]
}

#[test]
fn the_clean_series_is_the_transducer_response_and_the_noise_has_the_requested_snr() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{BASE}{SENSORS}");
    let reader = run(dir.path(), "s", &text, &[]);
    let study = Study::from_yaml(&text, Path::new("s.yaml")).unwrap();
    let window = study.analysis_window();
    let dt = 1.0 / study.sampling.sample_rate;
    let layout = reader.layout();
    // The simulated channels, then per sensor `<name>` and `<name>_clean`.
    let names: Vec<&str> = layout.series.iter().map(|s| s.name.as_str()).collect();
    let mut expected: Vec<&str> = study
        .stored_channels()
        .into_iter()
        .map(|c| CHANNELS[c].name)
        .collect();
    expected.extend([
        "acc",
        "acc_clean",
        "moment",
        "moment_clean",
        "quiet",
        "quiet_clean",
    ]);
    assert_eq!(names, expected);
    let mut worst_snr: f64 = 0.0;
    for row in 0..layout.n_cases() {
        let case = reader.read_case(row).unwrap();
        for (name, channel, f_n, zeta, snr) in EXPECTED {
            let input = series(&reader, &case, channel);
            let clean = series(&reader, &case, &format!("{name}_clean"));
            let noisy = series(&reader, &case, name);
            let sensor = Transducer {
                natural_frequency: f_n,
                damping_ratio: zeta,
            };
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(clean),
                bits(&sensor.respond(input, dt)),
                "{name} row {row}"
            );
            // The sensor rings: it is not its input.
            assert_ne!(bits(clean), bits(input));
            match snr {
                None => assert_eq!(bits(noisy), bits(clean), "{name} without noise"),
                Some(snr) => {
                    let w = &clean[window.clone()];
                    let n = w.len() as f64;
                    let mean = w.iter().sum::<f64>() / n;
                    let signal = w.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
                    let noise = window
                        .clone()
                        .map(|k| (noisy[k] - clean[k]).powi(2))
                        .sum::<f64>()
                        / n;
                    let measured = 10.0 * (signal / noise).log10();
                    worst_snr = worst_snr.max((measured - snr).abs());
                    // Noise on every sample, the transient's too.
                    assert!(noisy[..window.start].iter().zip(clean).all(|(a, b)| a != b));
                }
            }
        }
        // Two sensors with noise on one channel draw different noise.
        let acc = series(&reader, &case, "acc");
        let quiet = series(&reader, &case, "quiet");
        assert_ne!(
            acc[window.start] - series(&reader, &case, "acc_clean")[window.start],
            0.0
        );
        assert_ne!(acc, quiet);
    }
    assert!(worst_snr < 0.1, "SNR off by {worst_snr} dB");
    assert!(
        worst_snr < 1e-9,
        "the noise power is set exactly: {worst_snr} dB"
    );
}

/// The sensor series (and everything else) are the same bits on one or two
/// workers and from two shards merged.
#[test]
fn sensor_series_are_the_same_for_any_jobs_and_shards() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = format!("{BASE}{SENSORS}");
    run(d, "one", &text, &["-j", "1"]);
    run(d, "two", &text, &["-j", "2"]);
    crate::cli::assert_same_data(&d.join("one.h5"), &d.join("two.h5"));
    for k in 1..=2 {
        let shard = format!("{k}/2");
        crate::common::studyrun_ok(
            d,
            &[
                "run",
                "one.yaml",
                "--shard",
                &shard,
                "-o",
                &format!("p{k}.h5"),
                "-q",
            ],
        );
    }
    crate::common::studyrun_ok(d, &["merge", "merged.h5", "p2.h5", "p1.h5"]);
    crate::cli::assert_same_data(&d.join("one.h5"), &d.join("merged.h5"));
}

/// A run killed (-9) twice and resumed stores the uninterrupted run's sensor series.
#[test]
fn sensor_series_survive_kill_and_resume_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = format!("name: long\nduration: 0.4\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n{SENSORS}");
    std::fs::write(d.join("long.yaml"), &grid).unwrap();
    let journal = d.join("long.h5.journal");
    crate::cli::kill_when_journal_passes(d, &["long.yaml", "-j", "1", "-q"], &journal, 3000);
    let replayed = std::fs::metadata(&journal).unwrap().len();
    crate::cli::kill_when_journal_passes(
        d,
        &["long.yaml", "--resume", "-j", "1", "-q"],
        &journal,
        replayed + 3000,
    );
    crate::common::studyrun_ok(d, &["long.yaml", "--resume", "-q"]);
    crate::common::studyrun_ok(d, &["long.yaml", "-o", "straight.h5", "-q"]);
    crate::cli::assert_same_data(&d.join("long.h5"), &d.join("straight.h5"));
    let reader = StudyReader::open(d.join("long.h5")).unwrap();
    assert!(reader.layout().series.iter().any(|s| s.name == "acc_clean"));
}

/// Without `sensors:` the file has only the simulated channels, and the study with
/// sensors holds the same bits in everything the two share.
#[test]
fn without_sensors_nothing_is_stored_and_the_rest_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let plain = run(dir.path(), "plain", BASE, &[]);
    let with = run(dir.path(), "with", &format!("{BASE}{SENSORS}"), &[]);
    let (lp, lw) = (plain.layout(), with.layout());
    let names: Vec<&str> = lp.series.iter().map(|s| s.name.as_str()).collect();
    let simulated: Vec<&str> = CHANNELS
        .iter()
        .filter(|c| c.effect.is_none())
        .map(|c| c.name)
        .collect();
    assert_eq!(names, simulated);
    assert_eq!(lw.series[..lp.series.len()], lp.series[..]);
    assert_eq!(lw.series.len(), lp.series.len() + 6);
    assert_eq!((&lp.spectra, &lp.metrics), (&lw.spectra, &lw.metrics));
    let wall = lp.metrics.len() - 1;
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for row in 0..lp.n_cases() {
        let (a, b) = (plain.read_case(row).unwrap(), with.read_case(row).unwrap());
        for (x, y) in a.series.iter().zip(&b.series) {
            assert_eq!(bits(x), bits(y), "series of row {row}");
        }
        for (x, y) in a.spectra.iter().zip(&b.spectra) {
            assert_eq!(bits(x), bits(y), "spectrum of row {row}");
        }
        assert_eq!(
            bits(&a.metrics[..wall]),
            bits(&b.metrics[..wall]),
            "row {row}"
        );
    }
}

#[test]
fn bad_sensors_are_refused_by_field() {
    let refused = |sensors: &str| {
        Study::from_yaml(
            &format!("{BASE}sensors:\n{sensors}"),
            Path::new("grid.yaml"),
        )
        .expect_err("must be refused")
        .to_string()
    };
    let ok = "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n";
    let cases = [
        (
            "  - {name: a, channel: crank_momentum, natural_frequency: 1000, damping_ratio: 0.1}\n",
            "`sensors[0].channel`: unknown channel `crank_momentum`",
        ),
        (
            &format!("{ok}  - {{name: a, channel: bearing_force, natural_frequency: 1000, damping_ratio: 0.1}}\n"),
            "`sensors[1].name`: `a`: the series `a` is another sensor's",
        ),
        (
            &format!("{ok}  - {{name: a_clean, channel: bearing_force, natural_frequency: 1000, damping_ratio: 0.1}}\n"),
            "`sensors[1].name`: `a_clean`: the series `a_clean` is another sensor's",
        ),
        (
            "  - {name: crank_moment, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n",
            "`sensors[0].name`: `crank_moment` would store the series `crank_moment`, which is already a variable",
        ),
        (
            "  - {name: rpm, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n",
            "already a variable",
        ),
        (
            "  - {name: bearing_force_spectrum, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n",
            "already a variable",
        ),
        (
            "  - {name: status, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n",
            "already a variable",
        ),
        (
            "  - {name: 1acc, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n",
            "`sensors[0].name`: `1acc` is not a sensor name",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 0, damping_ratio: 0.1}\n",
            "`sensors[0].natural_frequency`: 0 Hz; expected 0 < natural_frequency < sample_rate/2 = 5000 Hz",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: \"5 kHz\", damping_ratio: 0.1}\n",
            "5000 Hz; expected 0 < natural_frequency < sample_rate/2 = 5000 Hz",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: \"1 kg\", damping_ratio: 0.1}\n",
            "`sensors[0].natural_frequency`",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0}\n",
            "`sensors[0].damping_ratio`: 0; expected a finite damping ratio > 0",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: -0.5}\n",
            "`sensors[0].damping_ratio`",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {snr_db: .inf}}\n",
            "`sensors[0].noise.snr_db`: inf is not allowed: a signal-to-noise ratio from -100 to 300 dB",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {snr_db: -4000}}\n",
            "`sensors[0].noise.snr_db`: -4000 is not allowed",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {snr_db: 301}}\n",
            "`sensors[0].noise.snr_db`: 301 is not allowed",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {snr_db: .nan, seed: 3}}\n",
            "`sensors[0].noise.snr_db`: NaN",
        ),
        (
            "  - {name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {snr: 3}}\n",
            "snr",
        ),
    ];
    for (sensors, needle) in cases {
        let err = refused(sensors);
        assert!(err.contains(needle), "{err:?} lacks {needle:?}");
        // The first sensor is on line 10, the second on line 11.
        let line = if sensors.lines().count() == 2 { 11 } else { 10 };
        assert!(
            err.starts_with(&format!("grid.yaml:{line}:")),
            "{err:?} lacks line {line}"
        );
    }
    let study = Study::from_yaml(&format!("{BASE}sensors:\n{ok}"), Path::new("grid.yaml")).unwrap();
    assert_eq!(study.sensors.len(), 1);
    assert_eq!(study.sensors[0].noise, None);
    let seeded = Study::from_yaml(
        &format!("{BASE}sensors:\n  - {{name: a, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {{snr_db: 20}}}}\n"),
        Path::new("grid.yaml"),
    )
    .unwrap();
    assert_eq!(seeded.sensors[0].noise.map(|n| n.seed), Some(0));
}
