//! The memory check of a study: refused when its run would need more memory than the
//! limits allow, decided before anything large is allocated.
//!
//! The check runs three times while a study is built, each on what is known by then:
//! before the cases are expanded (the samples per case, the case count and the design
//! values), once the cases' speeds give the per-revolution values and the references are
//! assigned, and on the finished study. The first two use a lower bound of the run's
//! needs (what is not known yet counts as nothing), so they refuse only studies the last,
//! exact check ([`Study::memory_estimate`], the figure `validate` and `--dry-run`
//! print) would refuse too.

use super::{at, Ctx};
use crate::study::config::{CaseValue, GridFile, SpeedSection};
use crate::study::memory::{bytes, Largest, Limits, MemoryEstimate, Shape};
use crate::study::{Study, StudyError};

/// Where the two remedies of a refusal point in the grid file: `sample_rate` (the
/// samples per case) and `max_cases` (the case count), as (line, column).
pub(super) struct Places {
    sample_rate: (u64, u64),
    max_cases: Option<(u64, u64)>,
}

impl Places {
    /// The places in `file`.
    pub(super) fn of(file: &GridFile) -> Self {
        Self {
            sample_rate: sample_rate_place(file),
            max_cases: file.max_cases.as_ref().map(|m| at(&m.referenced)),
        }
    }
}

/// Where the grid file sets the sample rate: `sample_rate`, or a recordings study's
/// first recording's (line, column; 1:1 when neither is there, which the sampling's
/// checks refuse first).
pub(super) fn sample_rate_place(file: &GridFile) -> (u64, u64) {
    let recorded = file
        .recordings
        .as_ref()
        .and_then(|r| r.value.first())
        .map(|r| &r.value.sample_rate);
    file.sample_rate
        .as_ref()
        .or(recorded)
        .map_or((1, 1), |v| at(&v.referenced))
}

/// What is known of a study before it is finished, for the lower-bound checks.
pub(super) struct Known {
    /// Samples per case.
    pub samples: u64,
    /// Cases the study holds: all, or one shard's.
    pub cases: u64,
    /// Whether the study holds one shard's cases only.
    pub sharded: bool,
    /// Values a sampled design holds while the study is expanded.
    pub design_values: u64,
    /// Ideal references the held cases use (0 before they are assigned).
    pub references: u64,
    /// Distinct ideal references of the whole study (0 before they are numbered).
    pub study_references: u64,
    /// Most whole revolutions of a case (0 before the speeds are known).
    pub revolutions: u64,
    /// Knots of the longest `speed:` table in the file (each case that has it holds
    /// a copy).
    pub speed_knots: u64,
}

impl Known {
    /// What the expansion found: `references` used by the held cases, of
    /// `study_references` in the study, and a case's most whole `revolutions`.
    pub(super) fn expanded(
        &mut self,
        references: usize,
        study_references: u64,
        revolutions: usize,
    ) {
        self.references = references as u64;
        self.study_references = study_references;
        self.revolutions = revolutions as u64;
    }
}

/// Knots of the longest `speed:` table of `file`: the top-level one or an explicit
/// case's.
pub(super) fn speed_knots(file: &GridFile) -> u64 {
    let knots = |s: &SpeedSection| s.time.as_ref().map_or(0, Vec::len);
    let top = file.speed.as_ref().map_or(0, |s| knots(&s.value));
    file.cases
        .iter()
        .flat_map(|c| c.value.values())
        .filter_map(|v| match &v.value {
            CaseValue::Speed(s) => Some(knots(s)),
            CaseValue::Scalar(_) => None,
        })
        .fold(top, usize::max) as u64
}

/// Refuses the study when even the lower bound of its run's memory from `known`
/// exceeds `limits`: one case's simulated channels per worker, the references, the
/// case table with its per-revolution values and the design values; no spectra, no
/// stored series, no sensors.
pub(super) fn check_lower_bound(
    ctx: &Ctx<'_>,
    places: &Places,
    known: &Known,
    limits: &Limits,
) -> Result<(), StudyError> {
    let shape = Shape {
        samples: known.samples,
        window: 0,
        spectra: 0,
        sensor_series: 0,
        stored_series: 0,
        stored_samples: 0,
        float32: true,
        cases: known.cases,
        references: known.references,
        study_references: known.study_references,
        design_values: known.design_values,
        replicates: 0,
        revolutions: known.revolutions,
        order_spectra: 0,
        speed_knots: known.speed_knots,
    };
    let estimate = MemoryEstimate::of(shape, limits.jobs);
    check(ctx, places, &estimate, limits, (true, known.sharded))
}

/// Refuses the finished `study` when its run's memory estimate exceeds `limits`.
pub(super) fn check_study(
    ctx: &Ctx<'_>,
    places: &Places,
    study: &Study,
    limits: &Limits,
) -> Result<(), StudyError> {
    let estimate = study.memory_estimate(limits.jobs);
    check(
        ctx,
        places,
        &estimate,
        limits,
        (false, study.part.is_some()),
    )
}

/// Refuses an `estimate` (a lower bound when `lower_bound`; of one shard's cases when
/// `sharded`) above `limits.memory`, naming the estimate, its parts, the limit and
/// what lowers it.
fn check(
    ctx: &Ctx<'_>,
    places: &Places,
    estimate: &MemoryEstimate,
    limits: &Limits,
    (lower_bound, sharded): (bool, bool),
) -> Result<(), StudyError> {
    if estimate.total <= limits.memory as f64 {
        return Ok(());
    }
    let shape = &estimate.shape;
    let (place, field, remedy) = match estimate.largest() {
        Largest::Samples => (
            Some(places.sample_rate),
            "sample_rate",
            format!(
                "a lower sample_rate or a shorter duration ({} samples per case now), {}or \
                 fewer workers (-j)",
                shape.samples,
                // The lower bound holds no record or spectra: only the exact estimate
                // shrinks with them.
                if lower_bound {
                    ""
                } else {
                    "`output: {dtype: float32}` (halves the encoded records), fewer \
                     `spectra: channels`, "
                }
            ),
        ),
        Largest::References => (
            Some(places.sample_rate),
            "sample_rate",
            format!(
                "a lower sample_rate or a shorter duration ({} samples per case now: the \
                 run keeps at least two ideal references per worker, of {} in all)",
                shape.samples, shape.references
            ),
        ),
        Largest::CaseTable => (
            places.max_cases,
            "grid",
            format!(
                "fewer cases ({} {}: fewer axis values), more shards (`--shard K/N` \
                 with a larger N: a shard holds only its own cases, about {} each), or \
                 fewer revolutions per case (a lower speed or a shorter duration)",
                shape.cases,
                if sharded { "in this shard" } else { "now" },
                bytes(shape.case_bytes()),
            ),
        ),
    };
    let (needs, parts) = if lower_bound {
        ("at least", estimate.lower_bound_parts())
    } else {
        ("about", estimate.to_string())
    };
    Err(ctx.err(
        place,
        field,
        format!(
            "the study needs {needs} {} of memory, more than the limit of {}: {parts}. \
             To need less: {remedy}",
            bytes(estimate.total),
            limits.describe(),
        ),
    ))
}
