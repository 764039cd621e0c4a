//! A study file as a labelled data set: a healthy bearing is labelled healthy in every
//! defect parameter, `noise_realization` repeats a case with its own noise, and an
//! `rpm` axis sits beside explicit cases that run a speed profile, every constant-speed
//! case storing its speed.

use studyrun::output::{Layout, ParamValues, StudyReader};
use studyrun::signal::sensor::{add_noise, noise_seed};
use studyrun::study::params::axis_value;
use studyrun::study::{study_layout, Study};

use crate::common::{bits, refused, study};

/// The values of the `[case]` parameter `name` of a layout, as numbers or texts.
fn numbers(layout: &Layout, name: &str) -> Vec<f64> {
    match &parameter(layout, name).values {
        ParamValues::F64(v) => v.clone(),
        ParamValues::Str(_) => panic!("{name} holds text"),
    }
}

fn texts(layout: &Layout, name: &str) -> Vec<String> {
    match &parameter(layout, name).values {
        ParamValues::Str(v) => v.clone(),
        ParamValues::F64(_) => panic!("{name} holds numbers"),
    }
}

fn parameter<'a>(layout: &'a Layout, name: &str) -> &'a studyrun::output::Param {
    layout
        .parameters
        .iter()
        .find(|p| p.spec.name == name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

fn whole_layout(study: &Study) -> Layout {
    let rows: Vec<usize> = (0..study.cases.len()).collect();
    study_layout(study, &rows, None)
}

const DEFECTS: &str = concat!(
    "name: healthy\nduration: 0.05\nsample_rate: 5000\nrpm: 600\n",
    "effects: [clearance, damping, defects]\n",
    "bearing:\n  defects: [{race: inner, angle: \"90 deg\", width: \"2 mm\", depth: \"20 um\", profile: flat}]\n",
    "grid:\n  defect_depth: [\"0 um\", \"20 um\"]\n  defect_race: [inner, ball]\n",
    "cases:\n  - {defect_depth: 0}\n",
);

/// A healthy bearing made the documented ways (`defect_depth: 0` as an axis value or
/// in a case, over a defect of the base case) stores NaN for the defect's angle,
/// width and depth and `none` for its race, like its `fault`; `--dry-run` shows it as
/// `none`. The defects keep their values.
#[test]
fn healthy_cases_store_no_defect_parameters() {
    let s = study(DEFECTS);
    let layout = whole_layout(&s);
    let fault = texts(&layout, "fault");
    assert_eq!(fault, ["none", "none", "inner", "ball", "none"]);
    let race = texts(&layout, "defect_race");
    assert_eq!(race, fault);
    for name in ["defect_angle", "defect_width", "defect_depth"] {
        let values = numbers(&layout, name);
        for (k, label) in fault.iter().enumerate() {
            assert_eq!(
                values[k].is_nan(),
                label == "none",
                "{name} of case {k}: {}",
                values[k]
            );
        }
    }
    assert_eq!(numbers(&layout, "defect_width")[2], 0.002);
    assert_eq!(numbers(&layout, "defect_depth")[3], 2e-5);
    assert!((numbers(&layout, "defect_angle")[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    let shown: Vec<String> = s
        .cases
        .iter()
        .map(|c| axis_value("defect_race", &c.params))
        .collect();
    assert_eq!(shown, race);
    // Without any defect, the default case: NaN and none.
    let plain = whole_layout(&study(
        "name: plain\nduration: 0.05\nsample_rate: 5000\ngrid:\n  rpm: [600]\n",
    ));
    assert!(numbers(&plain, "defect_width")[0].is_nan());
    assert_eq!(texts(&plain, "defect_race"), ["none"]);
}

const NOISY: &str = concat!(
    "name: noisy\nduration: 0.05\nsample_rate: 10000\ntransient: \"0.01 s\"\nrpm: 600\n",
    "sensors:\n  - {name: acc, channel: bearing_force_y, natural_frequency: \"2 kHz\", damping_ratio: 0.05, ",
    "noise: {snr_db: 10, seed: 7}}\n",
    "grid:\n  ball_count: [8, 9]\n  noise_realization: [0, 1, 2]\n",
);

/// Each realisation is a case of its own with the same simulation (the clean series
/// bit for bit) and the noise of `noise_seed(7, id, 0, r)`: realisation 0 the seed of
/// a study without the parameter, the others their own; two runs give the same bits.
#[test]
fn noise_realizations_are_cases_with_their_own_noise() {
    let dir = tempfile::tempdir().unwrap();
    let reader = crate::common::run_study(dir.path(), "noisy", NOISY);
    let s = study(NOISY);
    let layout = reader.layout();
    let realizations = numbers(layout, "noise_realization");
    assert_eq!(realizations, [0.0, 1.0, 2.0, 0.0, 1.0, 2.0]);
    let find = |name: &str| layout.series.iter().position(|v| v.name == name).unwrap();
    let (noisy, clean) = (find("acc"), find("acc_clean"));
    let window = s.analysis_window();
    let cases: Vec<_> = (0..6).map(|k| reader.read_case(k).unwrap()).collect();
    for (k, case) in cases.iter().enumerate() {
        let id = layout.case_ids[k];
        let r = realizations[k] as u64;
        let expected = add_noise(
            &case.series[clean],
            window.clone(),
            10.0,
            noise_seed(7, id, 0, r),
        );
        assert_eq!(
            bits(&case.series[noisy]),
            bits(&expected),
            "case {id}, realisation {r}"
        );
    }
    for group in [0..3, 3..6] {
        let first = &cases[group.start];
        for case in &cases[group.start + 1..group.end] {
            assert_eq!(bits(&case.series[clean]), bits(&first.series[clean]));
            assert_ne!(bits(&case.series[noisy]), bits(&first.series[noisy]));
        }
    }
    let again = crate::common::run_study(dir.path(), "again", NOISY);
    for (k, case) in cases.iter().enumerate() {
        assert_eq!(
            bits(&again.read_case(k).unwrap().series[noisy]),
            bits(&case.series[noisy])
        );
    }
    assert_ne!(noise_seed(7, 3, 0, 1), noise_seed(7, 3, 0, 0));
}

/// `noise_realization` is a whole number ≥ 0, a design column too; another value than
/// 0 needs a sensor with noise.
#[test]
fn noise_realizations_are_checked() {
    let head = "name: n\nduration: 0.05\nsample_rate: 10000\n";
    let sensor = "sensors:\n  - {name: acc, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1, noise: {snr_db: 10}}\n";
    for (value, shown) in [("-1", "-1"), ("1.5", "1.5")] {
        let message = refused(&format!(
            "{head}{sensor}grid:\n  noise_realization: [0, {value}]\n"
        ));
        assert!(message.contains("`grid.noise_realization[1]`"), "{message}");
        assert!(
            message.contains(&format!(
                "noise_realization must be a whole number, 0 or more, got {shown}"
            )),
            "{message}"
        );
    }
    let quiet = "sensors:\n  - {name: acc, channel: crank_moment, natural_frequency: 1000, damping_ratio: 0.1}\n";
    let message = refused(&format!(
        "{head}{quiet}grid:\n  noise_realization: [0, 3]\n"
    ));
    assert!(
        message.contains("`noise_realization`: 3 (case 1) draws another realisation of the sensors' noise, and no sensor has `noise:`"),
        "{message}"
    );
    let none = refused(&format!("{head}cases:\n  - {{noise_realization: 2}}\n"));
    assert!(none.contains("no sensor has `noise:`"), "{none}");
    let designed = study(&format!(
        "{head}{sensor}design:\n  method: random\n  samples: 32\n  parameters:\n    noise_realization: {{min: 0, max: 3}}\n"
    ));
    let drawn: Vec<u64> = designed
        .cases
        .iter()
        .map(|c| c.params.noise_realization)
        .collect();
    assert!(
        drawn.iter().all(|&r| r <= 3) && (0..=3).all(|r| drawn.contains(&r)),
        "{drawn:?}"
    );
}

const SPEEDS: &str = concat!(
    "name: speeds\nduration: 0.2\nsample_rate: 5000\n",
    "grid:\n  ball_count: [8, 9]\n  rpm: [300, 600]\n",
    "cases:\n",
    "  - {ball_count: 8, speed: {profile: ramp, from: \"300 rpm\", to: \"900 rpm\", over: \"0.2 s\"}}\n",
    "  - {ball_count: 9, speed: {profile: ramp, from: \"450 rpm\", to: \"450 rpm\", over: \"0.2 s\"}}\n",
    "  - {ball_count: 9, speed: {profile: sine, mean: \"500 rpm\", amplitude: \"0 rpm\", frequency: \"5 Hz\"}}\n",
    "  - {ball_count: 9}\n",
);

/// An `rpm` axis beside explicit cases with a `speed:` profile: the grid's cases run
/// the axis's speeds, the explicit ones their profiles (the one without its own speed
/// the base's 300 rpm), and the file stores `rpm` for every constant-speed case (a
/// profile that never changes included), NaN for the run-up only. Beside a top-level
/// `speed:` the axis is refused.
#[test]
fn an_rpm_axis_sits_beside_cases_with_a_speed_profile() {
    let s = study(SPEEDS);
    let profiles: Vec<Option<&str>> = s
        .cases
        .iter()
        .map(|c| c.params.speed.as_ref().map(|p| p.name()))
        .collect();
    assert_eq!(
        profiles,
        [
            None,
            None,
            None,
            None,
            Some("ramp"),
            Some("ramp"),
            Some("sine"),
            None
        ]
    );
    let rpm = numbers(&whole_layout(&s), "rpm");
    assert_eq!(&rpm[..4], [300.0, 600.0, 300.0, 600.0]);
    assert!(rpm[4].is_nan(), "the run-up varies");
    assert_eq!(&rpm[5..], [450.0, 500.0, 300.0]);
    assert_eq!(axis_value("rpm", &s.cases[5].params), "450");
    let message = refused(concat!(
        "name: s\nduration: 0.2\nsample_rate: 5000\n",
        "speed: {profile: ramp, from: \"300 rpm\", to: \"900 rpm\", over: \"0.2 s\"}\n",
        "grid:\n  rpm: [300, 600]\n",
    ));
    assert!(
        message.contains("`grid.rpm[0]`") && message.contains("rpm and speed both given"),
        "{message}"
    );
    let dir = tempfile::tempdir().unwrap();
    let reader: StudyReader = crate::common::run_study(dir.path(), "speeds", SPEEDS);
    assert_eq!(reader.statuses().unwrap().len(), 8);
    let stored = numbers(reader.layout(), "rpm");
    assert_eq!(bits(&stored), bits(&rpm));
}
