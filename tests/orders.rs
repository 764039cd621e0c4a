//! Order spectra (docs/model.md §7.9): a tone locked to the crank angle of a run-up
//! is one line in the order spectrum and smeared in the ordinary spectrum; an
//! outer-race defect in a run-up shows at BPFO's order in the envelope order
//! spectrum; sensor series as analysis channels; what a study not asking stores.

use std::path::Path;

use crate::common::run_study as run;

use studyrun::mechanism::SpeedProfile;
use studyrun::signal::order::{whole_revolutions, AngleResampling};
use studyrun::signal::spectrum::{SpectrumPlan, Window};
use studyrun::study::Study;

#[test]
fn a_tone_locked_to_the_crank_angle_is_one_order_line() {
    // x(t) = cos(k θ2(t)), θ2 of a run-up 300 → 900 rpm over 0.5 s, sampled at
    // 10 kHz; window 0.05 s to 0.5 s (4500 samples, 4 whole revolutions: orders
    // every 1/4). Order k = 9 sits on bin 36 and reads 1, the convention's
    // amplitude, to the Catmull–Rom interpolation's error (measured 1.6e-7;
    // asserted 1e-5); the ordinary spectrum spreads the tone over 45..135 Hz
    // (measured peak 0.33; asserted below 0.5).
    let drive = SpeedProfile::Ramp {
        from: 300.0,
        to: 900.0,
        over: 0.5,
    }
    .drive();
    let rate = 10_000.0;
    let times: Vec<f64> = (0..5001).map(|j| j as f64 / rate).collect();
    let window = 500..5000;
    let k = 9.0;
    let x: Vec<f64> = times[window.clone()]
        .iter()
        .map(|&t| (k * drive.motion(t).angle).cos())
        .collect();
    let r = whole_revolutions(&drive, times[window.start], times[window.end - 1]);
    assert_eq!(r, 4);
    let m = window.len();
    let resampling = AngleResampling::new(&drive, &times, window.clone(), r, m);
    let mut angle = vec![0.0; m];
    resampling.resample(&x, &mut angle);
    let mut plan = SpectrumPlan::new(m, Window::Hann).unwrap();
    let mut orders = vec![0.0; plan.bins()];
    plan.amplitude(&angle, &mut orders).unwrap();
    let line = orders[(k as usize) * r];
    println!("order {k} line {line:.9}");
    assert!((line - 1.0).abs() < 1e-5, "order line {line}");
    // Nothing else stands out: beyond the line's Hann neighbours, below 1e-3.
    let k0 = (k as usize) * r;
    for (b, a) in orders.iter().enumerate() {
        if b + 1 < k0 || b > k0 + 1 {
            assert!(*a < 1e-3, "order bin {b}: {a}");
        }
    }
    let mut time_spectrum = vec![0.0; plan.bins()];
    plan.amplitude(&x, &mut time_spectrum).unwrap();
    let peak = time_spectrum.iter().copied().fold(0.0, f64::max);
    println!("ordinary spectrum peak {peak:.4}");
    assert!(peak < 0.5, "ordinary spectrum peak {peak}");
}

/// A run-up at crank_ground (300 → 900 rpm over 0.6 s) with an outer-race defect
/// or none, no waviness, analysed from 0.1 s; the bearing force's envelope order
/// spectrum and a sensor's order spectrum.
///
/// The load turns with the crank past the fixed defect, so the defect's impacts
/// come in bursts once per revolution: lines at BPFO's order and its harmonics
/// with sidebands at every integer order, a dense comb. Measured (orders every
/// 0.2): at BPFO's order 3.467 the bearing force's envelope order spectrum reads
/// 19.0 N² against 2.1e-3 N² without the defect (x9100), at 2 BPFO x27000; the
/// noise-free sensor's 0.134 against 1.6e-5 N² (x8300). Asserted: x3.
const RUN_UP: &str = "name: runup\nduration: 0.6\nsample_rate: 20000\ntransient: \"0.1 s\"\n\
effects: [clearance, damping, defects]\nlocation: crank_ground\n\
speed: {profile: ramp, from: \"300 rpm\", to: \"900 rpm\", over: \"0.6 s\"}\n\
bearing:\n  defects: [{race: outer, angle: \"270 deg\", width: \"1 mm\", depth: \"20 um\"}]\n\
sensors:\n  - {name: acc, channel: bearing_force_y, natural_frequency: \"3 kHz\", damping_ratio: 0.05}\n\
spectra:\n  channels: [bearing_force, acc]\n  orders: true\n\
envelope:\n  channels: [bearing_force, acc_clean]\n  band: auto\n  orders: true\n\
grid:\n  defect_depth: [\"0 um\", \"20 um\"]\n";

#[test]
fn an_outer_race_defect_shows_at_the_bpfo_order_in_a_run_up() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(dir.path(), "runup", RUN_UP);
    let l = r.layout();
    let names: Vec<&str> = l.order_spectra.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "bearing_force_order_spectrum",
            "acc_order_spectrum",
            "bearing_force_envelope_order_spectrum",
            "acc_clean_envelope_order_spectrum"
        ]
    );
    assert_eq!(l.order_spectra[1].units, "N");
    assert_eq!(l.order_spectra[3].units, "N2");
    let summary = studyrun::inspect(&dir.path().join("runup.h5")).unwrap();
    let line = summary.lines().find(|s| s.starts_with("orders:")).unwrap();
    assert!(
        line.contains(&format!("{} bins", l.orders.len())) && line.ends_with(&names.join(", ")),
        "{line}"
    );
    assert!(l
        .spectra
        .iter()
        .any(|s| s.name == "acc_clean_envelope_spectrum"));
    let metric = |name: &str| l.metrics.iter().position(|s| s.name == name).unwrap();
    let order_values = l.n_metric_values() - l.order_spectra.len() * l.orders.len();
    let n_ord = l.orders.len();
    let spectrum = |row: usize, k: usize| {
        let c = r.read_case(row).unwrap();
        c.metrics[order_values + k * n_ord..order_values + (k + 1) * n_ord].to_vec()
    };
    let (flat, defect) = (r.read_case(0).unwrap(), r.read_case(1).unwrap());
    // BPFO is NaN in Hz for a run-up and defined as an order.
    assert!(defect.metrics[metric("bpfo")].is_nan());
    let bpfo = defect.metrics[metric("bpfo_order")];
    assert_eq!(bpfo, flat.metrics[metric("bpfo_order")]);
    let (di, d_o) = (29.2e-3, 46.6e-3);
    assert!((bpfo - 4.5 * 2.0 * di / (di + d_o)).abs() < 1e-12, "{bpfo}");
    let dk = l.orders[1];
    let line = |s: &[f64], o: f64| {
        l.orders
            .iter()
            .zip(s)
            .filter(|(q, _)| (**q - o).abs() <= dk)
            .map(|(_, a)| *a)
            .fold(0.0, f64::max)
    };
    for k in [2, 3] {
        let (a_flat, a_defect) = (line(&spectrum(0, k), bpfo), line(&spectrum(1, k), bpfo));
        let (h_flat, h_defect) = (
            line(&spectrum(0, k), 2.0 * bpfo),
            line(&spectrum(1, k), 2.0 * bpfo),
        );
        println!(
            "{}: BPFO order {bpfo:.4} line {a_defect:.4e} vs defect-free {a_flat:.4e} \
             (x{:.1}); 2 BPFO {h_defect:.4e} vs {h_flat:.4e} (x{:.1}); order bins every {dk}",
            names[k],
            a_defect / a_flat,
            h_defect / h_flat
        );
        assert!(
            a_defect > 3.0 * a_flat,
            "{}: {a_defect} vs {a_flat}",
            names[k]
        );
    }
}

#[test]
fn order_and_sensor_channel_settings_are_checked() {
    let refused = |text: &str| {
        Study::from_yaml(text, Path::new("grid.yaml"))
            .expect_err("must be refused")
            .to_string()
    };
    let base = "name: o\nduration: 0.1\nsample_rate: 10000\ntransient: \"0.02 s\"\n\
                sensors:\n  - {name: acc, channel: bearing_force_y, natural_frequency: 2000, damping_ratio: 0.1}\n";
    let err = refused(&format!(
        "{base}spectra:\n  channels: [acc_noisy]\ngrid:\n  rpm: [300]\n"
    ));
    assert!(
        err.starts_with("grid.yaml:8:")
            && err.contains("`spectra.channels[0]`: unknown channel `acc_noisy`")
            && err.contains("slider_acceleration")
            && err.contains("acc, acc_clean"),
        "{err}"
    );
    let err = refused(&format!(
        "{base}envelope:\n  channels: [bearing_force, ac]\ngrid:\n  rpm: [300]\n"
    ));
    assert!(
        err.contains("`envelope.channels[1]`: unknown channel `ac`") && err.contains("acc_clean"),
        "{err}"
    );
    // 0.08 s at 300 rpm is 0.4 revolutions: no whole one to resample.
    let err = refused(&format!(
        "{base}grid:\n  rpm: [300]\nspectra:\n  orders: true\n"
    ));
    assert!(
        err.contains("`spectra.orders`") && err.contains("at least one whole crank revolution"),
        "{err}"
    );
    // A study not asking has no order analysis; one asking has R and M.
    let plain = Study::from_yaml(
        &format!("{base}grid:\n  rpm: [1500]\n"),
        Path::new("g.yaml"),
    )
    .unwrap();
    assert!(plain.orders.is_none());
    let asked = Study::from_yaml(
        &format!("{base}grid:\n  rpm: [1500]\nspectra:\n  channels: [acc]\n  orders: true\n"),
        Path::new("g.yaml"),
    )
    .unwrap();
    let o = asked.orders.unwrap();
    // 0.02 s to 0.0999 s at 25 rev/s: 1.9975 turns, one whole.
    assert_eq!(
        (o.revolutions, o.samples, o.spectra, o.envelope),
        (1, 800, true, false)
    );
}
