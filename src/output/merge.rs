//! Combining shard files (`studyrun merge`) into one file equal to a single run.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use super::layout::shell_word;
use super::writer::WINDOW_VALUES;
use super::{history_line, side_paths, OutputLock, VarSpec};
use super::{CaseData, OutputError, StudyFileError};
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
///
/// One shard is open at a time, and the merged file is written a block of case rows
/// at a time (as many rows as fill the writer's 8 MiB window of metric values), its
/// parameters included: what is held for the whole merge is each case's and
/// reference's place and id (about 110 bytes per case), not their values.
pub fn merge(output: &Path, shards: &[PathBuf], force: bool) -> Result<usize, OutputError> {
    merge_in_blocks(output, shards, force, block_rows)
}

/// [`merge`], the merged file written in blocks of `rows(layout)` case rows.
fn merge_in_blocks(
    output: &Path,
    shards: &[PathBuf],
    force: bool,
    rows: fn(&Layout) -> usize,
) -> Result<usize, OutputError> {
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
    let (first, surveyed) = survey(shards)?;
    let (order, expected) = case_order(&first, &surveyed, shards)?;
    let refs = reference_places(&surveyed);
    let layout = merged_layout(
        &first,
        &surveyed,
        (&order, &refs),
        expected,
        (output, shards, force),
    );
    // The shards' ids are in the merged layout now: only their variables' order stays.
    let orders: Vec<Order> = surveyed.into_iter().map(|s| s.order).collect();
    let merged = Merged {
        shards,
        orders: &orders,
        order: &order,
        refs: &refs,
        layout: &layout,
        block_rows: rows(&layout),
    };
    merged.write(output)?;
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

/// What the merge keeps of a shard once it is checked and closed: its case ids, its
/// references' ids, each case's reference row, and where the first shard's
/// variables are in it.
struct Surveyed {
    case_ids: Vec<u64>,
    reference_ids: Vec<u64>,
    reference_index: Vec<u64>,
    order: Order,
}

/// The shards checked one at a time, each closed before the next is opened: none
/// with a pending case, all of one study and layout, every value read and its
/// checksums checked (which also checks that reading the cases later cannot crash).
/// Returns the first shard's layout without its cases (no ids, no parameter values)
/// and what the merge keeps of each shard.
fn survey(shards: &[PathBuf]) -> Result<(Layout, Vec<Surveyed>), OutputError> {
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
fn check_alike(
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
fn without_cases(l: &Layout) -> Layout {
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

/// Where a case of the merged file comes from: `(case id, shard, row)`.
type CasePlace = (u64, usize, usize);

/// `(reference id, shard, row)`: where a reference is read from.
type ReferencePlace = (u64, usize, usize);

/// `(id, shard, row)` of every id `ids` gives for each shard, sorted.
fn places(surveyed: &[Surveyed], ids: fn(&Surveyed) -> &[u64]) -> Vec<(u64, usize, usize)> {
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
fn reference_places(surveyed: &[Surveyed]) -> Vec<ReferencePlace> {
    let mut places = places(surveyed, |s| &s.reference_ids);
    places.dedup_by_key(|p| p.0);
    places
}

/// `(case id, shard, row)` of every case, sorted by id, and the study's case count
/// (the `study_cases` attribute of the first shard's `first`): refused unless the ids
/// are exactly `0..N-1`, each in one shard.
fn case_order(
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

/// Where each of the first shard's variables is in a shard.
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

impl Order {
    /// Where each variable of the first shard's `first` is in the shard of layout `l`.
    fn of(l: &Layout, first: &Layout) -> Self {
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
    }
}

/// The merged file's layout: the first shard's `first` (without cases), with every
/// case's ids and references in id order, every shard's references (`refs`) in id
/// order, the whole study's `file_cases`, no `shard`, and the merge's line on top of
/// `history`. Its parameters hold no values: [`Merged::write`] writes them.
fn merged_layout(
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

/// Case rows per block of the merged file: as many as fill the metric values the
/// writer holds before it writes them (`writer::WINDOW_VALUES`, 8 MiB), so that a
/// block's metric rows, gathered from every shard in turn, are written as one run of
/// consecutive rows; at least one.
fn block_rows(layout: &Layout) -> usize {
    (WINDOW_VALUES / layout.n_metric_values().max(1)).max(1)
}

/// The merged file being written: the checked shards and where their variables are,
/// where each case and reference comes from, and the merged layout.
struct Merged<'a> {
    shards: &'a [PathBuf],
    /// Where the merged file's variables are in each shard.
    orders: &'a [Order],
    order: &'a [CasePlace],
    refs: &'a [ReferencePlace],
    layout: &'a Layout,
    /// Case rows per block (at least one).
    block_rows: usize,
}

impl Merged<'_> {
    /// Writes the merged file into the output's partial file, a block of cases (with
    /// a share of the references) at a time, and renames it to `output` when
    /// complete.
    fn write(&self, output: &Path) -> Result<(), OutputError> {
        let (_, partial) = side_paths(output);
        ensure(!partial.exists(), || {
            format!(
                "{} is in the way: the merge writes there, and studyrun removes only its own \
                 files; move or remove it yourself",
                partial.display()
            )
        })?;
        let to_partial = OutputError::file(&partial);
        let mut writer = StudyWriter::create_unfilled(&partial, self.layout)
            .map_err(OutputError::file(&partial))?;
        let mut unfinished = RemoveOnDrop(Some(&partial));
        let (n_cases, n_refs) = (self.order.len(), self.refs.len());
        let blocks = n_cases.div_ceil(self.block_rows.max(1)).max(1);
        for b in 0..blocks {
            let cases = b * n_cases / blocks..(b + 1) * n_cases / blocks;
            let refs = b * n_refs / blocks..(b + 1) * n_refs / blocks;
            self.copy_block(&mut writer, (cases, refs), &partial)?;
            // The block's metric rows go into the file as consecutive runs.
            (writer.write_held_metrics()).map_err(OutputError::file(&partial))?;
        }
        writer.finish().map_err(to_partial)?;
        super::rename_durably(&partial, output).map_err(OutputError::io(
            format!("rename {} to", partial.display()),
            output,
        ))?;
        unfinished.0 = None;
        Ok(())
    }

    /// Copies the merged rows `cases` and reference rows `refs` from the shards, one
    /// shard open at a time (each was checked by [`survey`]), and writes their
    /// parameters.
    fn copy_block(
        &self,
        writer: &mut StudyWriter,
        (cases, refs): (Range<usize>, Range<usize>),
        partial: &Path,
    ) -> Result<(), OutputError> {
        let mut params = Gathered::new(self.layout, cases.len(), refs.len());
        let mut used = vec![false; self.shards.len()];
        for &(_, s, _) in self.order[cases.clone()]
            .iter()
            .chain(&self.refs[refs.clone()])
        {
            used[s] = true;
        }
        for (s, path) in self.shards.iter().enumerate().filter(|&(s, _)| used[s]) {
            let r = StudyReader::open_unchecked(path).map_err(OutputError::file(path))?;
            let o = &self.orders[s];
            for (k, src) in rows_of(s, &self.refs[refs.clone()], refs.start) {
                let series = r.read_reference(src).map_err(OutputError::file(path))?;
                let series: Vec<&[f64]> = (o.reference_series.iter())
                    .map(|&i| series[i].as_slice())
                    .collect();
                writer
                    .write_reference(k, &series)
                    .map_err(OutputError::file(partial))?;
                params.take(true, k - refs.start, r.layout(), o, src);
            }
            for (row, src) in rows_of(s, &self.order[cases.clone()], cases.start) {
                let c = r.read_case(src).map_err(OutputError::file(path))?;
                self.write_case(writer, row, &c, o, partial)?;
                params.take(false, row - cases.start, r.layout(), o, src);
            }
        }
        params.write(writer).map_err(OutputError::file(partial))
    }

    /// Writes case `c` of a shard whose variables are at `o` into row `row`.
    fn write_case(
        &self,
        writer: &mut StudyWriter,
        row: usize,
        c: &CaseData,
        o: &Order,
        partial: &Path,
    ) -> Result<(), OutputError> {
        let layout = self.layout;
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
        let record = CaseRecord {
            series: &series,
            spectra: &spectra,
            metrics: &metrics,
            status: c.status,
            message: &c.message,
            replicate_messages: &c.replicate_messages,
        };
        writer
            .write_case(row, &record)
            .map_err(OutputError::file(partial))
    }
}

/// `(merged row, row in the shard)` of the `places` that shard `s` holds, the first
/// of `places` being merged row `from`.
fn rows_of(
    s: usize,
    places: &[(u64, usize, usize)],
    from: usize,
) -> impl Iterator<Item = (usize, usize)> + '_ {
    (places.iter().enumerate())
        .filter(move |(_, &(_, shard, _))| shard == s)
        .map(move |(k, &(_, _, src))| (from + k, src))
}

/// The parameter values of a block of merged rows, gathered from the shards: per
/// parameter of the merged layout, then per reference parameter.
struct Gathered {
    cases: Vec<ParamValues>,
    references: Vec<ParamValues>,
}

impl Gathered {
    /// Room for `cases` case rows and `refs` reference rows of `layout`'s parameters
    /// (NaN and empty until taken).
    fn new(layout: &Layout, cases: usize, refs: usize) -> Self {
        let room = |params: &[Param], n: usize| {
            let kind = |p: &Param| match p.values {
                ParamValues::F64(_) => ParamValues::F64(vec![f64::NAN; n]),
                ParamValues::Str(_) => ParamValues::Str(vec![String::new(); n]),
            };
            params.iter().map(kind).collect()
        };
        Self {
            cases: room(&layout.parameters, cases),
            references: room(&layout.reference_parameters, refs),
        }
    }

    /// Takes row `src` of the parameters (the reference parameters when `reference`)
    /// of a shard of layout `l` whose variables are at `o` into position `at` of the
    /// block. A parameter of the other kind in the shard gives NaN or "".
    fn take(&mut self, reference: bool, at: usize, l: &Layout, o: &Order, src: usize) {
        let (block, params, positions) = if reference {
            (
                &mut self.references,
                &l.reference_parameters,
                &o.reference_parameters,
            )
        } else {
            (&mut self.cases, &l.parameters, &o.parameters)
        };
        for (values, &p) in block.iter_mut().zip(positions) {
            match (values, &params[p].values) {
                (ParamValues::F64(v), ParamValues::F64(from)) => v[at] = from[src],
                (ParamValues::Str(v), ParamValues::Str(from)) => v[at].clone_from(&from[src]),
                _ => {}
            }
        }
    }

    /// Writes the block's values into the next rows of each parameter.
    fn write(&self, writer: &mut StudyWriter) -> Result<(), StudyFileError> {
        for (reference, block) in [(false, &self.cases), (true, &self.references)] {
            for (p, values) in block.iter().enumerate() {
                writer.write_parameter_rows(reference, p, values)?;
            }
        }
        Ok(())
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{provenance, Storage};

    /// The layout of a file of cases `ids` of a 7-case study (`shard` "K/3" or ""),
    /// with a numeric and a text parameter, a spectrum, a metric and one reference
    /// per case parity.
    fn layout(ids: &[u64], shard: &str) -> Layout {
        let mut refs: Vec<u64> = ids.iter().map(|id| id % 2).collect();
        refs.sort_unstable();
        refs.dedup();
        let mut attributes = provenance();
        for (name, value) in [
            ("study_fingerprint", AttrValue::Str("f".into())),
            ("study_cases", AttrValue::I64(7)),
            ("file_cases", AttrValue::I64(ids.len() as i64)),
            ("shard", AttrValue::Str(shard.into())),
        ] {
            attributes.push((name.to_owned(), value));
        }
        let param = |name: &str, values| Param {
            spec: VarSpec::new(name, "1", name),
            values,
        };
        Layout {
            case_ids: ids.to_vec(),
            times: vec![0.0, 0.1],
            frequencies: vec![0.0, 5.0],
            spectra: vec![VarSpec::new("x_spectrum", "m", "amplitude of x")],
            metrics: vec![VarSpec::new("x_rms", "m", "rms of x")],
            parameters: vec![
                param(
                    "rpm",
                    ParamValues::F64(ids.iter().map(|&i| 100.0 * i as f64).collect()),
                ),
                param(
                    "label",
                    ParamValues::Str(ids.iter().map(|i| format!("c{i}")).collect()),
                ),
            ],
            reference_parameters: vec![param(
                "parity",
                ParamValues::Str(refs.iter().map(|r| format!("p{r}")).collect()),
            )],
            reference_series: vec![VarSpec::new("x_ideal", "m", "ideal x")],
            reference_index: ids
                .iter()
                .map(|id| refs.partition_point(|&r| r < id % 2) as u64)
                .collect(),
            reference_ids: refs,
            attributes,
            storage: Storage::default(),
            series: vec![],
            replicates: vec![],
            replicate_metrics: vec![],
            revolutions: vec![],
            revolution_metrics: vec![],
            orders: vec![],
            order_spectra: vec![],
            sk_frequencies: vec![],
            kurtosis: vec![],
        }
    }

    /// Writes the file of cases `ids` at `path`: case `i`'s spectrum and metric from
    /// `i`, case 5 failed.
    fn write(path: &Path, ids: &[u64], shard: &str) {
        let l = layout(ids, shard);
        let mut w = StudyWriter::create(path, &l).unwrap();
        for (row, &id) in ids.iter().enumerate() {
            let spectrum = [id as f64, -(id as f64)];
            let failed = id == 5;
            let record = CaseRecord {
                series: &[],
                spectra: &[&spectrum],
                metrics: &[0.5 * id as f64],
                status: if failed { Status::Failed } else { Status::Ok },
                message: if failed { "diverged" } else { "" },
                replicate_messages: &[],
            };
            w.write_case(row, &record).unwrap();
        }
        for (k, &r) in l.reference_ids.iter().enumerate() {
            w.write_reference(k, &[&[r as f64, 1.0]]).unwrap();
        }
        w.finish().unwrap();
    }

    #[test]
    fn a_merge_in_blocks_of_two_rows_equals_the_whole_file() {
        let dir = tempfile::tempdir().unwrap();
        let whole = dir.path().join("whole.h5");
        write(&whole, &[0, 1, 2, 3, 4, 5, 6], "");
        let mut shards = Vec::new();
        for k in 1..=3u64 {
            let path = dir.path().join(format!("part{k}.h5"));
            let ids: Vec<u64> = (0..7).filter(|id| id % 3 == k - 1).collect();
            write(&path, &ids, &format!("{k}/3"));
            shards.push(path);
        }
        shards.reverse();
        for (name, rows) in [
            ("two.h5", (|_| 2) as fn(&Layout) -> usize),
            ("one.h5", block_rows),
        ] {
            let merged = dir.path().join(name);
            assert_eq!(merge_in_blocks(&merged, &shards, false, rows).unwrap(), 7);
            let (a, b) = (
                StudyReader::open(&whole).unwrap(),
                StudyReader::open(&merged).unwrap(),
            );
            let (la, lb) = (a.layout(), b.layout());
            assert_eq!(la.case_ids, lb.case_ids, "{name}");
            assert_eq!(la.parameters, lb.parameters, "{name}");
            assert_eq!(la.reference_ids, lb.reference_ids, "{name}");
            assert_eq!(la.reference_parameters, lb.reference_parameters, "{name}");
            assert_eq!(la.reference_index, lb.reference_index, "{name}");
            for row in 0..7 {
                assert_eq!(
                    a.read_case(row).unwrap(),
                    b.read_case(row).unwrap(),
                    "{name} {row}"
                );
            }
            for k in 0..2 {
                assert_eq!(a.read_reference(k).unwrap(), b.read_reference(k).unwrap());
            }
            assert!(
                b.verify().unwrap().is_empty(),
                "{name}: every variable checksummed"
            );
        }
    }

    #[test]
    fn an_unfilled_file_takes_its_parameters_in_order_and_refuses_to_finish_without_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("unfilled.h5");
        let mut l = without_cases(&layout(&[0, 1, 2], ""));
        (l.case_ids, l.reference_ids, l.reference_index) = (vec![0, 1, 2], vec![0], vec![0; 3]);
        let mut w = StudyWriter::create_unfilled(&path, &l).unwrap();
        w.write_parameter_rows(false, 0, &ParamValues::F64(vec![1.0, 2.0]))
            .unwrap();
        let wrong_kind = w.write_parameter_rows(false, 1, &ParamValues::F64(vec![1.0]));
        assert!(wrong_kind
            .unwrap_err()
            .to_string()
            .contains("numbers for a text parameter"));
        let too_many = w.write_parameter_rows(false, 0, &ParamValues::F64(vec![3.0; 2]));
        assert!(too_many
            .unwrap_err()
            .to_string()
            .contains("rows 2..4, but the variable has 3"));
        let err = w.finish().unwrap_err().to_string();
        assert!(
            err.contains("rpm") && err.contains("2 of its 3 rows written"),
            "{err}"
        );
    }
}
