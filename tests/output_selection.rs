//! `output: {series, decimate}` end to end: a study stores exactly the series it
//! names at every `decimate`-th sample of the full-rate run, bit for bit, while its
//! spectra and metrics equal the full-rate study's; `series: none` stores no series
//! and no `time` coordinate; resume and merge give the uninterrupted file; bad
//! values are refused by field.

use std::path::Path;

use studyrun::output::{AttrValue, StudyReader};
use studyrun::study::Study;

use crate::cli::{assert_same_data, kill_when_journal_passes, studyrun, write};
use crate::common::{bits, read_case_but_wall_time, studyrun_ok};

/// Four short cases (two locations, two ball counts) with one noisy sensor.
const BASE: &str = "name: sel\nduration: 0.05\nsample_rate: 10000\ntransient: \"0.01 s\"\n\
    grid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9]\n\
    sensors:\n  - {name: acc, channel: bearing_force_y, natural_frequency: \"2 kHz\", \
    damping_ratio: 0.05, noise: {snr_db: 10, seed: 7}}\n";

/// Runs `BASE` with `output` appended into `<name>.h5` in `dir`.
fn run(dir: &Path, name: &str, output: &str) -> StudyReader {
    write(dir, &format!("{name}.yaml"), &format!("{BASE}{output}"));
    studyrun_ok(
        dir,
        &[&format!("{name}.yaml"), "-o", &format!("{name}.h5"), "-q"],
    );
    StudyReader::open(dir.join(format!("{name}.h5"))).unwrap()
}

/// Asserts that `a` and `b` hold the same spectra and metrics (but the wall time),
/// bit for bit, case by case.
fn same_spectra_and_metrics(a: &StudyReader, b: &StudyReader) {
    let (la, lb) = (a.layout(), b.layout());
    assert_eq!(la.spectra, lb.spectra);
    assert_eq!(la.metrics, lb.metrics);
    assert_eq!(la.frequencies, lb.frequencies);
    for row in 0..la.n_cases() {
        let (ca, cb) = (
            read_case_but_wall_time(a, row),
            read_case_but_wall_time(b, row),
        );
        assert_eq!(ca.status, studyrun::output::Status::Ok);
        assert_eq!(bits(&ca.metrics), bits(&cb.metrics), "metrics of row {row}");
        for (x, y) in ca.spectra.iter().zip(&cb.spectra) {
            assert_eq!(bits(x), bits(y), "spectra of row {row}");
        }
    }
}

/// `series: [slider_acceleration, acc_clean]`, `decimate: 4`: those two variables,
/// at times 0, 4/fs, 8/fs, … of the full run, equal to its samples there bit for bit
/// (the sensor's noise-free series too); the reference follows the same selection
/// and decimation; spectra and metrics unchanged.
#[test]
fn a_decimated_selection_stores_every_kth_sample_of_the_full_run() {
    let dir = tempfile::tempdir().unwrap();
    let full = run(dir.path(), "full", "");
    let dec = run(
        dir.path(),
        "dec",
        "output:\n  series: [acc_clean, slider_acceleration]\n  decimate: 4\n",
    );
    let (lf, ld) = (full.layout(), dec.layout());
    let names: Vec<&str> = ld.series.iter().map(|s| s.name.as_str()).collect();
    // Channels first, in CHANNELS order, then the sensor series.
    assert_eq!(names, ["slider_acceleration", "acc_clean"]);
    assert_eq!(lf.times.len(), 501);
    let every4: Vec<f64> = lf.times.iter().step_by(4).copied().collect();
    assert_eq!(ld.times.len(), 126);
    assert_eq!(bits(&ld.times), bits(&every4));
    let at = |name: &str| lf.series.iter().position(|s| s.name == name).unwrap();
    for row in 0..lf.n_cases() {
        let (cf, cd) = (full.read_case(row).unwrap(), dec.read_case(row).unwrap());
        for (k, name) in names.iter().enumerate() {
            let kept: Vec<f64> = cf.series[at(name)].iter().step_by(4).copied().collect();
            assert_eq!(bits(&cd.series[k]), bits(&kept), "{name}, row {row}");
        }
    }
    let refs: Vec<&str> = ld
        .reference_series
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(refs, ["reference_slider_acceleration"]);
    let ref_at = lf
        .reference_series
        .iter()
        .position(|s| s.name == "reference_slider_acceleration")
        .unwrap();
    for k in 0..ld.n_references() {
        let kept: Vec<f64> = full.read_reference(k).unwrap()[ref_at]
            .iter()
            .step_by(4)
            .copied()
            .collect();
        assert_eq!(bits(&dec.read_reference(k).unwrap()[0]), bits(&kept));
    }
    same_spectra_and_metrics(&full, &dec);
    assert_eq!(dec.attribute("decimate"), Some(&AttrValue::I64(4)));
    assert_eq!(
        dec.attribute("series_sample_rate"),
        Some(&AttrValue::F64(2500.0))
    );
    assert_eq!(full.attribute("decimate"), Some(&AttrValue::I64(1)));
    let inspect = studyrun_ok(dir.path(), &["inspect", "dec.h5"]);
    let text = String::from_utf8_lossy(&inspect.stdout);
    assert!(
        text.contains("series:   2 stored, 126 samples each at 2500 Hz (one sample in 4")
            && text.contains("slider_acceleration, acc_clean"),
        "{text}"
    );
}

/// `series: none`: no `[case, time]` or `[reference, time]` variable and no `time`
/// coordinate; spectra and metrics as with every series; shards of it merge into
/// the single run.
#[test]
fn no_series_stores_spectra_and_metrics_only() {
    let dir = tempfile::tempdir().unwrap();
    let full = run(dir.path(), "full", "");
    let none = run(dir.path(), "none", "output: {series: none, decimate: 3}\n");
    let l = none.layout();
    assert!(l.series.is_empty() && l.reference_series.is_empty() && l.times.is_empty());
    let file = hdf5::File::open(dir.path().join("none.h5")).unwrap();
    assert!(file.dataset("time").is_err(), "no time coordinate");
    assert!(file.dataset("frequency").is_ok());
    drop(file);
    same_spectra_and_metrics(&full, &none);
    let inspect = studyrun_ok(dir.path(), &["inspect", "none.h5"]);
    assert!(String::from_utf8_lossy(&inspect.stdout).contains("series:   none stored"));
    for k in 1..=2 {
        studyrun_ok(
            dir.path(),
            &[
                "none.yaml",
                "--shard",
                &format!("{k}/2"),
                "-o",
                &format!("part{k}.h5"),
                "-q",
            ],
        );
    }
    studyrun_ok(dir.path(), &["merge", "merged.h5", "part2.h5", "part1.h5"]);
    assert_same_data(&dir.path().join("none.h5"), &dir.path().join("merged.h5"));
}

/// A decimated, selective run killed twice and resumed equals an uninterrupted one.
#[test]
fn a_resumed_decimated_run_equals_the_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let grid = "name: long\nduration: 0.4\nsample_rate: 10000\n\
        output: {series: [bearing_force, eccentricity_x], decimate: 3}\n\
        grid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  \
        ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n";
    write(dir.path(), "long.yaml", grid);
    let journal = dir.path().join("long.h5.journal");
    kill_when_journal_passes(dir.path(), &["long.yaml", "-j", "1", "-q"], &journal, 1500);
    assert!(!dir.path().join("long.h5").exists());
    let replayed = std::fs::metadata(&journal).unwrap().len();
    kill_when_journal_passes(
        dir.path(),
        &["long.yaml", "--resume", "-j", "1", "-q"],
        &journal,
        replayed + 1500,
    );
    let resumed = studyrun_ok(dir.path(), &["long.yaml", "--resume"]);
    assert!(String::from_utf8_lossy(&resumed.stderr).contains("from the journal"));
    studyrun_ok(dir.path(), &["long.yaml", "-o", "straight.h5", "-q"]);
    let r = StudyReader::open(dir.path().join("long.h5")).unwrap();
    assert_eq!(r.layout().series.len(), 2);
    assert_eq!(r.layout().times.len(), 1334);
    assert_same_data(&dir.path().join("long.h5"), &dir.path().join("straight.h5"));
}

/// Bad `output.series` and `output.decimate` values are refused naming the field,
/// the value and what is allowed, at their place in the file.
#[test]
fn bad_output_settings_are_refused_by_field() {
    let refused = |output: &str| {
        Study::from_yaml(&format!("{BASE}{output}"), Path::new("grid.yaml"))
            .expect_err("must be refused")
            .to_string()
    };
    let cases = [
        (
            "output: {decimate: 0}\n",
            &[
                "grid.yaml:",
                "`output.decimate`",
                "0 is not allowed",
                "an integer from 1",
            ][..],
        ),
        (
            "output: {decimate: 2.5}\n",
            &["`output.decimate`", "2.5 is not allowed"][..],
        ),
        (
            "output: {decimate: \"4 Hz\"}\n",
            &["`output.decimate`", "\"4 Hz\" is not allowed"][..],
        ),
        (
            "output:\n  series: [slider_acceleration, slider_velocity]\n",
            &[
                "grid.yaml:",
                "`output.series[1]`",
                "unknown series `slider_velocity`",
                "crank_moment",
                "acc_clean",
            ][..],
        ),
        (
            "output:\n  series: [acc, crank_moment, acc]\n",
            &["`output.series[2]`", "series `acc` is listed twice"][..],
        ),
        (
            "output: {series: some}\n",
            &[
                "`output.series`",
                "`some` is not allowed",
                "`all` or `none`",
            ][..],
        ),
    ];
    for (output, needles) in cases {
        let err = refused(output);
        for needle in needles {
            assert!(err.contains(needle), "{output}: {err:?} lacks {needle:?}");
        }
    }
    let accepted = |output: &str| Study::from_yaml(&format!("{BASE}{output}"), Path::new("g.yaml"));
    let all = accepted("output: {series: all, decimate: 1}\n").unwrap();
    // Every channel the study's effects simulate: the housing's need `housing`.
    let simulated = studyrun::simulate::CHANNELS
        .iter()
        .filter(|c| c.effect.is_none())
        .count();
    assert_eq!(all.stored_channels().len(), simulated);
    assert_eq!(all.stored_sensor_series(), [0, 1]);
    let two = accepted("output: {series: [acc, crank_moment], decimate: 501}\n").unwrap();
    assert_eq!(two.stored_channels(), [1]);
    assert_eq!(two.stored_sensor_series(), [0]);
    assert_eq!(two.stored_times(), [0.0]);
}

/// The memory estimate counts the stored series at the stored rate: the encoded
/// record of a study without series holds its spectra only.
#[test]
fn the_memory_estimate_counts_the_stored_series_only() {
    let study = |output: &str| {
        Study::from_yaml(&format!("{BASE}{output}"), Path::new("g.yaml"))
            .unwrap()
            .memory_estimate(2)
    };
    let (all, dec, none) = (
        study(""),
        study("output: {decimate: 4}\n"),
        study("output: {series: none}\n"),
    );
    let n_f = 200.0 + 1.0; // 400 analysed samples
    let spectra = (3.0 * n_f) * 8.0 * (1.0 + 1.0 / 64.0) + 4096.0;
    assert!((none.record - spectra).abs() < 1e-6, "{}", none.record);
    let series = |n: f64| 14.0 * n * 8.0 * (1.0 + 1.0 / 64.0);
    assert!((all.record - spectra - series(501.0)).abs() < 1e-6);
    assert!((dec.record - spectra - series(126.0)).abs() < 1e-6);
    // The worker still holds the full-rate series while it analyses the case.
    assert!(none.per_case > 15.0 * 501.0 * 8.0);
    assert!(none.total < dec.total && dec.total < all.total);
}

/// `--dry-run` says how many series and samples a case stores.
#[test]
fn the_dry_run_shows_the_stored_series() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "g.yaml",
        &format!("{BASE}output: {{series: [crank_moment], decimate: 5}}\n"),
    );
    let out = studyrun(dir.path(), &["g.yaml", "--dry-run"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("1 stored series x 101 samples (output.decimate 5)")
            && text.contains("of 1 stored series x 101 samples"),
        "{text}"
    );
}

/// `spectra: {max_frequency: "1 kHz"}`: the file keeps the bins up to 1 kHz of every
/// `[case, frequency]` variable (amplitude and envelope spectra), the same bits as the
/// first bins of the full study's; the spectral kurtosis keeps its own axis whole;
/// metrics, which use every bin, are unchanged.
#[test]
fn max_frequency_stores_the_bins_up_to_it_and_changes_no_metric() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let envelope = "envelope: {channels: [bearing_force], band: auto}\noutput: {series: none}\n";
    let full = run(d, "full", envelope);
    let cut = run(
        d,
        "cut",
        &format!("{envelope}spectra: {{max_frequency: \"1 kHz\"}}\n"),
    );
    let (lf, lc) = (full.layout(), cut.layout());
    // 0.04 s analysed at 10 kHz: 400 samples, 25 Hz bins, 0 ..= 1000 Hz is 41 of them.
    assert_eq!(lf.frequencies.len(), 201);
    assert_eq!(lc.frequencies.len(), 41);
    assert_eq!(lc.frequencies[..], lf.frequencies[..41]);
    assert_eq!(lc.spectra, lf.spectra);
    assert_eq!(lc.kurtosis, lf.kurtosis);
    assert_eq!(lc.sk_frequencies, lf.sk_frequencies);
    // 400 samples: STFT segments of 32, 17 frequencies up to the Nyquist frequency.
    assert_eq!(lc.sk_frequencies.len(), 17);
    assert!(matches!(
        cut.attribute("max_frequency"),
        Some(AttrValue::F64(f)) if *f == 1000.0
    ));
    for row in 0..lf.n_cases() {
        let (f, c) = (
            read_case_but_wall_time(&full, row),
            read_case_but_wall_time(&cut, row),
        );
        assert_eq!(bits(&f.metrics), bits(&c.metrics), "metrics of row {row}");
        for (k, (x, y)) in f.spectra.iter().zip(&c.spectra).enumerate() {
            let kept = if k < lf.spectra.len() { 41 } else { x.len() };
            assert_eq!(bits(&x[..kept]), bits(y), "spectrum {k} of row {row}");
        }
    }
    let size = |name: &str| std::fs::metadata(d.join(name)).unwrap().len();
    assert!(
        size("cut.h5") < size("full.h5"),
        "{} {}",
        size("cut.h5"),
        size("full.h5")
    );
    for (value, needle) in [
        ("\"0 Hz\"", "0 Hz\" is not allowed"),
        ("\"6 kHz\"", "at most sample_rate/2 = 5000 Hz"),
        ("\"1 s\"", "spectra.max_frequency"),
    ] {
        let text = format!("{BASE}spectra: {{max_frequency: {value}}}\n");
        let err = Study::from_yaml(&text, Path::new("grid.yaml"))
            .expect_err(value)
            .to_string();
        assert!(
            err.contains("`spectra.max_frequency`") && err.contains(needle),
            "{err}"
        );
    }
}
