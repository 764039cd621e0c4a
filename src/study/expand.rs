//! From the serde mirror to a validated [`Study`]: units, effects, expansion, checks.

use std::collections::HashMap;
use std::path::Path;

use serde_saphyr::Location;

use super::config::{
    BandValue, BearingSection, CaseValue, DefectSection, EnvelopeSection, GridFile, OutputSection,
    RecordingSection, Scalar, SensorSection, SeriesValue, SpectraSection, SpeedSection,
    WavinessSection, S,
};
use super::memory::Limits;
use super::params::{lookup, ParamDef, PARAMETERS};
use super::units::Dimension;
use super::{Case, SeriesOutput, Shard, Study, StudyError, DEFAULT_MAX_CASES};
use crate::error::number;

mod analysis;
mod axes;
mod base;
mod collect;
mod ctx;
mod design;
mod effects;
mod journal;
mod memory_check;
mod recordings;
mod references;
mod replicates;
mod sensors;
mod solver;

use crate::bearing::stiffness::ContactGeometry;
use crate::bearing::{
    DampingModel, Defect, DefectProfile, DefectRace, Harmonic, RaceWaviness, RestitutionLaw,
};
use crate::mechanism::{CaseParams, Housing, JointKind, Location as Site, SpeedProfile};
use crate::signal::channel::{AnalysisChannel, Source};
use crate::signal::envelope::{Band, BandChoice, EnvelopeSettings};
use crate::signal::order::{whole_revolutions, OrderSettings};
use crate::signal::revolutions::revolution_count;
use crate::signal::sensor::{Sensor, CLEAN_SUFFIX};
use crate::signal::spectrum::frequencies;
use crate::simulate::{Sampling, CHANNELS};
use crate::solve::{
    rk4_step_fits, Method, SolverSettings, DEFAULT_ATOL, DEFAULT_RTOL, MAX_RTOL, MIN_RTOL,
};
use analysis::*;
use axes::*;
use base::*;
use collect::Collected;
use ctx::*;
use effects::effects;
pub use effects::Effects;
use journal::*;
use solver::solver;

/// Where each parameter of a case was set: (parameter, YAML field, line/column).
type Provenance = Vec<(&'static str, String, (u64, u64))>;

/// Builds the study from grid-file text, refusing it when its run would need more
/// memory than `limits` allow ([`memory_check`]: a lower bound before the cases are
/// expanded and once their speeds are known, the exact estimate at the end). The
/// steps: parse, sampling, effects and base case, solver, axes, case count, axis
/// values, memory, expansion, references, analysed window, spectra and output
/// settings, memory. With a `part`, the study holds only that shard's cases (a study
/// of recordings holds every case either way).
pub(super) fn build(
    text: &str,
    path: &Path,
    limits: &Limits,
    part: Option<Shard>,
) -> Result<Study, StudyError> {
    let ctx = Ctx { path };
    let file = parse(&ctx, text)?;
    check_name(&ctx, &file.name)?;
    match file.recordings {
        Some(_) => recordings::build_recordings(&ctx, file, text, limits),
        None => build_simulated(&ctx, file, text, limits, part),
    }
}

/// [`build`] for a study of simulated cases, its grid `file` parsed from `text`.
fn build_simulated(
    ctx: &Ctx<'_>,
    file: GridFile,
    text: &str,
    limits: &Limits,
    part: Option<Shard>,
) -> Result<Study, StudyError> {
    let sampling = sampling_of(ctx, &file)?;
    let effects = effects(ctx, &file)?;
    let mut prov = Provenance::new();
    let base = base_case(ctx, &file, &effects, &mut prov)?;
    let solver = solver(ctx, &file, &sampling)?;
    let (groups, axes_names) = axis_groups(ctx, &file)?;
    let rows = design::rows(ctx, &file)?;
    let (total, count) = case_count(ctx, &file, &groups, rows)?;
    // Before the design is drawn: its values are rows × parameters.
    let places = memory_check::Places::of(&file);
    let mut known = known_before_expansion(&file, &sampling, total, rows, part);
    memory_check::check_lower_bound(ctx, &places, &known, limits)?;
    let (collected, design) = expand_cases(
        ctx,
        &file,
        (&base, &prov),
        &effects,
        (&groups, &axes_names),
        (total, count, part),
    )?;
    check_joint_keys(ctx, &file, collected.joints)?;
    let transient = transient_of(ctx, &file, &sampling, collected.longest_revolution)?;
    let list = file.sensors.as_ref();
    let sensors = list.map(|l| sensors::sensors(ctx, l, &sampling, &effects));
    let sensors = sensors.transpose()?.unwrap_or_default();
    sensors::check_realizations(ctx, &sensors, collected.realization)?;
    let analysed = Analysed::Simulated(&sensors[..], &effects);
    let (window, spectrum_channels) = spectra_settings(ctx, file.spectra.as_ref(), analysed)?;
    let max_frequency = analysis::max_frequency(ctx, file.spectra.as_ref(), &sampling)?;
    let envelope = file
        .envelope
        .as_ref()
        .map(|e| envelope_settings(ctx, e, &sampling, transient, analysed))
        .transpose()?;
    let (float32, compression) = output_settings(ctx, file.output.as_ref())?;
    let figures = case_figures(ctx, &file, &sampling, transient, &collected)?;
    let (cases, references, whole) = collected.finish();
    known.expanded(references.len(), whole.references, figures.revolutions);
    memory_check::check_lower_bound(ctx, &places, &known, limits)?;
    let mut study = Study {
        name: file.name.value.clone(),
        description: file.description.clone().unwrap_or_default(),
        source: text.to_string(),
        path: ctx.path.to_path_buf(),
        sampling,
        solver,
        effects,
        transient,
        window,
        spectrum_channels,
        max_frequency,
        envelope,
        orders: figures.orders,
        float32,
        compression,
        axes: axes_names,
        cases,
        references,
        part,
        whole,
        design,
        replicates: figures.replicates,
        chaos_check: figures.chaos_check,
        revolutions: figures.revolutions,
        sensors: Vec::new(),
        output: SeriesOutput::default(),
        recordings: None,
    };
    let (list, output) = (file.sensors.as_ref(), file.output.as_ref());
    add_outputs(ctx, list, output, &mut study, sensors)?;
    memory_check::check_study(ctx, &places, &study, limits)?;
    Ok(study)
}

/// What the study's cases decide once the analysed window is known.
struct CaseFigures {
    /// Replicates per case, when asked for.
    replicates: Option<super::Replicates>,
    /// Whether the chaos check runs.
    chaos_check: bool,
    /// The most whole revolutions of a case in the analysed window.
    revolutions: usize,
    /// The order analysis, when asked for.
    orders: Option<OrderSettings>,
}

/// What the study's `collected` cases decide once the analysed window starts at
/// `transient` (s): the replicates and chaos check, the most whole revolutions of a
/// case (refused below 2 samples per revolution) and the order analysis.
fn case_figures(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    transient: f64,
    collected: &Collected,
) -> Result<CaseFigures, StudyError> {
    let (replicates, chaos_check) = replicates::resolve(ctx, file, &collected.tightest)?;
    let revolutions = collected.most_revolutions(transient, sampling.duration);
    check_samples_per_revolution(ctx, file, revolutions, sampling)?;
    let orders = order_settings(ctx, file, sampling, transient, |first, last| {
        collected.fewest_whole_revolutions(first, last)
    })?;
    Ok(CaseFigures {
        replicates,
        chaos_check,
        revolutions,
        orders,
    })
}

/// Refuses the keys of a `recordings:` study (`window`, `series`) in a study of
/// simulated cases.
fn refuse_recording_keys(ctx: &Ctx<'_>, file: &GridFile) -> Result<(), StudyError> {
    let given = [
        ("window", file.window.as_ref().map(|w| at(&w.referenced))),
        ("series", file.series.as_ref().map(|s| at(&s.referenced))),
    ];
    match given.into_iter().find(|(_, place)| place.is_some()) {
        Some((key, place)) => Err(ctx.err(
            place,
            key,
            "only a study with `recordings:` takes it; a simulated study's analysed \
             window is `transient` to `duration`",
        )),
        None => Ok(()),
    }
}

/// Adds the `sensors` of the file's `sensors:` list to `study`, their names checked
/// against the study's other variables, and the series output settings of its
/// `output:` section.
fn add_outputs(
    ctx: &Ctx<'_>,
    list: Option<&S<Vec<S<SensorSection>>>>,
    output: Option<&OutputSection>,
    study: &mut Study,
    sensors: Vec<Sensor>,
) -> Result<(), StudyError> {
    if let Some(list) = list {
        let taken = super::study_layout(study, &[], None)
            .names()
            .map(str::to_string)
            .collect();
        sensors::check_names(ctx, list, &sensors, &taken)?;
        study.sensors = sensors;
    }
    study.output = series_output(ctx, output, study)?;
    Ok(())
}

/// The grid file parsed from `text`, its parser errors in the user's words
/// ([`super::yaml::describe`]); an empty value is refused first, with its field.
fn parse(ctx: &Ctx<'_>, text: &str) -> Result<GridFile, StudyError> {
    if let Some((place, field, message)) = super::tree::first_empty(text) {
        return Err(ctx.err(Some(place), &field, message));
    }
    serde_saphyr::from_str(text).map_err(|e| {
        let (place, field, message) = super::yaml::describe(&e, text);
        ctx.err(place, &field, message)
    })
}

/// What is known of the study before its cases are expanded: `total` cases of the
/// samples of `sampling` (those of `part` held), a sampled design of `rows` rows, the
/// longest speed table.
fn known_before_expansion(
    file: &GridFile,
    sampling: &Sampling,
    total: u64,
    rows: u64,
    part: Option<Shard>,
) -> memory_check::Known {
    memory_check::Known {
        samples: sampling.len() as u64,
        cases: part.map_or(total, |s| collect::shard_size(total, s)),
        sharded: part.is_some(),
        design_values: file.design.as_ref().map_or(0, |d| {
            rows.saturating_mul(d.value.parameters.value.len() as u64)
        }),
        references: 0,
        study_references: 0,
        revolutions: 0,
        speed_knots: memory_check::speed_knots(file),
    }
}

/// The study's cases collected ([`Collected`], those of `part` kept): the `count`
/// combinations of the grid's axis `groups` (named `axes`), then the explicit
/// `cases:`, each with every row of a sampled design, from the base case (`total` in
/// all); with the design's description.
fn expand_cases(
    ctx: &Ctx<'_>,
    file: &GridFile,
    (base, prov): (&CaseParams, &Provenance),
    effects: &Effects,
    (groups, axes): (&[Vec<Axis<'_>>], &[String]),
    (total, count, part): (u64, u64, Option<Shard>),
) -> Result<(Collected, Option<super::DesignInfo>), StudyError> {
    let mut sampled = design::resolve(ctx, file, base, effects, axes)?;
    let info = sampled.as_ref().map(|d| d.info.clone());
    let mut resolved = resolve_axes(ctx, base, groups, effects)?;
    check_repeats(ctx, &resolved)?;
    if let Some(d) = &mut sampled {
        resolved.push(d.group());
    }
    let mut cases = Collected::new(part, total, file.replicates.is_some());
    expand_grid(ctx, base, prov, &resolved, count, effects, &mut cases)?;
    let explicit_design = info.as_ref().map(|_| &resolved[resolved.len() - 1]);
    expand_explicit(ctx, file, base, prov, explicit_design, effects, &mut cases)?;
    Ok((cases, info))
}

/// Refuses a speed that turns the crank more than once per two samples: no series
/// resolves such a revolution (its crank frequency is above the Nyquist frequency,
/// rpm > 30 × sample_rate at a constant speed), and its per-revolution values would
/// outnumber the samples (`grid: {rpm: [1e11]}` asked for 67 million per case).
fn check_samples_per_revolution(
    ctx: &Ctx<'_>,
    file: &GridFile,
    revolutions: usize,
    sampling: &Sampling,
) -> Result<(), StudyError> {
    let samples = sampling.len();
    if revolutions <= samples / 2 {
        return Ok(());
    }
    Err(ctx.err(
        Some(memory_check::sample_rate_place(file)),
        "grid",
        format!(
            "a case turns the crank {revolutions} times after the transient but is sampled \
             {samples} times: fewer than 2 samples per revolution, which no series resolves \
             (its crank frequency is above the Nyquist frequency); the speed must be at \
             most 30 × sample_rate rpm ({} rpm), or the sample_rate higher",
            number(30.0 * sampling.sample_rate)
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::params::ParamDef;

    #[test]
    fn parameter_names_are_unique() {
        let mut names: Vec<&str> = PARAMETERS.iter().map(|p: &ParamDef| p.name).collect();
        names.sort_unstable();
        let len = names.len();
        names.dedup();
        assert_eq!(names.len(), len);
    }
}
