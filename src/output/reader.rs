//! Reading a study file back: its layout, and cases one row at a time.

use std::ops::Range;
use std::path::{Path, PathBuf};

use hdf5::filters::Filter;
use hdf5::types::TypeDescriptor;
use hdf5::{Dataset, File, IndexType, IterationOrder};
use ndarray::Array2;

use super::attributes;
use super::datasets::{check_row, read_blocks, RowDatasets, READ_VALUES};
use super::error::{AtVariable, StudyFileError};
use super::guard::{self, Checked};
use super::layout::{
    AttrValue, Layout, Param, ParamValues, Role, Status, Storage, VarSpec, CASE, FORMAT_ATTR,
    FORMAT_VERSION, FREQUENCY, ORDER, REFERENCE, REFERENCE_INDEX, REPLICATE, REPLICATE_STATUS,
    REVOLUTION, ROLE_ATTR, SK_FREQUENCY, STATUS, TIME, TIME_UNITS, VARIABLES_DIGEST_ATTR,
};
use super::structure;
use super::text::{self, Strings};
use crate::simulate::sample_time;

/// One case read back from a file (owned). Values stored as float32 are widened
/// exactly to f64; rows never written read as NaN with status pending.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseData {
    /// One vector per [`Layout::series`], `times.len()` values each.
    pub series: Vec<Vec<f64>>,
    /// One vector per [`Layout::spectra`], `frequencies.len()` values each, then one
    /// per [`Layout::kurtosis`], `sk_frequencies.len()` values each.
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`Layout::metrics`], then one per replicate for each of
    /// [`Layout::replicate_metrics`] and one per revolution for each of
    /// [`Layout::revolution_metrics`] (as [`Record::metrics`](super::Record::metrics)).
    pub metrics: Vec<f64>,
    /// The case's state.
    pub status: Status,
    /// Why it failed (empty otherwise).
    pub message: String,
    /// In a file with replicates, for an ok case: why each replicate failed, one per
    /// replicate, empty where it did not (as [`Record::replicate_messages`](super::Record::replicate_messages)).
    /// Empty otherwise.
    pub replicate_messages: Vec<String>,
}

/// Reads a study file written by [`StudyWriter`](super::StudyWriter), also after
/// netCDF tools (NCO, nccopy, xarray) rewrote it: see the module doc of
/// [`output`](super).
///
/// A damaged file gives an error, never a crash: [`StudyReader::open`] and
/// [`StudyReader::check_cases`] first do their reads in a child process (see
/// `output::guard`).
pub struct StudyReader {
    path: PathBuf,
    layout: Layout,
    rows: RowDatasets,
    /// `error_message`, read whole at open (it is small).
    messages: Vec<String>,
    /// `replicate_error_message`, row-major, read whole at open (empty without
    /// replicates).
    replicate_messages: Vec<String>,
    /// Kept open for the datasets' lifetime.
    file: File,
}

impl std::fmt::Debug for StudyReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StudyReader")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl StudyReader {
    /// Opens the study file at `path` read-only and reads its layout, the statuses
    /// and the error messages. What [`StudyReader::read_case`] and
    /// [`StudyReader::read_reference`] read later is not checked for crashes here:
    /// call [`StudyReader::check_cases`] before reading the cases of a file that may
    /// be damaged.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, StudyFileError> {
        let path = path.as_ref();
        let checked = guard::check(guard::deadline(path, false), path, || {
            Self::open_unchecked(path).and_then(|r| r.statuses().map(|_| ()))
        });
        if let Checked::Crashed(reason) = checked {
            return Err(damaged(path, reason));
        }
        Self::open_unchecked(path)
    }

    /// Reads every case and reference in a child process (see `output::guard`): an
    /// error if that crashes or does not end, so that reading them here cannot crash.
    /// Errors the reads themselves report are left for them.
    pub fn check_cases(&self) -> Result<(), StudyFileError> {
        self.check_reads().map(drop)
    }

    /// [`StudyReader::check_cases`], saying whether the child's reads also ended
    /// without an error ([`Checked::Passed`]).
    fn check_reads(&self) -> Result<Checked, StudyFileError> {
        let checked = guard::check(guard::deadline(&self.path, true), &self.path, || {
            // The child has closed the descriptors it inherited: it opens the file anew.
            Self::open_unchecked(&self.path)?.read_every_row()
        });
        match checked {
            Checked::Crashed(reason) => Err(damaged(&self.path, reason)),
            checked => Ok(checked),
        }
    }

    /// Reads every reference, then every case a block of rows at a time (about
    /// [`READ_VALUES`] values per read).
    fn read_every_row(&self) -> Result<(), StudyFileError> {
        (0..self.layout.n_references()).try_for_each(|k| self.read_reference(k).map(drop))?;
        let n = self.layout.n_cases();
        let per_read = (READ_VALUES / self.layout.case_values().max(1)).max(1);
        (0..n)
            .step_by(per_read)
            .try_for_each(|start| self.read_cases(start..(start + per_read).min(n)).map(drop))
    }

    /// Reads every value of the file's variables and so checks every checksum: the
    /// Fletcher-32 of every chunk (HDF5 checks it on reading) and the digest of every
    /// string variable (checked at open); then checks the chunk index holds every
    /// chunk the statuses say was written, each inside the file and none sharing
    /// another's bytes (`output::structure`). The values are read in a child process
    /// first ([`StudyReader::check_cases`]); only if its reads failed are they read
    /// again here, to report the error. Returns the variables that carry no checksum
    /// (a netCDF tool's rewrite may drop them): none in a file studyrun wrote.
    pub fn verify(&self) -> Result<Vec<String>, StudyFileError> {
        if self.check_reads()? != Checked::Passed {
            self.read_every_row()?;
        }
        structure::check_chunks(&self.file, &self.layout, &self.rows, &self.statuses()?)
            .map_err(|reason| damaged(&self.path, reason))?;
        let mut unchecked = Vec::new();
        for name in member_names(&self.file).at(&self.path, "/")? {
            let Ok(ds) = self.file.dataset(&name) else {
                continue;
            };
            text::check_attributes_digest(&ds).at(&self.path, &name)?;
            let descriptor = ds
                .dtype()
                .and_then(|t| t.to_descriptor())
                .map_err(|e| damaged(&self.path, format!("`{name}`: its datatype: {e}")))?;
            if matches!(
                descriptor,
                TypeDescriptor::Float(_) | TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_)
            ) {
                structure::check_numeric_type(&ds)
                    .map_err(|reason| damaged(&self.path, format!("`{name}`: {reason}")))?;
            }
            let string = matches!(
                descriptor,
                TypeDescriptor::VarLenUnicode | TypeDescriptor::VarLenAscii
            );
            let checked = if string {
                ds.attr_names()
                    .at(&self.path, &name)?
                    .iter()
                    .any(|a| a == text::DIGEST_ATTR)
            } else {
                ds.filters().contains(&Filter::Fletcher32)
            };
            if !checked {
                unchecked.push(name);
            }
        }
        Ok(unchecked)
    }

    /// [`StudyReader::open`] without the check in a child process.
    pub(super) fn open_unchecked(path: &Path) -> Result<Self, StudyFileError> {
        let file = open_hdf5(path)?;
        let path = path.to_owned();
        let layout = read_layout(&file, &path)?;
        let rows = RowDatasets::open(&file, &layout, &path)?;
        let messages = read_messages(&rows.error_message, layout.n_cases(), &path)?;
        let replicate_messages = match &rows.replicates {
            Some((_, ds)) => read_messages(ds, layout.n_cases() * layout.replicates.len(), &path)?,
            None => Vec::new(),
        };
        Ok(Self {
            path,
            layout,
            rows,
            messages,
            replicate_messages,
            file,
        })
    }

    /// The layout, rebuilt from the file: coordinates, variables in file order,
    /// parameter values, root attributes (in creation order) and storage. Equal to the
    /// layout the file was created with, except that storage reads as
    /// [`Storage::default`] when the file has no series, spectra or reference series.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The root attribute `name`, if the caller wrote one.
    pub fn attribute(&self, name: &str) -> Option<&AttrValue> {
        self.layout.attribute(name)
    }

    /// Reads row `row` of every `[case, ...]` variable (`row` indexes
    /// [`Layout::case_ids`]).
    pub fn read_case(&self, row: usize) -> Result<CaseData, StudyFileError> {
        check_row(&self.path, CASE, row, self.layout.n_cases())?;
        let mut case = self.read_cases(row..row + 1)?;
        Ok(case.pop().expect("one row read"))
    }

    /// Reads rows `rows` of every `[case, ...]` variable, one HDF5 read per variable,
    /// as [`StudyReader::read_case`] reads each of them.
    pub fn read_cases(&self, rows: Range<usize>) -> Result<Vec<CaseData>, StudyFileError> {
        match rows.clone().last() {
            Some(last) => check_row(&self.path, CASE, last, self.layout.n_cases())?,
            None => return Ok(Vec::new()),
        }
        let (l, d) = (&self.layout, &self.rows);
        let read = |datasets: &[Dataset], specs: &[VarSpec]| {
            read_blocks(datasets, specs, rows.clone(), &self.path)
        };
        let series = read(&d.series, &l.series)?;
        let mut spectra = read(&d.spectra, &l.spectra)?;
        spectra.extend(read(&d.kurtosis, &l.kurtosis)?);
        let mut metrics = read(&d.metrics, &l.metrics)?;
        metrics.extend(read(&d.replicate_metrics, &l.replicate_metrics)?);
        metrics.extend(read(&d.revolution_metrics, &l.revolution_metrics)?);
        metrics.extend(read(&d.order_spectra, &l.order_spectra)?);
        let codes = (d.status.read_slice_1d::<i8, _>(rows.clone())).at(&self.path, STATUS)?;
        let row_of = |blocks: &[Array2<f64>], k: usize| -> Vec<Vec<f64>> {
            blocks.iter().map(|b| b.row(k).to_vec()).collect()
        };
        rows.enumerate()
            .map(|(k, row)| {
                let status = self.status(codes[k])?;
                Ok(CaseData {
                    series: row_of(&series, k),
                    spectra: row_of(&spectra, k),
                    metrics: metrics.iter().flat_map(|b| b.row(k)).copied().collect(),
                    status,
                    message: self.messages[row].clone(),
                    replicate_messages: match status {
                        Status::Ok => self.replicate_messages(row)?.to_vec(),
                        _ => Vec::new(),
                    },
                })
            })
            .collect()
    }

    /// Reads row `row` of every `[reference, time]` variable, one vector per
    /// [`Layout::reference_series`].
    pub fn read_reference(&self, row: usize) -> Result<Vec<Vec<f64>>, StudyFileError> {
        check_row(&self.path, REFERENCE, row, self.layout.n_references())?;
        let blocks = read_blocks(
            &self.rows.reference_series,
            &self.layout.reference_series,
            row..row + 1,
            &self.path,
        )?;
        Ok(blocks
            .into_iter()
            .map(|b| b.into_raw_vec_and_offset().0)
            .collect())
    }

    /// Why case row `row` failed (empty if it did not).
    pub fn message(&self, row: usize) -> Result<&str, StudyFileError> {
        check_row(&self.path, CASE, row, self.layout.n_cases())?;
        Ok(&self.messages[row])
    }

    /// Why each replicate of case row `row` failed, one per replicate (empty where it
    /// did not; none in a file without replicates). A failed case's replicate 0 has
    /// the case's message here, its perturbed replicates (not run) none.
    pub fn replicate_messages(&self, row: usize) -> Result<&[String], StudyFileError> {
        check_row(&self.path, CASE, row, self.layout.n_cases())?;
        let width = self.layout.replicates.len();
        Ok(self
            .replicate_messages
            .get(row * width..(row + 1) * width)
            .unwrap_or_default())
    }

    /// The number of replicates of ok cases that failed (`replicate_status` failed).
    pub fn failed_replicates(&self) -> Result<usize, StudyFileError> {
        let Some((ds, _)) = &self.rows.replicates else {
            return Ok(0);
        };
        let codes = ds.read_raw::<i8>().at(&self.path, REPLICATE_STATUS)?;
        let width = self.layout.replicates.len();
        let statuses = self.rows.status.read_raw::<i8>().at(&self.path, STATUS)?;
        Ok(codes
            .chunks(width.max(1))
            .zip(statuses)
            .filter(|(_, case)| *case == Status::Ok.code())
            .map(|(row, _)| row.iter().filter(|&&c| c == Status::Failed.code()).count())
            .sum())
    }

    /// The status of every case, in row order (to find what is left to run).
    pub fn statuses(&self) -> Result<Vec<Status>, StudyFileError> {
        let codes = self.rows.status.read_raw::<i8>().at(&self.path, STATUS)?;
        codes.into_iter().map(|c| self.status(c)).collect()
    }

    fn status(&self, code: i8) -> Result<Status, StudyFileError> {
        Status::from_code(code).ok_or_else(|| StudyFileError::Format {
            path: self.path.clone(),
            variable: STATUS.to_owned(),
            reason: format!("unknown status code {code}"),
        })
    }
}

/// The error of a file whose reading crashed (or hung) the check of `output::guard`.
pub(super) fn damaged(path: &Path, reason: String) -> StudyFileError {
    StudyFileError::Format {
        path: path.to_owned(),
        variable: "/".to_owned(),
        reason: format!("the file is damaged: {reason}"),
    }
}

/// Reads a message variable, `error_message` or `replicate_error_message` (`n`
/// strings, any string type, row-major), checked against its digest.
pub(super) fn read_messages(
    ds: &Dataset,
    n: usize,
    path: &Path,
) -> Result<Vec<String>, StudyFileError> {
    let name = ds.name().trim_start_matches('/').to_owned();
    let messages = text::read_dataset_text(ds).at(path, &name)?;
    text::check_digest(ds, text::DIGEST_ATTR, &messages, "strings").at(path, &name)?;
    if messages.len() != n {
        return Err(StudyFileError::Format {
            path: path.to_owned(),
            variable: name,
            reason: format!("{} values where {n} belong", messages.len()),
        });
    }
    Ok(messages)
}

/// Reads a 1-D id variable (`case`, `reference`, `reference_index`): int32 as
/// studyrun writes them, any other integer type as other writers (or older studyrun
/// versions, u64) left them; negative values are refused.
fn read_ids(file: &File, name: &str, path: &Path) -> Result<Vec<u64>, StudyFileError> {
    let ds = file.dataset(name).at(path, name)?;
    let ids = match ds.dtype().and_then(|t| t.to_descriptor()).at(path, name)? {
        TypeDescriptor::Unsigned(_) => ds.read_raw::<u64>().at(path, name)?,
        TypeDescriptor::Integer(_) => {
            let signed = ds.read_raw::<i64>().at(path, name)?;
            if let Some(bad) = signed.iter().find(|&&v| v < 0) {
                return Err(StudyFileError::Format {
                    path: path.to_owned(),
                    variable: name.to_owned(),
                    reason: format!("negative id {bad}"),
                });
            }
            signed.into_iter().map(|v| v as u64).collect()
        }
        other => {
            return Err(StudyFileError::Format {
                path: path.to_owned(),
                variable: name.to_owned(),
                reason: format!("type {other}, expected integers"),
            })
        }
    };
    Ok(ids)
}

/// Opens the HDF5 file at `path` for reading, refusing what is not a regular file or
/// has no HDF5 signature; the metadata cache bounded as the writer's, so an open
/// file's memory does not grow with the chunks read.
pub(super) fn open_hdf5(path: &Path) -> Result<File, StudyFileError> {
    let not_hdf5 = |reason: String| StudyFileError::NotHdf5 {
        path: path.to_owned(),
        reason,
    };
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(not_hdf5("does not exist".into()))
        }
        Err(e) => return Err(not_hdf5(format!("cannot be read: {e}"))),
        Ok(m) if m.is_dir() => return Err(not_hdf5("is a directory, not a study file".into())),
        // libhdf5 would wait for a FIFO's writer for ever.
        Ok(m) if !m.is_file() => {
            return Err(not_hdf5(
                "is not a regular file (a FIFO, device or socket), not a study file".into(),
            ))
        }
        Ok(_) => {}
    }
    let opened = File::with_options()
        .with_fapl(|p| p.mdc_config(&super::writer::bounded_metadata_cache()))
        .open(path);
    match opened {
        Err(e) if e.to_string().contains("file signature not found") => {
            Err(not_hdf5("is not an HDF5 file (no HDF5 signature)".into()))
        }
        opened => opened.at(path, "/"),
    }
}

/// Rebuilds the [`Layout`] of an open study file at `path`.
pub(super) fn read_layout(file: &File, path: &Path) -> Result<Layout, StudyFileError> {
    let format = format_error(path);
    check_format_version(file, path)?;
    let read = |name: &str| file.dataset(name).at(path, name);
    let mut layout = coordinates(file, path)?;
    read_variables(file, path, &mut layout)?;
    check_variables_digest(file, path, &layout)?;
    layout.attributes = root_attributes(file, path)?;
    let status = read(STATUS)?;
    check_type(&status, path, STATUS, "integers", |t| {
        matches!(t, TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_))
    })?;
    restore_written_times(&mut layout);
    layout.validate().map_err(|reason| format(reason, "/"))?;
    check_case_ids(&layout).map_err(|reason| format(reason, CASE))?;
    Ok(layout)
}

/// Checks the names and roles of the variables `layout` read from `file` against the
/// root attribute [`VARIABLES_DIGEST_ATTR`], if the file has it (a variable whose
/// attributes were lost is read as someone else's and left out of the layout).
fn check_variables_digest(file: &File, path: &Path, layout: &Layout) -> Result<(), StudyFileError> {
    if !file
        .attr_names()
        .at(path, "/")?
        .iter()
        .any(|a| a == VARIABLES_DIGEST_ATTR)
    {
        return Ok(());
    }
    // netCDF tools rewrite a scalar attribute as a one-element array.
    let stored = file
        .attr(VARIABLES_DIGEST_ATTR)
        .and_then(|a| a.read_raw::<i64>())
        .at(path, VARIABLES_DIGEST_ATTR)?;
    if stored != [text::variables_digest(layout)] {
        return Err(format_error(path)(
            "the variables with a studyrun_role do not match their checksum: a variable \
             was damaged (its attributes lost), removed or renamed"
                .into(),
            VARIABLES_DIGEST_ATTR,
        ));
    }
    Ok(())
}

/// The error of a file that is no readable study file, at `variable`.
fn format_error(path: &Path) -> impl Fn(String, &str) -> StudyFileError + '_ {
    move |reason, variable| StudyFileError::Format {
        path: path.to_owned(),
        variable: variable.to_owned(),
        reason,
    }
}

/// Refuses a file without this build's study file format attribute.
pub(super) fn check_format_version(file: &File, path: &Path) -> Result<(), StudyFileError> {
    let format = format_error(path);
    match attributes::read(file, FORMAT_ATTR) {
        Ok(AttrValue::I64(FORMAT_VERSION)) => {}
        Ok(other) => {
            return Err(StudyFileError::Version {
                path: path.to_owned(),
                found: match other {
                    AttrValue::I64(v) => v.to_string(),
                    other => format!("{other:?}"),
                },
                reads: FORMAT_VERSION,
            })
        }
        Err(e) => {
            return Err(format(
                format!("no study file format attribute ({e})"),
                FORMAT_ATTR,
            ))
        }
    }

    Ok(())
}

/// The layout's coordinates (cases, times, frequencies, references, replicates,
/// revolutions, orders, each case's reference), its variables still to be read.
fn coordinates(file: &File, path: &Path) -> Result<Layout, StudyFileError> {
    let read = |name: &str| file.dataset(name).at(path, name);
    Ok(Layout {
        case_ids: read_ids(file, CASE, path)?,
        // A file without series has no `time` coordinate.
        times: match file.dataset(TIME) {
            Ok(ds) => read_times(&ds, path)?,
            Err(_) => Vec::new(),
        },
        frequencies: read_floats(&read(FREQUENCY)?, path, FREQUENCY)?,
        reference_ids: read_ids(file, REFERENCE, path)?,
        series: Vec::new(),
        spectra: Vec::new(),
        metrics: Vec::new(),
        replicates: match file.dataset(REPLICATE) {
            Ok(_) => read_ids(file, REPLICATE, path)?,
            Err(_) => Vec::new(),
        },
        replicate_metrics: Vec::new(),
        revolutions: match file.dataset(REVOLUTION) {
            Ok(_) => read_ids(file, REVOLUTION, path)?,
            Err(_) => Vec::new(),
        },
        revolution_metrics: Vec::new(),
        orders: match file.dataset(ORDER) {
            Ok(ds) => read_floats(&ds, path, ORDER)?,
            Err(_) => Vec::new(),
        },
        sk_frequencies: match file.dataset(SK_FREQUENCY) {
            Ok(ds) => read_floats(&ds, path, SK_FREQUENCY)?,
            Err(_) => Vec::new(),
        },
        kurtosis: Vec::new(),
        order_spectra: Vec::new(),
        parameters: Vec::new(),
        reference_parameters: Vec::new(),
        reference_series: Vec::new(),
        // A file without references (measured recordings) has no `reference_index`.
        reference_index: match file.dataset(REFERENCE_INDEX) {
            Ok(_) => read_ids(file, REFERENCE_INDEX, path)?,
            Err(_) => Vec::new(),
        },
        attributes: Vec::new(),
        storage: Storage::default(),
    })
}

/// Every variable with a `studyrun_role` into `layout`, checked (type, shape, the
/// attributes' digest), and the storage of the first chunked row variable.
fn read_variables(file: &File, path: &Path, layout: &mut Layout) -> Result<(), StudyFileError> {
    let format = format_error(path);
    let mut storage_from: Option<Dataset> = None;
    for name in member_names(file).at(path, "/")? {
        let ds = match file.dataset(&name) {
            Ok(ds) => ds,
            Err(_) if file.group(&name).is_ok() => continue, // a group: not ours
            // A variable whose object header cannot be read: damage, not absence.
            Err(e) => return Err(e).at(path, &name),
        };
        let attribute_names = ds.attr_names().at(path, &name)?;
        if !attribute_names.iter().any(|a| a == ROLE_ATTR) {
            continue; // coordinates, built-ins and variables others added
        }
        text::check_attributes_digest(&ds).at(path, &name)?;
        let role_name = attributes::read_str(&ds, ROLE_ATTR).at(path, &name)?;
        let role = Role::parse(&role_name)
            .ok_or_else(|| format(format!("unknown {ROLE_ATTR} {role_name:?}"), &name))?;
        if !matches!(role, Role::Parameter | Role::ReferenceParameter) {
            check_type(&ds, path, &name, "floats", |t| {
                matches!(t, TypeDescriptor::Float(_))
            })?;
        }
        let spec = VarSpec {
            units: attributes::read_str(&ds, "units").at(path, &name)?,
            long_name: attributes::read_str(&ds, "long_name").at(path, &name)?,
            attributes: attributes::descriptive(&ds, &attribute_names).at(path, &name)?,
            name: name.clone(),
        };
        let (rows, cols) = match role {
            Role::Parameter | Role::Metric => (layout.n_cases(), None),
            Role::ReplicateMetric => (layout.n_cases(), Some(layout.replicates.len())),
            Role::RevolutionMetric => (layout.n_cases(), Some(layout.revolutions.len())),
            Role::OrderSpectrum => (layout.n_cases(), Some(layout.orders.len())),
            Role::Series => (layout.n_cases(), Some(layout.times.len())),
            Role::Spectrum => (layout.n_cases(), Some(layout.frequencies.len())),
            Role::SpectralKurtosis => (layout.n_cases(), Some(layout.sk_frequencies.len())),
            Role::ReferenceParameter => (layout.n_references(), None),
            Role::ReferenceSeries => (layout.n_references(), Some(layout.times.len())),
        };
        let expected: Vec<usize> = std::iter::once(rows).chain(cols).collect();
        if ds.shape() != expected {
            return Err(format(
                format!("shape {:?}, expected {expected:?}", ds.shape()),
                &name,
            ));
        }
        match role {
            Role::Parameter => layout.parameters.push(read_param(&ds, spec, path)?),
            Role::ReferenceParameter => layout
                .reference_parameters
                .push(read_param(&ds, spec, path)?),
            Role::Metric => layout.metrics.push(spec),
            Role::ReplicateMetric => layout.replicate_metrics.push(spec),
            Role::RevolutionMetric => layout.revolution_metrics.push(spec),
            Role::OrderSpectrum => layout.order_spectra.push(spec),
            Role::Series => layout.series.push(spec),
            Role::Spectrum => layout.spectra.push(spec),
            Role::SpectralKurtosis => layout.kurtosis.push(spec),
            Role::ReferenceSeries => layout.reference_series.push(spec),
        }
        let written_whole = matches!(
            role,
            Role::ReplicateMetric | Role::RevolutionMetric | Role::OrderSpectrum
        );
        if cols.is_some() && !written_whole && storage_from.is_none() {
            storage_from = Some(ds);
        }
    }
    if let Some(ds) = storage_from {
        layout.storage = read_storage(&ds).at(path, &ds.name())?;
    }

    Ok(())
}

/// The study's root attributes in creation order: netCDF's own (`_NCProperties`, ...)
/// and what is neither a string nor a number (arrays, other types) left out.
fn root_attributes(file: &File, path: &Path) -> Result<Vec<(String, AttrValue)>, StudyFileError> {
    let mut attributes = Vec::new();
    let names = file
        .attr_names_by(IndexType::CreationOrder, IterationOrder::Increasing)
        .or_else(|_| file.attr_names())
        .at(path, "/")?;
    // netCDF's own attributes (`_NCProperties`, ...) and what is neither a string nor
    // a number (arrays, other types) are not the study's.
    for name in names
        .into_iter()
        .filter(|n| n != FORMAT_ATTR && n != VARIABLES_DIGEST_ATTR && !n.starts_with('_'))
    {
        if let Ok(value) = attributes::read_value(file, &name).at(path, &name)? {
            attributes.push((name, value));
        }
    }

    Ok(attributes)
}

/// Checks the case ids against the root attributes of a study's file: every id below
/// `study_cases` (the study's case count), each in the file's shard (`shard` = `K/N`
/// holds the ids `id mod N = K − 1`), as many as `file_cases`. A layout without these
/// attributes (not a study's) passes.
fn check_case_ids(layout: &Layout) -> Result<(), String> {
    let attribute = |name: &str| layout.attribute(name);
    if let Some(&AttrValue::I64(n)) = attribute("file_cases") {
        if usize::try_from(n).ok() != Some(layout.n_cases()) {
            return Err(format!(
                "{} cases, but the file_cases attribute says {n}",
                layout.n_cases()
            ));
        }
    }
    if let Some(&AttrValue::I64(n)) = attribute("study_cases") {
        if let Some(id) = layout.case_ids.iter().find(|&&id| id >= n.max(0) as u64) {
            return Err(format!(
                "case id {id} is out of range: the study has {n} cases, ids 0 to {}",
                n - 1
            ));
        }
    }
    if let Some(AttrValue::Str(text)) = attribute("shard").filter(|v| v.as_text() != Some("")) {
        let (k, n) = text
            .split_once('/')
            .and_then(|(k, n)| Some((k.parse::<u64>().ok()?, n.parse::<u64>().ok()?)))
            .filter(|&(k, n)| (1..=n).contains(&k))
            .ok_or_else(|| format!("the shard attribute {text:?} is not K/N with 1 <= K <= N"))?;
        if let Some(id) = layout.case_ids.iter().find(|&&id| id % n != k - 1) {
            return Err(format!(
                "case id {id} does not belong to shard {k}/{n} (its ids are those with \
                 id mod {n} = {})",
                k - 1
            ));
        }
    }
    Ok(())
}

/// Largest move of a `time` value taken for a tool's rewrite of it (s): decoding `time`
/// to datetime64[ns] (xarray's default), which truncates to the nanosecond, and writing
/// it back moves some times by up to one nanosecond and a rounding.
const TIME_REWRITE_TOLERANCE: f64 = 2e-9;

/// Puts back the times studyrun writes, `sample_time(j × decimate, sample_rate)`, when
/// every time read is within [`TIME_REWRITE_TOLERANCE`] of them, so that a file whose
/// `time` a tool rewrote merges and resumes like the original. Otherwise (or without
/// the sampling attributes) the times stay as read.
fn restore_written_times(layout: &mut Layout) {
    let attribute = |name: &str| layout.attribute(name);
    let (Some(&AttrValue::F64(rate)), Some(&AttrValue::I64(decimate))) =
        (attribute("sample_rate"), attribute("decimate"))
    else {
        return;
    };
    let Ok(decimate) = usize::try_from(decimate) else {
        return;
    };
    let Some(written) = (0..layout.times.len())
        .map(|j| j.checked_mul(decimate).map(|k| sample_time(k, rate)))
        .collect::<Option<Vec<f64>>>()
    else {
        return;
    };
    let close = |(w, t): (&f64, &f64)| (w - t).abs() <= TIME_REWRITE_TOLERANCE;
    if decimate > 0 && written.iter().zip(&layout.times).all(close) {
        layout.times = written;
    }
}

/// The `time` coordinate's values (s from the start of the simulation), its type and
/// units checked first: [`TIME_UNITS`] in a spelling UDUNITS reads alike (xarray writes
/// `seconds since 1970-01-01`), or plain seconds. Other units (a tool's `milliseconds
/// since ...`, another date) are refused rather than taken for seconds.
fn read_times(ds: &Dataset, path: &Path) -> Result<Vec<f64>, StudyFileError> {
    let units = attributes::read_str(ds, "units").at(path, TIME)?;
    if !super::layout::seconds_from_the_epoch(&units) {
        return Err(StudyFileError::Format {
            path: path.to_owned(),
            variable: TIME.to_owned(),
            reason: format!("units {units:?}; studyrun reads `{TIME_UNITS}`"),
        });
    }
    read_floats(ds, path, TIME)
}

/// Refuses dataset `name` unless its stored type is `what` (`is`): libhdf5 1.10 takes a
/// damaged type as it finds it (a float of megabytes per element) and reads past its
/// buffers.
fn check_type(
    ds: &Dataset,
    path: &Path,
    name: &str,
    what: &str,
    is: impl Fn(&TypeDescriptor) -> bool,
) -> Result<(), StudyFileError> {
    let found = ds.dtype().and_then(|t| t.to_descriptor()).at(path, name)?;
    if is(&found) {
        Ok(())
    } else {
        Err(StudyFileError::Format {
            path: path.to_owned(),
            variable: name.to_owned(),
            reason: format!("type {found}, expected {what}"),
        })
    }
}

/// The values of 1-D float dataset `name`, its type checked first.
fn read_floats(ds: &Dataset, path: &Path, name: &str) -> Result<Vec<f64>, StudyFileError> {
    check_type(ds, path, name, "floats", |t| {
        matches!(t, TypeDescriptor::Float(_))
    })?;
    ds.read_raw::<f64>().at(path, name)
}

/// The root group's members in creation order (name order if not tracked).
fn member_names(file: &File) -> hdf5::Result<Vec<String>> {
    file.member_names_by(IndexType::CreationOrder, IterationOrder::Increasing)
        .or_else(|_| file.member_names())
}

/// Reads a parameter's values: floats as f64, strings as UTF-8.
fn read_param(ds: &Dataset, spec: VarSpec, path: &Path) -> Result<Param, StudyFileError> {
    let name = spec.name.clone();
    let values = match ds.dtype().and_then(|t| t.to_descriptor()).at(path, &name)? {
        TypeDescriptor::Float(_) => ParamValues::F64(ds.read_raw::<f64>().at(path, &name)?),
        other => {
            if let Strings::Text(v) = text::read_dataset(ds).at(path, &name)? {
                text::check_digest(ds, text::DIGEST_ATTR, &v, "strings").at(path, &name)?;
                return Ok(Param {
                    spec,
                    values: ParamValues::Str(v),
                });
            }
            return Err(StudyFileError::Format {
                path: path.to_owned(),
                variable: name,
                reason: format!("parameter of type {other}, expected float or string"),
            });
        }
    };
    Ok(Param { spec, values })
}

/// Storage options of a series or spectrum dataset: element size and deflate level.
fn read_storage(ds: &Dataset) -> hdf5::Result<Storage> {
    let float32 = ds.dtype()?.size() == 4;
    let deflate_level = ds
        .filters()
        .iter()
        .find_map(|f| match f {
            Filter::Deflate(level) => Some(*level),
            _ => None,
        })
        .unwrap_or(0);
    Ok(Storage {
        float32,
        deflate_level,
    })
}

#[cfg(test)]
mod tests {
    use super::super::layout::seconds_from_the_epoch;

    #[test]
    fn time_units_are_seconds_from_the_epoch_in_any_spelling() {
        for units in [
            super::TIME_UNITS,
            "seconds since 1970-01-01",
            "s since 1970-01-01T00:00:00Z",
            "second since 1970-01-01 00:00:00 UTC",
            "seconds since 1970-01-01 00:00:00 +00:00",
            "s",
            "seconds",
        ] {
            assert!(seconds_from_the_epoch(units), "{units}");
        }
        for units in [
            "milliseconds since 1970-01-01",
            "seconds since 2000-01-01",
            "days since 1970-01-01",
            "ms",
            "seconds since 1970-01-01 00:00:00 +01:00",
            "",
        ] {
            assert!(!seconds_from_the_epoch(units), "{units}");
        }
    }
}
