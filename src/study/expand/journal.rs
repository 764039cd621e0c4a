//! The plain journal (docs/model.md §2.10): the `journal:` section read into the
//! base case, and the refusals of keys that act on no case of the study.

use super::*;
use crate::study::config::JournalSection;
use crate::study::params::{is_ball_parameter, is_journal_parameter};
use indexmap::IndexMap;

/// The `journal:` section: its grid parameters (`journal_*`) through the parameter
/// table, the material, stiffness and friction speeds read in their units.
pub(super) fn journal_section(
    ctx: &Ctx<'_>,
    c: &mut CaseParams,
    j: &JournalSection,
    effects: &Effects,
    prov: &mut Provenance,
) -> Result<(), StudyError> {
    let friction = j.friction.as_ref();
    let coefficient = friction.and_then(|f| f.coefficient.clone());
    for (name, v, field) in [
        ("journal_radius", &j.radius, "journal.radius"),
        ("journal_clearance", &j.clearance, "journal.clearance"),
        ("journal_length", &j.length, "journal.length"),
        (
            "journal_friction_coefficient",
            &coefficient,
            "journal.friction.coefficient",
        ),
        ("journal_viscosity", &j.viscosity, "journal.viscosity"),
    ] {
        apply_given(ctx, c, (name, v, field), effects, prov)?;
    }
    let read = |v: &Option<S<Scalar>>, dim, field| -> Result<Option<f64>, StudyError> {
        v.as_ref().map(|v| ctx.quantity(v, dim, field)).transpose()
    };
    let m = &mut c.journal.material;
    let modulus = read(
        &j.youngs_modulus,
        Dimension::Pressure,
        "journal.youngs_modulus",
    )?;
    m.youngs_modulus = modulus.unwrap_or(m.youngs_modulus);
    let nu = read(
        &j.poisson_ratio,
        Dimension::Dimensionless,
        "journal.poisson_ratio",
    )?;
    m.poisson_ratio = nu.unwrap_or(m.poisson_ratio);
    let stiffness = read(&j.stiffness, Dimension::Stiffness, "journal.stiffness")?;
    c.journal.stiffness = stiffness.or(c.journal.stiffness);
    if let Some(f) = friction {
        let speeds = &mut c.journal.friction;
        let stick = read(
            &f.stick_speed,
            Dimension::Velocity,
            "journal.friction.stick_speed",
        )?;
        speeds.stick_speed = stick.unwrap_or(speeds.stick_speed);
        let slip = read(
            &f.slip_speed,
            Dimension::Velocity,
            "journal.friction.slip_speed",
        )?;
        speeds.slip_speed = slip.unwrap_or(speeds.slip_speed);
    }
    Ok(())
}

/// Refuses what acts on no case: a `journal:` section in a study without a plain
/// journal, a grid axis (or zip axis, or design column) of the ball bearing's own
/// parameters whose cases at a location are all plain journals, and one of the
/// journal's whose cases at a location are all ball bearings.
pub(super) fn check_joint_keys(
    ctx: &Ctx<'_>,
    file: &GridFile,
    joints: collect::Joints,
) -> Result<(), StudyError> {
    let (any_plain, any_ball) = (joints.plain, joints.ball);
    if let (Some(j), false) = (&file.journal, any_plain) {
        return Err(ctx.err(
            Some(at(&j.referenced)),
            "journal",
            "no case of the study has a plain journal at a location (joint: dry_clearance \
             or lubricated); the journal section acts on none, remove it or set `joint`",
        ));
    }
    for (name, place, field) in varied_parameters(file) {
        let Some(p) = lookup(name) else { continue };
        let (acts, kind) = if is_ball_parameter(p) {
            (any_ball, "ball bearing")
        } else if is_journal_parameter(p) {
            (any_plain, "plain journal")
        } else {
            continue;
        };
        if !acts && joints.located {
            return Err(ctx.err(
                Some(place),
                &field,
                format!(
                    "{name} is a parameter of the {kind}, and no case of this axis at a \
                     location has a {kind} (joint: {}); it would act on none",
                    if kind == "ball bearing" {
                        "ball_bearing"
                    } else {
                        "dry_clearance or lubricated"
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a key of explicit case `c` (its entry `explicit`, `params` the case it
/// makes) that acts on no joint of it: a ball bearing's own parameter on a plain
/// journal, a `journal_*` parameter on a ball bearing. An ideal case has no joint
/// and is not checked here.
pub(super) fn check_explicit_joint_keys(
    ctx: &Ctx<'_>,
    c: usize,
    explicit: &IndexMap<String, S<CaseValue>>,
    params: &CaseParams,
) -> Result<(), StudyError> {
    if params.location == Site::Ideal {
        return Ok(());
    }
    let plain = params.joint.is_plain();
    for (name, value) in explicit {
        let Some(p) = lookup(name) else { continue };
        let (kind, other) = if plain && is_ball_parameter(p) {
            ("ball bearing", "ball_bearing")
        } else if !plain && is_journal_parameter(p) {
            ("plain journal", "dry_clearance or lubricated")
        } else {
            continue;
        };
        return Err(ctx.err(
            Some(at(&value.referenced)),
            &format!("cases[{c}].{name}"),
            format!(
                "{name} is a parameter of the {kind}, and this case's joint is {} at {}; \
                 it would act on nothing: remove it, or give the case `joint: {other}`",
                params.joint, params.location
            ),
        ));
    }
    Ok(())
}

/// The grid's axes, the zip groups' and the design's columns: name, place, field.
fn varied_parameters(file: &GridFile) -> Vec<(&str, (u64, u64), String)> {
    let mut out: Vec<_> = file
        .grid
        .iter()
        .map(|(n, v)| (n.as_str(), at(&v.referenced), format!("grid.{n}")))
        .collect();
    for (g, group) in file.zip.iter().enumerate() {
        out.extend(
            group
                .value
                .iter()
                .map(|(n, v)| (n.as_str(), at(&v.referenced), format!("zip[{g}].{n}"))),
        );
    }
    if let Some(d) = &file.design {
        out.extend(d.value.parameters.value.iter().map(|(n, v)| {
            (
                n.as_str(),
                at(&v.referenced),
                format!("design.parameters.{n}"),
            )
        }));
    }
    out
}
