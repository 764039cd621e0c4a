//! The study file's [`Layout`] for a study (or a shard of it): which variables, with
//! which names, units and attributes, the file of a [`Study`] holds. The parts live by
//! family: `parameters` (`[case]` and `[reference]` labels and values),
//! `variables` (series, metrics, references' series) and `attributes` (root).

mod attributes;
mod parameters;
mod variables;

pub use variables::{
    reference_specs, stored_reference_channels, study_metric_specs, REFERENCE_CHANNELS,
};

use crate::numeric::hash::fnv1a;
use crate::output::{Layout, Storage, VarSpec};
use crate::signal::envelope::sk_frequencies;
use crate::signal::replicates::replicate_metric_specs;
use crate::signal::revolutions::revolution_metric_specs;
use crate::signal::spectrum::{frequencies, AMPLITUDE_NORMALISATION};
use crate::signal::{envelope_spectrum_specs, order_spectrum_specs, spectral_kurtosis_specs};
use crate::study::{Shard, Study};

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

/// The layout of the file for the cases at `rows` (indices into `study.cases`), the
/// whole study or `shard` of it.
pub fn study_layout(study: &Study, rows: &[usize], shard: Option<Shard>) -> Layout {
    let cases: Vec<_> = rows.iter().map(|&r| &study.cases[r]).collect();
    let n_window = study.analysis_window().len();
    let parameters = parameters::case_parameters(study, &cases);
    // The references this file's cases use, in index order: a shard holds only its own;
    // measured recordings have none.
    let simulated = cases.iter().filter(|_| study.recordings.is_none());
    let mut reference_ids: Vec<u64> = simulated.clone().map(|c| c.reference as u64).collect();
    reference_ids.sort_unstable();
    reference_ids.dedup();
    let reference_parameters = parameters::reference_parameters(study, &reference_ids);
    let attributes = attributes::root_attributes(study, rows.len(), shard);
    Layout {
        case_ids: cases.iter().map(|c| c.id).collect(),
        times: study.stored_times(),
        frequencies: frequencies(n_window, study.sampling.sample_rate)
            .into_iter()
            .take(study.stored_bins())
            .collect(),
        reference_index: simulated
            .map(|c| reference_ids.partition_point(|&id| id < c.reference as u64) as u64)
            .collect(),
        reference_ids,
        series: variables::stored_series_specs(study),
        spectra: study
            .spectrum_channels
            .iter()
            .map(|ch| {
                VarSpec::new(
                    format!("{}_spectrum", ch.name),
                    ch.units,
                    format!("one-sided amplitude spectrum of {}", ch.long_name),
                )
                .with("window", study.window.as_str())
                .with("normalisation", AMPLITUDE_NORMALISATION)
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
        sk_frequencies: match study.envelope {
            Some(_) => sk_frequencies(n_window, study.sampling.sample_rate),
            None => Vec::new(),
        },
        kurtosis: study
            .envelope
            .iter()
            .flat_map(|e| spectral_kurtosis_specs(e, n_window))
            .collect(),
        parameters,
        reference_parameters,
        reference_series: reference_specs(study),
        attributes,
        storage: Storage {
            float32: study.float32,
            deflate_level: study.compression,
        },
    }
}
