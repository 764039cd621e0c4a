//! The `design:` section resolved into one more group of the expansion: every
//! design parameter becomes an axis of `rows` values, and the axes vary together
//! (like a `zip:` group) as the fastest group, so the whole design repeats at
//! every grid point and explicit case.

use super::base::{check_case, without_effects_off};
use super::{at, Ctx, Effects, ResolvedAxis, Target};
use crate::mechanism::CaseParams;
use crate::study::config::{DesignParameter, DesignSection, GridFile, Scalar, S};
use crate::study::design::{self, Distribution, Method};
use crate::study::params::ParamDef;
use crate::study::StudyError;

/// A resolved design: what the file records, and its columns.
pub(super) struct Design {
    /// What the study file records.
    pub info: crate::study::DesignInfo,
    /// YAML field of each parameter (`design.parameters.clearance`).
    fields: Vec<String>,
    /// Per parameter, the value of every row and where the parameter is written.
    columns: Vec<(Vec<Target>, (u64, u64))>,
}

impl Design {
    /// The design as one expansion group of `info.rows` values per axis. Its columns
    /// move into the group, each freed once copied: a design's values are held once.
    pub fn group(&mut self) -> Vec<ResolvedAxis<'_>> {
        let columns = std::mem::take(&mut self.columns);
        self.fields
            .iter()
            .zip(columns)
            .map(|(field, (values, place))| ResolvedAxis {
                field,
                values: values.into_iter().map(|t| (t, place)).collect(),
            })
            .collect()
    }
}

/// The rows a design adds per grid point and explicit case, known before anything
/// is drawn (1 without a design); refuses a method, sample count or parameter count
/// the method does not allow.
pub(super) fn rows(ctx: &Ctx<'_>, file: &GridFile) -> Result<u64, StudyError> {
    let Some(section) = &file.design else {
        return Ok(1);
    };
    let d = &section.value;
    let method = method_of(ctx, d)?;
    let dims = d.parameters.value.len();
    let place = Some(at(&d.parameters.referenced));
    if dims == 0 {
        return Err(ctx.err(
            place,
            "design.parameters",
            "a design needs at least one parameter",
        ));
    }
    if dims > design::max_parameters(method) {
        return Err(ctx.err(
            place,
            "design.parameters",
            format!(
                "{dims} parameters; a {} design takes at most {} (the Sobol directions this \
                 engine carries: {})",
                method.name(),
                design::max_parameters(method),
                design::MAX_SOBOL_DIMENSIONS
            ),
        ));
    }
    let samples = d.samples.value;
    let place = Some(at(&d.samples.referenced));
    if samples == 0 {
        return Err(ctx.err(place, "design.samples", "0 is not allowed: 1 or more"));
    }
    if matches!(method, Method::Sobol | Method::Saltelli) && !design::is_power_of_two(samples) {
        return Err(ctx.err(
            place,
            "design.samples",
            format!(
                "{samples} is not allowed for a {} design: a power of two (e.g. {}), \
                 where the Sobol points are balanced",
                method.name(),
                samples.next_power_of_two()
            ),
        ));
    }
    method.rows(samples, dims).ok_or_else(|| {
        ctx.err(
            place,
            "design.samples",
            format!("{samples} samples overflow the case count"),
        )
    })
}

fn method_of(ctx: &Ctx<'_>, d: &DesignSection) -> Result<Method, StudyError> {
    Method::from_name(&d.method.value).ok_or_else(|| {
        ctx.err(
            Some(at(&d.method.referenced)),
            "design.method",
            format!(
                "`{}` is not a design method; expected one of {}",
                d.method.value,
                Method::NAMES.join(", ")
            ),
        )
    })
}

/// The design's `seed` (0 when not given; at most 2^63 − 1, as the file stores it)
/// and whether its points are scrambled (the default; only sobol and saltelli
/// designs take `scramble`).
fn seed_and_scramble(
    ctx: &Ctx<'_>,
    d: &DesignSection,
    method: Method,
) -> Result<(u64, bool), StudyError> {
    let seed = d.seed.as_ref().map_or(0, |s| s.value);
    if let Some(s) = d.seed.as_ref().filter(|s| s.value > i64::MAX as u64) {
        return Err(ctx.err(
            Some(at(&s.referenced)),
            "design.seed",
            format!(
                "{} is not allowed: 0 to 2^63 - 1 (the file stores it as a 64-bit integer)",
                s.value
            ),
        ));
    }
    let scramble = match &d.scramble {
        None => true,
        Some(s) if matches!(method, Method::Sobol | Method::Saltelli) => s.value,
        Some(s) => {
            return Err(ctx.err(
                Some(at(&s.referenced)),
                "design.scramble",
                format!(
                    "a {} design has nothing to scramble; scramble is for sobol and saltelli",
                    method.name()
                ),
            ))
        }
    };
    Ok((seed, scramble))
}

/// The design drawn and mapped onto its parameters; `axes` are the grid's axis
/// names (a parameter is either an axis or in the design).
pub(super) fn resolve(
    ctx: &Ctx<'_>,
    file: &GridFile,
    base: &CaseParams,
    effects: &Effects,
    axes: &[String],
) -> Result<Option<Design>, StudyError> {
    let Some(section) = &file.design else {
        return Ok(None);
    };
    let d = &section.value;
    let method = method_of(ctx, d)?;
    let rows = rows(ctx, file)?;
    let (seed, scramble) = seed_and_scramble(ctx, d, method)?;
    let mut columns = Vec::new();
    let mut fields = Vec::new();
    for (name, spec) in &d.parameters.value {
        let field = format!("design.parameters.{name}");
        let place = at(&spec.referenced);
        if axes.contains(name) || file.cases.iter().any(|c| c.value.contains_key(name)) {
            return Err(ctx.err(
                Some(place),
                &field,
                "this parameter is also a grid axis or set by an explicit case; give it in one place",
            ));
        }
        let column = column(ctx, base, effects, name, &spec.value, &field, place)?;
        check_extremes(ctx, base, effects, &column, &field, place)?;
        columns.push((column, place));
        fields.push(field);
    }
    let dims = columns.len();
    let unit = design::unit_points(method, d.samples.value as usize, dims, seed, scramble);
    let columns = columns
        .iter()
        .enumerate()
        .map(|(k, (column, place))| {
            let values = (0..rows as usize)
                .map(|r| column.value(unit[r * dims + k]))
                .collect();
            (values, *place)
        })
        .collect();
    Ok(Some(Design {
        info: crate::study::DesignInfo {
            method,
            samples: d.samples.value,
            seed,
            scramble: scramble && matches!(method, Method::Sobol | Method::Saltelli),
            parameters: d.parameters.value.keys().cloned().collect(),
            rows,
        },
        fields,
        columns,
    }))
}

/// How one design parameter turns a unit draw into a case's value.
enum Column {
    /// A scalar parameter drawn from a distribution; whole numbers for counts
    /// (`⌊x⌋` of a uniform draw over `[min, max + 1)`).
    Scalar(&'static ParamDef, Distribution),
    /// One of these values, equally likely.
    Choices(Vec<Target>),
}

impl Column {
    /// The values at the ends of what the column draws, each with the key of the grid
    /// file that sets it: `min` and `max` of a range (a count's own max), the extreme
    /// draws of a normal (`u` = 2⁻³³ and 1 − 2⁻³³, ±6.3 sd), every choice.
    fn extremes(&self) -> Vec<(String, Target)> {
        match self {
            Column::Scalar(_, Distribution::Normal { .. }) => vec![
                ("mean - 6.3 sd".into(), self.value(0.0)),
                ("mean + 6.3 sd".into(), self.value(1.0)),
            ],
            Column::Scalar(..) => vec![
                ("min".into(), self.value(0.0)),
                ("max".into(), self.value(1.0)),
            ],
            Column::Choices(options) => options
                .iter()
                .enumerate()
                .map(|(k, &t)| (format!("choices[{k}]"), t))
                .collect(),
        }
    }

    fn value(&self, u: f64) -> Target {
        match self {
            Column::Scalar(p, dist) if p.integer => {
                let Distribution::Uniform { max, .. } = *dist else {
                    unreachable!("counts are drawn uniformly")
                };
                Target::Param(p, dist.map(u).floor().min(max - 1.0))
            }
            Column::Scalar(p, dist) => Target::Param(p, dist.map(u)),
            Column::Choices(options) => {
                options[Distribution::Choice {
                    count: options.len(),
                }
                .map(u) as usize]
            }
        }
    }
}

/// Refuses a column whose extreme value (see [`Column::extremes`]) makes the base case
/// invalid: any row may draw it, so the design is refused whether or not one did.
fn check_extremes(
    ctx: &Ctx<'_>,
    base: &CaseParams,
    effects: &Effects,
    column: &Column,
    field: &str,
    place: (u64, u64),
) -> Result<(), StudyError> {
    for (which, target) in column.extremes() {
        let mut params = base.clone();
        target.set(&mut params);
        without_effects_off(&mut params, effects);
        check_case(&params).map_err(|e| {
            ctx.err(
                Some(place),
                &format!("{field}.{which}"),
                format!(
                    "{} (at the design's {which}, the other parameters at their base values: \
                     every row may draw it)",
                    e.refusal()
                ),
            )
        })?;
    }
    Ok(())
}

/// One parameter's column, checked: the parameter exists and its effect is on, its
/// values have its units, exactly one of `min`/`max`, `mean`/`sd` or `choices`.
fn column(
    ctx: &Ctx<'_>,
    base: &CaseParams,
    effects: &Effects,
    name: &str,
    spec: &DesignParameter,
    field: &str,
    place: (u64, u64),
) -> Result<Column, StudyError> {
    let parameter = DesignField {
        ctx,
        base,
        effects,
        name,
        field,
    };
    match spec {
        DesignParameter {
            choices: Some(list),
            min: None,
            max: None,
            mean: None,
            sd: None,
            scale: None,
        } => parameter.choices(list),
        DesignParameter {
            min: Some(lo),
            max: Some(hi),
            mean: None,
            sd: None,
            choices: None,
            scale,
        } => parameter.range((lo, hi), scale.as_ref()),
        DesignParameter {
            mean: Some(m),
            sd: Some(s),
            min: None,
            max: None,
            choices: None,
            scale: None,
        } => parameter.normal(m, s),
        _ => Err(ctx.err(
            Some(place),
            field,
            "give exactly one of: min and max (with scale: linear or log), mean and sd \
             (normal), or choices",
        )),
    }
}

/// A design parameter `name` at `field` of the grid file, with what its values are
/// resolved against.
struct DesignField<'a> {
    ctx: &'a Ctx<'a>,
    base: &'a CaseParams,
    effects: &'a Effects,
    name: &'a str,
    field: &'a str,
}

impl DesignField<'_> {
    /// The value `v` given at `sub` of the parameter's field.
    fn resolve(&self, v: &S<Scalar>, sub: &str) -> Result<Target, StudyError> {
        let field = format!("{}.{sub}", self.field);
        self.ctx
            .resolve(self.base, self.name, v, &field, self.effects)
    }

    /// The value `v` at `sub` of a scalar parameter, in base units; a name is refused.
    fn scalar(&self, v: &S<Scalar>, sub: &str) -> Result<(&'static ParamDef, f64), StudyError> {
        match self.resolve(v, sub)? {
            Target::Param(p, x) => Ok((p, x)),
            Target::Location(_) | Target::Joint(_) | Target::DefectRace(_) => Err(self.ctx.err(
                Some(at(&v.referenced)),
                &format!("{}.{sub}", self.field),
                format!(
                    "{} is a name: give its values as `choices: [...]`",
                    self.name
                ),
            )),
        }
    }

    /// `choices: [...]`: at least one, none repeated.
    fn choices(&self, list: &S<Vec<S<Scalar>>>) -> Result<Column, StudyError> {
        let (ctx, field) = (self.ctx, self.field);
        if list.value.is_empty() {
            return Err(ctx.err(
                Some(at(&list.referenced)),
                &format!("{field}.choices"),
                "give at least one choice",
            ));
        }
        let options = list
            .value
            .iter()
            .enumerate()
            .map(|(k, v)| self.resolve(v, &format!("choices[{k}]")))
            .collect::<Result<Vec<_>, _>>()?;
        for (k, t) in options.iter().enumerate() {
            if options[..k].iter().any(|o| o.same_as(t)) {
                return Err(ctx.err(
                    Some(at(&list.value[k].referenced)),
                    &format!("{field}.choices[{k}]"),
                    "repeats an earlier choice; give each choice once",
                ));
            }
        }
        Ok(Column::Choices(options))
    }

    /// `min` < `max` in the parameter's units, drawn uniformly on a linear or (for
    /// positive non-counts) log `scale`; counts are whole numbers from min to max.
    fn range(
        &self,
        (lo, hi): (&S<Scalar>, &S<Scalar>),
        scale: Option<&S<String>>,
    ) -> Result<Column, StudyError> {
        let (ctx, name, field) = (self.ctx, self.name, self.field);
        let (p, min) = self.scalar(lo, "min")?;
        let (_, max) = self.scalar(hi, "max")?;
        if min >= max {
            return Err(ctx.err(
                Some(at(&hi.referenced)),
                &format!("{field}.max"),
                format!(
                    "{max} is not allowed: above min = {min} {}",
                    p.dimension.base_unit()
                ),
            ));
        }
        let log = match scale {
            None => false,
            Some(s) if s.value == "linear" => false,
            Some(s) if s.value == "log" && !p.integer && min > 0.0 => true,
            Some(s) if s.value == "log" => {
                return Err(ctx.err(
                    Some(at(&s.referenced)),
                    &format!("{field}.scale"),
                    if p.integer {
                        format!(
                            "{name} is a count: drawn uniformly from min to max; leave scale out"
                        )
                    } else {
                        format!("log needs min > 0, got {min} {}", p.dimension.base_unit())
                    },
                ))
            }
            Some(s) => {
                return Err(ctx.err(
                    Some(at(&s.referenced)),
                    &format!("{field}.scale"),
                    format!("`{}` is not a scale; expected linear or log", s.value),
                ))
            }
        };
        Ok(Column::Scalar(
            p,
            if log {
                Distribution::LogUniform { min, max }
            } else if p.integer {
                Distribution::Uniform {
                    min,
                    max: max + 1.0,
                }
            } else {
                Distribution::Uniform { min, max }
            },
        ))
    }

    /// `mean` and `sd` > 0 of a normal distribution, in the parameter's units; not
    /// for counts.
    fn normal(&self, m: &S<Scalar>, s: &S<Scalar>) -> Result<Column, StudyError> {
        let (ctx, name, field) = (self.ctx, self.name, self.field);
        let (p, mean) = self.scalar(m, "mean")?;
        let sd = ctx.quantity(s, p.dimension, &format!("{field}.sd"))?;
        if p.integer || sd <= 0.0 {
            return Err(ctx.err(
                Some(at(&s.referenced)),
                &format!("{field}.sd"),
                if p.integer {
                    format!("{name} is a count; give min and max (or choices), not mean and sd")
                } else {
                    format!("{sd} is not allowed: a standard deviation > 0")
                },
            ));
        }
        Ok(Column::Scalar(p, Distribution::Normal { mean, sd }))
    }
}
