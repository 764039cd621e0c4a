//! The parameter variables of a study's file: every case's values (`[case]`) and the
//! ideal references' (`[reference]`).

use crate::bearing::fault_label;
use crate::mechanism::{CaseParams, Location};
use crate::output::{Param, ParamValues, VarSpec};
use crate::recordings::read::{ColumnRef, Selector};
use crate::study::params::{defect_race_name, speed_profile_field, stored_value};
use crate::study::{Case, Recording, Recordings, Study};

/// What `speed_profile` and `reference_speed_profile` hold.
const PROFILE_DESCRIPTION: &str =
    "crank speed profile: constant (rpm), ramp, sine (speed_*) or table (knots in the grid file)";

/// The name of a case's speed profile, `constant` for `rpm`.
fn profile_name(p: &CaseParams) -> String {
    p.speed
        .as_ref()
        .map_or("constant", |s| s.name())
        .to_string()
}

/// A label variable `name` (units `1`) with its `description` and one value per case.
fn label(name: &str, description: &str, values: impl Iterator<Item = String>) -> Param {
    Param {
        spec: VarSpec::new(name, "1", description),
        values: ParamValues::Str(values.collect()),
    }
}

/// The `[case]` parameter variables of `cases`: the recorded parameters of the study's
/// effects, then the labels (location, joint in a study with plain joints, design
/// row, speed profile, defect race, fault); for a recordings study
/// [`recording_parameters`].
pub(super) fn case_parameters(study: &Study, cases: &[&Case]) -> Vec<Param> {
    if let Some(recordings) = &study.recordings {
        return recording_parameters(study, recordings, cases);
    }
    let mut parameters: Vec<Param> = study
        .recorded_parameters()
        .map(|p| Param {
            spec: VarSpec::new(p.name, p.dimension.file_units(), p.long_name),
            values: ParamValues::F64(cases.iter().map(|c| stored_value(p, &c.params)).collect()),
        })
        .collect();
    parameters.push(label(
        "location",
        "bearing location: ideal, crank_ground, crank_rod or rod_slider",
        cases.iter().map(|c| c.params.location.name().to_string()),
    ));
    if study.has_plain_joints() {
        parameters.push(label(
            "joint",
            "joint at the location: ball_bearing, dry_clearance or lubricated",
            cases.iter().map(|c| c.params.joint.name().to_string()),
        ));
    }
    if let Some(d) = &study.design {
        parameters.push(Param {
            spec: VarSpec::new(
                "design_row",
                "1",
                "row of the sampled design (global attribute design_method) this case runs",
            ),
            values: ParamValues::F64(cases.iter().map(|c| (c.id % d.rows) as f64).collect()),
        });
    }
    parameters.push(Param {
        spec: VarSpec::new("speed_profile", "1", PROFILE_DESCRIPTION),
        values: ParamValues::Str(cases.iter().map(|c| profile_name(&c.params)).collect()),
    });
    parameters.push(Param {
        spec: VarSpec::new(
            "defect_race",
            "1",
            "race of the first defect: outer, inner or ball (none without a defect of \
             nonzero depth)",
        ),
        values: ParamValues::Str(
            cases
                .iter()
                .map(|c| defect_race_name(&c.params).to_string())
                .collect(),
        ),
    });
    parameters.push(Param {
        spec: VarSpec::new(
            "fault",
            "1",
            "fault label: the races with a defect of nonzero depth (outer, inner, ball, \
             joined by +), or none",
        ),
        values: ParamValues::Str(
            cases
                .iter()
                .map(|c| match c.params.location {
                    Location::Ideal => "none".to_string(),
                    _ if c.params.joint.is_plain() => "none".to_string(),
                    _ => fault_label(&c.params.bearing.defects),
                })
                .collect(),
        ),
    });
    parameters
}

/// The `[case]` parameter variables of a recordings study's `cases`: the speed
/// (`rpm`, and a profile's `speed_*` when a case runs one), `speed_profile`, `fault`,
/// and what was read: `recording_file`, `recording_variable` and
/// `recording_samples` (the samples the file holds; the case analyses the study's
/// window of them).
fn recording_parameters(study: &Study, recordings: &Recordings, cases: &[&Case]) -> Vec<Param> {
    let recording = |c: &Case| &recordings.list[c.id as usize];
    let text = |f: &dyn Fn(&Recording) -> String| {
        ParamValues::Str(cases.iter().map(|c| f(recording(c))).collect())
    };
    let mut parameters: Vec<Param> = study
        .recorded_parameters()
        .filter(|p| p.name == "rpm" || speed_profile_field(p.name).is_some())
        .map(|p| Param {
            spec: VarSpec::new(p.name, p.dimension.file_units(), p.long_name),
            values: ParamValues::F64(cases.iter().map(|c| p.get(&c.params)).collect()),
        })
        .collect();
    parameters.extend([
        Param {
            spec: VarSpec::new("speed_profile", "1", PROFILE_DESCRIPTION),
            values: ParamValues::Str(cases.iter().map(|c| profile_name(&c.params)).collect()),
        },
        Param {
            spec: VarSpec::new(
                "fault",
                "1",
                "fault label of the recording (outer, inner, ball, joined by +), or none",
            ),
            values: text(&|r| r.fault.clone()),
        },
        Param {
            spec: VarSpec::new(
                "recording_file",
                "1",
                "the recording's file as the grid file writes it (relative to its folder)",
            ),
            values: text(&|r| r.written.clone()),
        },
        Param {
            spec: VarSpec::new(
                "recording_variable",
                "1",
                "where in the file the samples are: variable, channel_index=K, column=C, or empty",
            ),
            values: text(&|r| selector_text(&r.selector)),
        },
        Param {
            spec: VarSpec::new(
                "recording_samples",
                "1",
                "samples the recording's file holds; the case analyses the study's first \
                 samples of them (global attribute duration)",
            ),
            values: ParamValues::F64(cases.iter().map(|c| recording(c).samples as f64).collect()),
        },
    ]);
    parameters
}

/// How `recording_variable` names a selector.
fn selector_text(selector: &Selector) -> String {
    match selector {
        Selector::Variable(v) => v.clone(),
        Selector::ChannelIndex(k) => format!("channel_index={k}"),
        Selector::Column(ColumnRef::Name(n)) => format!("column={n}"),
        Selector::Column(ColumnRef::Index(k)) => format!("column={k}"),
        Selector::None => String::new(),
    }
}

/// The `[reference]` parameter variables of the references `ids` ([`Study::reference`]): each ideal run's speed and speed profile.
pub(super) fn reference_parameters(study: &Study, ids: &[u64]) -> Vec<Param> {
    let references = || ids.iter().map(|&id| study.reference(id as usize));
    vec![
        Param {
            spec: VarSpec::new("reference_rpm", "rpm", "crank speed of the ideal mechanism"),
            values: ParamValues::F64(references().map(|r| r.rpm).collect()),
        },
        Param {
            spec: VarSpec::new("reference_speed_profile", "1", PROFILE_DESCRIPTION),
            values: ParamValues::Str(references().map(profile_name).collect()),
        },
    ]
}
