//! Where each case and reference of the merged file comes from, and the merged
//! file's layout.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use super::super::layout::shell_word;
use super::super::{history_line, AttrValue, Layout, OutputError};
use super::ensure;
use super::survey::Surveyed;

/// Where a case of the merged file comes from: `(case id, shard, row)`.
pub(super) type CasePlace = (u64, usize, usize);

/// `(reference id, shard, row)`: where a reference is read from.
pub(super) type ReferencePlace = (u64, usize, usize);

/// `(id, shard, row)` of every id `ids` gives for each shard, sorted.
pub(super) fn places(
    surveyed: &[Surveyed],
    ids: fn(&Surveyed) -> &[u64],
) -> Vec<(u64, usize, usize)> {
    let mut places: Vec<_> = surveyed
        .iter()
        .enumerate()
        .flat_map(|(s, shard)| {
            ids(shard)
                .iter()
                .enumerate()
                .map(move |(row, &id)| (id, s, row))
        })
        .collect();
    places.sort_unstable();
    places
}

/// Every reference of the shards, sorted by id, each from the first shard holding it
/// (a shard holds the references its cases use).
pub(super) fn reference_places(surveyed: &[Surveyed]) -> Vec<ReferencePlace> {
    let mut places = places(surveyed, |s| &s.reference_ids);
    places.dedup_by_key(|p| p.0);
    places
}

/// `(case id, shard, row)` of every case, sorted by id, and the study's case count
/// (the `study_cases` attribute of the first shard's `first`): refused unless the ids
/// are exactly `0..N-1`, each in one shard.
pub(super) fn case_order(
    first: &Layout,
    surveyed: &[Surveyed],
    shards: &[PathBuf],
) -> Result<(Vec<CasePlace>, usize), OutputError> {
    let order: Vec<CasePlace> = places(surveyed, |s| &s.case_ids);
    if let Some(w) = order.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(OutputError::Refused(format!(
            "case {} is in both {} and {}",
            w[0].0,
            shards[w[0].1].display(),
            shards[w[1].1].display()
        )));
    }
    let expected = match first.attribute("study_cases") {
        Some(&AttrValue::I64(n)) => n as usize,
        _ => {
            return Err(OutputError::Refused(format!(
                "{} has no study_cases attribute; is it a studyrun study file?",
                shards[0].display()
            )))
        }
    };
    ensure(order.len() == expected, || {
        format!(
            "the shards hold {} of the study's {expected} cases; merge all shards",
            order.len()
        )
    })?;
    // Sorted, distinct and as many as the study's cases: ids 0..N-1 unless one is off.
    if let Some((row, &(id, s, _))) = order.iter().enumerate().find(|&(row, o)| o.0 != row as u64) {
        return Err(OutputError::Refused(format!(
            "case {row} of the study is in no shard ({} holds case id {id} instead; the \
             study's ids are 0 to {})",
            shards[s].display(),
            expected.saturating_sub(1)
        )));
    }

    Ok((order, expected))
}

/// The merged file's layout: the first shard's `first` (without cases), with every
/// case's ids and references in id order, every shard's references (`refs`) in id
/// order, the whole study's `file_cases`, no `shard`, and the merge's line on top of
/// `history`. Its parameters hold no values: [`Merged::write`] writes them.
pub(super) fn merged_layout(
    first: &Layout,
    surveyed: &[Surveyed],
    (order, refs): (&[CasePlace], &[ReferencePlace]),
    expected: usize,
    (output, shards, force): (&Path, &[PathBuf], bool),
) -> Layout {
    let mut layout: Layout = first.clone();
    layout.case_ids = order.iter().map(|o| o.0).collect();
    layout.reference_ids = refs.iter().map(|r| r.0).collect();
    // Cases without references (measured recordings) refer to none.
    layout.reference_index = order
        .iter()
        .filter(|_| !refs.is_empty())
        .map(|&(_, s, row)| {
            let shard = &surveyed[s];
            let id = shard.reference_ids[shard.reference_index[row] as usize];
            refs.partition_point(|r| r.0 < id) as u64
        })
        .collect();
    for (name, value) in layout.attributes.iter_mut() {
        match name.as_str() {
            "file_cases" => *value = AttrValue::I64(expected as i64),
            "shard" => *value = AttrValue::Str(String::new()),
            _ => {}
        }
    }
    let line = merge_history_line(output, shards, force);
    match layout.attributes.iter_mut().find(|(n, _)| n == "history") {
        Some((_, AttrValue::Str(h))) if !h.is_empty() => *h = format!("{line}\n{h}"),
        Some((_, value)) => *value = AttrValue::Str(line),
        None => layout
            .attributes
            .push(("history".to_owned(), AttrValue::Str(line))),
    }
    layout
}

/// The merge's `history` line: `<now>: studyrun merge [--force] OUTPUT SHARD...`.
fn merge_history_line(output: &Path, shards: &[PathBuf], force: bool) -> String {
    let now = humantime::format_rfc3339_seconds(SystemTime::now()).to_string();
    let mut words = vec!["studyrun".to_owned(), "merge".to_owned()];
    if force {
        words.push("--force".to_owned());
    }
    words.extend(
        std::iter::once(output)
            .chain(shards.iter().map(PathBuf::as_path))
            .map(|p| shell_word(&p.to_string_lossy())),
    );
    history_line(&now, &words.join(" "))
}
