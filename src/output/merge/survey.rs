//! The shards checked one at a time, and what the merge keeps of each.

use std::path::{Path, PathBuf};

use super::super::{Layout, OutputError, ParamValues, Status, StudyReader};
use super::alike::{layout_difference, Order};
use super::ensure;

/// What the merge keeps of a shard once it is checked and closed: its case ids, its
/// references' ids, each case's reference row, and where the first shard's
/// variables are in it.
pub(super) struct Surveyed {
    pub(super) case_ids: Vec<u64>,
    pub(super) reference_ids: Vec<u64>,
    pub(super) reference_index: Vec<u64>,
    pub(super) order: Order,
}

/// The shards checked one at a time, each closed before the next is opened: none
/// with a pending case, all of one study and layout, every value read and its
/// checksums checked (which also checks that reading the cases later cannot crash).
/// Returns the first shard's layout without its cases (no ids, no parameter values)
/// and what the merge keeps of each shard.
pub(super) fn survey(shards: &[PathBuf]) -> Result<(Layout, Vec<Surveyed>), OutputError> {
    let mut first: Option<Layout> = None;
    let mut surveyed = Vec::with_capacity(shards.len());
    for path in shards {
        let r = StudyReader::open(path).map_err(OutputError::file(path))?;
        let statuses = r.statuses().map_err(OutputError::file(path))?;
        let pending = statuses.iter().filter(|&&s| s == Status::Pending).count();
        ensure(pending == 0, || {
            format!(
                "{} has {pending} pending cases: its run did not finish; finish it with --resume first",
                path.display()
            )
        })?;
        if let Some(first) = &first {
            check_alike(r.layout(), first, path, &shards[0])?;
        }
        r.verify().map_err(OutputError::file(path))?;
        let first = first.get_or_insert_with(|| without_cases(r.layout()));
        let l = r.layout();
        surveyed.push(Surveyed {
            case_ids: l.case_ids.clone(),
            reference_ids: l.reference_ids.clone(),
            reference_index: l.reference_index.clone(),
            order: Order::of(l, first),
        });
    }
    Ok((first.expect("at least one shard"), surveyed))
}

/// Refuses the shard at `path` of layout `l` unless it is of the study and layout of
/// the first shard's `first` (at `first_path`).
pub(super) fn check_alike(
    l: &Layout,
    first: &Layout,
    path: &Path,
    first_path: &Path,
) -> Result<(), OutputError> {
    let fingerprint = |l: &Layout| l.attribute("study_fingerprint").cloned();
    ensure(fingerprint(l) == fingerprint(first), || {
        format!(
            "{} belongs to a different study (or studyrun version) than {}",
            path.display(),
            first_path.display()
        )
    })?;
    match layout_difference(l, first) {
        Some(difference) => Err(OutputError::Refused(format!(
            "{} has a different layout than {}: {difference}",
            path.display(),
            first_path.display()
        ))),
        None => Ok(()),
    }
}

/// `l` without its cases and references: no ids, no reference rows, and each
/// parameter with no values (of its kind).
pub(super) fn without_cases(l: &Layout) -> Layout {
    let mut template = l.clone();
    template.case_ids = Vec::new();
    template.reference_ids = Vec::new();
    template.reference_index = Vec::new();
    let params = template.parameters.iter_mut();
    for p in params.chain(template.reference_parameters.iter_mut()) {
        p.values = match p.values {
            ParamValues::F64(_) => ParamValues::F64(Vec::new()),
            ParamValues::Str(_) => ParamValues::Str(Vec::new()),
        };
    }
    template
}
