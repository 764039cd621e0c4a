//! `envelope:` end to end: a study without it computes and stores nothing of it and
//! is bit-identical to the same study with it in everything they share; the grid
//! key's refusals; the waviness lines in the envelope spectrum of the bearing force.

use std::path::Path;

use crate::common::run_study as run;

use studyrun::signal::metric_specs;
use studyrun::study::Study;

const BASE: &str = "name: env\nduration: 0.1\nsample_rate: 10000\ntransient: \"0.02 s\"\ngrid:\n  location: [ideal, crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  rpm: [600]\n";

const ENVELOPE: &str =
    "envelope:\n  channels: [bearing_force, crank_moment]\n  band: [\"1 kHz\", \"4 kHz\"]\n";

#[test]
fn without_envelope_nothing_is_stored_and_the_rest_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let plain = run(dir.path(), "plain", BASE);
    let with = run(dir.path(), "with", &format!("{BASE}{ENVELOPE}"));
    let (lp, lw) = (plain.layout(), with.layout());
    // The plain file holds exactly the metrics and spectra of a study without
    // `envelope:` and no envelope attribute.
    assert_eq!(lp.metrics, metric_specs(None, true));
    let names: Vec<&str> = lp
        .metrics
        .iter()
        .chain(&lp.spectra)
        .map(|s| s.name.as_str())
        .collect();
    for bad in [
        "envelope", "kurtosis", "ftf", "bpfo", "bpfi", "bsf", "crest",
    ] {
        assert!(!names.iter().any(|n| n.contains(bad)), "{bad} in {names:?}");
    }
    assert!(plain.attribute("envelope_band").is_none());
    assert!(with.attribute("envelope_band").is_some());
    // The envelope file adds an envelope spectrum, a spectral kurtosis (on its own
    // `sk_frequency` axis) and 15 metrics per channel, 4 frequencies and their 4
    // orders; no order spectra unless asked.
    assert_eq!(lw.spectra.len(), lp.spectra.len() + 2);
    assert_eq!(lw.kurtosis.len(), 2);
    assert!(lp.kurtosis.is_empty() && lp.sk_frequencies.is_empty());
    assert_eq!(lw.metrics.len(), lp.metrics.len() + 2 * 15 + 8);
    assert!(lw.orders.is_empty() && lw.order_spectra.is_empty());
    assert_eq!(lw.spectra[..lp.spectra.len()], lp.spectra[..]);
    for row in 0..lp.n_cases() {
        let (a, b) = (plain.read_case(row).unwrap(), with.read_case(row).unwrap());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (x, y) in a.series.iter().zip(&b.series) {
            assert_eq!(bits(x), bits(y), "series of row {row}");
        }
        for (x, y) in a.spectra.iter().zip(&b.spectra) {
            assert_eq!(bits(x), bits(y), "spectrum of row {row}");
        }
        // Every metric of the plain study but wall_time (the last), by name.
        for (k, spec) in lp.metrics[..lp.metrics.len() - 1].iter().enumerate() {
            let j = lw.metrics.iter().position(|s| s == spec).unwrap();
            assert_eq!(
                a.metrics[k].to_bits(),
                b.metrics[j].to_bits(),
                "{} of row {row}",
                spec.name
            );
        }
        // The fixed band is stored per case; the ideal case has no bearing force
        // (NaN) but a crank moment.
        let value = |name: &str| b.metrics[lw.metrics.iter().position(|s| s.name == name).unwrap()];
        assert_eq!(value("crank_moment_envelope_band_low"), 1000.0);
        assert_eq!(value("crank_moment_envelope_band_high"), 4000.0);
        assert!(value("crank_moment_rms") > 0.0);
        let ideal = row < 2;
        assert_eq!(value("bearing_force_rms").is_nan(), ideal, "row {row}");
        assert_eq!(value("bpfo").is_nan(), ideal, "row {row}");
    }
}

#[test]
fn bad_envelope_settings_are_refused_by_field() {
    let refused = |envelope: &str| {
        Study::from_yaml(&format!("{BASE}{envelope}"), Path::new("grid.yaml"))
            .expect_err("must be refused")
            .to_string()
    };
    let cases = [
        (
            "envelope:\n  channels: [bearing_forces]\n",
            "`envelope.channels[0]`: unknown channel `bearing_forces`",
        ),
        (
            "envelope:\n  channels: [bearing_force, bearing_force]\n",
            "listed twice",
        ),
        ("envelope:\n  channels: []\n", "at least one channel"),
        (
            "envelope:\n  channels: [bearing_force]\n  band: [\"4 kHz\", \"1 kHz\"]\n",
            "0 <= low < high <= sample_rate / 2 = 5000 Hz",
        ),
        (
            "envelope:\n  channels: [bearing_force]\n  band: [100, 6000]\n",
            "[100 Hz, 6000 Hz] is not allowed",
        ),
        (
            "envelope:\n  channels: [bearing_force]\n  band: [\"1 kHz\"]\n",
            "1 values; expected two frequencies",
        ),
        (
            "envelope:\n  channels: [bearing_force]\n  band: narrow\n",
            "expected `auto`, `kurtogram` or two frequencies",
        ),
        (
            "envelope:\n  channels: [bearing_force]\n  band: [1001, 1009]\n",
            "holds no frequency bin of the analysed window (800 samples: bins every 12.5 Hz)",
        ),
        (
            "envelope:\n  channels: [bearing_force]\n  band: [\"1 kg\", 2000]\n",
            "envelope.band",
        ),
    ];
    for (envelope, needle) in cases {
        let err = refused(envelope);
        assert!(err.contains(needle), "{err:?} lacks {needle:?}");
        // `channels:` is on line 10 of the grid, `band:` on line 11.
        let line = if envelope.contains("band") { 11 } else { 10 };
        assert!(
            err.starts_with(&format!("grid.yaml:{line}:")),
            "{err:?} lacks line {line}"
        );
    }
    let ok = Study::from_yaml(
        &format!("{BASE}envelope:\n  channels: [bearing_force]\n"),
        Path::new("grid.yaml"),
    )
    .unwrap();
    assert_eq!(
        ok.envelope.unwrap().band,
        studyrun::signal::envelope::BandChoice::Auto
    );
}

#[test]
fn inner_waviness_shows_in_the_bearing_force_envelope() {
    // crank_ground at 600 rpm, the paper's bearing (9 balls), waviness of 35 waves on
    // both races or none; 0.4 s analysed at 20 kHz (2.5 Hz bins), band by the
    // kurtogram (`band: kurtogram`: the line tested, 36 f_in, is none of the
    // candidate lines `auto` weighs). Inner waviness under the balls gives a bearing
    // force turning with orders q N_b = N_w + 1 = 36 of the inner pass frequency
    // f_in = BPFI / N_b; the load turns with the crank, so |F| is modulated at
    // 36 f_in = 221.3 Hz. Measured: that line is 29x the flat races' (0.0234 against
    // 0.0008 N²) and 3.7x the wavy spectrum's median up to 1 kHz; asserted: 5x and 2x.
    let dir = tempfile::tempdir().unwrap();
    let text = "name: wavy\nduration: 0.45\nsample_rate: 20000\ntransient: \"0.05 s\"\n\
                envelope:\n  channels: [bearing_force]\n  band: kurtogram\n\
                grid:\n  location: [crank_ground]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  rpm: [600]\n";
    let r = run(dir.path(), "wavy", text);
    let l = r.layout();
    let spectrum = l
        .spectra
        .iter()
        .position(|s| s.name == "bearing_force_envelope_spectrum")
        .unwrap();
    let bpfi = l.metrics.iter().position(|s| s.name == "bpfi").unwrap();
    let (flat, wavy) = (r.read_case(0).unwrap(), r.read_case(1).unwrap());
    let f_in = wavy.metrics[bpfi] / 9.0;
    let line = |env: &[f64]| {
        l.frequencies
            .iter()
            .zip(env)
            .filter(|(f, _)| (**f - 36.0 * f_in).abs() <= 2.5)
            .map(|(_, a)| *a)
            .fold(0.0, f64::max)
    };
    let (a_flat, a_wavy) = (line(&flat.spectra[spectrum]), line(&wavy.spectra[spectrum]));
    let mut floor: Vec<f64> = wavy.spectra[spectrum][1..400].to_vec();
    floor.sort_by(f64::total_cmp);
    let median = floor[floor.len() / 2];
    assert!(a_wavy > 5.0 * a_flat, "{a_wavy} vs flat {a_flat}");
    assert!(a_wavy > 2.0 * median, "{a_wavy} vs median {median}");
}
