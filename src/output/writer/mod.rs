//! Creating a study file and writing cases into it, in any order.

use std::path::{Path, PathBuf};

use hdf5::plist::file_access::{FileAccessBuilder, MetadataCacheConfig};
use hdf5::plist::file_create::{AttrCreationOrder, LinkCreationOrder};
use hdf5::types::{TypeDescriptor, VarLenUnicode};
use hdf5::{Dataset, File, H5Type};

use super::attributes;
use super::datasets::{check_row, RowDatasets};
use super::dimension_scales::{attach_scale, set_scale};
use super::direct_chunk::{chunked_by_row, write_row_chunk};
use super::encode::{self, ChunkEncoder};
use super::error::{AtVariable, StudyFileError};
use super::layout::{
    Layout, Param, ParamValues, Role, Status, VarSpec, CASE, ERROR_MESSAGE, FORMAT_ATTR,
    FORMAT_VERSION, FREQUENCY, ORDER, REFERENCE, REFERENCE_INDEX, REPLICATE,
    REPLICATE_ERROR_MESSAGE, REPLICATE_STATUS, REVOLUTION, ROLE_ATTR, SK_FREQUENCY, STATUS, TIME,
    TIME_UNITS, VARIABLES_DIGEST_ATTR,
};
use super::reader::{read_layout, StudyReader};
use super::reserve::Reservation;
use super::text;
use super::writeback::Writeback;

mod create;
mod parameters;
mod scalars;

pub(super) use create::bounded_metadata_cache;
use create::*;
use parameters::Unfilled;
use scalars::Scalars;
pub(super) use scalars::WINDOW_VALUES;

/// One finished (or failed) case, borrowed from the caller.
///
/// An empty `series`, `spectra` or `metrics` list leaves those variables as they are
/// (NaN in a new file), e.g. for a failed case; a non-empty one must hold every
/// variable of the layout, in layout order, each of the dimension's length.
///
/// `Row` is `[f64]` for values ([`CaseRecord`], [`StudyWriter::write_case`]) or `[u8]`
/// for rows already encoded as stored chunks by a [`ChunkEncoder`] of the file's
/// storage ([`EncodedRecord`], [`StudyWriter::write_encoded`]).
#[derive(Debug)]
pub struct Record<'a, Row: ?Sized> {
    /// One row per [`Layout::series`], `times.len()` values each (their units).
    pub series: &'a [&'a Row],
    /// One row per [`Layout::spectra`], `frequencies.len()` values each, then one
    /// per [`Layout::kurtosis`], `sk_frequencies.len()` values each
    /// ([`Layout::spectrum_rows`]).
    pub spectra: &'a [&'a Row],
    /// One value per [`Layout::metrics`], then, per
    /// [`Layout::replicate_metrics`], one per replicate, then, per
    /// [`Layout::revolution_metrics`], one per revolution, then, per
    /// [`Layout::order_spectra`], one per order
    /// ([`Layout::n_metric_values`] in all).
    pub metrics: &'a [f64],
    /// The case's state.
    pub status: Status,
    /// Why it failed; empty for a successful case. NUL bytes are stored as U+FFFD.
    pub message: &'a str,
    /// In a file with replicates, for a successful case: why each replicate failed,
    /// one per [`Layout::replicates`] entry, empty where it did not (`replicate_status`
    /// says ok or failed from it). Empty otherwise: a failed case's replicate 0 has
    /// its `message`, and its perturbed replicates stay pending (they did not run).
    pub replicate_messages: &'a [String],
}

impl<Row: ?Sized> Clone for Record<'_, Row> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<Row: ?Sized> Copy for Record<'_, Row> {}

/// A case whose series and spectra are values (f64, in their units).
pub type CaseRecord<'a> = Record<'a, [f64]>;

/// A case whose series and spectra are stored chunk bytes made by
/// [`ChunkEncoder::encode`] for the file's [`Storage`](super::Storage), e.g. on a
/// worker thread.
pub type EncodedRecord<'a> = Record<'a, [u8]>;

/// A row the writer accepts: values, or the bytes of a stored chunk.
trait Row {
    /// Why the row cannot be a row of `len` elements stored as `encoder` stores them.
    fn misfit(&self, len: usize, encoder: &ChunkEncoder) -> Option<String>;
}

impl Row for [f64] {
    fn misfit(&self, len: usize, _: &ChunkEncoder) -> Option<String> {
        (self.len() != len).then(|| format!("{} values, the dimension has {len}", self.len()))
    }
}

impl Row for [u8] {
    fn misfit(&self, len: usize, encoder: &ChunkEncoder) -> Option<String> {
        let storage = encoder.storage();
        // The row's bytes (unfiltered) and the Fletcher-32 checksum.
        let raw = len * if storage.float32 { 4 } else { 8 } + 4;
        if storage.deflate_level == 0 && self.len() != raw {
            Some(format!(
                "an unfiltered chunk of {} bytes, the row and its checksum have {raw}",
                self.len()
            ))
        } else if storage.deflate_level > 0 && self.is_empty() {
            Some("an empty chunk, a deflated row is never empty".to_owned())
        } else {
            None
        }
    }
}

/// Writes a study file: [`StudyWriter::create`] lays out every variable and writes
/// coordinates, parameters and attributes; [`StudyWriter::write_case`],
/// [`StudyWriter::write_encoded`] and [`StudyWriter::write_reference`] fill rows in any
/// order. Rows never written keep NaN (series, spectra, metrics), status 0 (pending)
/// and an empty message.
///
/// Series, spectra and reference series are written with HDF5's direct chunk write:
/// a row is one chunk, encoded (float32 conversion, shuffle, deflate) by a
/// [`ChunkEncoder`], here or by the caller, and copied into the file as it is. The
/// per-case metrics are held until a window of them is full, then written in runs of
/// consecutive rows; statuses (a byte per case) and the non-empty messages are
/// written by [`StudyWriter::flush`] and [`StudyWriter::finish`] (or, best effort,
/// when the writer is dropped): a file whose writer never flushed shows every case
/// pending (see `writer::scalars`).
///
/// HDF5's metadata cache is bounded to 512 KiB, so that memory does not grow with
/// the number of chunks (the chunk index's B-tree nodes are several
/// times larger in memory than the cache counts them).
pub struct StudyWriter {
    path: PathBuf,
    file: File,
    layout: Layout,
    rows: RowDatasets,
    /// Encodes rows handed over as values.
    encoder: ChunkEncoder,
    /// The chunk being written from values, reused.
    chunk: Vec<u8>,
    scalars: Scalars,
    /// Disk blocks reserved for the chunks [`StudyWriter::write_encoded`] appends.
    reservation: Reservation,
    /// The write-out of those chunks, started as they are written.
    writeback: Writeback,
    /// The parameter rows written so far of a file made by
    /// [`StudyWriter::create_unfilled`]; none for any other.
    unfilled: Option<Unfilled>,
}

/// Upper bound of HDF5's metadata cache for a written file (bytes, as HDF5 counts
/// entries: their size on disk).
const METADATA_CACHE_BYTES: usize = 512 * 1024;

/// Writes `texts` into the string variable `ds` whole, with their digest.
pub(super) fn write_strings(ds: &Dataset, texts: &[String]) -> hdf5::Result<()> {
    let values = texts
        .iter()
        .map(|m| attributes::vlen(m))
        .collect::<hdf5::Result<Vec<_>>>()?;
    ds.write_raw(&values)?;
    text::write_digest(ds, text::DIGEST_ATTR, texts)
}

impl std::fmt::Debug for StudyWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StudyWriter")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl StudyWriter {
    /// Creates (or replaces) the study file at `path` with `layout`: every variable,
    /// dimension scale and attribute, and the values known now (coordinates,
    /// parameters, `reference_index`).
    pub fn create(path: impl AsRef<Path>, layout: &Layout) -> Result<Self, StudyFileError> {
        Self::create_as(path.as_ref(), layout, false)
    }

    /// Creates the study file at `path` like [`StudyWriter::create`], except that
    /// the parameter and reference parameter variables are left unwritten: the
    /// parameters of `layout` hold no values (their kind is the variable's type), and
    /// [`StudyWriter::write_parameter_rows`] writes them a block of rows at a time,
    /// so that a caller with many cases never holds them whole.
    pub fn create_unfilled(
        path: impl AsRef<Path>,
        layout: &Layout,
    ) -> Result<Self, StudyFileError> {
        Self::create_as(path.as_ref(), layout, true)
    }

    /// [`StudyWriter::create`], or [`StudyWriter::create_unfilled`] when `unfilled`.
    fn create_as(path: &Path, layout: &Layout, unfilled: bool) -> Result<Self, StudyFileError> {
        let path = path.to_owned();
        layout
            .validate_as(unfilled)
            .map_err(|reason| StudyFileError::Layout {
                path: path.clone(),
                reason,
            })?;
        let file = File::with_options()
            .with_fapl(file_access)
            .with_fcpl(|p| {
                p.link_creation_order(LinkCreationOrder::Indexed)
                    .attr_creation_order(AttrCreationOrder::Indexed)
            })
            .create(&path)
            .at(&path, "/")?;
        Creator {
            path: &path,
            file: &file,
            layout,
            unfilled,
        }
        .build()?;
        file.flush().at(&path, "/")?;
        let rows = RowDatasets::open(&file, layout, &path)?;
        let mut writer = Self::from_parts(path, file, layout.clone(), rows)?;
        writer.unfilled = unfilled.then(|| Unfilled::new(layout));
        Ok(writer)
    }

    /// Writes `values` into the next rows of parameter `index` of
    /// [`Layout::parameters`] (of [`Layout::reference_parameters`] when `reference`)
    /// of a file made by [`StudyWriter::create_unfilled`]: each parameter's blocks
    /// follow one another from row 0, and [`StudyWriter::finish`] refuses a file with
    /// a row of a parameter not written.
    pub fn write_parameter_rows(
        &mut self,
        reference: bool,
        index: usize,
        values: &ParamValues,
    ) -> Result<(), StudyFileError> {
        let Some(unfilled) = &mut self.unfilled else {
            return Err(self.record_error(
                "parameters",
                "the file was made with its parameters written".to_owned(),
            ));
        };
        let file = (&self.file, self.path.as_path(), &self.layout);
        unfilled.write(file, reference, index, values)
    }

    /// Opens an existing study file to write more rows into it (to resume a study).
    /// Its layout is read back from the file; see [`StudyWriter::layout`]. Like
    /// [`StudyReader::open`], a damaged file is an error, not a crash (its reads are
    /// checked in a child process first).
    pub fn open(path: impl AsRef<Path>) -> Result<Self, StudyFileError> {
        drop(StudyReader::open(path.as_ref())?);
        let path = path.as_ref().to_owned();
        let file = File::with_options()
            .with_fapl(file_access)
            .open_rw(&path)
            .at(&path, "/")?;
        let layout = read_layout(&file, &path)?;
        let rows = RowDatasets::open(&file, &layout, &path)?;
        Self::from_parts(path, file, layout, rows)
    }

    /// Checks that every array is chunked one row per chunk (direct chunk writes
    /// depend on it) and assembles the writer.
    fn from_parts(
        path: PathBuf,
        file: File,
        layout: Layout,
        rows: RowDatasets,
    ) -> Result<Self, StudyFileError> {
        let arrays = rows
            .series
            .iter()
            .zip(&layout.series)
            .chain(rows.spectra.iter().zip(&layout.spectra))
            .chain(rows.kurtosis.iter().zip(&layout.kurtosis))
            .chain(rows.reference_series.iter().zip(&layout.reference_series));
        let filters = encode::filters(layout.storage);
        for (ds, spec) in arrays {
            if !chunked_by_row(ds) || ds.filters() != filters {
                return Err(StudyFileError::Format {
                    path,
                    variable: spec.name.clone(),
                    reason: format!(
                        "chunks {:?} with the filters {:?}, not one row per chunk with {filters:?}",
                        ds.chunk(),
                        ds.filters()
                    ),
                });
            }
        }
        let scalars = Scalars::read(&rows, &layout, &path)?;
        Ok(Self {
            reservation: Reservation::new(&path),
            writeback: Writeback::new(&path),
            path,
            file,
            encoder: ChunkEncoder::new(layout.storage),
            layout,
            rows,
            chunk: Vec::new(),
            scalars,
            unfilled: None,
        })
    }

    /// The file's layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `record` into row `row` of every `[case, ...]` variable (`row` indexes
    /// [`Layout::case_ids`]), encoding its series and spectra here. Everything is
    /// checked before anything is written; the scalars reach the file at the next
    /// flush, so a case interrupted mid-write stays pending.
    pub fn write_case(
        &mut self,
        row: usize,
        record: &CaseRecord<'_>,
    ) -> Result<(), StudyFileError> {
        self.check_case(row, record)?;
        let Self {
            path,
            layout,
            rows,
            encoder,
            chunk,
            ..
        } = self;
        for (values, ds, spec) in case_arrays(rows, layout, record) {
            chunk.clear();
            encoder.encode(values, chunk);
            write_row_chunk(ds, row, chunk).at(path, &spec.name)?;
        }
        self.scalars.set(row, record)?;
        Ok(())
    }

    /// Writes `record`, whose series and spectra are stored chunks made by a
    /// [`ChunkEncoder`] for this file's storage, into row `row` like
    /// [`StudyWriter::write_case`]: the chunks go into the file unchanged, into disk
    /// blocks reserved ahead of them (`fallocate` where the system has it), and their
    /// write-out to the disk started (`output::writeback`). Returns
    /// the file's length before they were written ([`StudyWriter::file_len`]): the
    /// chunks follow it, which is what a crash journal records to find them again.
    pub fn write_encoded(
        &mut self,
        row: usize,
        record: &EncodedRecord<'_>,
    ) -> Result<u64, StudyFileError> {
        self.check_case(row, record)?;
        let before = self.file_len();
        let bytes = record.series.iter().chain(record.spectra).map(|c| c.len());
        self.reservation.ahead(before, bytes.sum::<usize>() as u64);
        for (chunk, ds, spec) in case_arrays(&self.rows, &self.layout, record) {
            write_row_chunk(ds, row, chunk).at(&self.path, &spec.name)?;
        }
        self.scalars.set(row, record)?;
        self.writeback.start(before, self.file_len() - before);
        Ok(before)
    }

    /// The file's size (bytes: HDF5's end of allocated space, or the end of the file
    /// if that is further). A chunk [`StudyWriter::write_encoded`] writes next lies
    /// after it, possibly after some metadata: HDF5 writes a chunk's raw bytes through
    /// to the file at once, in space allocated at the end of the file (small-data
    /// aggregation is off, see `file_access`). What a crash journal records to find a
    /// case's chunks again.
    pub fn file_len(&self) -> u64 {
        self.file.size()
    }

    /// Checks a record against the layout before anything of it is written.
    fn check_case<R: Row + ?Sized>(
        &self,
        row: usize,
        record: &Record<'_, R>,
    ) -> Result<(), StudyFileError> {
        check_row(&self.path, CASE, row, self.layout.n_cases())?;
        let n_time = self.layout.times.len();
        let series = self.layout.series.iter().map(|s| (s, n_time));
        self.check_rows("series", series, record.series)?;
        let spectra: Vec<_> = self.layout.spectrum_rows().collect();
        self.check_rows("spectra", spectra.into_iter(), record.spectra)?;
        let n_values = self.layout.n_metric_values();
        if !record.metrics.is_empty() && record.metrics.len() != n_values {
            return Err(self.record_error(
                "metrics",
                format!(
                    "{} values for {} metrics, {} replicate metrics x {} replicates, \
                     {} revolution metrics x {} revolutions and {} order spectra x {} orders",
                    record.metrics.len(),
                    self.layout.metrics.len(),
                    self.layout.replicate_metrics.len(),
                    self.layout.replicates.len(),
                    self.layout.revolution_metrics.len(),
                    self.layout.revolutions.len(),
                    self.layout.order_spectra.len(),
                    self.layout.orders.len(),
                ),
            ));
        }
        let n_replicates = self.layout.replicates.len();
        let replicates = record.replicate_messages.len();
        if replicates != 0 && (replicates != n_replicates || record.status != Status::Ok) {
            return Err(self.record_error(
                "replicate_messages",
                format!(
                    "{replicates} messages for a case of status {:?} with {n_replicates} \
                     replicates: one per replicate of an ok case, or none",
                    record.status
                ),
            ));
        }
        Ok(())
    }

    /// Writes row `row` of every `[reference, time]` variable: one slice per
    /// [`Layout::reference_series`], `times.len()` values each.
    pub fn write_reference(&mut self, row: usize, series: &[&[f64]]) -> Result<(), StudyFileError> {
        check_row(&self.path, REFERENCE, row, self.layout.n_references())?;
        let n_time = self.layout.times.len();
        if series.len() != self.layout.reference_series.len() {
            return Err(self.record_error(
                "reference_series",
                format!(
                    "{} series for {} reference series variables",
                    series.len(),
                    self.layout.reference_series.len()
                ),
            ));
        }
        let specs = self.layout.reference_series.iter().map(|s| (s, n_time));
        self.check_rows("reference_series", specs, series)?;
        for (i, values) in series.iter().enumerate() {
            let (ds, name) = (
                &self.rows.reference_series[i],
                &self.layout.reference_series[i].name,
            );
            self.chunk.clear();
            self.encoder.encode(values, &mut self.chunk);
            write_row_chunk(ds, row, &self.chunk).at(&self.path, name)?;
        }
        Ok(())
    }

    /// Writes the metric rows held now, in runs of consecutive rows; the statuses and
    /// messages wait for the next flush (a text variable rewritten takes new space in
    /// the file each time).
    pub(in crate::output) fn write_held_metrics(&mut self) -> Result<(), StudyFileError> {
        self.scalars.write_metrics()
    }

    /// Writes the per-case scalars and flushes everything written so far to disk.
    pub fn flush(&mut self) -> Result<(), StudyFileError> {
        self.scalars.write()?;
        self.file.flush().at(&self.path, "/")
    }

    /// Flushes and closes the file, reporting errors that dropping would hide, then
    /// releases the disk blocks reserved past its end.
    pub fn finish(mut self) -> Result<(), StudyFileError> {
        if let Some(unfilled) = &self.unfilled {
            unfilled.check_complete(&self.layout, &self.path)?;
        }
        self.flush()?;
        let Self {
            path,
            file,
            rows,
            scalars,
            reservation,
            ..
        } = self;
        drop(scalars);
        drop(rows);
        file.close().at(&path, "/")?;
        drop(reservation);
        Ok(())
    }

    /// Checks a record's list of rows against the layout's variables: empty, or one
    /// row of `len` elements per variable.
    fn check_rows<'s, R: Row + ?Sized>(
        &self,
        group: &str,
        specs: impl ExactSizeIterator<Item = (&'s VarSpec, usize)>,
        values: &[&R],
    ) -> Result<(), StudyFileError> {
        if values.is_empty() {
            return Ok(());
        }
        if values.len() != specs.len() {
            return Err(self.record_error(
                group,
                format!("{} slices for {} variables", values.len(), specs.len()),
            ));
        }
        for ((spec, len), v) in specs.zip(values) {
            if let Some(reason) = v.misfit(len, &self.encoder) {
                return Err(self.record_error(&spec.name, reason));
            }
        }
        Ok(())
    }

    fn record_error(&self, variable: &str, reason: String) -> StudyFileError {
        StudyFileError::Record {
            path: self.path.clone(),
            variable: variable.to_owned(),
            reason,
        }
    }
}

/// A record's series then spectra rows, each with its dataset and variable.
fn case_arrays<'a, R: ?Sized>(
    rows: &'a RowDatasets,
    layout: &'a Layout,
    record: &'a Record<'_, R>,
) -> impl Iterator<Item = (&'a R, &'a Dataset, &'a VarSpec)> {
    let series = record.series.iter().zip(&rows.series).zip(&layout.series);
    let spectra = record
        .spectra
        .iter()
        .zip(rows.spectra.iter().chain(&rows.kurtosis))
        .zip(layout.spectra.iter().chain(&layout.kurtosis));
    series
        .chain(spectra)
        .map(|((values, ds), spec)| (&**values, ds, spec))
}
