//! Combining shard files (`studyrun merge`) into one file equal to a single run.

use std::path::{Path, PathBuf};

use std::time::SystemTime;

use super::layout::shell_word;
use super::OutputError;
use super::{history_line, side_paths, OutputLock, VarSpec};
use crate::output::{
    AttrValue, CaseRecord, Layout, Param, ParamValues, Status, StudyReader, StudyWriter,
};

/// Refuses with `message` unless `ok`.
fn ensure(ok: bool, message: impl FnOnce() -> String) -> Result<(), OutputError> {
    if ok {
        Ok(())
    } else {
        Err(OutputError::Refused(message()))
    }
}

/// What differs between the variables `a` of a shard and `b` of the first (matched by
/// name, in any order: ncks sorts them by name): a variable one of them lacks, or one
/// whose units or long name differ; `None` when they are alike.
fn variables_difference<'a>(
    a: impl IntoIterator<Item = &'a VarSpec>,
    b: impl IntoIterator<Item = &'a VarSpec>,
) -> Option<String> {
    let a: Vec<&VarSpec> = a.into_iter().collect();
    let b: Vec<&VarSpec> = b.into_iter().collect();
    let find = |specs: &[&'a VarSpec], name: &str| specs.iter().find(|s| s.name == name).copied();
    for x in &a {
        match find(&b, &x.name) {
            None => return Some(format!("it has a variable `{}`", x.name)),
            Some(y) if y.units != x.units => {
                return Some(format!(
                    "its `{}` has the units `{}`, not `{}`",
                    x.name, x.units, y.units
                ))
            }
            Some(y) if y.long_name != x.long_name => {
                return Some(format!("its `{}` has another long_name", x.name))
            }
            Some(_) => {}
        }
    }
    b.iter()
        .find(|y| find(&a, &y.name).is_none())
        .map(|y| format!("it has no variable `{}`", y.name))
}

/// What keeps the shard of layout `l` from merging with the first shard's `first`, in
/// words; `None` when nothing does.
fn layout_difference(l: &Layout, first: &Layout) -> Option<String> {
    fn params(l: &Layout) -> impl Iterator<Item = &VarSpec> {
        l.parameters.iter().map(|p| &p.spec)
    }
    let coordinates = [
        ("time", l.times != first.times),
        ("frequency", l.frequencies != first.frequencies),
        ("replicate", l.replicates != first.replicates),
        ("revolution", l.revolutions != first.revolutions),
        ("order", l.orders != first.orders),
        ("sk_frequency", l.sk_frequencies != first.sk_frequencies),
    ];
    if let Some((name, _)) = coordinates.iter().find(|(_, differs)| *differs) {
        return Some(format!("its `{name}` coordinate differs"));
    }
    variables_difference(&l.series, &first.series)
        .or_else(|| variables_difference(&l.spectra, &first.spectra))
        .or_else(|| variables_difference(&l.kurtosis, &first.kurtosis))
        .or_else(|| variables_difference(&l.metrics, &first.metrics))
        .or_else(|| variables_difference(&l.replicate_metrics, &first.replicate_metrics))
        .or_else(|| variables_difference(&l.revolution_metrics, &first.revolution_metrics))
        .or_else(|| variables_difference(&l.order_spectra, &first.order_spectra))
        .or_else(|| variables_difference(params(l), params(first)))
        .or_else(|| {
            let refs = |l: &'_ Layout| {
                l.reference_parameters
                    .iter()
                    .map(|p| p.spec.clone())
                    .collect::<Vec<_>>()
            };
            variables_difference(&refs(l), &refs(first))
        })
        .or_else(|| variables_difference(&l.reference_series, &first.reference_series))
}

/// For each variable of `want`, its index in `have` (same names, checked before).
fn positions(want: &[VarSpec], have: &[VarSpec]) -> Vec<usize> {
    want.iter()
        .map(|w| {
            have.iter()
                .position(|h| h.name == w.name)
                .expect("same variables")
        })
        .collect()
}

/// Merges `shards` (files of `studyrun --shard K/N` runs of one study) into `output`.
/// Every case of the study must be present exactly once, in finished shard files
/// (no partial files, no pending cases); empty shards are allowed. Shards that netCDF
/// tools rewrote are merged too: variables are matched by name, whatever their
/// order. The merged file's variables are in the first shard's order; its `history`
/// is the first shard's with the merge's line on top. Returns the number of cases.
pub fn merge(output: &Path, shards: &[PathBuf], force: bool) -> Result<usize, OutputError> {
    ensure(!shards.is_empty(), || {
        "merge needs at least one shard file".into()
    })?;
    check_inputs(output, shards)?;
    // Nothing replaced that is not ours: no shard, no FIFO or link, and with --force
    // only a study file; checked again under the lock.
    let inputs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    super::overwrite::check_output(output, force, &inputs)?;
    let _lock = OutputLock::acquire(output)?;
    super::overwrite::check_output(output, force, &inputs)?;
    let readers = open_shards(shards)?;
    let (order, expected) = case_order(&readers, shards)?;
    let shard_order = shard_orders(&readers);
    // Every value of every shard read and its checksums checked before anything is
    // copied (this also checks that reading the cases below cannot crash).
    for (r, path) in readers.iter().zip(shards) {
        r.verify().map_err(OutputError::file(path))?;
    }

    let refs = reference_places(&readers);
    let layout = merged_layout(
        &readers,
        &order,
        &refs,
        &shard_order,
        expected,
        (output, shards, force),
    );
    write_merged(
        output,
        shards,
        &readers,
        (&order, &refs),
        &shard_order,
        &layout,
    )?;
    Ok(order.len())
}

/// Refuses shards that are partial files, have a journal beside them, are given twice
/// or are the output itself.
fn check_inputs(output: &Path, shards: &[PathBuf]) -> Result<(), OutputError> {
    for (k, p) in shards.iter().enumerate() {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        ensure(
            super::DataFile::output_of(Path::new(&name)).is_none(),
            || {
                format!(
                    "{} is the partial file of an unfinished run; finish it with --resume first",
                    p.display()
                )
            },
        )?;
        let (journal, _) = side_paths(p);
        ensure(!journal.exists(), || {
            format!(
                "{} has the journal of an interrupted run beside it ({}), whose result will \
                 replace it; finish that run with --resume first",
                p.display(),
                journal.display()
            )
        })?;
        let same = |q: &PathBuf| match (std::fs::canonicalize(p), std::fs::canonicalize(q)) {
            (Ok(a), Ok(b)) => a == b,
            _ => p == q,
        };
        if let Some(q) = shards[..k].iter().find(|q| same(q)) {
            return Err(OutputError::Refused(format!(
                "{} is given twice (also as {})",
                p.display(),
                q.display()
            )));
        }
        ensure(!same(&output.to_path_buf()), || {
            format!("{} is both a shard and the merged output", p.display())
        })?;
    }
    Ok(())
}

/// The shards opened: none with a pending case, all of one study and layout.
fn open_shards(shards: &[PathBuf]) -> Result<Vec<StudyReader>, OutputError> {
    let readers: Vec<StudyReader> = shards
        .iter()
        .map(|p| StudyReader::open(p).map_err(OutputError::file(p)))
        .collect::<Result<_, _>>()?;
    for (r, path) in readers.iter().zip(shards) {
        let statuses = r.statuses().map_err(OutputError::file(path))?;
        let pending = statuses.iter().filter(|&&s| s == Status::Pending).count();
        ensure(pending == 0, || {
            format!(
                "{} has {pending} pending cases: its run did not finish; finish it with --resume first",
                path.display()
            )
        })?;
    }
    let first = readers[0].layout();
    let attr = |r: &StudyReader, name: &str| r.attribute(name).cloned();
    for (r, path) in readers.iter().zip(shards).skip(1) {
        ensure(
            attr(r, "study_fingerprint") == attr(&readers[0], "study_fingerprint"),
            || {
                format!(
                    "{} belongs to a different study (or studyrun version) than {}",
                    path.display(),
                    shards[0].display()
                )
            },
        )?;
        if let Some(difference) = layout_difference(r.layout(), first) {
            return Err(OutputError::Refused(format!(
                "{} has a different layout than {}: {difference}",
                path.display(),
                shards[0].display()
            )));
        }
    }

    Ok(readers)
}

/// Where a case of the merged file comes from: `(case id, shard, row)`.
type CasePlace = (u64, usize, usize);

/// `(reference id, shard, row)`: where a reference is read from.
type ReferencePlace = (u64, usize, usize);

/// `(id, shard, row)` of every id `ids` gives for each shard's layout, sorted.
fn places(readers: &[StudyReader], ids: fn(&Layout) -> &[u64]) -> Vec<(u64, usize, usize)> {
    let mut places: Vec<_> = readers
        .iter()
        .enumerate()
        .flat_map(|(s, r)| {
            ids(r.layout())
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
fn reference_places(readers: &[StudyReader]) -> Vec<ReferencePlace> {
    let mut places = places(readers, |l| &l.reference_ids);
    places.dedup_by_key(|p| p.0);
    places
}

/// `(case id, shard, row)` of every case, sorted by id, and the study's case count:
/// refused unless the ids are exactly `0..N-1`, each in one shard.
fn case_order(
    readers: &[StudyReader],
    shards: &[PathBuf],
) -> Result<(Vec<CasePlace>, usize), OutputError> {
    let attr = |r: &StudyReader, name: &str| r.attribute(name).cloned();
    let order: Vec<CasePlace> = places(readers, |l| &l.case_ids);
    if let Some(w) = order.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(OutputError::Refused(format!(
            "case {} is in both {} and {}",
            w[0].0,
            shards[w[0].1].display(),
            shards[w[1].1].display()
        )));
    }
    let expected = match attr(&readers[0], "study_cases") {
        Some(AttrValue::I64(n)) => n as usize,
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

/// Where each of the first shard's variables is in each shard.
struct Order {
    series: Vec<usize>,
    spectra: Vec<usize>,
    metrics: Vec<usize>,
    replicate_metrics: Vec<usize>,
    revolution_metrics: Vec<usize>,
    order_spectra: Vec<usize>,
    parameters: Vec<usize>,
    reference_parameters: Vec<usize>,
    reference_series: Vec<usize>,
}

/// Each shard's variables in the first shard's order.
fn shard_orders(readers: &[StudyReader]) -> Vec<Order> {
    let first = readers[0].layout();
    // Each shard's variables in the first shard's order.
    let shard_order: Vec<Order> = readers
        .iter()
        .map(|r| {
            let l = r.layout();
            let specs = |ps: &[Param]| ps.iter().map(|p| p.spec.clone()).collect();
            let (want, have): (Vec<VarSpec>, Vec<VarSpec>) =
                (specs(&first.parameters), specs(&l.parameters));
            let (want_refs, have_refs): (Vec<VarSpec>, Vec<VarSpec>) = (
                specs(&first.reference_parameters),
                specs(&l.reference_parameters),
            );
            Order {
                series: positions(&first.series, &l.series),
                spectra: positions(&first.spectra, &l.spectra)
                    .into_iter()
                    .chain(
                        positions(&first.kurtosis, &l.kurtosis)
                            .into_iter()
                            .map(|i| l.spectra.len() + i),
                    )
                    .collect(),
                metrics: positions(&first.metrics, &l.metrics),
                replicate_metrics: positions(&first.replicate_metrics, &l.replicate_metrics),
                revolution_metrics: positions(&first.revolution_metrics, &l.revolution_metrics),
                order_spectra: positions(&first.order_spectra, &l.order_spectra),
                parameters: positions(&want, &have),
                reference_parameters: positions(&want_refs, &have_refs),
                reference_series: positions(&first.reference_series, &l.reference_series),
            }
        })
        .collect();
    shard_order
}

/// The values of a parameter (of the kind of `like`) at `places` (`(id, shard, row)`),
/// `at(shard)` being the parameter in that shard.
fn gathered<'r>(
    places: &[(u64, usize, usize)],
    like: &ParamValues,
    at: impl Fn(usize) -> &'r Param,
) -> ParamValues {
    match like {
        ParamValues::F64(_) => ParamValues::F64(
            places
                .iter()
                .map(|&(_, s, row)| match &at(s).values {
                    ParamValues::F64(v) => v[row],
                    ParamValues::Str(_) => f64::NAN,
                })
                .collect(),
        ),
        ParamValues::Str(_) => ParamValues::Str(
            places
                .iter()
                .map(|&(_, s, row)| match &at(s).values {
                    ParamValues::Str(v) => v[row].clone(),
                    ParamValues::F64(_) => String::new(),
                })
                .collect(),
        ),
    }
}

/// The merged file's layout: the first shard's, with every case's ids, references and
/// parameters in id order, every shard's references (`refs`) in id order, the whole study's `file_cases`, no `shard`, and the merge's
/// line on top of `history`.
fn merged_layout(
    readers: &[StudyReader],
    order: &[CasePlace],
    refs: &[ReferencePlace],
    shard_order: &[Order],
    expected: usize,
    (output, shards, force): (&Path, &[PathBuf], bool),
) -> Layout {
    let first = readers[0].layout();
    let mut layout: Layout = first.clone();
    layout.case_ids = order.iter().map(|o| o.0).collect();
    for (p, param) in layout.parameters.iter_mut().enumerate() {
        let at = |s: usize| &readers[s].layout().parameters[shard_order[s].parameters[p]];
        param.values = gathered(order, &param.values, at);
    }
    layout.reference_ids = refs.iter().map(|r| r.0).collect();
    for (p, param) in layout.reference_parameters.iter_mut().enumerate() {
        let at = |s: usize| {
            &readers[s].layout().reference_parameters[shard_order[s].reference_parameters[p]]
        };
        param.values = gathered(refs, &param.values, at);
    }
    // Cases without references (measured recordings) refer to none.
    layout.reference_index = order
        .iter()
        .filter(|_| !refs.is_empty())
        .map(|&(_, s, row)| {
            let l = readers[s].layout();
            let id = l.reference_ids[l.reference_index[row] as usize];
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

/// Writes the merged file into the output's partial file, the references and cases
/// copied from the shards, and renames it to `output` when complete.
fn write_merged(
    output: &Path,
    shards: &[PathBuf],
    readers: &[StudyReader],
    (order, refs): (&[CasePlace], &[ReferencePlace]),
    shard_order: &[Order],
    layout: &Layout,
) -> Result<(), OutputError> {
    let (_, partial) = side_paths(output);
    ensure(!partial.exists(), || {
        format!(
            "{} is in the way: the merge writes there, and studyrun removes only its own \
             files; move or remove it yourself",
            partial.display()
        )
    })?;
    let to_partial = OutputError::file(&partial);
    let mut writer = StudyWriter::create(&partial, layout).map_err(OutputError::file(&partial))?;
    let mut unfinished = RemoveOnDrop(Some(&partial));
    for (k, &(_, s, src)) in refs.iter().enumerate() {
        let series = readers[s]
            .read_reference(src)
            .map_err(OutputError::file(&shards[s]))?;
        let series: Vec<&[f64]> = shard_order[s]
            .reference_series
            .iter()
            .map(|&i| series[i].as_slice())
            .collect();
        writer
            .write_reference(k, &series)
            .map_err(OutputError::file(&partial))?;
    }
    for (row, &(_, s, src)) in order.iter().enumerate() {
        let c = readers[s]
            .read_case(src)
            .map_err(OutputError::file(&shards[s]))?;
        let o = &shard_order[s];
        let series: Vec<&[f64]> = o.series.iter().map(|&i| c.series[i].as_slice()).collect();
        let spectra: Vec<&[f64]> = o.spectra.iter().map(|&i| c.spectra[i].as_slice()).collect();
        let mut metrics: Vec<f64> = o.metrics.iter().map(|&i| c.metrics[i]).collect();
        let (n_scalar, n_rep) = (o.metrics.len(), layout.replicates.len());
        for &i in &o.replicate_metrics {
            let at = n_scalar + i * n_rep;
            metrics.extend_from_slice(&c.metrics[at..at + n_rep]);
        }
        let n_rev = layout.revolutions.len();
        let after_replicates = n_scalar + o.replicate_metrics.len() * n_rep;
        for &i in &o.revolution_metrics {
            let at = after_replicates + i * n_rev;
            metrics.extend_from_slice(&c.metrics[at..at + n_rev]);
        }
        let n_ord = layout.orders.len();
        let after_revolutions = after_replicates + o.revolution_metrics.len() * n_rev;
        for &i in &o.order_spectra {
            let at = after_revolutions + i * n_ord;
            metrics.extend_from_slice(&c.metrics[at..at + n_ord]);
        }
        writer
            .write_case(
                row,
                &CaseRecord {
                    series: &series,
                    spectra: &spectra,
                    metrics: &metrics,
                    status: c.status,
                    message: &c.message,
                    replicate_messages: &c.replicate_messages,
                },
            )
            .map_err(OutputError::file(&partial))?;
    }
    writer.finish().map_err(to_partial)?;
    super::rename_durably(&partial, output).map_err(OutputError::io(
        format!("rename {} to", partial.display()),
        output,
    ))?;
    unfinished.0 = None;
    Ok(())
}

/// The merge's partial file, removed when the merge stops before renaming it.
struct RemoveOnDrop<'a>(Option<&'a Path>);

impl Drop for RemoveOnDrop<'_> {
    fn drop(&mut self) {
        if let Some(path) = self.0 {
            let _ = std::fs::remove_file(path);
        }
    }
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
