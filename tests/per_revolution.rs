//! The `[case, revolution]` metrics (docs/model.md §6.1): over a window of whole
//! revolutions their mean square and peak give the whole-window metrics back, the
//! revolutions are counted from the crank angle at constant and varying speed, the
//! `[case]` metrics are still §6's over the file's own series, and the values are
//! the same bits for any `-j` and from shards merged.

use std::path::Path;

use studyrun::output::{ParamValues, StudyReader};
use studyrun::signal::metrics::Deviation;
use studyrun::signal::revolutions::revolution_metric_specs;
use studyrun::study::Study;

use crate::cli::{assert_same_data, write};
use crate::common::studyrun_ok as ok;

/// 300 and 600 rpm over 0.2 s ≤ t < 0.6 s: two and four whole revolutions, 2000 and
/// 1000 samples each.
const GRID: &str = "name: revs\nduration: 0.6\nsample_rate: 10000\ntransient: \"0.2 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  rpm: [300, 600]\n";

/// The `[case, revolution]` values of `name` for file row `row`.
fn per_revolution(r: &StudyReader, row: usize, name: &str) -> Vec<f64> {
    let l = r.layout();
    let n = l.revolutions.len();
    let m = l
        .revolution_metrics
        .iter()
        .position(|s| s.name == format!("{name}_per_revolution"))
        .unwrap();
    let at = l.metrics.len() + l.replicate_metrics.len() * l.replicates.len() + m * n;
    r.read_case(row).unwrap().metrics[at..at + n].to_vec()
}

/// Over a whole number of revolutions of equal sample counts the mean over the
/// revolutions of rms² is the whole window's rms² (to 1e-12 relative) and the
/// largest per-revolution peak is the window's peak (exactly); a case with fewer
/// revolutions than the study's most is padded with NaN. The `[case]` deviations are
/// still those of the file's series against its reference series, bit for bit.
#[test]
fn whole_revolutions_give_the_window_metrics_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "revs.yaml", GRID);
    ok(d, &["revs.yaml", "-o", "revs.h5", "-q"]);
    let r = StudyReader::open(d.join("revs.h5")).unwrap();
    let l = r.layout();
    assert_eq!(l.revolutions, vec![0, 1, 2, 3]);
    assert_eq!(l.revolution_metrics, revolution_metric_specs());
    let rpm = l.parameters.iter().find(|p| p.spec.name == "rpm").unwrap();
    let window = 2000..6000;
    for row in 0..l.n_cases() {
        let c = r.read_case(row).unwrap();
        let metric = |name: &str| c.metrics[l.metrics.iter().position(|m| m.name == name).unwrap()];
        let ParamValues::F64(rpms) = &rpm.values else {
            panic!("rpm is a number");
        };
        // 0.2 s per revolution at 300 rpm, 0.1 s at 600 rpm.
        let count = (0.4 * rpms[row] / 60.0).round() as usize;
        assert!(count == 2 || count == 4, "rpm {}", rpms[row]);
        for ch in ["slider_acceleration", "crank_moment", "bearing_force"] {
            let rms = per_revolution(&r, row, &format!("{ch}_rms_deviation"));
            let peak = per_revolution(&r, row, &format!("{ch}_peak_deviation"));
            assert!(
                rms[..count].iter().all(|v| v.is_finite() && *v > 0.0),
                "{rms:?}"
            );
            assert!(rms[count..]
                .iter()
                .chain(&peak[count..])
                .all(|v| v.is_nan()));
            let mean_square = rms[..count].iter().map(|v| v * v).sum::<f64>() / count as f64;
            let whole = metric(&format!("{ch}_rms_deviation"));
            let error = (mean_square - whole * whole).abs() / (whole * whole);
            assert!(error < 1e-12, "{ch} row {row}: relative error {error:e}");
            let largest = peak[..count]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(largest, metric(&format!("{ch}_peak_deviation")), "{ch}");
        }
        // The window metrics of the channels stored with their reference.
        let reference = r.read_reference(l.reference_index[row] as usize).unwrap();
        for ch in ["slider_acceleration", "crank_moment"] {
            let s = l.series.iter().position(|s| s.name == ch).unwrap();
            let k = l
                .reference_series
                .iter()
                .position(|s| s.name == format!("reference_{ch}"))
                .unwrap();
            let dev =
                Deviation::between(&c.series[s][window.clone()], &reference[k][window.clone()]);
            assert_eq!(
                dev.rms.to_bits(),
                metric(&format!("{ch}_rms_deviation")).to_bits()
            );
            assert_eq!(
                dev.peak.to_bits(),
                metric(&format!("{ch}_peak_deviation")).to_bits()
            );
        }
    }
}

/// The study's revolution dimension is its most whole revolutions after the
/// transient: 4 for 600 rpm over 0.4 s; for a ramp from 300 to 900 rpm over 0.6 s,
/// `θ2(0.6) − θ2(0.2) = 4π + α (0.6² − 0.2²)/2` with `α = 20π/0.6 rad/s²`, 4.67
/// revolutions, so 4; a window shorter than a revolution has none and no variables.
#[test]
fn revolutions_are_counted_from_the_crank_angle() {
    let load = |text: &str| Study::from_yaml(text, Path::new("revs.yaml")).unwrap();
    assert_eq!(load(GRID).revolutions, 4);
    let ramp = "name: ramp\nduration: 0.6\nsample_rate: 10000\ntransient: \"0.2 s\"\nspeed: {profile: ramp, from: \"300 rpm\", to: \"900 rpm\", over: \"0.6 s\"}\ngrid:\n  location: [crank_ground]\n";
    assert_eq!(load(ramp).revolutions, 4);
    let slow = "name: slow\nduration: 0.6\nsample_rate: 10000\ntransient: \"0.2 s\"\nspeed: {profile: ramp, from: \"100 rpm\", to: \"100 rpm\", over: \"0.6 s\"}\ngrid:\n  location: [crank_ground]\n";
    let study = load(slow);
    assert_eq!(study.revolutions, 0);
    let layout = studyrun::study::study_layout(&study, &[], None);
    assert!(layout.revolutions.is_empty() && layout.revolution_metrics.is_empty());
}

/// `-j 1`, `-j 2` and two shards merged hold the same `[case, revolution]` bits.
#[test]
fn per_revolution_metrics_are_the_same_bits_for_any_jobs_and_shards() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "revs.yaml", GRID);
    ok(d, &["revs.yaml", "-j", "1", "-o", "one.h5", "-q"]);
    ok(d, &["revs.yaml", "-j", "2", "-o", "two.h5", "-q"]);
    assert_same_data(&d.join("one.h5"), &d.join("two.h5"));
    for k in 1..=2 {
        let (shard, out) = (format!("{k}/2"), format!("part{k}.h5"));
        ok(d, &["revs.yaml", "--shard", &shard, "-o", &out, "-q"]);
    }
    ok(d, &["merge", "merged.h5", "part2.h5", "part1.h5"]);
    assert_same_data(&d.join("one.h5"), &d.join("merged.h5"));
    let (one, merged) = (
        StudyReader::open(d.join("one.h5")).unwrap(),
        StudyReader::open(d.join("merged.h5")).unwrap(),
    );
    assert_eq!(one.layout().revolutions, merged.layout().revolutions);
    assert_eq!(
        one.layout().revolution_metrics,
        merged.layout().revolution_metrics
    );
    // The comparison covers real values: four finite revolutions at 600 rpm.
    let row = (0..one.layout().n_cases())
        .find(|&row| per_revolution(&one, row, "bearing_force_rms_deviation")[3].is_finite())
        .unwrap();
    assert_eq!(
        format!(
            "{:?}",
            per_revolution(&one, row, "slider_acceleration_peak_deviation")
        ),
        format!(
            "{:?}",
            per_revolution(&merged, row, "slider_acceleration_peak_deviation")
        )
    );
}
