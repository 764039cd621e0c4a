//! The root attributes of a study's file: provenance, the study and its sampling, and
//! what each optional section (replicates, chaos check, design, envelope, orders) adds.

use crate::output::{provenance, AttrValue};
use crate::signal::envelope::{kurtogram_depth, stft_segment, EnvelopeSettings};
use crate::signal::spectrum::AMPLITUDE_NORMALISATION;
use crate::study::{Shard, Study};

use super::{StudyFingerprint, MODEL_CONVENTIONS};

/// The root attributes of the file of `study` (or of `shard` of it) holding
/// `shard_rows` cases: provenance, [`study_attributes`] and [`section_attributes`].
pub(super) fn root_attributes(
    study: &Study,
    shard_rows: usize,
    shard: Option<Shard>,
) -> Vec<(String, AttrValue)> {
    let mut attributes = provenance();
    attributes.extend(study_attributes(study, shard_rows, shard));
    attributes.extend(section_attributes(study));
    attributes
}

/// What every study file says of its study: name, grid, cases (of the study and in
/// this file, and the `shard`), model conventions, solver, sampling (s, Hz), how
/// spectra are made, effects and the study's fingerprint.
fn study_attributes(
    study: &Study,
    shard_rows: usize,
    shard: Option<Shard>,
) -> Vec<(String, AttrValue)> {
    vec![
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
        ("study_cases".to_string(), (study.whole.cases as i64).into()),
        ("file_cases".to_string(), (shard_rows as i64).into()),
        (
            "shard".to_string(),
            shard.map_or(String::new(), |s| s.to_string()).into(),
        ),
        ("model_conventions".to_string(), MODEL_CONVENTIONS.into()),
        (
            "solver".to_string(),
            match study.recordings {
                Some(_) => "none (measured recordings, nothing simulated)".to_string(),
                None => study.solver.to_string(),
            }
            .into(),
        ),
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
            AMPLITUDE_NORMALISATION.into(),
        ),
        (
            "effects".to_string(),
            study.effects.names().join(",").into(),
        ),
        (
            "study_fingerprint".to_string(),
            StudyFingerprint::of(study, None).hex().into(),
        ),
    ]
}

/// What the optional sections of `study` add: replicates, the chaos check's
/// threshold, the sampled design, the envelope analysis and the order analysis.
fn section_attributes(study: &Study) -> Vec<(String, AttrValue)> {
    let mut attributes = Vec::new();
    if let Some(f) = study.max_frequency {
        attributes.push(("max_frequency".to_string(), f.into()));
    }
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
        attributes.extend(envelope_attributes(envelope, study.analysis_window().len()));
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
    attributes
}

/// The root attributes of a study with `envelope:`: how its band is chosen and the
/// sizes of the kurtogram and the STFT for `n` analysed samples (docs/model.md §7.4–§7.6).
fn envelope_attributes(envelope: &EnvelopeSettings, n: usize) -> Vec<(String, AttrValue)> {
    let band = envelope.band.describe();
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
