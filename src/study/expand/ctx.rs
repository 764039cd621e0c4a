//! The expansion's context: errors placed at a file, line, column and dotted field, and
//! the values of the grid file read in their units.

use super::*;

pub(super) fn at(l: &Location) -> (u64, u64) {
    (l.line(), l.column())
}

pub(super) struct Ctx<'a> {
    pub(super) path: &'a Path,
}

impl Ctx<'_> {
    pub(super) fn err(
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
    pub(super) fn quantity(
        &self,
        v: &S<Scalar>,
        dim: Dimension,
        field: &str,
    ) -> Result<f64, StudyError> {
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
    pub(super) fn apply(
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
    pub(super) fn resolve(
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
                        "{} is not a location; expected one of ideal, crank_ground, crank_rod, rod_slider",
                        v.value
                    ),
                ));
            };
            let site = t
                .parse()
                .map_err(|e: crate::error::ParamError| self.err(Some(place), field, e.refusal()))?;
            return Ok(Target::Location(site));
        }
        if let Some(target) = self.named(name, v, field) {
            return target;
        }
        let param = lookup(name).ok_or_else(|| {
            let names: Vec<&str> = PARAMETERS.iter().map(|p| p.name).collect();
            self.err(
                Some(place),
                field,
                format!(
                    "unknown parameter; expected location, joint, defect_race or one of: {}",
                    names.join(", ")
                ),
            )
        })?;
        check_speed(case, param.name).map_err(|m| self.err(Some(place), field, m))?;
        let x = self.quantity(v, param.dimension, field)?;
        if param.integer && (x.fract() != 0.0 || x < 0.0 || x > u32::MAX as f64) {
            let rule = whole_number_rule(case, param.name, &v.value);
            return Err(self.err(Some(place), field, rule));
        }
        Ok(Target::Param(param, x))
    }

    /// The value of a name-valued key (`joint`, `defect_race`), checked; `None` for
    /// any other key.
    fn named(&self, name: &str, v: &S<Scalar>, field: &str) -> Option<Result<Target, StudyError>> {
        let place = at(&v.referenced);
        let (parsed, what, allowed) = match name {
            "joint" => (
                match &v.value {
                    Scalar::Text(t) => t.parse::<JointKind>().ok().map(Target::Joint),
                    Scalar::Num(_) => None,
                },
                "joint",
                "ball_bearing, dry_clearance, lubricated",
            ),
            "defect_race" => (
                match &v.value {
                    Scalar::Text(t) => t.parse::<DefectRace>().ok().map(Target::DefectRace),
                    Scalar::Num(_) => None,
                },
                "defect race",
                "outer, inner, ball",
            ),
            _ => return None,
        };
        Some(parsed.ok_or_else(|| {
            self.err(
                Some(place),
                field,
                format!("{} is not a {what}; expected one of {allowed}", v.value),
            )
        }))
    }
}

/// What a count parameter `name` allows, for the refusal of `value`, which is not a
/// whole number in range.
fn whole_number_rule(case: &CaseParams, name: &str, value: &Scalar) -> String {
    match name {
        "ball_count" => match max_balls(&case.bearing) {
            Some(max) if max >= 3 => format!(
                "ball_count must be a whole number of balls from 3 to {max}, got {value} \
                 ({max} balls fit between these races)"
            ),
            _ => format!("ball_count must be a whole number of balls, 3 or more, got {value}"),
        },
        "noise_realization" => {
            format!("noise_realization must be a whole number, 0 or more, got {value}")
        }
        _ => format!("{name} must be a whole number of waves, 1 or more, got {value}"),
    }
}

impl Ctx<'_> {
    /// A `speed:` section written at `loc` under the name `prefix` (`speed`,
    /// `cases[2].speed`) as a checked profile; records where its scalar fields came
    /// from in `prov`.
    pub(super) fn speed(
        &self,
        s: &SpeedSection,
        loc: &Location,
        prefix: &str,
        prov: &mut Provenance,
    ) -> Result<SpeedProfile, StudyError> {
        let place = Some(at(loc));
        let fields = self.speed_fields(s, place, prefix)?;
        let profile = s.profile.as_str();
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

    /// The fields of the speed profile `s` (at `place`, written at `prefix`), checked:
    /// a known profile, given exactly its fields.
    fn speed_fields(
        &self,
        s: &SpeedSection,
        place: Option<(u64, u64)>,
        prefix: &str,
    ) -> Result<&'static [&'static str], StudyError> {
        let fields: &'static [&'static str] = match s.profile.as_str() {
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
        Ok(fields)
    }
}
