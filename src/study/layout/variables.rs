//! The data variables of a study's file: series, metrics and the ideal references'
//! series.

use crate::output::VarSpec;
use crate::signal::metric_specs;
use crate::signal::replicates::{chaos_specs, summary_specs};
use crate::simulate::CHANNELS;
use crate::study::Study;

/// The `[case]` metrics of a study's file: [`metric_specs`], then with replicates
/// their [`summary_specs`], then with the chaos check its [`chaos_specs`].
pub fn study_metric_specs(study: &Study) -> Vec<VarSpec> {
    let mut specs = metric_specs(study.envelope.as_ref(), study.recordings.is_none());
    if study.replicates.is_some() {
        specs.extend(summary_specs());
    }
    if study.chaos_check {
        specs.extend(chaos_specs());
    }
    specs
}

/// The `[case, time]` variables of a study's file: its stored channels
/// ([`Study::stored_channels`]), then its stored sensor series, then a recordings
/// study's measured series ([`Study::stores_recording`]).
pub(super) fn stored_series_specs(study: &Study) -> Vec<VarSpec> {
    let sensors: Vec<VarSpec> = study.sensors.iter().flat_map(|s| s.specs()).collect();
    let channels = study.stored_channels().into_iter().map(|k| {
        let c = &CHANNELS[k];
        VarSpec::new(c.name, c.units, c.long_name)
    });
    let sensors = study
        .stored_sensor_series()
        .into_iter()
        .map(|k| sensors[k].clone());
    let recording = study
        .recordings
        .iter()
        .filter(|_| study.stores_recording())
        .map(|r| {
            let s = &r.series;
            VarSpec::new(s.name.clone(), s.units, s.long_name.clone())
        });
    channels.chain(sensors).chain(recording).collect()
}

/// The reference series an ideal run may store: the channels an ideal mechanism has.
pub const REFERENCE_CHANNELS: [&str; 6] = [
    "slider_acceleration",
    "crank_moment",
    "crank_ground_force_x",
    "crank_ground_force_y",
    "crank_rod_force_x",
    "crank_rod_force_y",
];

/// The channels of [`REFERENCE_CHANNELS`] a study's file stores for each ideal run:
/// those among its stored channels ([`Study::stored_channels`]), at the same
/// decimation.
pub fn stored_reference_channels(study: &Study) -> Vec<&'static str> {
    let stored: Vec<&str> = study
        .stored_channels()
        .into_iter()
        .map(|k| CHANNELS[k].name)
        .collect();
    REFERENCE_CHANNELS
        .into_iter()
        .filter(|c| stored.contains(c))
        .collect()
}

/// The [`VarSpec`]s of the reference series a study's file stores
/// (`reference_<channel>` for each of [`stored_reference_channels`]).
pub fn reference_specs(study: &Study) -> Vec<VarSpec> {
    stored_reference_channels(study)
        .iter()
        .map(|name| {
            let ch = CHANNELS
                .iter()
                .find(|c| c.name == *name)
                .expect("reference channels exist");
            VarSpec::new(
                format!("reference_{name}"),
                ch.units,
                format!("ideal mechanism: {}", ch.long_name),
            )
        })
        .collect()
}
