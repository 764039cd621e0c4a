//! The per-case scalars of a study file being written: metrics, statuses and messages.
//!
//! Memory stays flat in the number of cases: metric rows (the `[case]` metrics and the
//! `[case, replicate]`, `[case, revolution]` and `[case, order]` arrays) are held only
//! until about [`WINDOW_VALUES`] values wait, then written in runs of consecutive
//! rows; statuses are one byte per case, and only non-empty messages are held. The
//! statuses and messages reach the file at [`Scalars::write`] (the writer's flush), so
//! a file whose writer never flushed shows every case pending.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use hdf5::Dataset;
use ndarray::ArrayView2;

use super::super::attributes;
use super::super::datasets::RowDatasets;
use super::super::error::{AtVariable, StudyFileError};
use super::super::layout::{
    Layout, Status, ERROR_MESSAGE, REPLICATE_ERROR_MESSAGE, REPLICATE_STATUS, STATUS,
};
use super::super::reader::read_messages;
use super::super::text;
use super::Record;

/// Metric values held before they are written (8 bytes each: 8 MiB).
pub(in crate::output) const WINDOW_VALUES: usize = 1 << 20;

/// Strings written (and digested) per block when a message variable is written.
const STRING_BLOCK: usize = 1 << 16;

/// A message variable, `[case]` or `[case, replicate]`: its dataset, its rows and
/// values per row, and its non-empty messages by row-major index.
struct Messages {
    ds: Dataset,
    rows: usize,
    width: usize,
    texts: BTreeMap<usize, String>,
}

impl Messages {
    /// The messages `ds` holds now (`rows` × `width` of them), keeping the non-empty
    /// ones.
    fn read(ds: &Dataset, rows: usize, width: usize, path: &Path) -> Result<Self, StudyFileError> {
        let all = read_messages(ds, rows * width, path)?;
        let texts = all
            .into_iter()
            .enumerate()
            .filter(|(_, m)| !m.is_empty())
            .collect();
        Ok(Self {
            ds: ds.clone(),
            rows,
            width,
            texts,
        })
    }

    /// Sets message `at` (row-major; NUL, which HDF5 strings cannot hold, as U+FFFD).
    fn set(&mut self, at: usize, text: &str) {
        if text.is_empty() {
            self.texts.remove(&at);
        } else {
            self.texts.insert(at, text.replace('\0', "\u{FFFD}"));
        }
    }

    /// Writes every message, whole rows of about [`STRING_BLOCK`] at a time, then
    /// their digest.
    fn write(&self) -> hdf5::Result<()> {
        let per_block = (STRING_BLOCK / self.width.max(1)).max(1);
        let mut crc = 0;
        let mut block = Vec::new();
        for start in (0..self.rows).step_by(per_block) {
            let end = (start + per_block).min(self.rows);
            block.clear();
            for at in start * self.width..end * self.width {
                let text = self.texts.get(&at).map_or("", String::as_str);
                crc = text::digest_continue(crc, text);
                block.push(attributes::vlen(text)?);
            }
            if self.ds.ndim() == 1 {
                self.ds.write_slice(&block[..], start..end)?;
            } else {
                let view = ArrayView2::from_shape((end - start, self.width), &block[..])
                    .map_err(|e| hdf5::Error::from(e.to_string()))?;
                self.ds.write_slice(view, (start..end, ..))?;
            }
        }
        text::write_digest_value(&self.ds, text::DIGEST_ATTR, crc)
    }
}

/// `replicate_status` and `replicate_error_message`: codes row-major, and the number
/// of replicates.
struct ReplicateScalars {
    status: (Dataset, Vec<i8>),
    messages: Messages,
    width: usize,
}

/// The `[case]` scalars and `[case, replicate]`, `[case, revolution]` and
/// `[case, order]` metric arrays of a file being written (see the module doc).
pub(super) struct Scalars {
    path: PathBuf,
    /// Per metric, then per replicate, revolution and order metric: its dataset and
    /// the values per case (1, or the number of replicates, revolutions or orders).
    metrics: Vec<(Dataset, usize)>,
    /// Rows set and not yet written: the row's values laid out as
    /// [`Record::metrics`].
    pending: BTreeMap<usize, Vec<f64>>,
    pending_values: usize,
    status: (Dataset, Vec<i8>),
    messages: Messages,
    replicates: Option<ReplicateScalars>,
    /// Statuses or messages changed since the last write.
    dirty: bool,
}

impl Scalars {
    /// The scalars of the file whose per-row datasets are `rows`: its statuses and
    /// messages as it holds them now (pending and empty in a new file).
    pub(super) fn read(
        rows: &RowDatasets,
        layout: &Layout,
        path: &Path,
    ) -> Result<Self, StudyFileError> {
        let n_replicates = layout.replicates.len();
        let widths = [
            (&rows.metrics, 1),
            (&rows.replicate_metrics, n_replicates),
            (&rows.revolution_metrics, layout.revolutions.len()),
            (&rows.order_spectra, layout.orders.len()),
        ];
        let metrics = widths
            .into_iter()
            .flat_map(|(datasets, width)| datasets.iter().map(move |ds| (ds.clone(), width)))
            .collect();
        let status = rows.status.read_raw::<i8>().at(path, STATUS)?;
        let messages = Messages::read(&rows.error_message, layout.n_cases(), 1, path)?;
        let replicates = match &rows.replicates {
            Some((status, messages)) => Some(ReplicateScalars {
                status: (
                    status.clone(),
                    status.read_raw::<i8>().at(path, REPLICATE_STATUS)?,
                ),
                messages: Messages::read(messages, layout.n_cases(), n_replicates, path)?,
                width: n_replicates,
            }),
            None => None,
        };
        Ok(Self {
            path: path.to_owned(),
            metrics,
            pending: BTreeMap::new(),
            pending_values: 0,
            status: (rows.status.clone(), status),
            messages,
            replicates,
            dirty: false,
        })
    }

    /// Records row `row`'s metrics (if any, laid out as [`Record::metrics`]), status
    /// and messages; writes the metric rows held once they reach [`WINDOW_VALUES`].
    pub(super) fn set<R: ?Sized>(
        &mut self,
        row: usize,
        record: &Record<'_, R>,
    ) -> Result<(), StudyFileError> {
        let (metrics, status, message) = (record.metrics, record.status, record.message);
        if !metrics.is_empty() {
            self.pending_values += metrics.len();
            if let Some(old) = self.pending.insert(row, metrics.to_vec()) {
                self.pending_values -= old.len();
            }
        }
        self.status.1[row] = status.code();
        self.messages.set(row, message);
        if let Some(r) = &mut self.replicates {
            let width = r.width;
            for k in 0..width {
                let (state, text) = match status {
                    Status::Ok => match record.replicate_messages.get(k) {
                        Some(m) if !m.is_empty() => (Status::Failed, m.as_str()),
                        _ => (Status::Ok, ""),
                    },
                    Status::Failed if k == 0 => (Status::Failed, message),
                    _ => (Status::Pending, ""),
                };
                r.status.1[row * width + k] = state.code();
                r.messages.set(row * width + k, text);
            }
        }
        self.dirty = true;
        if self.pending_values >= WINDOW_VALUES {
            self.write_metrics()?;
        }
        Ok(())
    }

    /// Writes the metric rows held, one run of consecutive rows at a time.
    pub(super) fn write_metrics(&mut self) -> Result<(), StudyFileError> {
        let pending = std::mem::take(&mut self.pending);
        self.pending_values = 0;
        let mut run: Vec<(usize, Vec<f64>)> = Vec::new();
        for (row, values) in pending {
            if run.last().is_some_and(|(last, _)| last + 1 != row) {
                self.write_run(&run)?;
                run.clear();
            }
            run.push((row, values));
        }
        if !run.is_empty() {
            self.write_run(&run)?;
        }
        Ok(())
    }

    /// Writes consecutive rows `run` (each row's values laid out as
    /// [`Record::metrics`]) into every metric dataset.
    fn write_run(&self, run: &[(usize, Vec<f64>)]) -> Result<(), StudyFileError> {
        let first = run[0].0;
        let rows = first..first + run.len();
        let mut at = 0;
        let mut block = Vec::new();
        for (ds, width) in &self.metrics {
            block.clear();
            for (_, values) in run {
                block.extend_from_slice(&values[at..at + width]);
            }
            at += width;
            let written = if ds.ndim() == 1 {
                ds.write_slice(&block[..], rows.clone())
            } else {
                ArrayView2::from_shape((run.len(), *width), &block)
                    .map_err(|e| hdf5::Error::from(e.to_string()))
                    .and_then(|view| ds.write_slice(view, (rows.clone(), ..)))
            };
            written.at(&self.path, &ds.name())?;
        }
        Ok(())
    }

    /// Writes the metric rows held, and the statuses and messages if any changed
    /// (the statuses last).
    pub(super) fn write(&mut self) -> Result<(), StudyFileError> {
        self.write_metrics()?;
        if !self.dirty {
            return Ok(());
        }
        let path = &self.path;
        if let Some(r) = &self.replicates {
            r.messages.write().at(path, REPLICATE_ERROR_MESSAGE)?;
            r.status
                .0
                .write_raw(&r.status.1)
                .at(path, REPLICATE_STATUS)?;
        }
        self.messages.write().at(path, ERROR_MESSAGE)?;
        self.status.0.write_raw(&self.status.1).at(path, STATUS)?;
        self.dirty = false;
        Ok(())
    }
}

impl Drop for Scalars {
    /// Writes what [`StudyWriter::finish`](super::StudyWriter::finish) did not (errors
    /// cannot be reported here).
    fn drop(&mut self) {
        let _ = self.write();
    }
}
