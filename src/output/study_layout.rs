//! The study file's [`Layout`] for a study (or a shard of it).

use crate::bearing::fault_label;
use crate::mechanism::CaseParams;
use crate::output::{provenance, AttrValue, Layout, Param, ParamValues, Storage, VarSpec};
use crate::signal::envelope::{kurtogram_depth, stft_segment, BandChoice, EnvelopeSettings};
use crate::signal::replicates::{chaos_specs, replicate_metric_specs, summary_specs};
use crate::signal::revolutions::revolution_metric_specs;
use crate::signal::spectrum::frequencies;
use crate::signal::{envelope_spectrum_specs, metric_specs, order_spectrum_specs};
use crate::simulate::CHANNELS;
use crate::study::Shard;
use crate::study::Study;

/// The specification this engine implements: `docs/model.md` of this studyrun
/// version (sign of the crank moment, force on the housing, cage angle in closed
/// form, the modelling decisions of §10).
pub const MODEL_CONVENTIONS: &str = concat!(
    "docs/model.md of studyrun ",
    env!("CARGO_PKG_VERSION"),
    " (Xu & Li 2014 restated; decisions in section 10)"
);

/// Identifies a study run: grid text, studyrun version and shard. A journal or a
/// shard file is only combined with others of the same study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StudyFingerprint(pub u64);

impl StudyFingerprint {
    /// The fingerprint of `study` run as `shard`.
    pub fn of(study: &Study, shard: Option<Shard>) -> Self {
        let shard = shard.map_or(String::new(), |s| s.to_string());
        Self(fnv1a(&[
            study.source.as_bytes(),
            b"\0",
            env!("CARGO_PKG_VERSION").as_bytes(),
            b"\0",
            shard.as_bytes(),
        ]))
    }

    /// As 16 hex digits.
    pub fn hex(self) -> String {
        format!("{:016x}", self.0)
    }
}

/// What `speed_profile` and `reference_speed_profile` hold.
const PROFILE_DESCRIPTION: &str =
    "crank speed profile: constant (rpm), ramp, sine (speed_*) or table (knots in the grid file)";

/// The name of a case's speed profile, `constant` for `rpm`.
fn profile_name(p: &CaseParams) -> String {
    p.speed
        .as_ref()
        .map_or("constant", |s| s.name())
        .to_string()
}

/// The layout of the file for the cases at `rows` (indices into `study.cases`), the
/// whole study or `shard` of it.
pub fn study_layout(study: &Study, rows: &[usize], shard: Option<Shard>) -> Layout {
    let cases: Vec<_> = rows.iter().map(|&r| &study.cases[r]).collect();
    let n_window = study.analysis_window().len();
    let mut parameters: Vec<Param> = study
        .effects
        .recorded_parameters()
        .map(|p| Param {
            spec: VarSpec::new(p.name, p.dimension.file_units(), p.long_name),
            values: ParamValues::F64(cases.iter().map(|c| p.get(&c.params)).collect()),
        })
        .collect();
    parameters.push(Param {
        spec: VarSpec::new(
            "location",
            "1",
            "bearing location: ideal, crank_ground or crank_rod",
        ),
        values: ParamValues::Str(
            cases
                .iter()
                .map(|c| c.params.location.name().to_string())
                .collect(),
        ),
    });
    if let Some(d) = &study.design {
        parameters.push(Param {
            spec: VarSpec::new(
                "design_row",
                "1",
                "row of the sampled design (global attribute design_method) this case runs",
            ),
            values: ParamValues::F64(cases.iter().map(|c| (c.id % d.rows) as f64).collect()),
        });
    }
    parameters.push(Param {
        spec: VarSpec::new("speed_profile", "1", PROFILE_DESCRIPTION),
        values: ParamValues::Str(cases.iter().map(|c| profile_name(&c.params)).collect()),
    });
    parameters.push(Param {
        spec: VarSpec::new(
            "defect_race",
            "1",
            "race of the first defect: outer, inner or ball (none without defects)",
        ),
        values: ParamValues::Str(
            cases
                .iter()
                .map(|c| {
                    c.params
                        .bearing
                        .defects
                        .first()
                        .map_or("none", |d| d.race.name())
                        .to_string()
                })
                .collect(),
        ),
    });
    parameters.push(Param {
        spec: VarSpec::new(
            "fault",
            "1",
            "fault label: the races with a defect of nonzero depth (outer, inner, ball, \
             joined by +), or none",
        ),
        values: ParamValues::Str(
            cases
                .iter()
                .map(|c| match c.params.location {
                    crate::mechanism::Location::Ideal => "none".to_string(),
                    _ => fault_label(&c.params.bearing.defects),
                })
                .collect(),
        ),
    });
    let reference_parameters = vec![
        Param {
            spec: VarSpec::new("reference_rpm", "rpm", "crank speed of the ideal mechanism"),
            values: ParamValues::F64(study.references.iter().map(|r| r.rpm).collect()),
        },
        Param {
            spec: VarSpec::new("reference_speed_profile", "1", PROFILE_DESCRIPTION),
            values: ParamValues::Str(study.references.iter().map(profile_name).collect()),
        },
    ];
    let mut attributes = provenance();
    let shard_rows = rows.len();
    attributes.extend([
        (
            "title".to_string(),
            format!("studyrun study {}", study.name).into(),
        ),
        ("study_name".to_string(), study.name.clone().into()),
        (
            "study_description".to_string(),
            study.description.clone().into(),
        ),
        ("grid_yaml".to_string(), study.source.clone().into()),
        ("grid_axes".to_string(), study.axes.join(",").into()),
        ("study_cases".to_string(), (study.cases.len() as i64).into()),
        ("file_cases".to_string(), (shard_rows as i64).into()),
        (
            "shard".to_string(),
            shard.map_or(String::new(), |s| s.to_string()).into(),
        ),
        ("model_conventions".to_string(), MODEL_CONVENTIONS.into()),
        ("solver".to_string(), study.solver.to_string().into()),
        ("duration".to_string(), study.sampling.duration.into()),
        ("sample_rate".to_string(), study.sampling.sample_rate.into()),
        ("transient".to_string(), study.transient.into()),
        (
            "decimate".to_string(),
            (study.output.decimate as i64).into(),
        ),
        (
            "series_sample_rate".to_string(),
            study.stored_sample_rate().into(),
        ),
        (
            "analysis_window".to_string(),
            "transient <= time < duration (the sample at time = duration left out): \
             the samples the metrics and spectra use"
                .into(),
        ),
        ("spectrum_window".to_string(), study.window.clone().into()),
        (
            "spectrum_normalisation".to_string(),
            "one-sided amplitude: a sinusoid of amplitude A on a bin reads A; mean not removed"
                .into(),
        ),
        (
            "effects".to_string(),
            study.effects.names().join(",").into(),
        ),
        (
            "study_fingerprint".to_string(),
            StudyFingerprint::of(study, None).hex().into(),
        ),
    ]);
    if let Some(r) = &study.replicates {
        attributes.extend([
            ("replicates".to_string(), (r.count as i64).into()),
            ("replicate_perturbation".to_string(), r.perturbation.into()),
            ("replicate_seed".to_string(), (r.seed as i64).into()),
        ]);
    }
    if study.chaos_check {
        attributes.push((
            "horizon_threshold".to_string(),
            crate::signal::replicates::HORIZON_THRESHOLD.into(),
        ));
    }
    if let Some(d) = &study.design {
        attributes.extend([
            ("design_method".to_string(), d.method.name().into()),
            ("design_samples".to_string(), (d.samples as i64).into()),
            ("design_seed".to_string(), (d.seed as i64).into()),
            ("design_scrambled".to_string(), i64::from(d.scramble).into()),
            ("design_rows".to_string(), (d.rows as i64).into()),
            (
                "design_parameters".to_string(),
                d.parameters.join(",").into(),
            ),
        ]);
    }
    if let Some(envelope) = &study.envelope {
        attributes.extend(envelope_attributes(envelope, n_window));
    }
    if let Some(o) = &study.orders {
        // docs/model.md §7.9: R whole revolutions in M angle samples.
        attributes.extend([
            (
                "order_revolutions".to_string(),
                (o.revolutions as i64).into(),
            ),
            ("order_samples".to_string(), (o.samples as i64).into()),
        ]);
    }
    Layout {
        case_ids: cases.iter().map(|c| c.id).collect(),
        times: study.stored_times(),
        frequencies: frequencies(n_window, study.sampling.sample_rate),
        reference_ids: (0..study.references.len() as u64).collect(),
        series: stored_series_specs(study),
        spectra: study
            .spectrum_channels
            .iter()
            .map(|ch| {
                VarSpec::new(
                    format!("{}_spectrum", ch.name),
                    ch.units,
                    format!("one-sided amplitude spectrum of {}", ch.long_name),
                )
            })
            .chain(study.envelope.iter().flat_map(envelope_spectrum_specs))
            .collect(),
        metrics: study_metric_specs(study),
        replicates: study
            .replicates
            .map_or(Vec::new(), |r| (0..r.count as u64).collect()),
        replicate_metrics: if study.replicates.is_some() {
            replicate_metric_specs()
        } else {
            Vec::new()
        },
        revolutions: (0..study.revolutions as u64).collect(),
        revolution_metrics: if study.revolutions > 0 {
            revolution_metric_specs()
        } else {
            Vec::new()
        },
        orders: study.orders.map_or(Vec::new(), |o| o.orders()),
        order_spectra: study.orders.map_or(Vec::new(), |o| {
            order_spectrum_specs(&o, &study.spectrum_channels, study.envelope.as_ref())
        }),
        parameters,
        reference_parameters,
        reference_series: reference_specs(study),
        reference_index: cases.iter().map(|c| c.reference as u64).collect(),
        attributes,
        storage: Storage {
            float32: study.float32,
            deflate_level: study.compression,
        },
    }
}

/// The root attributes of a study with `envelope:`: how its band is chosen and the
/// sizes of the kurtogram and the STFT for `n` analysed samples (docs/model.md §7.4–§7.6).
fn envelope_attributes(envelope: &EnvelopeSettings, n: usize) -> Vec<(String, AttrValue)> {
    let band = match envelope.band {
        BandChoice::Auto => "auto".to_string(),
        BandChoice::Fixed(b) => format!("{} Hz to {} Hz", b.low, b.high),
    };
    let segment = stft_segment(n);
    vec![
        ("envelope_band".to_string(), band.into()),
        (
            "kurtogram_depth".to_string(),
            i64::from(kurtogram_depth(n)).into(),
        ),
        ("stft_segment".to_string(), (segment as i64).into()),
        ("stft_hop".to_string(), ((segment / 2) as i64).into()),
    ]
}

/// The `[case]` metrics of a study's file: [`metric_specs`], then with replicates
/// their [`summary_specs`], then with the chaos check its [`chaos_specs`].
pub fn study_metric_specs(study: &Study) -> Vec<VarSpec> {
    let mut specs = metric_specs(study.envelope.as_ref());
    if study.replicates.is_some() {
        specs.extend(summary_specs());
    }
    if study.chaos_check {
        specs.extend(chaos_specs());
    }
    specs
}

/// FNV-1a, 64 bit: the study fingerprint.
pub fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for &b in *part {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// The `[case, time]` variables of a study's file: its stored channels
/// ([`Study::stored_channels`]), then its stored sensor series.
fn stored_series_specs(study: &Study) -> Vec<VarSpec> {
    let sensors: Vec<VarSpec> = study.sensors.iter().flat_map(|s| s.specs()).collect();
    let channels = study.stored_channels().into_iter().map(|k| {
        let c = &CHANNELS[k];
        VarSpec::new(c.name, c.units, c.long_name)
    });
    let sensors = study
        .stored_sensor_series()
        .into_iter()
        .map(|k| sensors[k].clone());
    channels.chain(sensors).collect()
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
