//! From the serde mirror to a validated [`Study`]: units, effects, expansion, checks.

use std::collections::HashMap;
use std::path::Path;

use serde_saphyr::Location;

use super::config::{
    BandValue, BearingSection, CaseValue, DefectSection, EnvelopeSection, GridFile, OutputSection,
    Scalar, SeriesValue, SpectraSection, SpeedSection, WavinessSection, S,
};
use super::memory::Limits;
use super::params::{lookup, ParamDef, PARAMETERS};
use super::units::Dimension;
use super::{Case, SeriesOutput, Study, StudyError, DEFAULT_MAX_CASES};
use crate::error::number;

mod design;
mod memory_check;
mod replicates;
mod sensors;
use crate::bearing::stiffness::ContactGeometry;
use crate::bearing::{
    DampingModel, Defect, DefectProfile, DefectRace, Harmonic, RaceWaviness, RestitutionLaw,
};
use crate::mechanism::{CaseParams, Housing, Location as Site, SpeedProfile};
use crate::output::study_layout;
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

/// Which effects a study simulates; anything off is not computed at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Effects {
    /// Diametral clearance (off: zero clearance).
    pub clearance: bool,
    /// Raceway waviness (off: perfect races, no per-ball waviness terms).
    pub waviness: bool,
    /// Contact damping (off: C = 0).
    pub damping: bool,
    /// Gravity along −y.
    pub gravity: bool,
    /// Localized defects (off: no defects, no defect code in the kernel).
    pub defects: bool,
    /// The sprung housing at crank_ground (docs/model.md §3.9; off: rigid ground, no
    /// housing state, no `housing_*` series).
    pub housing: bool,
}

impl Effects {
    const NAMES: [&'static str; 6] = [
        "clearance",
        "waviness",
        "damping",
        "gravity",
        "defects",
        "housing",
    ];

    /// The names of the effects that are on.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [
            self.clearance,
            self.waviness,
            self.damping,
            self.gravity,
            self.defects,
            self.housing,
        ];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, o)| *o)
            .map(|(n, _)| *n)
            .collect()
    }

    /// The indices into [`CHANNELS`] of the channels simulated under these effects:
    /// those whose effect is `None` or on, in [`CHANNELS`] order.
    pub fn channels(&self) -> Vec<usize> {
        let on = self.names();
        (0..CHANNELS.len())
            .filter(|&c| CHANNELS[c].effect.is_none_or(|e| on.contains(&e)))
            .collect()
    }

    /// The parameters a study file records per case: every one of [`PARAMETERS`]
    /// but the housing's (`m_h`, `k_h`, `c_h`) while the housing effect is off.
    pub fn recorded_parameters(&self) -> impl Iterator<Item = &'static ParamDef> + '_ {
        PARAMETERS
            .iter()
            .filter(|p| self.housing || !HOUSING_PARAMETERS.contains(&p.name))
    }

    /// The effect a parameter belongs to, if switching that effect off forbids it.
    fn governing(&self, param: &str) -> Option<(&'static str, bool)> {
        if param.contains("waviness") {
            Some(("waviness", self.waviness))
        } else if param == "damping" {
            Some(("damping", self.damping))
        } else if param == "clearance" {
            Some(("clearance", self.clearance))
        } else if param.starts_with("defect") {
            Some(("defects", self.defects))
        } else if HOUSING_PARAMETERS.contains(&param) {
            Some(("housing", self.housing))
        } else {
            None
        }
    }
}

/// The parameters of the housing (`housing:`, docs/model.md §3.9).
const HOUSING_PARAMETERS: [&str; 3] = ["m_h", "k_h", "c_h"];

/// One axis of the expansion: parameter name, its values, and its YAML field.
type Axis<'a> = (&'a String, &'a S<Vec<S<Scalar>>>, String);

/// Where each parameter of a case was set: (parameter, YAML field, line/column).
type Provenance = Vec<(&'static str, String, (u64, u64))>;

fn at(l: &Location) -> (u64, u64) {
    (l.line(), l.column())
}

struct Ctx<'a> {
    path: &'a Path,
}

impl Ctx<'_> {
    fn err(
        &self,
        place: Option<(u64, u64)>,
        field: &str,
        message: impl Into<String>,
    ) -> StudyError {
        StudyError {
            path: self.path.to_path_buf(),
            location: place,
            field: field.to_string(),
            message: message.into(),
        }
    }

    /// A quantity in `dim`'s base unit, finite.
    fn quantity(&self, v: &S<Scalar>, dim: Dimension, field: &str) -> Result<f64, StudyError> {
        let place = Some(at(&v.referenced));
        let x = match &v.value {
            Scalar::Num(x) => *x,
            Scalar::Text(t) => dim.parse(t).map_err(|m| self.err(place, field, m))?,
        };
        if !x.is_finite() {
            return Err(self.err(
                place,
                field,
                format!("{} is not finite; expected {}", v.value, dim.accepted()),
            ));
        }
        Ok(x)
    }

    /// Sets parameter `name` (or `location`) of `case` from `v`, recording where.
    fn apply(
        &self,
        case: &mut CaseParams,
        name: &str,
        v: &S<Scalar>,
        field: &str,
        effects: &Effects,
        prov: &mut Provenance,
    ) -> Result<(), StudyError> {
        let target = self.resolve(case, name, v, field, effects)?;
        target.set(case);
        prov.push((target.name(), field.to_string(), at(&v.referenced)));
        Ok(())
    }

    /// What setting parameter `name` (or `location`) from `v` does, checked: the
    /// effect is on, the parameter exists, the unit fits, a count is a whole number.
    /// `case` (the case being built) only words the messages.
    fn resolve(
        &self,
        case: &CaseParams,
        name: &str,
        v: &S<Scalar>,
        field: &str,
        effects: &Effects,
    ) -> Result<Target, StudyError> {
        let place = at(&v.referenced);
        if let Some((effect, false)) = effects.governing(name) {
            return Err(self.err(
                Some(place),
                field,
                format!("the {effect} effect is off (effects: [{}]); add `{effect}` to `effects` to set it", effects.names().join(", ")),
            ));
        }
        if name == "location" {
            let Scalar::Text(t) = &v.value else {
                return Err(self.err(
                    Some(place),
                    field,
                    format!(
                        "{} is not a location; expected one of ideal, crank_ground, crank_rod",
                        v.value
                    ),
                ));
            };
            let site = t
                .parse()
                .map_err(|e: crate::error::ParamError| self.err(Some(place), field, e.refusal()))?;
            return Ok(Target::Location(site));
        }
        if name == "defect_race" {
            let race = match &v.value {
                Scalar::Text(t) => t.parse::<DefectRace>().ok(),
                Scalar::Num(_) => None,
            };
            return race.map(Target::DefectRace).ok_or_else(|| {
                self.err(
                    Some(place),
                    field,
                    format!(
                        "{} is not a defect race; expected one of outer, inner, ball",
                        v.value
                    ),
                )
            });
        }
        let param = lookup(name).ok_or_else(|| {
            let names: Vec<&str> = PARAMETERS.iter().map(|p| p.name).collect();
            self.err(
                Some(place),
                field,
                format!(
                    "unknown parameter; expected location, defect_race or one of: {}",
                    names.join(", ")
                ),
            )
        })?;
        check_speed(case, param.name).map_err(|m| self.err(Some(place), field, m))?;
        let x = self.quantity(v, param.dimension, field)?;
        if param.integer && (x.fract() != 0.0 || x < 0.0 || x > u32::MAX as f64) {
            let rule = if param.name == "ball_count" {
                match max_balls(&case.bearing) {
                    Some(max) if max >= 3 => format!(
                        "ball_count must be a whole number of balls from 3 to {max}, got {} \
                         ({max} balls fit between these races)",
                        v.value
                    ),
                    _ => format!(
                        "ball_count must be a whole number of balls, 3 or more, got {}",
                        v.value
                    ),
                }
            } else {
                format!(
                    "{} must be a whole number of waves, 1 or more, got {}",
                    param.name, v.value
                )
            };
            return Err(self.err(Some(place), field, rule));
        }
        Ok(Target::Param(param, x))
    }
}

impl Ctx<'_> {
    /// A `speed:` section written at `loc` under the name `prefix` (`speed`,
    /// `cases[2].speed`) as a checked profile; records where its scalar fields came
    /// from in `prov`.
    fn speed(
        &self,
        s: &SpeedSection,
        loc: &Location,
        prefix: &str,
        prov: &mut Provenance,
    ) -> Result<SpeedProfile, StudyError> {
        let place = Some(at(loc));
        let fields: &[&str] = match s.profile.as_str() {
            "ramp" => &["from", "to", "over"],
            "sine" => &["mean", "amplitude", "frequency"],
            "table" => &["time", "rpm"],
            other => {
                return Err(self.err(
                    place,
                    &format!("{prefix}.profile"),
                    format!("unknown profile `{other}`; expected ramp, sine or table"),
                ))
            }
        };
        let profile = s.profile.as_str();
        let given = [
            ("from", s.from.is_some()),
            ("to", s.to.is_some()),
            ("over", s.over.is_some()),
            ("mean", s.mean.is_some()),
            ("amplitude", s.amplitude.is_some()),
            ("frequency", s.frequency.is_some()),
            ("time", s.time.is_some()),
            ("rpm", s.rpm.is_some()),
        ];
        for (key, present) in given {
            let takes = fields.contains(&key);
            if present != takes {
                let why = if present {
                    format!("`{key}` is not a field of the {profile} profile")
                } else {
                    format!("the {profile} profile needs `{key}`")
                };
                return Err(self.err(
                    place,
                    &format!("{prefix}.{key}"),
                    format!("{why}; it takes {}", fields.join(", ")),
                ));
            }
        }
        let one = |v: &Option<Scalar>, dim: Dimension, key: &str| {
            let v = S::new(v.clone().unwrap_or(Scalar::Num(f64::NAN)), *loc, *loc);
            self.quantity(&v, dim, &format!("{prefix}.{key}"))
        };
        let list = |v: &Option<Vec<Scalar>>, dim: Dimension, key: &str| {
            v.iter()
                .flatten()
                .enumerate()
                .map(|(k, x)| {
                    let x = S::new(x.clone(), *loc, *loc);
                    self.quantity(&x, dim, &format!("{prefix}.{key}[{k}]"))
                })
                .collect::<Result<Vec<f64>, StudyError>>()
        };
        let p = match profile {
            "ramp" => SpeedProfile::Ramp {
                from: one(&s.from, Dimension::Speed, "from")?,
                to: one(&s.to, Dimension::Speed, "to")?,
                over: one(&s.over, Dimension::Time, "over")?,
            },
            "sine" => SpeedProfile::Sine {
                mean: one(&s.mean, Dimension::Speed, "mean")?,
                amplitude: one(&s.amplitude, Dimension::Speed, "amplitude")?,
                frequency: one(&s.frequency, Dimension::Frequency, "frequency")?,
            },
            _ => SpeedProfile::Table {
                time: list(&s.time, Dimension::Time, "time")?,
                rpm: list(&s.rpm, Dimension::Speed, "rpm")?,
            },
        };
        p.validate().map_err(|e| {
            let field = e.field.replacen("speed", prefix, 1);
            self.err(place, &field, e.refusal())
        })?;
        for key in fields {
            if let Some(param) = lookup(&format!("speed_{key}")) {
                prov.push((param.name, format!("{prefix}.{key}"), at(loc)));
            }
        }
        Ok(p)
    }
}

/// Why `param` cannot be set in `case`: `rpm` where the case has a `speed:`
/// profile, a `speed_*` axis of another profile than the case's.
fn check_speed(case: &CaseParams, param: &str) -> Result<(), String> {
    let has = case.speed.as_ref().map(SpeedProfile::name);
    let needs = match param {
        "speed_from" | "speed_to" | "speed_over" => "ramp",
        "speed_mean" | "speed_amplitude" | "speed_frequency" => "sine",
        "rpm" => match has {
            Some(p) => {
                return Err(format!(
                    "rpm and speed both given: the case's speed is a {p} profile (`speed:`); \
                     give one of them"
                ))
            }
            None => return Ok(()),
        },
        _ => return Ok(()),
    };
    match has {
        Some(p) if p == needs => Ok(()),
        _ => Err(format!(
            "{param} sets a field of the {needs} profile, and the case's speed is {}; \
             give `speed: {{profile: {needs}, ...}}`",
            has.map_or("the constant `rpm`".to_string(), |p| format!(
                "a {p} profile"
            ))
        )),
    }
}

/// What one value of a grid sets in a case, resolved once before the expansion.
#[derive(Debug, Clone, Copy)]
enum Target {
    /// A scalar parameter, in its base unit.
    Param(&'static ParamDef, f64),
    /// The bearing location.
    Location(Site),
    /// The race of the first defect.
    DefectRace(DefectRace),
}

impl Target {
    fn set(&self, case: &mut CaseParams) {
        match *self {
            Target::Param(p, x) => p.set(case, x),
            Target::Location(site) => case.location = site,
            Target::DefectRace(race) => Defect::first(&mut case.bearing.defects).race = race,
        }
    }

    /// The parameter's name, as in [`Provenance`].
    fn name(&self) -> &'static str {
        match self {
            Target::Param(p, _) => p.name,
            Target::Location(_) => "location",
            Target::DefectRace(_) => "defect_race",
        }
    }

    /// Whether two values of one axis are the same (`-0` is `0`).
    fn same_as(&self, other: &Target) -> bool {
        match (self, other) {
            (Target::Param(_, a), Target::Param(_, b)) => a == b,
            (Target::Location(a), Target::Location(b)) => a == b,
            (Target::DefectRace(a), Target::DefectRace(b)) => a == b,
            _ => false,
        }
    }
}

/// The most balls of the bearing's race diameters that fit side by side around the
/// pitch circle: balls of diameter `D = (d_o − d_i)/2` with centres on the circle of
/// diameter `d_m = (d_i + d_o)/2` touch when `N_b = π / asin(D/d_m)` (a full
/// complement, no cage). `None` when the diameters are not a bearing.
pub(crate) fn max_balls(b: &crate::bearing::BearingParams) -> Option<usize> {
    let (di, d_o) = (b.inner_race_diameter, b.outer_race_diameter);
    if !(di.is_finite() && d_o.is_finite() && di > 0.0 && d_o > di) {
        return None;
    }
    let ratio = (d_o - di) / (d_o + di);
    Some((std::f64::consts::PI / ratio.asin() + 1e-9).floor() as usize)
}

/// One grid axis with its values resolved: its YAML field and, per value, what it
/// sets and where it is written.
struct ResolvedAxis<'a> {
    field: &'a str,
    values: Vec<(Target, (u64, u64))>,
}

/// Builds the study from grid-file text, refusing it when its run would need more
/// memory than `limits` allow ([`memory_check`]: a lower bound before the cases are
/// expanded and once their speeds are known, the exact estimate at the end). The
/// steps: parse, sampling, effects and base case, solver, axes, case count, axis
/// values, memory, expansion, references, analysed window, spectra and output
/// settings, memory.
pub(super) fn build(text: &str, path: &Path, limits: &Limits) -> Result<Study, StudyError> {
    let ctx = Ctx { path };
    if let Some((place, field, message)) = super::tree::first_empty(text) {
        return Err(ctx.err(Some(place), &field, message));
    }
    let file: GridFile = serde_saphyr::from_str(text).map_err(|e| {
        let (place, field, message) = super::yaml::describe(&e, text);
        ctx.err(place, &field, message)
    })?;
    check_name(&ctx, &file.name)?;
    let sampling = sampling_of(&ctx, &file)?;
    let effects = effects(&ctx, &file)?;
    let mut prov = Provenance::new();
    let base = base_case(&ctx, &file, &effects, &mut prov)?;
    let solver = solver(&ctx, &file, &sampling)?;
    let (groups, axes_names) = axis_groups(&ctx, &file)?;
    let rows = design::rows(&ctx, &file)?;
    let (total, count) = case_count(&ctx, &file, &groups, rows)?;
    // Before the design is drawn: its values are rows × parameters.
    let places = memory_check::Places::of(&file);
    let mut known = memory_check::Known {
        samples: sampling.len() as u64,
        cases: total,
        design_values: file.design.as_ref().map_or(0, |d| {
            rows.saturating_mul(d.value.parameters.value.len() as u64)
        }),
        references: 0,
        revolutions: 0,
        speed_knots: memory_check::speed_knots(&file),
    };
    memory_check::check_lower_bound(&ctx, &places, &known, limits)?;
    let sampled = design::resolve(&ctx, &file, &base, &effects, &axes_names)?;
    let mut resolved = resolve_axes(&ctx, &base, &groups, &effects)?;
    check_repeats(&ctx, &resolved)?;
    if let Some(d) = &sampled {
        resolved.push(d.group());
    }
    let mut cases = Vec::with_capacity(total as usize);
    expand_grid(&ctx, &base, &prov, &resolved, count, &effects, &mut cases)?;
    let explicit_design = sampled.as_ref().map(|_| &resolved[resolved.len() - 1]);
    expand_explicit(
        &ctx,
        &file,
        &base,
        &prov,
        explicit_design,
        &effects,
        &mut cases,
    )?;
    let references = assign_references(&mut cases);
    let transient = transient_of(&ctx, &file, &sampling, &cases)?;
    let sensors = match &file.sensors {
        Some(list) => sensors::sensors(&ctx, list, &sampling, &effects)?,
        None => Vec::new(),
    };
    let analysed = (&sensors[..], &effects);
    let (window, spectrum_channels) = spectra_settings(&ctx, file.spectra.as_ref(), analysed)?;
    let envelope = file
        .envelope
        .as_ref()
        .map(|e| envelope_settings(&ctx, e, &sampling, transient, analysed))
        .transpose()?;
    let orders = order_settings(&ctx, &file, &sampling, transient, &cases)?;
    let (float32, compression) = output_settings(&ctx, file.output.as_ref())?;
    let (replicates, chaos_check) = replicates::resolve(&ctx, &file)?;
    let revolutions = cases
        .iter()
        .map(|c| revolution_count(&c.params.drive(), transient, sampling.duration))
        .max()
        .unwrap_or(0);
    known.references = references.len() as u64;
    known.revolutions = revolutions as u64;
    memory_check::check_lower_bound(&ctx, &places, &known, limits)?;
    let mut study = Study {
        name: file.name.value,
        description: file.description.unwrap_or_default(),
        source: text.to_string(),
        path: path.to_path_buf(),
        sampling,
        solver,
        effects,
        transient,
        window,
        spectrum_channels,
        envelope,
        orders,
        float32,
        compression,
        axes: axes_names,
        cases,
        references,
        design: sampled.map(|d| d.info),
        replicates,
        chaos_check,
        revolutions,
        sensors: Vec::new(),
        output: SeriesOutput::default(),
    };
    if let Some(list) = &file.sensors {
        let taken = study_layout(&study, &[], None)
            .names()
            .map(str::to_string)
            .collect();
        sensors::check_names(&ctx, list, &sensors, &taken)?;
        study.sensors = sensors;
    }
    study.output = series_output(&ctx, file.output.as_ref(), &study)?;
    memory_check::check_study(&ctx, &places, &study, limits)?;
    Ok(study)
}

/// The order analysis the file asks for (`spectra: {orders: true}`,
/// `envelope: {orders: true}`), or `None`: `R` is the fewest whole revolutions any
/// case turns between the analysed window's first and last samples (at least one),
/// `M` the window's sample count (docs/model.md §7.9).
fn order_settings(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    transient: f64,
    cases: &[Case],
) -> Result<Option<OrderSettings>, StudyError> {
    let spectra = file.spectra.as_ref().and_then(|s| s.orders.as_ref());
    let envelope = file.envelope.as_ref().and_then(|e| e.value.orders.as_ref());
    let asked = |o: Option<&S<bool>>| o.is_some_and(|o| o.value);
    if !asked(spectra) && !asked(envelope) {
        return Ok(None);
    }
    let (key, field) = match spectra.filter(|o| o.value) {
        Some(o) => (o, "spectra.orders"),
        None => (envelope.expect("asked"), "envelope.orders"),
    };
    let window = sampling.analysis_window(transient);
    let (first, last) = (
        window.start as f64 / sampling.sample_rate,
        (window.end.max(1) - 1) as f64 / sampling.sample_rate,
    );
    let mut fewest: Option<(usize, u64)> = None;
    for c in cases {
        let r = whole_revolutions(&c.params.drive(), first, last);
        if fewest.is_none_or(|(f, _)| r < f) {
            fewest = Some((r, c.id));
        }
    }
    let (revolutions, id) = fewest.unwrap_or((0, 0));
    if revolutions == 0 || window.len() < 2 {
        return Err(ctx.err(
            Some(at(&key.referenced)),
            field,
            format!(
                "order spectra need at least one whole crank revolution in every case's \
                 analysed window ({first} s to {last} s); case {id} turns less: lengthen \
                 `duration` or shorten `transient`"
            ),
        ));
    }
    Ok(Some(OrderSettings {
        revolutions,
        samples: window.len(),
        spectra: asked(spectra),
        envelope: asked(envelope),
    }))
}

/// `duration` and `sample_rate`, checked.
fn sampling_of(ctx: &Ctx<'_>, file: &GridFile) -> Result<Sampling, StudyError> {
    let sampling = Sampling {
        duration: ctx.quantity(&file.duration, Dimension::Time, "duration")?,
        sample_rate: ctx.quantity(&file.sample_rate, Dimension::Frequency, "sample_rate")?,
    };
    sampling.validate().map_err(|e| {
        ctx.err(
            Some(at(if e.field == "duration" {
                &file.duration.referenced
            } else {
                &file.sample_rate.referenced
            })),
            &e.field,
            e.refusal(),
        )
    })?;
    Ok(sampling)
}

/// The axes in groups (each grid axis a group of one; zip groups vary together) and
/// their names in expansion order; refuses unequal zips, empty axes, an axis given
/// twice and an empty study.
fn axis_groups<'a>(
    ctx: &Ctx<'_>,
    file: &'a GridFile,
) -> Result<(Vec<Vec<Axis<'a>>>, Vec<String>), StudyError> {
    let mut groups: Vec<Vec<Axis<'_>>> = file
        .grid
        .iter()
        .map(|(name, values)| vec![(name, values, format!("grid.{name}"))])
        .collect();
    for (g, group) in file.zip.iter().enumerate() {
        let axes: Vec<_> = group
            .value
            .iter()
            .map(|(n, v)| (n, v, format!("zip[{g}].{n}")))
            .collect();
        if let Some(&(_, first, _)) = axes.first() {
            for (_, v, field) in &axes {
                if v.value.len() != first.value.len() {
                    return Err(ctx.err(
                        Some(at(&v.referenced)),
                        field,
                        format!("{} values, but `{}` in the same zip group has {}; zipped axes need equal lengths", v.value.len(), axes[0].0, first.value.len()),
                    ));
                }
            }
            groups.push(axes);
        }
    }
    let mut axes_names = Vec::new();
    for group in &groups {
        for (name, values, field) in group {
            if values.value.is_empty() {
                return Err(ctx.err(
                    Some(at(&values.referenced)),
                    field,
                    "an axis needs at least one value",
                ));
            }
            if axes_names.contains(*name) {
                return Err(ctx.err(
                    Some(at(&values.referenced)),
                    field,
                    "this parameter is already an axis",
                ));
            }
            axes_names.push((*name).clone());
        }
    }
    if groups.is_empty() && file.cases.is_empty() && file.design.is_none() {
        return Err(ctx.err(
            None,
            "grid",
            "the study is empty: give `grid:` axes, `zip:` groups, `cases:` or a `design:`",
        ));
    }
    Ok((groups, axes_names))
}

/// The number of cases in all and from the axes, refused above `max_cases` before
/// anything is expanded.
fn case_count(
    ctx: &Ctx<'_>,
    file: &GridFile,
    groups: &[Vec<Axis<'_>>],
    design_rows: u64,
) -> Result<(u64, u64), StudyError> {
    let max_cases = file
        .max_cases
        .as_ref()
        .map(|m| m.value)
        .unwrap_or(DEFAULT_MAX_CASES);
    // Without axes the grid has no point, unless a design stands alone on the base.
    let alone = file.design.is_some() && file.cases.is_empty();
    let empty = if groups.is_empty() && !alone { 0 } else { 1 };
    let product = groups
        .iter()
        .try_fold(empty, |acc: u64, g| {
            acc.checked_mul(g[0].1.value.len() as u64)
        })
        .and_then(|p| p.checked_mul(design_rows));
    let total = product.and_then(|p| {
        (file.cases.len() as u64)
            .checked_mul(design_rows)
            .and_then(|c| p.checked_add(c))
    });
    match total {
        Some(t) if t <= max_cases => Ok((t, product.unwrap_or(0))),
        _ => Err(ctx.err(
            file.max_cases.as_ref().map(|m| at(&m.referenced)),
            "grid",
            match total {
                Some(t) => format!(
                    "the grid expands to {t} cases, more than max_cases = {max_cases}; their case \
                     table alone would need about {} of memory; raise `max_cases` if you mean it",
                    super::memory::bytes(t as f64 * super::memory::case_table_bytes())
                ),
                None => format!(
                    "the grid expands to over 2^64 cases, more than max_cases = {max_cases}"
                ),
            },
        )),
    }
}

/// Every axis value resolved once (units, effects, whole numbers).
fn resolve_axes<'a>(
    ctx: &Ctx<'_>,
    base: &CaseParams,
    groups: &'a [Vec<Axis<'_>>],
    effects: &Effects,
) -> Result<Vec<Vec<ResolvedAxis<'a>>>, StudyError> {
    groups
        .iter()
        .map(|group| {
            group
                .iter()
                .map(|(name, values, field)| {
                    let values = values
                        .value
                        .iter()
                        .enumerate()
                        .map(|(k, v)| {
                            let target =
                                ctx.resolve(base, name, v, &format!("{field}[{k}]"), effects)?;
                            Ok((target, at(&v.referenced)))
                        })
                        .collect::<Result<Vec<_>, StudyError>>()?;
                    Ok(ResolvedAxis {
                        field: field.as_str(),
                        values,
                    })
                })
                .collect::<Result<Vec<_>, StudyError>>()
        })
        .collect()
}

/// The grid's `count` cases: each is the base with one value of every group (mixed
/// radix over the groups, last group fastest). Where each value came from is only
/// put together when a case is refused.
fn expand_grid(
    ctx: &Ctx<'_>,
    base: &CaseParams,
    prov: &Provenance,
    resolved: &[Vec<ResolvedAxis<'_>>],
    count: u64,
    effects: &Effects,
    cases: &mut Vec<Case>,
) -> Result<(), StudyError> {
    let mut picks = vec![0usize; resolved.len()];
    for i in 0..count {
        let mut rest = i;
        for (g, group) in resolved.iter().enumerate().rev() {
            let len = group[0].values.len() as u64;
            picks[g] = (rest % len) as usize;
            rest /= len;
        }
        let mut params = base.clone();
        for (group, &k) in resolved.iter().zip(&picks) {
            for axis in group {
                axis.values[k].0.set(&mut params);
            }
        }
        let provenance = || {
            let mut p = prov.clone();
            for (group, &k) in resolved.iter().zip(&picks) {
                for axis in group {
                    let (target, place) = axis.values[k];
                    p.push((target.name(), format!("{}[{k}]", axis.field), place));
                }
            }
            p
        };
        cases.push(finish_case(ctx, params, effects, provenance, i)?);
    }
    Ok(())
}

/// The explicit `cases:`, each over the base, after the grid's; with a design,
/// each explicit case once per design row (the design's group, rows fastest).
fn expand_explicit(
    ctx: &Ctx<'_>,
    file: &GridFile,
    base: &CaseParams,
    prov: &Provenance,
    design: Option<&Vec<ResolvedAxis<'_>>>,
    effects: &Effects,
    cases: &mut Vec<Case>,
) -> Result<(), StudyError> {
    let rows = design.map_or(1, |g| g[0].values.len());
    for (c, explicit) in file.cases.iter().enumerate() {
        if let (Some(rpm), true) = (
            explicit.value.get("rpm"),
            explicit.value.contains_key("speed"),
        ) {
            return Err(ctx.err(
                Some(at(&rpm.referenced)),
                &format!("cases[{c}].rpm"),
                "rpm and speed both given; give either `rpm` (a constant speed) or `speed` \
                 (a profile)",
            ));
        }
        for row in 0..rows {
            let mut params = base.clone();
            let mut case_prov = prov.clone();
            for axis in design.into_iter().flatten() {
                let (target, place) = axis.values[row];
                target.set(&mut params);
                case_prov.push((target.name(), format!("{}[{row}]", axis.field), place));
            }
            for (name, value) in &explicit.value {
                let field = format!("cases[{c}].{name}");
                match &value.value {
                    CaseValue::Scalar(x) => {
                        let v = S::new(x.clone(), value.referenced, value.defined);
                        ctx.apply(&mut params, name, &v, &field, effects, &mut case_prov)?;
                    }
                    CaseValue::Speed(sp) if name == "speed" => {
                        params.speed =
                            Some(ctx.speed(sp, &value.referenced, &field, &mut case_prov)?);
                        params.rpm = f64::NAN;
                    }
                    CaseValue::Speed(_) => {
                        return Err(ctx.err(
                            Some(at(&value.referenced)),
                            &field,
                            format!("`{name}` takes a single value; only `speed` takes a mapping"),
                        ))
                    }
                }
            }
            let id = cases.len() as u64;
            cases.push(finish_case(ctx, params, effects, || case_prov, id)?);
        }
    }
    Ok(())
}

/// One reference per distinct ideal mechanism, found by hashing (not by comparing
/// every case with every reference); sets each case's `reference`.
fn assign_references(cases: &mut [Case]) -> Vec<CaseParams> {
    let mut references: Vec<CaseParams> = Vec::new();
    let mut index: HashMap<ReferenceKey, usize> = HashMap::new();
    for case in cases {
        let reference = reference_of(&case.params);
        case.reference = *index.entry(reference_key(&reference)).or_insert_with(|| {
            references.push(reference);
            references.len() - 1
        });
    }
    references
}

/// The start of the analysed window (s): the grid's `transient`, or `auto` (the
/// longest first crank revolution of any case, at most half the duration); it must
/// leave two samples for the spectra and metrics.
fn transient_of(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    cases: &[Case],
) -> Result<f64, StudyError> {
    let revolution = cases
        .iter()
        .map(|c| c.params.revolution_time())
        .fold(0.0, f64::max);
    let transient = match &file.transient {
        None => revolution.min(0.5 * sampling.duration),
        Some(S {
            value: Scalar::Text(t),
            ..
        }) if t == "auto" => revolution.min(0.5 * sampling.duration),
        Some(v) => {
            let x = ctx.quantity(v, Dimension::Time, "transient")?;
            if !(0.0..sampling.duration).contains(&x) {
                return Err(ctx.err(
                    Some(at(&v.referenced)),
                    "transient",
                    format!(
                        "{} s is not allowed: >= 0 and below duration = {} s",
                        number(x),
                        number(sampling.duration)
                    ),
                ));
            }
            x
        }
    };
    // Spectra (Hann) and metrics need two samples in `transient ≤ t < duration`.
    let analysed = sampling.analysis_window(transient).len();
    if analysed < 2 {
        let last_sample = sampling.len() - 1;
        return Err(ctx.err(
            file.transient.as_ref().map(|v| at(&v.referenced)),
            "transient",
            format!(
                "{} s leaves {analysed} sample(s) in the analysed window \
                 transient <= t < duration = {} s at {} Hz; at least 2 are needed \
                 (a transient of at most {} s, or a longer duration)",
                number(transient),
                number(sampling.duration),
                number(sampling.sample_rate),
                number(last_sample.saturating_sub(2) as f64 / sampling.sample_rate)
            ),
        ));
    }
    Ok(transient)
}

/// The spectrum window's name and the channels with spectra (simulated channels or
/// the series of `sensors`).
fn spectra_settings(
    ctx: &Ctx<'_>,
    spectra: Option<&SpectraSection>,
    analysed: (&[Sensor], &Effects),
) -> Result<(String, Vec<AnalysisChannel>), StudyError> {
    let default = SpectraSection::default();
    let spectra = spectra.unwrap_or(&default);
    let window = match &spectra.window {
        None => "hann".to_string(),
        Some(w) if w.value == "hann" || w.value == "rectangular" => w.value.clone(),
        Some(w) => {
            return Err(ctx.err(
                Some(at(&w.referenced)),
                "spectra.window",
                format!(
                    "`{}` is not a window; expected hann or rectangular",
                    w.value
                ),
            ))
        }
    };
    let channels = match &spectra.channels {
        None => ["slider_acceleration", "crank_moment", "bearing_force"]
            .into_iter()
            .map(|name| AnalysisChannel::simulated(name).expect("a channel"))
            .collect(),
        Some(list) => list
            .value
            .iter()
            .enumerate()
            .map(|(k, c)| analysis_channel(ctx, c, &format!("spectra.channels[{k}]"), analysed))
            .collect::<Result<_, _>>()?,
    };
    Ok((window, channels))
}

/// The channel of [`CHANNELS`] named by `c` (at `field`), simulated under `effects`.
fn channel_named(
    ctx: &Ctx<'_>,
    c: &S<String>,
    field: &str,
    effects: &Effects,
) -> Result<&'static str, StudyError> {
    let channel = CHANNELS
        .iter()
        .find(|ch| ch.name == c.value)
        .ok_or_else(|| {
            let names: Vec<&str> = CHANNELS.iter().map(|ch| ch.name).collect();
            ctx.err(
                Some(at(&c.referenced)),
                field,
                format!(
                    "unknown channel `{}`; expected one of: {}",
                    c.value,
                    names.join(", ")
                ),
            )
        })?;
    match channel.effect {
        Some(effect) if !effects.names().contains(&effect) => Err(ctx.err(
            Some(at(&c.referenced)),
            field,
            format!(
                "channel `{}` is simulated with the {effect} effect only, which is off \
                 (effects: [{}]); add `{effect}` to `effects` to use it",
                c.value,
                effects.names().join(", ")
            ),
        )),
        _ => Ok(channel.name),
    }
}

/// The series named by `c` (at `field`): a channel of [`CHANNELS`] the study's
/// `effects` simulate or a series of `sensors` (`<name>` or `<name>_clean`).
fn analysis_channel(
    ctx: &Ctx<'_>,
    c: &S<String>,
    field: &str,
    (sensors, effects): (&[Sensor], &Effects),
) -> Result<AnalysisChannel, StudyError> {
    if let Some(ch) = AnalysisChannel::simulated(&c.value) {
        channel_named(ctx, c, field, effects)?;
        return Ok(ch);
    }
    for (k, sensor) in sensors.iter().enumerate() {
        let [noisy, clean] = sensor.specs();
        for (j, spec) in [noisy, clean].into_iter().enumerate() {
            if spec.name == c.value {
                let units = CHANNELS
                    .iter()
                    .find(|ch| ch.name == sensor.channel)
                    .expect("sensor channels are validated")
                    .units;
                return Ok(AnalysisChannel {
                    name: spec.name,
                    units,
                    long_name: spec.long_name,
                    source: Source::Sensor(2 * k + j),
                });
            }
        }
    }
    let names: Vec<String> = CHANNELS
        .iter()
        .map(|ch| ch.name.to_string())
        .chain(
            sensors
                .iter()
                .flat_map(|s| [s.name.clone(), format!("{}{CLEAN_SUFFIX}", s.name)]),
        )
        .collect();
    Err(ctx.err(
        Some(at(&c.referenced)),
        field,
        format!(
            "unknown channel `{}`; expected a simulated channel or a sensor series, one of: {}",
            c.value,
            names.join(", ")
        ),
    ))
}

/// The `envelope:` settings: distinct channels, and a band `[low, high]` with
/// `0 <= low < high <= sample_rate / 2` holding at least one bin of the analysed
/// window, or `auto` (the default).
fn envelope_settings(
    ctx: &Ctx<'_>,
    section: &S<EnvelopeSection>,
    sampling: &Sampling,
    transient: f64,
    analysed: (&[Sensor], &Effects),
) -> Result<EnvelopeSettings, StudyError> {
    let list = &section.value.channels;
    if list.value.is_empty() {
        return Err(ctx.err(
            Some(at(&list.referenced)),
            "envelope.channels",
            "at least one channel is needed",
        ));
    }
    let mut channels: Vec<AnalysisChannel> = Vec::new();
    for (k, c) in list.value.iter().enumerate() {
        let field = format!("envelope.channels[{k}]");
        let channel = analysis_channel(ctx, c, &field, analysed)?;
        if channels.iter().any(|ch| ch.name == channel.name) {
            return Err(ctx.err(
                Some(at(&c.referenced)),
                &field,
                format!("channel `{}` is listed twice", channel.name),
            ));
        }
        channels.push(channel);
    }
    let band = match &section.value.band {
        None => BandChoice::Auto,
        Some(S {
            value: BandValue::Name(name),
            ..
        }) if name == "auto" => BandChoice::Auto,
        Some(v) => {
            let place = Some(at(&v.referenced));
            let bad = |message: String| ctx.err(place, "envelope.band", message);
            let BandValue::Range(edges) = &v.value else {
                return Err(bad(
                    "expected `auto` or two frequencies [low, high], e.g. [\"2 kHz\", \"8 kHz\"]"
                        .to_string(),
                ));
            };
            let [low, high] = edges.as_slice() else {
                return Err(bad(format!(
                    "{} values; expected two frequencies [low, high] or `auto`",
                    edges.len()
                )));
            };
            let hz = |s: &Scalar| -> Result<f64, StudyError> {
                let x = match s {
                    Scalar::Num(x) => *x,
                    Scalar::Text(t) => Dimension::Frequency
                        .parse(t)
                        .map_err(|m| ctx.err(place, "envelope.band", m))?,
                };
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(bad(format!("{s} is not a finite frequency")))
                }
            };
            let band = Band {
                low: hz(low)?,
                high: hz(high)?,
            };
            let nyquist = 0.5 * sampling.sample_rate;
            if !(0.0 <= band.low && band.low < band.high && band.high <= nyquist) {
                return Err(bad(format!(
                    "[{} Hz, {} Hz] is not allowed: 0 <= low < high <= sample_rate / 2 = {nyquist} Hz",
                    band.low, band.high
                )));
            }
            let n = sampling.analysis_window(transient).len();
            let bins = frequencies(n, sampling.sample_rate)
                .into_iter()
                .filter(|&f| band.contains(f))
                .count();
            if bins == 0 {
                return Err(bad(format!(
                    "[{} Hz, {} Hz] holds no frequency bin of the analysed window \
                     ({n} samples: bins every {} Hz); widen the band",
                    band.low,
                    band.high,
                    sampling.sample_rate / n as f64
                )));
            }
            BandChoice::Fixed(band)
        }
    };
    Ok(EnvelopeSettings { channels, band })
}

/// Whether series and spectra are stored as float32, and the deflate level.
fn output_settings(
    ctx: &Ctx<'_>,
    output: Option<&OutputSection>,
) -> Result<(bool, u8), StudyError> {
    let default = OutputSection::default();
    let output = output.unwrap_or(&default);
    let float32 = match &output.dtype {
        None => false,
        Some(d) if d.value == "float64" => false,
        Some(d) if d.value == "float32" => true,
        Some(d) => {
            return Err(ctx.err(
                Some(at(&d.referenced)),
                "output.dtype",
                format!("`{}` is not allowed: float64 or float32", d.value),
            ))
        }
    };
    let compression = match &output.compression {
        // Level 1 gets nearly all of deflate's gain on these data (measured: 1.30 vs 1.31 at 4).
        None => 1,
        Some(c) if c.value <= 9 => c.value,
        Some(c) => {
            return Err(ctx.err(
                Some(at(&c.referenced)),
                "output.compression",
                format!("{} is not allowed: a deflate level 0..=9", c.value),
            ))
        }
    };
    Ok((float32, compression))
}

/// `output.series` and `output.decimate`: the series names checked against what
/// `study` simulates (its channels and sensor series; distinct), `decimate` an
/// integer from 1 to the samples per case.
fn series_output(
    ctx: &Ctx<'_>,
    output: Option<&OutputSection>,
    study: &Study,
) -> Result<SeriesOutput, StudyError> {
    let mut chosen = SeriesOutput::default();
    let Some(output) = output else {
        return Ok(chosen);
    };
    if let Some(d) = &output.decimate {
        let samples = study.sampling.len();
        let k = match d.value {
            Scalar::Num(x) if x.fract() == 0.0 && (1.0..=samples as f64).contains(&x) => x,
            _ => {
                return Err(ctx.err(
                    Some(at(&d.referenced)),
                    "output.decimate",
                    format!(
                        "{} is not allowed: an integer from 1 (every sample) to {samples} \
                         (the samples per case)",
                        d.value
                    ),
                ))
            }
        };
        chosen.decimate = k as usize;
    }
    let Some(series) = &output.series else {
        return Ok(chosen);
    };
    let place = Some(at(&series.referenced));
    chosen.names = match &series.value {
        SeriesValue::Name(n) if n == "all" => None,
        SeriesValue::Name(n) if n == "none" => Some(Vec::new()),
        SeriesValue::Name(n) => {
            return Err(ctx.err(
                place,
                "output.series",
                format!("`{n}` is not allowed: a list of series names, `all` or `none`"),
            ))
        }
        SeriesValue::List(list) => {
            let allowed: Vec<String> = study
                .simulated_channels()
                .into_iter()
                .map(|c| CHANNELS[c].name.to_string())
                .chain(study.sensors.iter().flat_map(|s| s.specs()).map(|v| v.name))
                .collect();
            let mut names: Vec<String> = Vec::new();
            for (k, name) in list.iter().enumerate() {
                let field = format!("output.series[{k}]");
                if !allowed.contains(name) {
                    return Err(ctx.err(
                        place,
                        &field,
                        format!(
                            "unknown series `{name}`; expected one of: {} (or `all` or `none` \
                             instead of a list)",
                            allowed.join(", ")
                        ),
                    ));
                }
                if names.contains(name) {
                    return Err(ctx.err(place, &field, format!("series `{name}` is listed twice")));
                }
                names.push(name.clone());
            }
            Some(names)
        }
    };
    Ok(chosen)
}

/// The ideal mechanism a case is compared with: same bodies, speed and gravity.
fn reference_of(p: &CaseParams) -> CaseParams {
    CaseParams {
        location: Site::Ideal,
        bearing: Default::default(),
        housing: None,
        ..p.clone()
    }
}

/// What an ideal mechanism depends on: its bodies, speed (with the profile's numbers)
/// and gravity. Destructured in full, so that a new parameter cannot be left out
/// unnoticed.
type ReferenceKey = ([u64; 9], Option<Vec<u64>>, bool);

fn reference_key(p: &CaseParams) -> ReferenceKey {
    let CaseParams {
        mechanism,
        bearing: _,
        location: _,
        rpm,
        speed,
        gravity,
        housing: _,
    } = p;
    let crate::mechanism::MechanismParams {
        crank_length,
        rod_length,
        crank_mass,
        crank_inertia,
        rod_mass,
        rod_inertia,
        slider_mass,
        slider_inertia,
    } = mechanism;
    let bits = |x: &f64| (x + 0.0).to_bits();
    (
        [
            bits(crank_length),
            bits(rod_length),
            bits(crank_mass),
            bits(crank_inertia),
            bits(rod_mass),
            bits(rod_inertia),
            bits(slider_mass),
            bits(slider_inertia),
            bits(rpm),
        ],
        speed.as_ref().map(SpeedProfile::key),
        *gravity,
    )
}

/// Refuses a value an axis already has (a grid axis), or a row a zip group already
/// has: the same cases would run twice.
fn check_repeats(ctx: &Ctx<'_>, groups: &[Vec<ResolvedAxis<'_>>]) -> Result<(), StudyError> {
    let key = |t: &Target| match *t {
        Target::Param(_, x) => (x + 0.0).to_bits(),
        Target::Location(site) => site as u64,
        Target::DefectRace(race) => race as u64,
    };
    for group in groups {
        let rows = group[0].values.len();
        let mut seen: HashMap<Vec<u64>, usize> = HashMap::with_capacity(rows);
        for k in 0..rows {
            let row: Vec<u64> = group.iter().map(|a| key(&a.values[k].0)).collect();
            if let Some(&first) = seen.get(&row) {
                let same = group
                    .iter()
                    .all(|a| a.values[k].0.same_as(&a.values[first].0));
                if same {
                    let axis = &group[0];
                    let message = if group.len() == 1 {
                        format!(
                            "repeats {}[{first}] (the same value); give each value of an axis once",
                            axis.field
                        )
                    } else {
                        let zip = axis.field.split('.').next().unwrap_or(axis.field);
                        format!(
                            "row {k} of {zip} repeats its row {first} (the same value of every \
                             axis of the group); give each combination once"
                        )
                    };
                    return Err(ctx.err(
                        Some(axis.values[k].1),
                        &format!("{}[{k}]", axis.field),
                        message,
                    ));
                }
            }
            seen.insert(row, k);
        }
    }
    Ok(())
}

/// The study name gives the default output file `<name>.h5` in the working directory:
/// a plain file name.
fn check_name(ctx: &Ctx<'_>, name: &S<String>) -> Result<(), StudyError> {
    let n = &name.value;
    let why = if n.trim().is_empty() {
        Some("is empty")
    } else if n.contains('/') || n.contains('\\') {
        Some("contains a path separator (/ or \\)")
    } else if n.contains("..") {
        Some("contains `..`")
    } else if n.starts_with('.') {
        Some("starts with a dot (a hidden file)")
    } else if n.chars().any(char::is_control) {
        Some("contains a control character")
    } else if n.len() > 200 {
        Some("is longer than 200 bytes")
    } else {
        None
    };
    match why {
        None => Ok(()),
        Some(why) => Err(ctx.err(
            Some(at(&name.referenced)),
            "name",
            format!(
                "{:?} {why}; the name gives the default output file <name>.h5 in the \
                 working directory, so it must be a plain file name: not empty, no / or \\, \
                 no `..`, not starting with a dot, no control characters, at most 200 bytes",
                n
            ),
        )),
    }
}

/// Applies the effects that are off, then validates, pointing errors at the YAML
/// (`prov`, called only then, says where each parameter was set).
fn finish_case(
    ctx: &Ctx<'_>,
    mut params: CaseParams,
    effects: &Effects,
    prov: impl FnOnce() -> Provenance,
    id: u64,
) -> Result<Case, StudyError> {
    if !effects.clearance {
        params.bearing.clearance = 0.0;
    }
    if !effects.waviness {
        params.bearing.inner_waviness = RaceWaviness::default();
        params.bearing.outer_waviness = RaceWaviness::default();
    }
    if !effects.damping {
        params.bearing.damping = 0.0;
        params.bearing.damping_model = DampingModel::CompressionOnly;
    }
    if !effects.defects {
        params.bearing.defects.clear();
    }
    params.gravity = effects.gravity;
    let checked = params.validate().and_then(|()| balls_fit(&params));
    checked.map_err(|e| {
        let prov = prov();
        let source = prov.iter().rev().find(|(name, _, _)| {
            lookup(name).is_some_and(|p| p.field == e.field)
                || (*name == "location" && e.field == "location")
        });
        match source {
            Some((_, field, place)) => {
                ctx.err(Some(*place), field, format!("{} (case {id})", e.refusal()))
            }
            None => ctx.err(
                None,
                &e.field,
                format!("{} (case {id}, default value)", e.refusal()),
            ),
        }
    })?;
    Ok(Case {
        id,
        params,
        reference: 0,
    })
}

/// A bearing's balls fit between its races ([`max_balls`]).
fn balls_fit(params: &CaseParams) -> Result<(), crate::error::ParamError> {
    let b = &params.bearing;
    match max_balls(b) {
        Some(max) if params.location != Site::Ideal && b.ball_count > max => {
            Err(crate::error::ParamError::new(
                "bearing.ball_count",
                b.ball_count,
                format!(
                    "at most {max} balls fit between these races (balls of diameter \
                     (d_o - d_i)/2 = {:.2} mm side by side around the pitch circle of \
                     diameter (d_i + d_o)/2 = {:.2} mm)",
                    0.5e3 * (b.outer_race_diameter - b.inner_race_diameter),
                    0.5e3 * (b.outer_race_diameter + b.inner_race_diameter)
                ),
            ))
        }
        _ => Ok(()),
    }
}

fn effects(ctx: &Ctx<'_>, file: &GridFile) -> Result<Effects, StudyError> {
    let Some(list) = &file.effects else {
        return Ok(Effects {
            clearance: true,
            waviness: true,
            damping: true,
            gravity: false,
            defects: false,
            housing: false,
        });
    };
    let mut e = Effects {
        clearance: false,
        waviness: false,
        damping: false,
        gravity: false,
        defects: false,
        housing: false,
    };
    for (k, name) in list.value.iter().enumerate() {
        let slot = match name.value.as_str() {
            "clearance" => &mut e.clearance,
            "waviness" => &mut e.waviness,
            "damping" => &mut e.damping,
            "gravity" => &mut e.gravity,
            "defects" => &mut e.defects,
            "housing" => &mut e.housing,
            other => {
                return Err(ctx.err(
                    Some(at(&name.referenced)),
                    &format!("effects[{k}]"),
                    format!(
                        "unknown effect `{other}`; expected any of: {}",
                        Effects::NAMES.join(", ")
                    ),
                ))
            }
        };
        if *slot {
            return Err(ctx.err(
                Some(at(&name.referenced)),
                &format!("effects[{k}]"),
                format!("`{}` is listed twice; list each effect once", name.value),
            ));
        }
        *slot = true;
    }
    Ok(e)
}

/// docs/model.md defaults, then the file's `mechanism:`, `bearing:`, `rpm:` or
/// `speed:`, and `location:`.
fn base_case(
    ctx: &Ctx<'_>,
    file: &GridFile,
    effects: &Effects,
    prov: &mut Provenance,
) -> Result<CaseParams, StudyError> {
    let mut c = CaseParams::default();
    if effects.housing {
        c.housing = Some(Housing::default());
    }
    if effects.waviness {
        // the paper's Table 2 (docs/model.md §2.8): N_i = N_o = 35, Π_p = 4 µm.
        c.bearing.inner_waviness = RaceWaviness::single(35, 4e-6);
        c.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    }
    let set = |c: &mut CaseParams,
               name: &str,
               v: &Option<S<Scalar>>,
               field: &str,
               prov: &mut Provenance| match v {
        Some(v) => ctx.apply(c, name, v, field, effects, prov),
        None => Ok(()),
    };
    if let Some(m) = &file.mechanism {
        for (name, v) in [
            ("crank_length", &m.crank_length),
            ("rod_length", &m.rod_length),
            ("crank_mass", &m.crank_mass),
            ("crank_inertia", &m.crank_inertia),
            ("rod_mass", &m.rod_mass),
            ("rod_inertia", &m.rod_inertia),
            ("slider_mass", &m.slider_mass),
            ("slider_inertia", &m.slider_inertia),
        ] {
            set(&mut c, name, v, &format!("mechanism.{name}"), prov)?;
        }
    }
    if let Some(b) = &file.bearing {
        for (name, v) in [
            ("ball_count", &b.ball_count),
            ("clearance", &b.clearance),
            ("damping", &b.damping),
            ("inner_race_diameter", &b.inner_race_diameter),
            ("outer_race_diameter", &b.outer_race_diameter),
        ] {
            set(&mut c, name, v, &format!("bearing.{name}"), prov)?;
        }
        match &b.stiffness {
            Some(S {
                value: Scalar::Text(t),
                referenced,
                ..
            }) if t == "harris" => {
                c.bearing.stiffness = harris(ctx, b.geometry.as_ref(), at(referenced))?;
            }
            other => set(&mut c, "stiffness", other, "bearing.stiffness", prov)?,
        }
        damping_law(ctx, &mut c, b, effects)?;
        for (race, section) in [
            ("", &b.waviness),
            ("inner_", &b.inner_waviness),
            ("outer_", &b.outer_waviness),
        ] {
            if let Some(w) = section {
                waviness(ctx, &mut c, race, w, effects, prov)?;
            }
        }
        if let Some(d) = b.geometry.as_ref().and_then(|g| g.ball_diameter.as_ref()) {
            c.bearing.ball_diameter =
                ctx.quantity(d, Dimension::Length, "bearing.geometry.ball_diameter")?;
        }
        if let Some(list) = &b.defects {
            c.bearing.defects = defects(ctx, list, effects)?;
        }
    }
    if let Some(h) = &file.housing {
        if !effects.housing {
            return Err(ctx.err(
                Some(at(&h.referenced)),
                "housing",
                format!(
                    "the housing effect is off (effects: [{}]); add `housing` to `effects` \
                     to set it",
                    effects.names().join(", ")
                ),
            ));
        }
        for (name, v) in [
            ("m_h", &h.value.m_h),
            ("k_h", &h.value.k_h),
            ("c_h", &h.value.c_h),
        ] {
            set(&mut c, name, v, &format!("housing.{name}"), prov)?;
        }
    }
    match (&file.speed, &file.rpm) {
        (Some(_), Some(rpm)) => {
            return Err(ctx.err(
                Some(at(&rpm.referenced)),
                "rpm",
                "rpm and speed both given; give either `rpm` (a constant speed) or `speed` \
                 (a profile)",
            ))
        }
        (Some(speed), None) => {
            c.speed = Some(ctx.speed(&speed.value, &speed.referenced, "speed", prov)?);
            c.rpm = f64::NAN;
        }
        (None, rpm) => set(&mut c, "rpm", rpm, "rpm", prov)?,
    }
    set(&mut c, "location", &file.location, "location", prov)?;
    Ok(c)
}

/// `bearing.damping_model` with its `restitution` or `alpha` (docs/model.md §2.5):
/// each key only with the laws that use it, the values in range.
fn damping_law(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    b: &BearingSection,
    effects: &Effects,
) -> Result<(), StudyError> {
    const NAMES: &str = "compression_only, two_sided, hunt_crossley_alpha, hunt_crossley, \
                         lankarani_nikravesh, flores or gonthier";
    let model = match &b.damping_model {
        None => DampingModel::CompressionOnly,
        Some(m) => match m.value.as_str() {
            "compression_only" => DampingModel::CompressionOnly,
            "two_sided" => DampingModel::TwoSided,
            "hunt_crossley_alpha" => DampingModel::HuntCrossleyAlpha { alpha: 0.0 },
            name => match RestitutionLaw::ALL.into_iter().find(|l| l.name() == name) {
                Some(law) => DampingModel::Restitution {
                    law,
                    restitution: 1.0,
                },
                None => {
                    return Err(ctx.err(
                        Some(at(&m.referenced)),
                        "bearing.damping_model",
                        format!("`{name}` is not allowed: {NAMES}"),
                    ))
                }
            },
        },
    };
    let name = b
        .damping_model
        .as_ref()
        .map_or("compression_only", |m| m.value.as_str());
    let model_at = b.damping_model.as_ref().map(|m| at(&m.referenced));
    let unused = |key: &str, v: &S<Scalar>, uses: &str| {
        ctx.err(
            Some(at(&v.referenced)),
            &format!("bearing.{key}"),
            format!("damping_model {name} does not use {key}; {key} belongs to {uses}"),
        )
    };
    let effect_off = |key: &str, v: &S<Scalar>| {
        (!effects.damping).then(|| {
            ctx.err(
                Some(at(&v.referenced)),
                &format!("bearing.{key}"),
                format!(
                    "the damping effect is off (effects: [{}]); add `damping` to `effects` to set it",
                    effects.names().join(", ")
                ),
            )
        })
    };
    let missing = |key: &str, what: &str| {
        ctx.err(
            model_at,
            &format!("bearing.{key}"),
            format!("damping_model {name} needs `{key}`: {what}"),
        )
    };
    const RESTITUTION_LAWS: &str = "hunt_crossley, lankarani_nikravesh, flores and gonthier";
    c.bearing.damping_model = match model {
        DampingModel::HuntCrossleyAlpha { .. } => {
            if let Some(v) = &b.restitution {
                return Err(unused("restitution", v, RESTITUTION_LAWS));
            }
            let v = b
                .alpha
                .as_ref()
                .ok_or_else(|| missing("alpha", "a rate in s/m, >= 0"))?;
            if let Some(e) = effect_off("alpha", v) {
                return Err(e);
            }
            let alpha = ctx.quantity(v, Dimension::InverseSpeed, "bearing.alpha")?;
            if !(alpha.is_finite() && alpha >= 0.0) {
                return Err(ctx.err(
                    Some(at(&v.referenced)),
                    "bearing.alpha",
                    format!("{} is not allowed: a finite rate >= 0 s/m", v.value),
                ));
            }
            DampingModel::HuntCrossleyAlpha { alpha }
        }
        DampingModel::Restitution { law, .. } => {
            if let Some(v) = &b.alpha {
                return Err(unused("alpha", v, "hunt_crossley_alpha"));
            }
            let v = b
                .restitution
                .as_ref()
                .ok_or_else(|| missing("restitution", "a coefficient of restitution in (0, 1]"))?;
            if let Some(e) = effect_off("restitution", v) {
                return Err(e);
            }
            let e = ctx.quantity(v, Dimension::Dimensionless, "bearing.restitution")?;
            if !(e > 0.0 && e <= 1.0) {
                return Err(ctx.err(
                    Some(at(&v.referenced)),
                    "bearing.restitution",
                    format!(
                        "{} is not allowed: a coefficient of restitution in (0, 1]",
                        v.value
                    ),
                ));
            }
            DampingModel::Restitution {
                law,
                restitution: e,
            }
        }
        other => {
            if let Some(v) = &b.restitution {
                return Err(unused("restitution", v, RESTITUTION_LAWS));
            }
            if let Some(v) = &b.alpha {
                return Err(unused("alpha", v, "hunt_crossley_alpha"));
            }
            other
        }
    };
    if let (Some(v), DampingModel::HuntCrossleyAlpha { .. } | DampingModel::Restitution { .. }) =
        (&b.damping, c.bearing.damping_model)
    {
        return Err(ctx.err(
            Some(at(&v.referenced)),
            "bearing.damping",
            format!(
                "damping_model {name} does not use the damping coefficient C; it belongs to \
                 compression_only and two_sided"
            ),
        ));
    }
    if matches!(
        c.bearing.damping_model,
        DampingModel::HuntCrossleyAlpha { .. } | DampingModel::Restitution { .. }
    ) {
        // C belongs to the other laws: 0 in the case and in its file.
        c.bearing.damping = 0.0;
    }
    Ok(())
}

/// A `waviness:` (race = "") or `inner_/outer_waviness:` section.
fn waviness(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    race: &str,
    w: &WavinessSection,
    effects: &Effects,
    prov: &mut Provenance,
) -> Result<(), StudyError> {
    let section = if race.is_empty() {
        "bearing.waviness".to_string()
    } else {
        format!("bearing.{race}waviness")
    };
    if let Some(list) = &w.harmonics {
        if let Some((key, v)) = [
            ("number", &w.number),
            ("amplitude", &w.amplitude),
            ("phase", &w.phase),
        ]
        .into_iter()
        .find_map(|(k, v)| v.as_ref().map(|v| (k, v)))
        {
            return Err(ctx.err(
                Some(at(&v.referenced)),
                &format!("{section}.{key}"),
                "give either `harmonics:` or a single number/amplitude/phase, not both",
            ));
        }
        if let Some((effect, false)) = effects.governing("waviness") {
            return Err(ctx.err(
                Some(at(&list.referenced)),
                &format!("{section}.harmonics"),
                format!("the {effect} effect is off; add `{effect}` to `effects` to set it"),
            ));
        }
        let mut harmonics = Vec::new();
        for (k, h) in list.value.iter().enumerate() {
            let field = format!("{section}.harmonics[{k}]");
            let number = ctx.quantity(
                &h.number,
                Dimension::Dimensionless,
                &format!("{field}.number"),
            )?;
            if number.fract() != 0.0 || !(1.0..=u32::MAX as f64).contains(&number) {
                return Err(ctx.err(
                    Some(at(&h.number.referenced)),
                    &format!("{field}.number"),
                    format!("{number} is not allowed: a whole number >= 1"),
                ));
            }
            harmonics.push(Harmonic {
                number: number as u32,
                amplitude: ctx.quantity(
                    &h.amplitude,
                    Dimension::Length,
                    &format!("{field}.amplitude"),
                )?,
                phase: h
                    .phase
                    .as_ref()
                    .map(|p| ctx.quantity(p, Dimension::Angle, &format!("{field}.phase")))
                    .transpose()?
                    .unwrap_or(0.0),
            });
        }
        let races: Vec<&mut RaceWaviness> = match race {
            "inner_" => vec![&mut c.bearing.inner_waviness],
            "outer_" => vec![&mut c.bearing.outer_waviness],
            _ => vec![&mut c.bearing.inner_waviness, &mut c.bearing.outer_waviness],
        };
        for r in races {
            r.harmonics = harmonics.clone();
        }
    }
    for (key, v) in [
        ("number", &w.number),
        ("amplitude", &w.amplitude),
        ("phase", &w.phase),
    ] {
        if let Some(v) = v {
            ctx.apply(
                c,
                &format!("{race}waviness_{key}"),
                v,
                &format!("{section}.{key}"),
                effects,
                prov,
            )?;
        }
    }
    if let Some(v) = &w.offset {
        let names: &[&str] = match race {
            "" => &["inner_waviness_offset", "outer_waviness_offset"],
            "inner_" => &["inner_waviness_offset"],
            _ => &["outer_waviness_offset"],
        };
        for name in names {
            ctx.apply(c, name, v, &format!("{section}.offset"), effects, prov)?;
        }
    }
    Ok(())
}

/// The `bearing.defects:` list, each checked with its field named.
fn defects(
    ctx: &Ctx<'_>,
    list: &S<Vec<DefectSection>>,
    effects: &Effects,
) -> Result<Vec<Defect>, StudyError> {
    if !effects.defects {
        return Err(ctx.err(
            Some(at(&list.referenced)),
            "bearing.defects",
            format!(
                "the defects effect is off (effects: [{}]); add `defects` to `effects` to set it",
                effects.names().join(", ")
            ),
        ));
    }
    list.value
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let field = format!("bearing.defects[{k}]");
            let race = d.race.value.parse::<DefectRace>().map_err(|_| {
                ctx.err(
                    Some(at(&d.race.referenced)),
                    &format!("{field}.race"),
                    format!("`{}` is not allowed: outer, inner or ball", d.race.value),
                )
            })?;
            let profile = match d.profile.as_ref().map(|p| (p.value.as_str(), p)) {
                None | Some(("flat", _)) => DefectProfile::Flat,
                Some(("rounded", _)) => DefectProfile::Rounded,
                Some((other, p)) => {
                    return Err(ctx.err(
                        Some(at(&p.referenced)),
                        &format!("{field}.profile"),
                        format!("`{other}` is not allowed: flat or rounded"),
                    ))
                }
            };
            let angle = d
                .angle
                .as_ref()
                .map(|a| ctx.quantity(a, Dimension::Angle, &format!("{field}.angle")))
                .transpose()?
                .unwrap_or(0.0);
            let width = ctx.quantity(&d.width, Dimension::Length, &format!("{field}.width"))?;
            let depth = ctx.quantity(&d.depth, Dimension::Length, &format!("{field}.depth"))?;
            let defect = Defect {
                race,
                angle,
                width,
                depth,
                profile,
            };
            defect.validate(&field).map_err(|e| {
                let place = if e.field.ends_with("width") {
                    &d.width.referenced
                } else {
                    &d.depth.referenced
                };
                ctx.err(Some(at(place)), &e.field, e.refusal())
            })?;
            Ok(defect)
        })
        .collect()
}

/// `stiffness: harris`: Harris's method on the (default SKF 98205) contact geometry.
fn harris(
    ctx: &Ctx<'_>,
    g: Option<&super::config::GeometrySection>,
    place: (u64, u64),
) -> Result<f64, StudyError> {
    let mut geometry = ContactGeometry::skf_98205();
    if let Some(g) = g {
        for (key, v, dim, slot) in [
            (
                "ball_diameter",
                &g.ball_diameter,
                Dimension::Length,
                &mut geometry.ball_diameter,
            ),
            (
                "pitch_diameter",
                &g.pitch_diameter,
                Dimension::Length,
                &mut geometry.pitch_diameter,
            ),
            (
                "inner_conformity",
                &g.inner_conformity,
                Dimension::Dimensionless,
                &mut geometry.inner_conformity,
            ),
            (
                "outer_conformity",
                &g.outer_conformity,
                Dimension::Dimensionless,
                &mut geometry.outer_conformity,
            ),
            (
                "youngs_modulus",
                &g.youngs_modulus,
                Dimension::Pressure,
                &mut geometry.youngs_modulus,
            ),
            (
                "poisson_ratio",
                &g.poisson_ratio,
                Dimension::Dimensionless,
                &mut geometry.poisson_ratio,
            ),
        ] {
            if let Some(v) = v {
                *slot = ctx.quantity(v, dim, &format!("bearing.geometry.{key}"))?;
            }
        }
    }
    geometry
        .harris_stiffness()
        .map(|k| k.total)
        .map_err(|e| ctx.err(Some(place), &e.field, e.refusal()))
}

fn solver(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
) -> Result<SolverSettings, StudyError> {
    let s = match &file.solver {
        Some(s) => s,
        None => return Ok(SolverSettings::new(Method::DEFAULT)),
    };
    let positive = |v: &Option<S<Scalar>>,
                    dim: Dimension,
                    field: &str,
                    default: f64|
     -> Result<f64, StudyError> {
        match v {
            None => Ok(default),
            Some(v) => {
                let x = ctx.quantity(v, dim, field)?;
                if x > 0.0 {
                    Ok(x)
                } else {
                    Err(ctx.err(
                        Some(at(&v.referenced)),
                        field,
                        format!("{x} is not allowed: > 0"),
                    ))
                }
            }
        }
    };
    // A tolerance or step outside these ranges is a typo or a misunderstanding: a
    // relative tolerance of 10 % or more integrates nothing, one below 1e-14 asks
    // for more than float64 holds; no step can be longer than the run.
    let within = |v: &Option<S<Scalar>>, x: f64, field: &str, ok: bool, rule: String| match v {
        Some(v) if !ok => Err(ctx.err(
            Some(at(&v.referenced)),
            field,
            format!("{x} is not allowed: {rule}"),
        )),
        _ => Ok(x),
    };
    let rtol = positive(
        &s.rtol,
        Dimension::Dimensionless,
        "solver.rtol",
        DEFAULT_RTOL,
    )?;
    let rtol = within(
        &s.rtol,
        rtol,
        "solver.rtol",
        (MIN_RTOL..MAX_RTOL).contains(&rtol),
        format!(
            "a relative tolerance > 0, from {MIN_RTOL:e} up to (not including) {MAX_RTOL}; \
             1e-6 to 1e-10 are usual"
        ),
    )?;
    let atol = positive(
        &s.atol,
        Dimension::Dimensionless,
        "solver.atol",
        DEFAULT_ATOL,
    )?;
    let duration = sampling.duration;
    let spacing = 1.0 / sampling.sample_rate;
    let method = match s.method.as_ref().map(|m| m.value.as_str()) {
        Some("dopri5") => Method::DormandPrince { rtol, atol },
        Some("tsit5") => Method::Tsit5 { rtol, atol },
        None | Some("dop853") => Method::Dop853 { rtol, atol },
        Some("sdirk4") => Method::Sdirk4 { rtol, atol },
        Some("rk4") => {
            let step = positive(&s.step, Dimension::Time, "solver.step", 20e-6)?;
            let rule = format!(
                "RK4's fixed step must be at most the sample spacing 1/sample_rate = {spacing} s \
                 (and the duration {duration} s): with longer steps the samples between \
                 them are only interpolated"
            );
            if s.step.is_none() && !rk4_step_fits(step, spacing) {
                return Err(ctx.err(
                    s.method.as_ref().map(|m| at(&m.referenced)),
                    "solver.step",
                    format!("the default step {step} s is too long: {rule}; give `step`"),
                ));
            }
            let ok = rk4_step_fits(step, spacing) && step <= duration;
            Method::Rk4 {
                step: within(&s.step, step, "solver.step", ok, rule)?,
            }
        }
        Some(other) => {
            let m = s.method.as_ref().map(|m| at(&m.referenced));
            return Err(ctx.err(
                m,
                "solver.method",
                format!("`{other}` is not allowed: dopri5, tsit5, dop853, rk4 or sdirk4"),
            ));
        }
    };
    // A setting the chosen method would ignore is refused, not dropped silently.
    let method_name = s.method.as_ref().map_or("dop853", |m| m.value.as_str());
    let given =
        |v: &Option<S<Scalar>>| v.as_ref().map(|v| (at(&v.referenced), v.value.to_string()));
    let flag = |v: &Option<S<bool>>| v.as_ref().map(|v| (at(&v.referenced), v.value.to_string()));
    let (events, switch) = (flag(&s.locate_events), flag(&s.stiffness_switch));
    let (ignored, takes) = match method {
        Method::Rk4 { .. } => (
            vec![
                ("rtol", given(&s.rtol)),
                ("atol", given(&s.atol)),
                ("max_step", given(&s.max_step)),
                ("locate_events", events),
                ("stiffness_switch", switch),
            ],
            "a fixed `step` (s)",
        ),
        Method::Sdirk4 { .. } => (
            vec![("step", given(&s.step)), ("stiffness_switch", switch)],
            "`rtol`, `atol`, `max_step` and `locate_events`",
        ),
        _ => (
            vec![("step", given(&s.step))],
            "`rtol`, `atol`, `max_step`, `locate_events` and `stiffness_switch`",
        ),
    };
    if let Some((field, Some((place, value)))) = ignored.into_iter().find(|(_, v)| v.is_some()) {
        return Err(ctx.err(
            Some(place),
            &format!("solver.{field}"),
            format!("{value} is not allowed with method {method_name}, which takes {takes}"),
        ));
    }
    let mut settings = SolverSettings::new(method);
    if let Some(l) = &s.locate_events {
        settings.locate_events = l.value;
    }
    if let Some(l) = &s.stiffness_switch {
        settings.stiffness_switch = l.value;
    }
    if let Some(m) = &s.max_steps {
        if m.value == 0 {
            return Err(ctx.err(
                Some(at(&m.referenced)),
                "solver.max_steps",
                "0 is not allowed: a budget of at least 1 step per case",
            ));
        }
        settings.max_steps = m.value;
    }
    let max_step = positive(
        &s.max_step,
        Dimension::Time,
        "solver.max_step",
        f64::INFINITY,
    )?;
    settings.max_step = within(
        &s.max_step,
        max_step,
        "solver.max_step",
        max_step <= duration,
        format!("a largest step > 0 and at most the duration {duration} s"),
    )?;
    Ok(settings)
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
