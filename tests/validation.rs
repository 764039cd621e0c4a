//! Invalid inputs are refused with an error that names the field.

use studyrun::bearing::{BearingParams, RaceWaviness};
use studyrun::mechanism::{CartesianSliderCrank, CaseParams};

fn refused(case: CaseParams, field: &str) {
    let err = CartesianSliderCrank::new(&case)
        .expect_err("must be refused")
        .to_string();
    assert!(err.contains(field), "error `{err}` does not name `{field}`");
}

#[test]
fn out_of_range_inputs_are_refused_naming_the_field() {
    let with_bearing = |f: fn(&mut BearingParams)| {
        let mut c = CaseParams::default();
        f(&mut c.bearing);
        c
    };
    refused(with_bearing(|b| b.ball_count = 2), "bearing.ball_count");
    refused(
        with_bearing(|b| b.inner_race_diameter = b.outer_race_diameter),
        "bearing.inner_race_diameter",
    );
    refused(with_bearing(|b| b.stiffness = -1.0), "bearing.stiffness");
    refused(with_bearing(|b| b.damping = f64::NAN), "bearing.damping");
    refused(
        with_bearing(|b| b.clearance = f64::INFINITY),
        "bearing.clearance",
    );
    refused(
        with_bearing(|b| b.outer_waviness = RaceWaviness::single(0, 1e-6)),
        "bearing.outer_waviness.harmonics[0].number",
    );
    refused(
        with_bearing(|b| b.inner_waviness = RaceWaviness::single(35, f64::NAN)),
        "bearing.inner_waviness.harmonics[0].amplitude",
    );
    refused(
        CaseParams {
            rpm: f64::NAN,
            ..CaseParams::default()
        },
        "rpm",
    );
    let mut c = CaseParams::default();
    c.mechanism.rod_length = 0.04;
    refused(c, "mechanism.rod_length");
    let mut c = CaseParams::default();
    c.mechanism.crank_mass = 0.0;
    refused(c, "mechanism.crank_mass");
}

#[test]
fn error_message_shows_value_and_rule() {
    let mut c = CaseParams::default();
    c.bearing.ball_count = 2;
    let err = CartesianSliderCrank::new(&c).unwrap_err().to_string();
    assert_eq!(
        err,
        "invalid parameter `bearing.ball_count` = 2: an integer >= 3"
    );
}
