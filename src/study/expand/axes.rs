//! The grid's axes, zip groups and explicit cases: resolved once, counted, expanded
//! into cases, each value checked against the case it lands in.

use super::*;

/// One axis of the expansion: parameter name, its values, and its YAML field.
pub(super) type Axis<'a> = (&'a String, &'a S<Vec<S<Scalar>>>, String);

/// Why `param` cannot be set in `case`: `rpm` where the case has a `speed:`
/// profile, a `speed_*` axis of another profile than the case's.
pub(super) fn check_speed(case: &CaseParams, param: &str) -> Result<(), String> {
    let has = case.speed.as_ref().map(SpeedProfile::name);
    let needs = match (crate::study::params::speed_profile_field(param), param) {
        (Some(profile), _) => profile,
        (None, "rpm") => match has {
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
pub(super) enum Target {
    /// A scalar parameter, in its base unit.
    Param(&'static ParamDef, f64),
    /// The bearing location.
    Location(Site),
    /// The joint kind at the location.
    Joint(JointKind),
    /// The race of the first defect.
    DefectRace(DefectRace),
}

impl Target {
    pub(super) fn set(&self, case: &mut CaseParams) {
        match *self {
            Target::Param(p, x) => p.set(case, x),
            Target::Location(site) => case.location = site,
            Target::Joint(joint) => case.joint = joint,
            Target::DefectRace(race) => Defect::first(&mut case.bearing.defects).race = race,
        }
    }

    /// The parameter's name, as in [`Provenance`].
    pub(super) fn name(&self) -> &'static str {
        match self {
            Target::Param(p, _) => p.name,
            Target::Location(_) => "location",
            Target::Joint(_) => "joint",
            Target::DefectRace(_) => "defect_race",
        }
    }

    /// Whether two values of one axis are the same (`-0` is `0`).
    pub(super) fn same_as(&self, other: &Target) -> bool {
        match (self, other) {
            (Target::Param(_, a), Target::Param(_, b)) => a == b,
            (Target::Location(a), Target::Location(b)) => a == b,
            (Target::Joint(a), Target::Joint(b)) => a == b,
            (Target::DefectRace(a), Target::DefectRace(b)) => a == b,
            _ => false,
        }
    }
}

/// One grid axis with its values resolved: its YAML field and, per value, what it
/// sets and where it is written.
pub(super) struct ResolvedAxis<'a> {
    pub(super) field: &'a str,
    pub(super) values: Vec<(Target, (u64, u64))>,
}

/// The axes in groups (each grid axis a group of one; zip groups vary together) and
/// their names in expansion order; refuses unequal zips, empty axes, an axis given
/// twice and an empty study.
pub(super) fn axis_groups<'a>(
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
pub(super) fn case_count(
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
        _ => {
            Err(ctx.err(
                file.max_cases.as_ref().map(|m| at(&m.referenced)),
                "grid",
                match total {
                    Some(t) => format!(
                    "the grid expands to {t} cases, more than max_cases = {max_cases}; their case \
                     table alone would need about {} of memory; raise `max_cases` if you mean it",
                    crate::study::memory::bytes(t as f64 * crate::study::memory::case_table_bytes())
                ),
                    None => format!(
                        "the grid expands to over 2^64 cases, more than max_cases = {max_cases}"
                    ),
                },
            ))
        }
    }
}

/// Every axis value resolved once (units, effects, whole numbers).
pub(super) fn resolve_axes<'a>(
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
pub(super) fn expand_grid(
    ctx: &Ctx<'_>,
    base: &CaseParams,
    prov: &Provenance,
    resolved: &[Vec<ResolvedAxis<'_>>],
    count: u64,
    effects: &Effects,
    cases: &mut Collected,
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
pub(super) fn expand_explicit(
    ctx: &Ctx<'_>,
    file: &GridFile,
    base: &CaseParams,
    prov: &Provenance,
    design: Option<&Vec<ResolvedAxis<'_>>>,
    effects: &Effects,
    cases: &mut Collected,
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
            super::check_explicit_joint_keys(ctx, c, &explicit.value, &params)?;
            let id = cases.next_id();
            cases.push(finish_case(ctx, params, effects, || case_prov, id)?);
        }
    }
    Ok(())
}

/// Refuses a value an axis already has (a grid axis), or a row a zip group already
/// has: the same cases would run twice.
pub(super) fn check_repeats(
    ctx: &Ctx<'_>,
    groups: &[Vec<ResolvedAxis<'_>>],
) -> Result<(), StudyError> {
    let key = |t: &Target| match *t {
        Target::Param(_, x) => (x + 0.0).to_bits(),
        Target::Location(site) => site as u64,
        Target::Joint(joint) => joint as u64,
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
