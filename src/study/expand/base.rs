//! The base case: the bearing, its contact law, waviness, defects and stiffness read
//! from the grid file's sections, and the checks that make a case runnable.

use super::*;

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
pub(super) fn balls_fit(params: &CaseParams) -> Result<(), crate::error::ParamError> {
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

/// docs/model.md defaults, then the file's `mechanism:`, `bearing:`, `rpm:` or
/// `speed:`, and `location:`.
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
pub(super) fn damping_law(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    b: &BearingSection,
    effects: &Effects,
) -> Result<(), StudyError> {
    pub(super) const NAMES: &str =
        "compression_only, two_sided, hunt_crossley_alpha, hunt_crossley, \
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
    pub(super) const RESTITUTION_LAWS: &str =
        "hunt_crossley, lankarani_nikravesh, flores and gonthier";
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
