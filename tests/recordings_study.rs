//! `recordings:` studies (docs/grid-file.md, Recordings): measured recordings, one
//! case each, through the chain a simulated channel goes through, into the same file
//! layout. The fixtures are the synthetic rig recordings of
//! tests/data/recordings/rig (make.py there): an outer-race fault (BPFO impacts), an
//! inner-race fault (BPFI impacts modulated at the shaft speed) and a healthy
//! bearing, at 12 kHz and 1800 rpm, of 6000, 7200 and 6600 samples.

use std::path::{Path, PathBuf};

use studyrun::output::StudyReader;
use studyrun::recordings::read::{read_samples, Selector};
use studyrun::study::Study;

/// The fixtures' folder.
fn rig() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/recordings/rig")
}

/// The bearing and envelope of the fixtures' study.
const HEAD: &str = "name: rig\n\
bearing: {ball_count: 9, geometry: {ball_diameter: \"7.94 mm\", pitch_diameter: \"39.04 mm\"}}\n\
envelope: {channels: [vibration], band: auto}\n";

/// The three fixtures as `recordings:` entries (absolute paths).
fn recordings() -> String {
    let r = rig();
    format!(
        "recordings:\n\
  - {{file: {o}, sample_rate: \"12 kHz\", rpm: 1800, fault: outer}}\n\
  - {{file: {i}, channel_index: 0, sample_rate: \"12 kHz\", rpm: 1800, fault: inner}}\n\
  - {{file: {h}, variable: rig.de, sample_rate: \"12 kHz\", rpm: 1800, fault: none}}\n",
        o = r.join("outer.npy").display(),
        i = r.join("inner.wav").display(),
        h = r.join("healthy.mat").display(),
    )
}

/// The value of metric `name` in case `row` of `reader`.
fn metric(reader: &StudyReader, row: usize, name: &str) -> f64 {
    let k = reader
        .layout()
        .metrics
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| panic!("no metric {name}"));
    reader.read_case(row).unwrap().metrics[k]
}

/// The envelope band energies name each recording's fault: the labelled line's is
/// the largest of BPFO, BPFI and 2·BSF by a factor 10 and more, the healthy
/// recording's lines all 100 times below the outer-race fault's. The
/// characteristic frequencies are the closed forms of docs/model.md §7.3 with the
/// outer race fixed.
#[test]
fn band_energies_name_each_recordings_fault() {
    let dir = tempfile::tempdir().unwrap();
    let reader = crate::common::run_study(dir.path(), "rig", &format!("{HEAD}{}", recordings()));
    let energy =
        |row: usize, line: &str| metric(&reader, row, &format!("vibration_envelope_energy_{line}"));
    let lines = ["bpfo", "bpfi", "2bsf"];
    for (row, fault) in [(0, "bpfo"), (1, "bpfi")] {
        let e: Vec<f64> = lines.iter().map(|l| energy(row, l)).collect();
        let labelled = e[lines.iter().position(|l| *l == fault).unwrap()];
        for (l, x) in lines.iter().zip(&e) {
            if *l != fault {
                assert!(
                    labelled > 10.0 * x,
                    "row {row}: {fault} {labelled} vs {l} {x}"
                );
            }
        }
    }
    for l in lines {
        assert!(energy(2, l) < 0.01 * energy(0, "bpfo"), "healthy {l}");
    }
    let (f, ratio) = (30.0, 7.94 / 39.04);
    let closed = [
        ("ftf", f / 2.0 * (1.0 - ratio)),
        ("bpfo", 4.5 * f * (1.0 - ratio)),
        ("bpfi", 4.5 * f * (1.0 + ratio)),
        ("bsf", f / (2.0 * ratio) * (1.0 - ratio * ratio)),
    ];
    for (name, want) in closed {
        let got = metric(&reader, 0, name);
        assert!((got - want).abs() < 1e-9 * want, "{name}: {got} vs {want}");
    }
    // The band chosen sits inside the Nyquist band and holds the 3 kHz resonance.
    let (low, high) = (
        metric(&reader, 0, "vibration_envelope_band_low"),
        metric(&reader, 0, "vibration_envelope_band_high"),
    );
    assert!(
        low < 3000.0 && 3000.0 < high && high <= 6000.0,
        "[{low}, {high}]"
    );
}

/// The file holds what docs/result-file.md says of a recordings study: the series
/// `vibration` over the shortest recording's samples, bit for bit the file's; each
/// recording's sample count, file and label; no reference, no deviation or
/// integrator metric, no `location`.
#[test]
fn the_file_holds_the_recordings_and_no_reference() {
    let dir = tempfile::tempdir().unwrap();
    let reader = crate::common::run_study(dir.path(), "rig", &format!("{HEAD}{}", recordings()));
    let l = reader.layout();
    assert_eq!(l.times.len(), 6000, "the shortest recording's samples");
    assert_eq!((l.reference_ids.len(), l.reference_index.len()), (0, 0));
    let names: Vec<&str> = l.series.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["vibration"]);
    let param = |name: &str| {
        l.parameters
            .iter()
            .find(|p| p.spec.name == name)
            .unwrap_or_else(|| panic!("no parameter {name}"))
    };
    assert_eq!(
        format!("{:?}", param("recording_samples").values),
        "F64([6000.0, 7200.0, 6600.0])"
    );
    assert_eq!(
        format!("{:?}", param("fault").values),
        "Str([\"outer\", \"inner\", \"none\"])"
    );
    assert!(l.parameters.iter().all(|p| p.spec.name != "location"));
    for absent in [
        "slider_acceleration_rms_deviation",
        "steps",
        "max_bearing_force",
    ] {
        assert!(l.metrics.iter().all(|m| m.name != absent), "{absent}");
    }
    let stored = &reader.read_case(0).unwrap().series[0];
    let file = read_samples(&rig().join("outer.npy"), &Selector::None).unwrap();
    assert_eq!(
        crate::common::bits(stored),
        crate::common::bits(&file.values)
    );
    let out = crate::common::studyrun_ok(dir.path(), &["inspect", "rig.h5"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("3 ok, 0 failed"), "{text}");
    assert!(
        text.contains("solver:   none (measured recordings"),
        "{text}"
    );
}

/// One worker, two, and two shards merged write the same bits.
#[test]
fn recordings_are_the_same_for_any_jobs_and_shards() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = format!("{HEAD}{}", recordings());
    std::fs::write(d.join("rig.yaml"), &text).unwrap();
    let ok = |args: &[&str]| crate::common::studyrun_ok(d, args);
    ok(&["rig.yaml", "-j", "1", "-o", "one.h5", "-q"]);
    ok(&["rig.yaml", "-j", "2", "-o", "two.h5", "-q"]);
    crate::cli::assert_same_data(&d.join("one.h5"), &d.join("two.h5"));
    for k in 1..=2 {
        let (shard, out) = (format!("{k}/2"), format!("p{k}.h5"));
        ok(&["run", "rig.yaml", "--shard", &shard, "-o", &out, "-q"]);
    }
    ok(&["merge", "merged.h5", "p2.h5", "p1.h5"]);
    crate::cli::assert_same_data(&d.join("one.h5"), &d.join("merged.h5"));
    // A finished run resumed is already complete, the same file.
    ok(&["rig.yaml", "-o", "one.h5", "--resume", "-q"]);
    crate::cli::assert_same_data(&d.join("one.h5"), &d.join("two.h5"));
}

/// The example study reads its fixtures relative to its own folder, whatever the
/// working directory.
#[test]
fn relative_files_resolve_against_the_grid_files_folder() {
    let grid = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/recordings.yaml");
    let study = Study::load(&grid).unwrap_or_else(|e| panic!("{e}"));
    let list = &study.recordings.as_ref().unwrap().list;
    assert_eq!(list.len(), 3);
    assert!(list.iter().all(|r| r.file.is_file()), "{list:?}");
    assert_eq!(study.sampling.len(), 6000);
    assert_eq!(study.spectrum_channels[0].name, "vibration");
}

/// `window:` sets the analysed length, `series:` the series' name; a contact angle
/// moves the lines as `cos φ` does (docs/model.md §7.3), and a simulated study
/// refuses one.
#[test]
fn window_series_and_contact_angle() {
    let text = format!(
        "{}window: \"0.25 s\"\nseries: accel\n{}",
        HEAD.replace("[vibration]", "[accel]")
            .replace("39.04 mm\"", "39.04 mm\", contact_angle: \"30 deg\""),
        recordings()
    );
    let study = crate::common::study(&text);
    assert_eq!(study.sampling.len(), 3001);
    assert_eq!(study.spectrum_channels[0].name, "accel");
    let b = &study.cases[0].params.bearing;
    let freqs = studyrun::signal::fault_frequencies::FaultFrequencies::of(&study.cases[0].params);
    let g = 7.94 / 39.04 * (30f64).to_radians().cos();
    assert!(
        (freqs.bpfo - 135.0 * (1.0 - g)).abs() < 1e-9,
        "{}",
        freqs.bpfo
    );
    assert!(
        (freqs.bpfi - 135.0 * (1.0 + g)).abs() < 1e-9,
        "{}",
        freqs.bpfi
    );
    assert!((b.contact_angle - 30f64.to_radians()).abs() < 1e-15);
    // A speed profile per recording: its lines move (NaN), its fields are recorded.
    let ramp = format!("{HEAD}{}", recordings()).replacen(
        "rpm: 1800, fault: outer",
        "speed: {profile: ramp, from: 1200, to: 1800, over: 0.5}, fault: outer",
        1,
    );
    let study = crate::common::study(&ramp);
    let p = &study.cases[0].params;
    assert_eq!(p.speed.as_ref().map(|s| s.name()), Some("ramp"));
    let lines = studyrun::signal::fault_frequencies::FaultFrequencies::of(p);
    assert!(lines.bpfo.is_nan() && study.cases[1].params.constant_rpm() == Some(1800.0));
    let layout = studyrun::study::study_layout(&study, &[0, 1, 2], None);
    assert!(layout
        .parameters
        .iter()
        .any(|q| q.spec.name == "speed_from"));
    let err = crate::common::refused(
        "name: s\nduration: 0.1\nsample_rate: 1000\nbearing: {geometry: {contact_angle: \"10 deg\"}}\n",
    );
    assert!(
        err.contains("`bearing.geometry.contact_angle`") && err.contains("planar"),
        "{err}"
    );
}

/// Writes `text` as `dir/<name>` and returns its path.
fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

/// The refusal of a study of `HEAD` with one more recording `entry` after the
/// fixtures (recording 3), or of `extra` top-level keys.
fn refused_with(entry: &str, extra: &str) -> String {
    crate::common::refused(&format!("{HEAD}{extra}{}{entry}", recordings()))
}

/// Bad input is refused before anything runs, naming the recording (its index and
/// file) and the field.
#[test]
fn bad_recordings_are_refused_naming_recording_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let nan = write(d, "nan.csv", "x\n0.5\nnan\n1.0\n");
    let short = write(d, "short.csv", "x\n0.5\n1.0\n");
    let txt = write(d, "rec.txt", "0.5\n");
    let outer = rig().join("outer.npy").display().to_string();
    let entry = |file: &str, more: &str| {
        format!("- {{file: {file}, sample_rate: \"12 kHz\", rpm: 1800, fault: outer{more}}}\n")
    };
    let cases: Vec<(String, &str, Vec<String>)> = vec![
        (
            entry("/nonexistent/x.npy", ""),
            "recordings[3].file",
            vec!["recording 3".into(), "no such file".into()],
        ),
        (
            entry(
                &rig().join("healthy.mat").display().to_string(),
                ", variable: rig.xx",
            ),
            "recordings[3].variable",
            vec!["recording 3".into(), "healthy.mat".into()],
        ),
        (
            entry(&nan, ""),
            "recordings[3].file",
            vec!["nan.csv".into(), "finite".into()],
        ),
        (
            entry(&short, ""),
            "recordings[3].file",
            vec!["short.csv".into(), "too short".into()],
        ),
        (
            entry(&txt, ""),
            "recordings[3].file",
            vec!["rec.txt".into(), "unknown extension".into()],
        ),
        (
            entry(&outer, "").replace("12 kHz", "10 kHz"),
            "recordings[3].sample_rate",
            vec!["recording 3".into(), "one sample rate".into()],
        ),
        (
            entry(&outer, "").replace("outer}", "cage}"),
            "recordings[3].fault",
            vec!["`cage`".into()],
        ),
        (
            entry(
                &outer,
                ", speed: {profile: ramp, from: 600, to: 1200, over: 1}",
            ),
            "recordings[3].speed",
            vec!["not both".into()],
        ),
        (
            entry(&outer, ", variable: a, column: 0"),
            "recordings[3].column",
            vec!["one of".into()],
        ),
    ];
    for (e, field, needles) in cases {
        let err = refused_with(&e, "");
        assert!(err.contains(&format!("`{field}`")), "{field} not in: {err}");
        for n in needles {
            assert!(err.contains(&n), "`{n}` not in: {err}");
        }
    }
    let top: [(&str, &str, &str); 8] = [
        ("window: \"1 s\"\n", "`recordings[0].file`", "for `window`"),
        ("joint: dry_clearance\n", "`joint`", "outer race fixed"),
        (
            "journal: {clearance: \"0.1 mm\"}\n",
            "`journal`",
            "outer race fixed",
        ),
        ("duration: 1\n", "`duration`", "disagrees"),
        ("sample_rate: 10000\n", "`sample_rate`", "disagrees"),
        ("grid: {rpm: [600]}\n", "`grid`", "recordings"),
        ("rpm: 600\n", "`rpm`", "each recording"),
        (
            "spectra: {channels: [slider_acceleration]}\n",
            "`spectra.channels[0]`",
            "vibration",
        ),
    ];
    for (extra, field, needle) in top {
        let err = refused_with("", extra);
        assert!(
            err.contains(field) && err.contains(needle),
            "{extra}: {err}"
        );
    }
    // What agrees is accepted.
    crate::common::study(&format!(
        "{HEAD}sample_rate: 12000\nduration: 0.4999166666666667\n{}",
        recordings()
    ));
    // A simulated study takes neither `window` nor a missing `duration`.
    let err = crate::common::refused("name: s\nduration: 0.1\nsample_rate: 1000\nwindow: 0.05\n");
    assert!(
        err.contains("`window`") && err.contains("recordings"),
        "{err}"
    );
    let err = crate::common::refused("name: s\nsample_rate: 1000\n");
    assert!(
        err.contains("`duration`") && err.contains("missing"),
        "{err}"
    );
}

/// With a known speed a recording gets order spectra: the squared envelope's order
/// spectrum of the outer-race recording peaks at the BPFO order (BPFO / 30 Hz =
/// 3.585 cycles per revolution) among the orders up to 5; a recording without a speed
/// makes order spectra refused.
#[test]
fn order_spectra_of_a_recording_with_a_speed() {
    let dir = tempfile::tempdir().unwrap();
    let head = HEAD.replace("band: auto}", "band: auto, orders: true}");
    let reader = crate::common::run_study(dir.path(), "orders", &format!("{head}{}", recordings()));
    let l = reader.layout();
    let names: Vec<&str> = l.order_spectra.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["vibration_envelope_order_spectrum"]);
    let case = reader.read_case(0).unwrap();
    let spectrum = &case.metrics[l.metrics.len()..];
    assert_eq!(spectrum.len(), l.orders.len());
    let peak = (0..l.orders.len())
        .filter(|&k| l.orders[k] > 1.0 && l.orders[k] < 5.0)
        .max_by(|&a, &b| spectrum[a].total_cmp(&spectrum[b]))
        .unwrap();
    let bpfo_order = metric(&reader, 0, "bpfo_order");
    assert!(
        (l.orders[peak] - bpfo_order).abs() < 0.1,
        "peak at {} vs {bpfo_order}",
        l.orders[peak]
    );
    let no_speed =
        format!("{head}{}", recordings()).replace(", rpm: 1800, fault: outer", ", fault: outer");
    let err = crate::common::refused(&no_speed);
    assert!(
        err.contains("`envelope.orders`") && err.contains("case 0"),
        "{err}"
    );
}

/// The 14 MFPT recordings (`../shared/data/mfpt`, never part of the repository; the
/// test says SKIPPED without them) as a recordings study read from their MAT files:
/// the characteristic orders are the data set README's (BPFO 3.245, BPFI 4.755, BSF
/// 2.556, FTF 0.406 per shaft revolution, to 0.002), and with `band: auto` the
/// labelled fault's band energy is the largest of BPFO, BPFI and 2·BSF in all 14.
#[test]
fn mfpt_recordings_study_names_every_fault() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mfpt");
    if !data.is_dir() {
        println!("SKIPPED: {} absent", data.display());
        return;
    }
    let mut text = String::from(
        "name: mfpt\n\
bearing: {ball_count: 8, geometry: {ball_diameter: \"5.969 mm\", pitch_diameter: \"31.623 mm\"}}\n\
envelope: {channels: [vibration], band: auto}\n\
output: {series: none}\n\
recordings:\n",
    );
    let mut labels = Vec::new();
    for (prefix, fault, line) in [
        ("InnerRaceFault", "inner", "bpfi"),
        ("OuterRaceFault", "outer", "bpfo"),
    ] {
        for load in 1..=7 {
            let file = data.join(format!("{prefix}_vload_{load}.mat"));
            text += &format!(
                "- {{file: {}, variable: bearing.gs, sample_rate: \"48828 Hz\", rpm: 1500, fault: {fault}}}\n",
                file.display()
            );
            labels.push(line);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let reader = crate::common::run_study(dir.path(), "mfpt", &text);
    for (name, want) in [
        ("bpfo_order", 3.245),
        ("bpfi_order", 4.755),
        ("bsf_order", 2.556),
        ("ftf_order", 0.406),
    ] {
        let got = metric(&reader, 0, name);
        assert!((got - want).abs() < 2e-3, "{name}: {got} vs {want}");
    }
    for (row, labelled) in labels.iter().enumerate() {
        let energy = |l: &str| metric(&reader, row, &format!("vibration_envelope_energy_{l}"));
        let largest = ["bpfo", "bpfi", "2bsf"]
            .into_iter()
            .max_by(|a, b| energy(a).total_cmp(&energy(b)))
            .unwrap();
        assert_eq!(largest, *labelled, "row {row}");
    }
}
