//! The `replicates:` section and `chaos_check`, checked.

use super::{at, Ctx};
use crate::study::config::GridFile;
use crate::study::units::Dimension;
use crate::study::{Replicates, StudyError};

/// Most runs per case `replicates.count` allows.
pub(super) const MAX_REPLICATES: u64 = 1000;

/// The study's replicates (none without the section) and whether its chaos check
/// runs: `chaos_check` as given, else on with two or more replicates; on needs two.
pub(super) fn resolve(
    ctx: &Ctx<'_>,
    file: &GridFile,
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
