//! `studyrun inspect`: a summary of a result file.

use std::fmt::Write;
use std::path::Path;

use anyhow::{Context, Result};

use crate::output::{shell_word, AttrValue, DataFile, ParamValues, Status, StudyReader};

/// A human-readable summary of the study file at `path`: the study, its grid,
/// status counts and every failed case with its parameters and error.
pub fn inspect(path: &Path) -> Result<String> {
    let r = StudyReader::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let l = r.layout();
    let attr = |name: &str| match r.attribute(name) {
        Some(AttrValue::Str(s)) => s.clone(),
        Some(AttrValue::F64(x)) => x.to_string(),
        Some(AttrValue::I64(x)) => x.to_string(),
        None => "?".to_string(),
    };
    let statuses = r.statuses()?;
    let count = |s: Status| statuses.iter().filter(|&&x| x == s).count();
    let mut out = String::new();
    let axes = attr("grid_axes");
    writeln!(out, "file:     {}", path.display())?;
    writeln!(
        out,
        "study:    {} — {}",
        attr("study_name"),
        attr("study_description")
    )?;
    writeln!(
        out,
        "made by:  studyrun {} (commit {}), {}",
        attr("studyrun_version"),
        attr("git_commit"),
        attr("created")
    )?;
    writeln!(out, "grid:     {axes}")?;
    writeln!(
        out,
        "sampling: {} s at {} Hz; analysed {} s <= t < {} s, {} frequency bins",
        attr("duration"),
        attr("sample_rate"),
        attr("transient"),
        attr("duration"),
        l.frequencies.len()
    )?;
    if l.series.is_empty() {
        writeln!(out, "series:   none stored (metrics and spectra only)")?;
    } else {
        let names: Vec<&str> = l.series.iter().map(|s| s.name.as_str()).collect();
        let every = match attr("decimate").as_str() {
            "1" | "?" => "every sample of the output".to_string(),
            k => format!("one sample in {k} of the output, no anti-alias filter"),
        };
        writeln!(
            out,
            "series:   {} stored, {} samples each at {} Hz ({every}): {}",
            names.len(),
            l.times.len(),
            attr("series_sample_rate"),
            names.join(", ")
        )?;
    }
    writeln!(out, "solver:   {}", attr("solver"))?;
    writeln!(out, "effects:  {}", attr("effects"))?;
    writeln!(
        out,
        "cases:    {} in this file of {} in the study: {} ok, {} failed, {} pending",
        l.case_ids.len(),
        attr("study_cases"),
        count(Status::Ok),
        count(Status::Failed),
        count(Status::Pending)
    )?;
    if let Some(note) = interrupted_run(path) {
        writeln!(out, "run:      {note}")?;
    }
    if !l.replicates.is_empty() {
        writeln!(
            out,
            "replicates: {} per case, perturbation {} m, seed {}{}",
            l.replicates.len(),
            attr("replicate_perturbation"),
            attr("replicate_seed"),
            if l.metrics.iter().any(|m| m.name == "chaotic") {
                "; predictability_horizon and chaotic per case"
            } else {
                ""
            }
        )?;
    }
    if !l.orders.is_empty() {
        let names: Vec<&str> = l.order_spectra.iter().map(|s| s.name.as_str()).collect();
        writeln!(
            out,
            "orders:   {} bins 1/{} order apart ({} angle samples over {} whole revolutions): {}",
            l.orders.len(),
            attr("order_revolutions"),
            attr("order_samples"),
            attr("order_revolutions"),
            names.join(", ")
        )?;
    }
    let failed: Vec<usize> = (0..statuses.len())
        .filter(|&k| statuses[k] == Status::Failed)
        .collect();
    if !failed.is_empty() {
        writeln!(out, "failed cases:")?;
    }
    for row in failed {
        let mut labels = Vec::new();
        for axis in axes.split(',').filter(|a| !a.is_empty()) {
            if let Some(p) = l.parameters.iter().find(|p| p.spec.name == axis) {
                let v = match &p.values {
                    ParamValues::F64(v) => format!("{}", v[row]),
                    ParamValues::Str(v) => v[row].clone(),
                };
                labels.push(format!("{axis}={v}"));
            }
        }
        let message = r.message(row)?;
        writeln!(
            out,
            "  case {} ({}): {message}",
            l.case_ids[row],
            labels.join(", ")
        )?;
    }
    Ok(out)
}

/// A note when `path` belongs to an interrupted run: it is a run's partial file (its
/// finished cases are in the journal, not yet marked here), or a result file beside
/// the journal of a run that will replace it.
fn interrupted_run(path: &Path) -> Option<String> {
    let partial = DataFile::output_of(path);
    let output = partial
        .as_ref()
        .map_or(path, |(output, _)| output.as_path());
    let (journal, _) = super::side_paths(output);
    if !journal.is_file() {
        return None;
    }
    Some(if partial.is_some() {
        format!(
            "interrupted: the partial file of {}, whose cases are marked done only when \
             the run finishes; the journal {} records the finished ones, and \
             `studyrun GRID -o {} --resume` continues the run",
            output.display(),
            journal.display(),
            shell_word(&output.to_string_lossy())
        )
    } else {
        format!(
            "the journal {} beside this file holds an interrupted run that replaces it when \
             `--resume` finishes it",
            journal.display()
        )
    })
}
