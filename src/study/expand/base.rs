//! The base case: the bearing, its contact law, waviness, defects and stiffness read
//! from the grid file's sections, and the checks that make a case runnable.

use super::*;
use crate::study::config::{HarmonicSection, HousingSection};

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

/// The study name gives the default output file `<name>.h5` in the working directory:
/// a plain file name.
pub(super) fn check_name(ctx: &Ctx<'_>, name: &S<String>) -> Result<(), StudyError> {
    let n = &name.value;
    let why = if n.trim().is_empty() {
        Some("is empty")
    } else if n.contains('/') || n.contains('\\') {
        Some("contains a path separator (/ or \\)")
    } else if n.contains("..") {
        Some("contains `..`")
    } else if n.starts_with('.') {
        Some("starts with a dot (a hidden file)")
    } else if n.chars().any(crate::study::yaml::is_hidden_control) {
        Some("contains a control character (or a bidirectional or line-separator mark)")
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
pub(super) fn finish_case(
    ctx: &Ctx<'_>,
    mut params: CaseParams,
    effects: &Effects,
    prov: impl FnOnce() -> Provenance,
    id: u64,
) -> Result<Case, StudyError> {
    without_effects_off(&mut params, effects);
    check_case(&params).map_err(|e| {
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

/// `params` with what the effects turned off taken out: no clearance (the journal's
/// contact stiffness kept at its value for the given clearance), waviness, damping
/// or defects; gravity as the effects say.
pub(super) fn without_effects_off(params: &mut CaseParams, effects: &Effects) {
    if !effects.clearance {
        params.bearing.clearance = 0.0;
        let journal = &mut params.journal;
        journal.stiffness = Some(journal.contact_stiffness());
        journal.geometry.clearance = 0.0;
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
}

/// A case's parameters valid each on its own ([`CaseParams::validate`]) and together
/// (the balls fit the races).
pub(super) fn check_case(params: &CaseParams) -> Result<(), crate::error::ParamError> {
    params.validate().and_then(|()| balls_fit(params))
}

/// A bearing's balls fit between its races ([`max_balls`]).
pub(super) fn balls_fit(params: &CaseParams) -> Result<(), crate::error::ParamError> {
    let b = &params.bearing;
    match max_balls(b) {
        Some(max)
            if params.location != Site::Ideal && !params.joint.is_plain() && b.ball_count > max =>
        {
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

/// Applies the setting `v` (when given) at `field` to the parameter `name` of `c`,
/// recording where in `prov`.
pub(super) fn apply_given(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    (name, v, field): (&str, &Option<S<Scalar>>, &str),
    effects: &Effects,
    prov: &mut Provenance,
) -> Result<(), StudyError> {
    match v {
        Some(v) => ctx.apply(c, name, v, field, effects, prov),
        None => Ok(()),
    }
}

/// docs/model.md defaults, then the file's `mechanism:`, `bearing:`, `housing:`,
/// `journal:`, `rpm:` or `speed:`, `location:` and `joint:`.
pub(super) fn base_case(
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
            let field = format!("mechanism.{name}");
            apply_given(ctx, &mut c, (name, v, &field), effects, prov)?;
        }
    }
    if let Some(b) = &file.bearing {
        bearing_section(ctx, &mut c, b, effects, prov)?;
    }
    if let Some(h) = &file.housing {
        housing_section(ctx, &mut c, h, effects, prov)?;
    }
    if let Some(j) = &file.journal {
        journal_section(ctx, &mut c, &j.value, effects, prov)?;
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
        (None, rpm) => apply_given(ctx, &mut c, ("rpm", rpm, "rpm"), effects, prov)?,
    }
    let location = ("location", &file.location, "location");
    apply_given(ctx, &mut c, location, effects, prov)?;
    apply_given(ctx, &mut c, ("joint", &file.joint, "joint"), effects, prov)?;
    Ok(c)
}

/// The `bearing:` section: its scalars, the stiffness (a value or `harris`), the
/// damping law, waviness, ball diameter and defects.
fn bearing_section(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    b: &BearingSection,
    effects: &Effects,
    prov: &mut Provenance,
) -> Result<(), StudyError> {
    for (name, v) in [
        ("ball_count", &b.ball_count),
        ("clearance", &b.clearance),
        ("damping", &b.damping),
        ("inner_race_diameter", &b.inner_race_diameter),
        ("outer_race_diameter", &b.outer_race_diameter),
    ] {
        let field = format!("bearing.{name}");
        apply_given(ctx, c, (name, v, &field), effects, prov)?;
    }
    match &b.stiffness {
        Some(S {
            value: Scalar::Text(t),
            referenced,
            ..
        }) if t == "harris" => {
            c.bearing.stiffness = harris(ctx, b.geometry.as_ref(), at(referenced))?;
        }
        other => {
            let stiffness = ("stiffness", other, "bearing.stiffness");
            apply_given(ctx, c, stiffness, effects, prov)?;
        }
    }
    damping_law(ctx, c, b, effects)?;
    for (race, section) in [
        ("", &b.waviness),
        ("inner_", &b.inner_waviness),
        ("outer_", &b.outer_waviness),
    ] {
        if let Some(w) = section {
            waviness(ctx, c, race, w, effects, prov)?;
        }
    }
    if let Some(d) = b.geometry.as_ref().and_then(|g| g.ball_diameter.as_ref()) {
        c.bearing.ball_diameter =
            ctx.quantity(d, Dimension::Length, "bearing.geometry.ball_diameter")?;
    }
    if let Some(a) = b.geometry.as_ref().and_then(|g| g.contact_angle.as_ref()) {
        let field = "bearing.geometry.contact_angle";
        if ctx.quantity(a, Dimension::Angle, field)? != 0.0 {
            return Err(ctx.err(
                Some(at(&a.referenced)),
                field,
                format!(
                    "{} is not allowed for a simulated case: its bearing model is planar \
                     (contact angle 0); a nonzero contact angle is for the characteristic \
                     frequencies of `recordings:`",
                    a.value
                ),
            ));
        }
    }
    if let Some(list) = &b.defects {
        c.bearing.defects = defects(ctx, list, effects)?;
    }
    Ok(())
}

/// The `housing:` section (docs/model.md §3.9), only with the housing effect on.
fn housing_section(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    h: &S<HousingSection>,
    effects: &Effects,
    prov: &mut Provenance,
) -> Result<(), StudyError> {
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
        let field = format!("housing.{name}");
        apply_given(ctx, c, (name, v, &field), effects, prov)?;
    }
    Ok(())
}

/// The values `bearing.damping_model` takes.
const DAMPING_MODELS: &str = "compression_only, two_sided, hunt_crossley_alpha, hunt_crossley, \
                              lankarani_nikravesh, flores or gonthier";
/// The laws that take `restitution`.
const RESTITUTION_LAWS: &str = "hunt_crossley, lankarani_nikravesh, flores and gonthier";

/// `bearing.damping_model` with its `restitution` or `alpha` (docs/model.md §2.5):
/// each key only with the laws that use it, the values in range.
pub(super) fn damping_law(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    b: &BearingSection,
    effects: &Effects,
) -> Result<(), StudyError> {
    let keys = DampingKeys {
        ctx,
        b,
        effects,
        name: b
            .damping_model
            .as_ref()
            .map_or("compression_only", |m| m.value.as_str()),
    };
    c.bearing.damping_model = match damping_model(ctx, b)? {
        DampingModel::HuntCrossleyAlpha { .. } => keys.alpha()?,
        DampingModel::Restitution { law, .. } => keys.restitution(law)?,
        other => {
            if let Some(v) = &b.restitution {
                return Err(keys.unused("restitution", v, RESTITUTION_LAWS));
            }
            if let Some(v) = &b.alpha {
                return Err(keys.unused("alpha", v, "hunt_crossley_alpha"));
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
                "damping_model {} does not use the damping coefficient C; it belongs to \
                 compression_only and two_sided",
                keys.name
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

/// The law named by `bearing.damping_model` (compression-only when not given), its
/// `alpha` or `restitution` still unset.
fn damping_model(ctx: &Ctx<'_>, b: &BearingSection) -> Result<DampingModel, StudyError> {
    let Some(m) = &b.damping_model else {
        return Ok(DampingModel::CompressionOnly);
    };
    Ok(match m.value.as_str() {
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
                    format!("`{name}` is not allowed: {DAMPING_MODELS}"),
                ))
            }
        },
    })
}

/// The `bearing:` keys of a damping law named `name` (as written), read and refused
/// with the law named.
struct DampingKeys<'a> {
    ctx: &'a Ctx<'a>,
    b: &'a BearingSection,
    effects: &'a Effects,
    name: &'a str,
}

impl DampingKeys<'_> {
    /// `key` is set but the law does not use it; it belongs to the laws `uses`.
    fn unused(&self, key: &str, v: &S<Scalar>, uses: &str) -> StudyError {
        let name = self.name;
        self.ctx.err(
            Some(at(&v.referenced)),
            &format!("bearing.{key}"),
            format!("damping_model {name} does not use {key}; {key} belongs to {uses}"),
        )
    }

    /// `key`, set to `v`, with the damping effect off.
    fn effect_off(&self, key: &str, v: &S<Scalar>) -> Option<StudyError> {
        (!self.effects.damping).then(|| {
            self.ctx.err(
                Some(at(&v.referenced)),
                &format!("bearing.{key}"),
                format!(
                    "the damping effect is off (effects: [{}]); add `damping` to `effects` to set it",
                    self.effects.names().join(", ")
                ),
            )
        })
    }

    /// The law needs `key`, `what`, which is not given.
    fn missing(&self, key: &str, what: &str) -> StudyError {
        let model_at = self.b.damping_model.as_ref().map(|m| at(&m.referenced));
        self.ctx.err(
            model_at,
            &format!("bearing.{key}"),
            format!("damping_model {} needs `{key}`: {what}", self.name),
        )
    }

    /// Hunt–Crossley with its `alpha` (s/m, ≥ 0).
    fn alpha(&self) -> Result<DampingModel, StudyError> {
        let b = self.b;
        if let Some(v) = &b.restitution {
            return Err(self.unused("restitution", v, RESTITUTION_LAWS));
        }
        let v = b
            .alpha
            .as_ref()
            .ok_or_else(|| self.missing("alpha", "a rate in s/m, >= 0"))?;
        if let Some(e) = self.effect_off("alpha", v) {
            return Err(e);
        }
        let alpha = self
            .ctx
            .quantity(v, Dimension::InverseSpeed, "bearing.alpha")?;
        if !(alpha.is_finite() && alpha >= 0.0) {
            return Err(self.ctx.err(
                Some(at(&v.referenced)),
                "bearing.alpha",
                format!("{} is not allowed: a finite rate >= 0 s/m", v.value),
            ));
        }
        Ok(DampingModel::HuntCrossleyAlpha { alpha })
    }

    /// The restitution `law` with its coefficient of restitution in (0, 1].
    fn restitution(&self, law: RestitutionLaw) -> Result<DampingModel, StudyError> {
        let b = self.b;
        if let Some(v) = &b.alpha {
            return Err(self.unused("alpha", v, "hunt_crossley_alpha"));
        }
        let v = b
            .restitution
            .as_ref()
            .ok_or_else(|| self.missing("restitution", "a coefficient of restitution in (0, 1]"))?;
        if let Some(e) = self.effect_off("restitution", v) {
            return Err(e);
        }
        let e = self
            .ctx
            .quantity(v, Dimension::Dimensionless, "bearing.restitution")?;
        if !(e > 0.0 && e <= 1.0) {
            return Err(self.ctx.err(
                Some(at(&v.referenced)),
                "bearing.restitution",
                format!(
                    "{} is not allowed: a coefficient of restitution in (0, 1]",
                    v.value
                ),
            ));
        }
        Ok(DampingModel::Restitution {
            law,
            restitution: e,
        })
    }
}

/// A `waviness:` (race = "") or `inner_/outer_waviness:` section.
pub(super) fn waviness(
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
        let harmonics = harmonics(ctx, &section, w, list, effects)?;
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

/// The `harmonics:` list of the waviness section `w` at `section`: each harmonic's
/// number (a whole number ≥ 1), amplitude (m) and phase (rad, 0 when not given).
/// Refused next to a single number/amplitude/phase, or with the waviness effect off.
fn harmonics(
    ctx: &Ctx<'_>,
    section: &str,
    w: &WavinessSection,
    list: &S<Vec<HarmonicSection>>,
    effects: &Effects,
) -> Result<Vec<Harmonic>, StudyError> {
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
    Ok(harmonics)
}

/// The `bearing.defects:` list, each checked with its field named.
pub(super) fn defects(
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
pub(super) fn harris(
    ctx: &Ctx<'_>,
    g: Option<&crate::study::config::GeometrySection>,
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
