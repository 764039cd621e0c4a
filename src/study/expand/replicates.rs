//! The `replicates:` section and `chaos_check`, checked.

use super::{at, Ctx};
use crate::error::number;
use crate::mechanism::{CaseParams, Location};
use crate::study::config::GridFile;
use crate::study::units::Dimension;
use crate::study::{Replicates, StudyError};

/// Most runs per case `replicates.count` allows.
pub(super) const MAX_REPLICATES: u64 = 1000;

/// The largest perturbation as a fraction of a case's smallest length scale
/// ([`perturbation_bound`]).
const PERTURBATION_FRACTION: f64 = 0.01;

/// The length scale of a case with a bearing but no clearance, waviness or defect
/// (m): the order of the balls' Hertz deflection under the mechanism's loads.
const CONTACT_SCALE: f64 = 1e-6;

/// The largest start perturbation replicates of `case` allow (m), with the length it
/// is a fraction of, described: [`PERTURBATION_FRACTION`] of the smallest of the radial
/// play |P_d|/2, every waviness amplitude and every defect depth (those above 0), or of
/// [`CONTACT_SCALE`] with none of them (a plain journal: of its radial clearance
/// `c`, or of [`CONTACT_SCALE`] at zero clearance); `None` for the ideal mechanism (no bearing to
/// start off centre in). A perturbed start then lies in replicate 0's contact state
/// and changes every contact force by about 1.5 % at most (docs/model.md §9.5).
pub(super) fn perturbation_bound(case: &CaseParams) -> Option<(f64, String)> {
    if case.location == Location::Ideal {
        return None;
    }
    if case.joint.is_plain() {
        let c = case.journal.geometry.clearance;
        let (scale, what) = if c > 0.0 {
            (c, "the journal's radial clearance c")
        } else {
            (CONTACT_SCALE, "the contact scale")
        };
        let what = format!("{what} ({})", micrometres(scale));
        return Some((PERTURBATION_FRACTION * scale, what));
    }
    let b = &case.bearing;
    let mut scales = vec![(
        0.5 * b.clearance.abs(),
        "the radial play |P_d|/2".to_string(),
    )];
    for (race, w) in [("inner", &b.inner_waviness), ("outer", &b.outer_waviness)] {
        for h in &w.harmonics {
            scales.push((h.amplitude, format!("the {race} race's waviness amplitude")));
        }
    }
    for d in &b.defects {
        scales.push((d.depth, "the defect depth".to_string()));
    }
    let smallest = scales
        .into_iter()
        .filter(|(x, _)| *x > 0.0)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or((
            CONTACT_SCALE,
            "a Hertz deflection, with no clearance, waviness or defect".into(),
        ));
    Some((
        PERTURBATION_FRACTION * smallest.0,
        format!("{} ({})", smallest.1, micrometres(smallest.0)),
    ))
}

/// A length in µm, for messages.
fn micrometres(x: f64) -> String {
    format!("{} µm", number(1e6 * x))
}

/// Refuses a perturbation above the bound of any case ([`perturbation_bound`]), naming
/// the case where the bound is smallest (`tightest`: its id, the bound and what it is
/// 1 % of).
fn check_perturbation(
    ctx: &Ctx<'_>,
    file: &GridFile,
    perturbation: f64,
    tightest: &Option<(u64, (f64, String))>,
) -> Result<(), StudyError> {
    let Some((id, (bound, scale))) = tightest
        .as_ref()
        .filter(|(_, (bound, _))| perturbation > *bound)
    else {
        return Ok(());
    };
    let r = &file.replicates.as_ref().expect("replicates given").value;
    Err(ctx.err(
        Some(at(&r.perturbation.referenced)),
        "replicates.perturbation",
        format!(
            "{} ({}) is not allowed: at most {} in case {id}, 1 % of {scale} (a perturbed \
             start must stay a small disturbance of the centred one: in its contact state, \
             every contact force changed by about 1.5 % at most)",
            r.perturbation.value,
            micrometres(perturbation),
            micrometres(*bound)
        ),
    ))
}

/// The study's replicates (none without the section) and whether its chaos check
/// runs: `chaos_check` as given, else on with two or more replicates; on needs two.
/// The perturbation is checked against every case's bound (`tightest`, the smallest:
/// its case id, the bound and what it is 1 % of).
pub(super) fn resolve(
    ctx: &Ctx<'_>,
    file: &GridFile,
    tightest: &Option<(u64, (f64, String))>,
) -> Result<(Option<Replicates>, bool), StudyError> {
    let replicates = match &file.replicates {
        None => None,
        Some(section) => {
            let r = &section.value;
            let count = r.count.value;
            if !(1..=MAX_REPLICATES).contains(&count) {
                return Err(ctx.err(
                    Some(at(&r.count.referenced)),
                    "replicates.count",
                    format!("{count} is not allowed: 1 to {MAX_REPLICATES} runs per case"),
                ));
            }
            let field = "replicates.perturbation";
            let perturbation = ctx.quantity(&r.perturbation, Dimension::Length, field)?;
            if perturbation <= 0.0 {
                return Err(ctx.err(
                    Some(at(&r.perturbation.referenced)),
                    field,
                    format!(
                        "{} is not allowed: a length above 0, e.g. \"1 nm\"",
                        r.perturbation.value
                    ),
                ));
            }
            let seed = r.seed.as_ref().map_or(0, |s| s.value);
            if let Some(s) = r.seed.as_ref().filter(|s| s.value > i64::MAX as u64) {
                return Err(ctx.err(
                    Some(at(&s.referenced)),
                    "replicates.seed",
                    format!(
                        "{} is not allowed: 0 to 2^63 - 1 (the file stores it as a 64-bit integer)",
                        s.value
                    ),
                ));
            }
            check_perturbation(ctx, file, perturbation, tightest)?;
            Some(Replicates {
                count: count as usize,
                perturbation,
                seed,
            })
        }
    };
    let count = replicates.map_or(1, |r| r.count);
    let chaos_check = match &file.chaos_check {
        None => count >= 2,
        Some(c) if c.value && count < 2 => {
            return Err(ctx.err(
                Some(at(&c.referenced)),
                "chaos_check",
                format!(
                    "true needs replicates to compare: give `replicates: {{count: R, \
                     perturbation: \"1 nm\"}}` with R >= 2 (the study has {count} run per case)"
                ),
            ))
        }
        Some(c) => c.value,
    };
    Ok((replicates, chaos_check))
}
