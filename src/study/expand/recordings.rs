//! A `recordings:` study (docs/grid-file.md, Recordings): each measured recording one
//! case, read and checked before anything runs, all analysed over one window at one
//! sample rate.

use std::path::PathBuf;

use super::*;
use crate::bearing::BearingParams;
use crate::recordings::read::{read_samples, ColumnRef, ReadError, Selector};
use crate::study::{Recording, Recordings, WholeStudy};

/// The default name of a recordings study's measured series.
const SERIES: &str = "vibration";

/// Builds a recordings study from its parsed grid `file` (`text` at `path`): the
/// bearing's geometry, every recording read and checked, the common sampling, then
/// the analysis and output settings a simulated study has.
pub(super) fn build_recordings(
    ctx: &Ctx<'_>,
    file: GridFile,
    text: &str,
    limits: &Limits,
) -> Result<Study, StudyError> {
    refuse_simulation_keys(ctx, &file)?;
    let bearing = recording_bearing(ctx, &file)?;
    let list = file.recordings.as_ref().expect("a recordings study");
    if list.value.is_empty() {
        return Err(ctx.err(
            Some(at(&list.referenced)),
            "recordings",
            "at least one recording is needed",
        ));
    }
    let dir = ctx.path.parent().map(PathBuf::from).unwrap_or_default();
    let mut read = Vec::with_capacity(list.value.len());
    let mut cases = Vec::with_capacity(list.value.len());
    for (k, entry) in list.value.iter().enumerate() {
        let (recording, params) = recording_case(ctx, k, entry, &dir, &bearing)?;
        cases.push(Case {
            id: k as u64,
            params,
            reference: 0,
        });
        read.push(recording);
    }
    let sampling = common_sampling(ctx, &file, &read)?;
    let read = read.into_iter().map(|(r, _)| r).collect();
    let transient = recorded_transient(ctx, &file, &sampling, &cases)?;
    let name = file.series.as_ref().map_or(SERIES, |s| s.value.as_str());
    let recordings = Recordings {
        series: AnalysisChannel::recording(name),
        list: read,
    };
    let analysed = Analysed::Recording(&recordings.series);
    let (window, spectrum_channels) = spectra_settings(ctx, file.spectra.as_ref(), analysed)?;
    let envelope = file
        .envelope
        .as_ref()
        .map(|e| envelope_settings(ctx, e, &sampling, transient, analysed))
        .transpose()?;
    let (float32, compression) = output_settings(ctx, file.output.as_ref())?;
    let mut study = Study {
        name: file.name.value.clone(),
        description: file.description.clone().unwrap_or_default(),
        source: text.to_string(),
        path: ctx.path.to_path_buf(),
        sampling,
        solver: SolverSettings::default(),
        effects: Effects::NONE,
        transient,
        window,
        spectrum_channels,
        max_frequency: analysis::max_frequency(ctx, file.spectra.as_ref(), &sampling)?,
        envelope,
        orders: recorded_orders(ctx, &file, &sampling, transient, &cases)?,
        float32,
        compression,
        axes: Vec::new(),
        whole: WholeStudy::of(&cases),
        cases,
        references: Vec::new(),
        part: None,
        design: None,
        replicates: None,
        chaos_check: false,
        revolutions: 0,
        sensors: Vec::new(),
        output: SeriesOutput::default(),
        recordings: Some(recordings),
    };
    study.output = series_output(ctx, file.output.as_ref(), &study)?;
    memory_check::check_study(ctx, &memory_check::Places::of(&file), &study, limits)?;
    Ok(study)
}

/// The start of a recordings study's analysed window (s): 0 without `transient`, else
/// as a simulated study's ([`transient_of`]) over the recordings' `cases`.
fn recorded_transient(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    cases: &[Case],
) -> Result<f64, StudyError> {
    if file.transient.is_none() {
        return Ok(0.0);
    }
    let revolution = cases.iter().map(|c| c.params.revolution_time());
    transient_of(ctx, file, sampling, revolution.fold(0.0, f64::max))
}

/// A recordings study's order analysis ([`order_settings`]) over its `cases`.
fn recorded_orders(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    transient: f64,
    cases: &[Case],
) -> Result<Option<OrderSettings>, StudyError> {
    order_settings(ctx, file, sampling, transient, |first, last| {
        let drives = cases.iter().map(|c| (c.id, c.params.drive()));
        collect::fewest_whole_revolutions(drives, first, last)
    })
}

/// A place in the grid file, (line, column), when serde kept one.
type Place = Option<(u64, u64)>;

/// Refuses what only a simulated study has: its simulation sections, its axes and
/// explicit cases, designs, replicates and sensors.
fn refuse_simulation_keys(ctx: &Ctx<'_>, file: &GridFile) -> Result<(), StudyError> {
    let place = |l: &Location| Some(at(l));
    let given: [(&str, bool, Place); 16] = [
        ("grid", !file.grid.is_empty(), None),
        ("zip", !file.zip.is_empty(), None),
        ("cases", !file.cases.is_empty(), None),
        ("design", file.design.is_some(), None),
        ("replicates", file.replicates.is_some(), None),
        ("chaos_check", file.chaos_check.is_some(), None),
        ("sensors", file.sensors.is_some(), None),
        ("effects", file.effects.is_some(), None),
        ("mechanism", file.mechanism.is_some(), None),
        ("housing", file.housing.is_some(), None),
        ("solver", file.solver.is_some(), None),
        ("location", file.location.is_some(), None),
        ("joint", file.joint.is_some(), None),
        ("journal", file.journal.is_some(), None),
        (
            "rpm",
            file.rpm.is_some(),
            file.rpm.as_ref().and_then(|r| place(&r.referenced)),
        ),
        (
            "speed",
            file.speed.is_some(),
            file.speed.as_ref().and_then(|s| place(&s.referenced)),
        ),
    ];
    if let Some((key, _, at)) = given.into_iter().find(|(_, g, _)| *g) {
        let why = match key {
            "rpm" | "speed" => "each recording gives its own `rpm` or `speed`",
            "location" | "joint" | "journal" => {
                "a recording's bearing has its outer race fixed, its inner race at `rpm`"
            }
            _ => "it describes simulated cases; each recording is one case",
        };
        return Err(ctx.err(
            at,
            key,
            format!("not allowed in a study with `recordings:`: {why}"),
        ));
    }
    Ok(())
}

/// The bearing of a recordings study: `ball_count` and the `geometry`'s
/// `ball_diameter` `D`, `pitch_diameter` `d_m` and `contact_angle` (default 0), the
/// raceway diameters `d_m ∓ D` (docs/model.md §7.3, §7.10). The geometry is required
/// with `envelope:`, whose characteristic frequencies it gives.
fn recording_bearing(ctx: &Ctx<'_>, file: &GridFile) -> Result<BearingParams, StudyError> {
    let mut bearing = BearingParams::default();
    let default = BearingSection::default();
    let b = file.bearing.as_ref().unwrap_or(&default);
    let other = [
        ("clearance", b.clearance.is_some()),
        ("stiffness", b.stiffness.is_some()),
        ("damping", b.damping.is_some()),
        ("damping_model", b.damping_model.is_some()),
        ("restitution", b.restitution.is_some()),
        ("alpha", b.alpha.is_some()),
        ("inner_race_diameter", b.inner_race_diameter.is_some()),
        ("outer_race_diameter", b.outer_race_diameter.is_some()),
        ("waviness", b.waviness.is_some()),
        ("inner_waviness", b.inner_waviness.is_some()),
        ("outer_waviness", b.outer_waviness.is_some()),
        ("defects", b.defects.is_some()),
    ];
    if let Some((key, _)) = other.into_iter().find(|(_, g)| *g) {
        return Err(ctx.err(
            None,
            &format!("bearing.{key}"),
            "not allowed in a study with `recordings:`: its bearing is `ball_count` and \
             `geometry` (ball_diameter, pitch_diameter, contact_angle)",
        ));
    }
    if let Some(n) = &b.ball_count {
        let count = ctx.quantity(n, Dimension::Dimensionless, "bearing.ball_count")?;
        if !(count >= 3.0 && count.fract() == 0.0 && count <= 1e6) {
            let rule = "an integer >= 3";
            return Err(ctx.err(Some(at(&n.referenced)), "bearing.ball_count", rule));
        }
        bearing.ball_count = count as usize;
    }
    let g = b.geometry.as_ref();
    let length = |v: Option<&S<Scalar>>, key: &str| -> Result<Option<f64>, StudyError> {
        let field = format!("bearing.geometry.{key}");
        v.map(|v| ctx.quantity(v, Dimension::Length, &field))
            .transpose()
    };
    let ball = length(g.and_then(|g| g.ball_diameter.as_ref()), "ball_diameter")?;
    let pitch = length(g.and_then(|g| g.pitch_diameter.as_ref()), "pitch_diameter")?;
    let (ball, pitch) = match (ball, pitch) {
        (Some(d), Some(dm)) if d > 0.0 && dm > d => (d, dm),
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                None,
                "bearing.geometry",
                "ball_diameter must be above 0 and below pitch_diameter",
            ))
        }
        _ if file.envelope.is_none() => return Ok(bearing),
        _ => {
            return Err(ctx.err(
                None,
                "bearing.geometry",
                "a recordings study with `envelope:` needs bearing.geometry.ball_diameter \
                 and pitch_diameter: its characteristic frequencies come from them",
            ))
        }
    };
    bearing.ball_diameter = ball;
    bearing.inner_race_diameter = pitch - ball;
    bearing.outer_race_diameter = pitch + ball;
    if let Some(a) = g.and_then(|g| g.contact_angle.as_ref()) {
        let field = "bearing.geometry.contact_angle";
        let angle = ctx.quantity(a, Dimension::Angle, field)?;
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&angle.abs()) {
            let rule = format!("{} is not allowed: below 90 deg in size", a.value);
            return Err(ctx.err(Some(at(&a.referenced)), field, rule));
        }
        bearing.contact_angle = angle;
    }
    Ok(bearing)
}

/// Recording `k` of the list (`entry`, its file relative to `dir`): read and
/// checked, with its case's parameters (`bearing`, the speed, the inner race
/// turning); the sample rate it gives is checked against the others later.
fn recording_case(
    ctx: &Ctx<'_>,
    k: usize,
    entry: &S<RecordingSection>,
    dir: &Path,
    bearing: &BearingParams,
) -> Result<((Recording, f64), CaseParams), StudyError> {
    let r = &entry.value;
    let prefix = format!("recordings[{k}]");
    let file = dir.join(&r.file.value);
    let selector = selector_of(ctx, k, r)?;
    let rate_field = format!("{prefix}.sample_rate");
    let rate = ctx.quantity(&r.sample_rate, Dimension::Frequency, &rate_field)?;
    if rate <= 0.0 {
        let rule = format!("{} is not allowed: above 0 Hz", r.sample_rate.value);
        return Err(ctx.err(Some(at(&r.sample_rate.referenced)), &rate_field, rule));
    }
    let mut params = CaseParams {
        location: Site::CrankGround,
        bearing: bearing.clone(),
        rpm: f64::NAN,
        ..CaseParams::default()
    };
    match (&r.rpm, &r.speed) {
        (Some(_), Some(s)) => {
            let why = "give `rpm` or `speed`, not both";
            return Err(ctx.err(Some(at(&s.referenced)), &format!("{prefix}.speed"), why));
        }
        (Some(rpm), None) => {
            let field = format!("{prefix}.rpm");
            params.rpm = ctx.quantity(rpm, Dimension::Speed, &field)?;
            if params.rpm <= 0.0 {
                let rule = format!("{} is not allowed: above 0 rev/min", rpm.value);
                return Err(ctx.err(Some(at(&rpm.referenced)), &field, rule));
            }
        }
        (None, Some(s)) => {
            let field = format!("{prefix}.speed");
            params.speed = Some(ctx.speed(&s.value, &s.referenced, &field, &mut Vec::new())?);
        }
        (None, None) => {}
    }
    let fault = fault_of(ctx, &prefix, &r.fault)?;
    let samples =
        read_samples(&file, &selector).map_err(|e| read_refusal(ctx, k, entry, &file, e))?;
    if let Some(header) = samples.sample_rate.filter(|&h| h != rate) {
        return Err(ctx.err(
            Some(at(&r.sample_rate.referenced)),
            &rate_field,
            format!(
                "recording {k} ({}): {} Hz, but the file's header says {} Hz",
                file.display(),
                number(rate),
                number(header)
            ),
        ));
    }
    let recording = Recording {
        file,
        written: r.file.value.clone(),
        selector,
        samples: samples.values.len(),
        fault,
    };
    Ok(((recording, rate), params))
}

/// Where recording `r` (number `k`) says its samples are: at most one of `variable`,
/// `channel_index` and `column`, or none.
fn selector_of(ctx: &Ctx<'_>, k: usize, r: &RecordingSection) -> Result<Selector, StudyError> {
    let mut given = Vec::new();
    if let Some(v) = &r.variable {
        given.push((
            "variable",
            at(&v.referenced),
            Selector::Variable(v.value.clone()),
        ));
    }
    if let Some(c) = &r.channel_index {
        given.push((
            "channel_index",
            at(&c.referenced),
            Selector::ChannelIndex(c.value as usize),
        ));
    }
    if let Some(c) = &r.column {
        let column = match &c.value {
            Scalar::Num(x) if x.fract() == 0.0 && *x >= 0.0 => ColumnRef::Index(*x as usize),
            Scalar::Text(name) => ColumnRef::Name(name.clone()),
            Scalar::Num(x) => {
                let field = format!("recordings[{k}].column");
                let rule = format!("{x} is not allowed: a header name or a 0-based index");
                return Err(ctx.err(Some(at(&c.referenced)), &field, rule));
            }
        };
        given.push(("column", at(&c.referenced), Selector::Column(column)));
    }
    match given.len() {
        0 => Ok(Selector::None),
        1 => Ok(given.pop().expect("one").2),
        _ => Err(ctx.err(
            Some(given[1].1),
            &format!("recordings[{k}].{}", given[1].0),
            format!(
                "give one of variable, channel_index and column, not both `{}` and `{}`",
                given[0].0, given[1].0
            ),
        )),
    }
}

/// The fault label `fault` (at `prefix.fault`): `none`, or races of
/// [`DefectRace::ALL`] joined by `+`, each once; written in that order, as a
/// simulated case's label is.
fn fault_of(ctx: &Ctx<'_>, prefix: &str, fault: &S<String>) -> Result<String, StudyError> {
    let field = format!("{prefix}.fault");
    if fault.value == "none" {
        return Ok(fault.value.clone());
    }
    let parts: Vec<&str> = fault.value.split('+').map(str::trim).collect();
    let known = |p: &&str| DefectRace::ALL.iter().any(|r| r.name() == *p);
    let twice = |p: &&str| parts.iter().filter(|q| *q == p).count() > 1;
    if let Some(bad) = parts.iter().find(|p| !known(p) || twice(p)) {
        return Err(ctx.err(
            Some(at(&fault.referenced)),
            &field,
            format!(
                "`{}` is not a fault label (`{bad}`): none, or outer, inner, ball, each once, \
                 joined by +",
                fault.value
            ),
        ));
    }
    let races = DefectRace::ALL.iter().map(|r| r.name());
    Ok(races
        .filter(|r| parts.contains(r))
        .collect::<Vec<_>>()
        .join("+"))
}

/// A recording that cannot be read, refused at the field the error is about: the
/// selector's for what it names, the file's otherwise; naming recording `k`, its file
/// and what is wrong.
fn read_refusal(
    ctx: &Ctx<'_>,
    k: usize,
    entry: &S<RecordingSection>,
    file: &Path,
    e: ReadError,
) -> StudyError {
    let r = &entry.value;
    let selector = [
        ("variable", r.variable.as_ref().map(|v| at(&v.referenced))),
        (
            "channel_index",
            r.channel_index.as_ref().map(|v| at(&v.referenced)),
        ),
        ("column", r.column.as_ref().map(|v| at(&v.referenced))),
    ]
    .into_iter()
    .find_map(|(key, place)| place.map(|p| (key, p)));
    let (key, place) = match (&e, selector) {
        (ReadError::Selection { .. } | ReadError::Shape { .. }, Some(s)) => s,
        _ => ("file", at(&r.file.referenced)),
    };
    ctx.err(
        Some(place),
        &format!("recordings[{k}].{key}"),
        format!("recording {k} ({}) cannot be used: {e}", file.display()),
    )
}

/// The sampling every recording is analysed at: their one sample rate (another is
/// refused, naming the recording) and a duration of `window` or the shortest
/// recording's samples (its last sample left out of the analysis, as the one at
/// `t = duration` of a simulated case is); a grid's `duration` and `sample_rate`
/// only if they agree.
fn common_sampling(
    ctx: &Ctx<'_>,
    file: &GridFile,
    read: &[(Recording, f64)],
) -> Result<Sampling, StudyError> {
    let entries = &file.recordings.as_ref().expect("a recordings study").value;
    let rate = read[0].1;
    if let Some(k) = read.iter().position(|(_, r)| *r != rate) {
        return Err(ctx.err(
            Some(at(&entries[k].value.sample_rate.referenced)),
            &format!("recordings[{k}].sample_rate"),
            format!(
                "recording {k} ({}) is sampled at {} Hz, recording 0 at {} Hz: every \
                 recording of a study shares one sample rate",
                read[k].0.file.display(),
                number(read[k].1),
                number(rate)
            ),
        ));
    }
    let shortest = (0..read.len())
        .min_by_key(|&k| read[k].0.samples)
        .expect("at least one recording");
    let available = read[shortest].0.samples;
    let duration = match &file.window {
        Some(w) => ctx.quantity(w, Dimension::Time, "window")?,
        None => available.saturating_sub(1) as f64 / rate,
    };
    let sampling = Sampling {
        duration,
        sample_rate: rate,
    };
    let too_short = available < 3 || sampling.validate().is_ok() && sampling.len() > available;
    if too_short {
        return Err(ctx.err(
            Some(at(&entries[shortest].value.file.referenced)),
            &format!("recordings[{shortest}].file"),
            format!(
                "recording {shortest} ({}) holds {available} samples: too short for the \
                 analysis, which needs at least 3{}",
                read[shortest].0.file.display(),
                match &file.window {
                    Some(_) => format!(" and {} for `window`", sampling.len()),
                    None => String::new(),
                }
            ),
        ));
    }
    sampling.validate().map_err(|e| {
        let place = file.window.as_ref().map(|w| at(&w.referenced));
        ctx.err(place, "window", e.refusal())
    })?;
    check_given(ctx, file, &sampling)?;
    Ok(sampling)
}

/// Refuses a grid's `duration` or `sample_rate` unless it agrees with the
/// recordings' `sampling` (to 1e-9 of it).
fn check_given(ctx: &Ctx<'_>, file: &GridFile, sampling: &Sampling) -> Result<(), StudyError> {
    let given = [
        (
            "duration",
            &file.duration,
            Dimension::Time,
            sampling.duration,
        ),
        (
            "sample_rate",
            &file.sample_rate,
            Dimension::Frequency,
            sampling.sample_rate,
        ),
    ];
    for (key, v, dim, want) in given {
        let Some(v) = v else { continue };
        let x = ctx.quantity(v, dim, key)?;
        if (x - want).abs() > 1e-9 * want.abs() {
            return Err(ctx.err(
                Some(at(&v.referenced)),
                key,
                format!(
                    "{} disagrees with the recordings' {} {}: a recordings study takes it \
                     from them (leave it out, or use `window:` for the analysed length)",
                    v.value,
                    number(want),
                    dim.base_unit()
                ),
            ));
        }
    }
    Ok(())
}
