//! Combining shard files (`studyrun merge`) into one file equal to a single run.

use std::path::{Path, PathBuf};

use anyhow::{bail, ensure, Context, Result};

use super::side_paths;
use crate::output::{AttrValue, CaseRecord, Layout, ParamValues, StudyReader, StudyWriter};

/// Merges `shards` (files of `studyrun --shard K/N` runs of one study) into `output`.
/// Every case of the study must be present exactly once. Returns the number of cases.
pub fn merge(output: &Path, shards: &[PathBuf], force: bool) -> Result<usize> {
    ensure!(!shards.is_empty(), "merge needs at least one shard file");
    if output.exists() && !force {
        bail!("{} exists; use --force to overwrite it", output.display());
    }
    let readers: Vec<StudyReader> = shards
        .iter()
        .map(|p| StudyReader::open(p).with_context(|| format!("cannot open shard {}", p.display())))
        .collect::<Result<_>>()?;
    let first = readers[0].layout();
    let attr = |r: &StudyReader, name: &str| r.attribute(name).cloned();
    for (r, path) in readers.iter().zip(shards).skip(1) {
        ensure!(
            attr(r, "study_fingerprint") == attr(&readers[0], "study_fingerprint"),
            "{} belongs to a different study (or studyrun version) than {}",
            path.display(),
            shards[0].display()
        );
        let l = r.layout();
        ensure!(
            l.times == first.times
                && l.frequencies == first.frequencies
                && l.series == first.series
                && l.spectra == first.spectra
                && l.metrics == first.metrics
                && l.reference_ids == first.reference_ids,
            "{} has a different layout than {}",
            path.display(),
            shards[0].display()
        );
    }
    // (shard, row) of every case, sorted by case id.
    let mut order: Vec<(u64, usize, usize)> = readers
        .iter()
        .enumerate()
        .flat_map(|(s, r)| {
            r.layout()
                .case_ids
                .iter()
                .enumerate()
                .map(move |(row, &id)| (id, s, row))
        })
        .collect();
    order.sort_unstable();
    if let Some(w) = order.windows(2).find(|w| w[0].0 == w[1].0) {
        bail!(
            "case {} is in both {} and {}",
            w[0].0,
            shards[w[0].1].display(),
            shards[w[1].1].display()
        );
    }
    let expected = match attr(&readers[0], "study_cases") {
        Some(AttrValue::I64(n)) => n as usize,
        _ => bail!(
            "{} has no study_cases attribute; is it a studyrun study file?",
            shards[0].display()
        ),
    };
    ensure!(
        order.len() == expected,
        "the shards hold {} of the study's {expected} cases; merge all shards",
        order.len()
    );

    let mut layout: Layout = first.clone();
    layout.case_ids = order.iter().map(|o| o.0).collect();
    layout.reference_index = order
        .iter()
        .map(|&(_, s, row)| readers[s].layout().reference_index[row])
        .collect();
    for (p, param) in layout.parameters.iter_mut().enumerate() {
        param.values = match &param.values {
            ParamValues::F64(_) => ParamValues::F64(
                order
                    .iter()
                    .map(
                        |&(_, s, row)| match &readers[s].layout().parameters[p].values {
                            ParamValues::F64(v) => v[row],
                            ParamValues::Str(_) => f64::NAN,
                        },
                    )
                    .collect(),
            ),
            ParamValues::Str(_) => ParamValues::Str(
                order
                    .iter()
                    .map(
                        |&(_, s, row)| match &readers[s].layout().parameters[p].values {
                            ParamValues::Str(v) => v[row].clone(),
                            ParamValues::F64(_) => String::new(),
                        },
                    )
                    .collect(),
            ),
        };
    }
    for (name, value) in layout.attributes.iter_mut() {
        if name == "file_cases" {
            *value = AttrValue::I64(expected as i64);
        }
    }
    let (_, partial) = side_paths(output);
    let mut writer = StudyWriter::create(&partial, &layout)
        .with_context(|| format!("cannot create {}", partial.display()))?;
    for k in 0..layout.reference_ids.len() {
        let series = readers[0].read_reference(k)?;
        let refs: Vec<&[f64]> = series.iter().map(Vec::as_slice).collect();
        writer.write_reference(k, &refs)?;
    }
    for (row, &(_, s, src)) in order.iter().enumerate() {
        let c = readers[s].read_case(src)?;
        let series: Vec<&[f64]> = c.series.iter().map(Vec::as_slice).collect();
        let spectra: Vec<&[f64]> = c.spectra.iter().map(Vec::as_slice).collect();
        writer.write_case(
            row,
            &CaseRecord {
                series: &series,
                spectra: &spectra,
                metrics: &c.metrics,
                status: c.status,
                message: &c.message,
            },
        )?;
    }
    writer.finish()?;
    std::fs::rename(&partial, output).with_context(|| {
        format!(
            "cannot rename {} to {}",
            partial.display(),
            output.display()
        )
    })?;
    Ok(order.len())
}
