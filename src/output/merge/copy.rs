//! Writing the merged file a block of case rows at a time, from one shard open at a
//! time.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::super::datasets::READ_VALUES;
use super::super::writer::WINDOW_VALUES;
use super::super::{side_paths, CaseData, OutputError, StudyFileError};
use super::super::{CaseRecord, Layout, Param, ParamValues, StudyReader, StudyWriter};
use super::alike::Order;
use super::ensure;
use super::places::{CasePlace, ReferencePlace};

/// Case rows per block of the merged file: as many as fill the metric values the
/// writer holds before it writes them (`writer::WINDOW_VALUES`, 8 MiB), so that a
/// block's metric rows, gathered from every shard in turn, are written as one run of
/// consecutive rows; at least one.
pub(super) fn block_rows(layout: &Layout) -> usize {
    (WINDOW_VALUES / layout.n_metric_values().max(1)).max(1)
}

/// The merged file being written: the checked shards and where their variables are,
/// where each case and reference comes from, and the merged layout.
pub(super) struct Merged<'a> {
    pub(super) shards: &'a [PathBuf],
    /// Where the merged file's variables are in each shard.
    pub(super) orders: &'a [Order],
    pub(super) order: &'a [CasePlace],
    pub(super) refs: &'a [ReferencePlace],
    pub(super) layout: &'a Layout,
    /// Case rows per block (at least one).
    pub(super) block_rows: usize,
}

impl Merged<'_> {
    /// Writes the merged file into the output's partial file, a block of cases (with
    /// a share of the references) at a time, and renames it to `output` when
    /// complete.
    pub(super) fn write(&self, output: &Path) -> Result<(), OutputError> {
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
        super::super::rename_durably(&partial, output).map_err(OutputError::io(
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
            let rows: Vec<(usize, usize)> =
                rows_of(s, &self.order[cases.clone()], cases.start).collect();
            let per_read = (READ_VALUES / self.layout.case_values().max(1)).max(1);
            // Runs of consecutive rows of the shard, each read at once.
            let runs = rows.chunk_by(|a, b| b.1 == a.1 + 1);
            for run in runs.flat_map(|run| run.chunks(per_read)) {
                let src = run[0].1..run[run.len() - 1].1 + 1;
                let read = r.read_cases(src).map_err(OutputError::file(path))?;
                for (&(row, src), c) in run.iter().zip(&read) {
                    self.write_case(writer, row, c, o, partial)?;
                    params.take(false, row - cases.start, r.layout(), o, src);
                }
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
pub(super) fn rows_of(
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
pub(super) struct Gathered {
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
pub(super) struct RemoveOnDrop<'a>(Option<&'a Path>);

impl Drop for RemoveOnDrop<'_> {
    fn drop(&mut self) {
        if let Some(path) = self.0 {
            let _ = std::fs::remove_file(path);
        }
    }
}
