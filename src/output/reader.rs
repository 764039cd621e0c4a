//! Reading a study file back: its layout, and cases one row at a time.

use std::path::{Path, PathBuf};

use hdf5::filters::Filter;
use hdf5::types::{TypeDescriptor, VarLenAscii, VarLenUnicode};
use hdf5::{Dataset, File, IndexType, IterationOrder};

use super::attributes;
use super::datasets::{check_row, RowDatasets};
use super::error::{AtVariable, StudyFileError};
use super::layout::{
    AttrValue, Layout, Param, ParamValues, Role, Status, Storage, VarSpec, CASE, ERROR_MESSAGE,
    FORMAT_ATTR, FORMAT_VERSION, FREQUENCY, REFERENCE, REFERENCE_INDEX, ROLE_ATTR, STATUS, TIME,
};

/// One case read back from a file (owned). Values stored as float32 are widened
/// exactly to f64; rows never written read as NaN with status pending.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseData {
    /// One vector per [`Layout::series`], `times.len()` values each.
    pub series: Vec<Vec<f64>>,
    /// One vector per [`Layout::spectra`], `frequencies.len()` values each.
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`Layout::metrics`].
    pub metrics: Vec<f64>,
    /// The case's state.
    pub status: Status,
    /// Why it failed (empty otherwise).
    pub message: String,
}

/// Reads a study file written by [`StudyWriter`](super::StudyWriter).
pub struct StudyReader {
    path: PathBuf,
    layout: Layout,
    rows: RowDatasets,
    /// Kept open for the datasets' lifetime.
    _file: File,
}

impl std::fmt::Debug for StudyReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StudyReader")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl StudyReader {
    /// Opens the study file at `path` read-only and reads its layout.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, StudyFileError> {
        let path = path.as_ref().to_owned();
        let file = File::open(&path).at(&path, "/")?;
        let layout = read_layout(&file, &path)?;
        let rows = RowDatasets::open(&file, &layout, &path)?;
        Ok(Self {
            path,
            layout,
            rows,
            _file: file,
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
        self.layout
            .attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }

    /// Reads row `row` of every `[case, ...]` variable (`row` indexes
    /// [`Layout::case_ids`]).
    pub fn read_case(&self, row: usize) -> Result<CaseData, StudyFileError> {
        check_row(&self.path, CASE, row, self.layout.n_cases())?;
        let series = self.read_rows(&self.rows.series, &self.layout.series, row)?;
        let spectra = self.read_rows(&self.rows.spectra, &self.layout.spectra, row)?;
        let metrics = self
            .rows
            .metrics
            .iter()
            .zip(&self.layout.metrics)
            .map(|(ds, spec)| read_one::<f64>(ds, row).at(&self.path, &spec.name))
            .collect::<Result<_, _>>()?;
        let message = read_one::<VarLenUnicode>(&self.rows.error_message, row)
            .at(&self.path, ERROR_MESSAGE)?
            .as_str()
            .to_owned();
        let code = read_one::<i8>(&self.rows.status, row).at(&self.path, STATUS)?;
        Ok(CaseData {
            series,
            spectra,
            metrics,
            status: self.status(code)?,
            message,
        })
    }

    /// Reads row `row` of every `[reference, time]` variable, one vector per
    /// [`Layout::reference_series`].
    pub fn read_reference(&self, row: usize) -> Result<Vec<Vec<f64>>, StudyFileError> {
        check_row(&self.path, REFERENCE, row, self.layout.n_references())?;
        self.read_rows(
            &self.rows.reference_series,
            &self.layout.reference_series,
            row,
        )
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

    fn read_rows(
        &self,
        datasets: &[Dataset],
        specs: &[VarSpec],
        row: usize,
    ) -> Result<Vec<Vec<f64>>, StudyFileError> {
        datasets
            .iter()
            .zip(specs)
            .map(|(ds, spec)| {
                ds.read_slice_1d::<f64, _>((row, ..))
                    .map(|a| a.to_vec())
                    .at(&self.path, &spec.name)
            })
            .collect()
    }
}

/// Reads one element of a 1-D dataset.
fn read_one<T: hdf5::H5Type + Clone>(ds: &Dataset, row: usize) -> hdf5::Result<T> {
    let values = ds.read_slice_1d::<T, _>(row..row + 1)?;
    values
        .first()
        .cloned()
        .ok_or_else(|| hdf5::Error::from(format!("row {row} read nothing")))
}

/// Rebuilds the [`Layout`] of an open study file at `path`.
pub(super) fn read_layout(file: &File, path: &Path) -> Result<Layout, StudyFileError> {
    let format = |reason: String, variable: &str| StudyFileError::Format {
        path: path.to_owned(),
        variable: variable.to_owned(),
        reason,
    };
    match attributes::read(file, FORMAT_ATTR) {
        Ok(AttrValue::I64(FORMAT_VERSION)) => {}
        Ok(other) => {
            return Err(format(
                format!("format version {other:?}, this build reads {FORMAT_VERSION}"),
                FORMAT_ATTR,
            ))
        }
        Err(_) => return Err(format("no study file format attribute".into(), FORMAT_ATTR)),
    }

    let read = |name: &str| file.dataset(name).at(path, name);
    let mut layout = Layout {
        case_ids: read(CASE)?.read_raw::<u64>().at(path, CASE)?,
        times: read(TIME)?.read_raw::<f64>().at(path, TIME)?,
        frequencies: read(FREQUENCY)?.read_raw::<f64>().at(path, FREQUENCY)?,
        reference_ids: read(REFERENCE)?.read_raw::<u64>().at(path, REFERENCE)?,
        series: Vec::new(),
        spectra: Vec::new(),
        metrics: Vec::new(),
        parameters: Vec::new(),
        reference_parameters: Vec::new(),
        reference_series: Vec::new(),
        reference_index: read(REFERENCE_INDEX)?
            .read_raw::<u64>()
            .at(path, REFERENCE_INDEX)?,
        attributes: Vec::new(),
        storage: Storage::default(),
    };

    let mut storage_from: Option<Dataset> = None;
    for name in member_names(file).at(path, "/")? {
        let ds = match file.dataset(&name) {
            Ok(ds) => ds,
            Err(_) => continue, // not a dataset: not ours
        };
        if !ds
            .attr_names()
            .at(path, &name)?
            .iter()
            .any(|a| a == ROLE_ATTR)
        {
            continue; // coordinates, built-ins and variables others added
        }
        let role_name = attributes::read_str(&ds, ROLE_ATTR).at(path, &name)?;
        let role = Role::parse(&role_name)
            .ok_or_else(|| format(format!("unknown {ROLE_ATTR} {role_name:?}"), &name))?;
        let spec = VarSpec {
            units: attributes::read_str(&ds, "units").at(path, &name)?,
            long_name: attributes::read_str(&ds, "long_name").at(path, &name)?,
            name: name.clone(),
        };
        let (rows, cols) = match role {
            Role::Parameter | Role::Metric => (layout.n_cases(), None),
            Role::Series => (layout.n_cases(), Some(layout.times.len())),
            Role::Spectrum => (layout.n_cases(), Some(layout.frequencies.len())),
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
            Role::Series => layout.series.push(spec),
            Role::Spectrum => layout.spectra.push(spec),
            Role::ReferenceSeries => layout.reference_series.push(spec),
        }
        if cols.is_some() && storage_from.is_none() {
            storage_from = Some(ds);
        }
    }
    if let Some(ds) = storage_from {
        layout.storage = read_storage(&ds).at(path, &ds.name())?;
    }

    let names = file
        .attr_names_by(IndexType::CreationOrder, IterationOrder::Increasing)
        .or_else(|_| file.attr_names())
        .at(path, "/")?;
    for name in names.into_iter().filter(|n| n != FORMAT_ATTR) {
        let value = attributes::read(file, &name).at(path, &name)?;
        layout.attributes.push((name, value));
    }

    layout.validate().map_err(|reason| format(reason, "/"))?;
    Ok(layout)
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
        TypeDescriptor::VarLenUnicode => ParamValues::Str(
            ds.read_raw::<VarLenUnicode>()
                .at(path, &name)?
                .iter()
                .map(|s| s.as_str().to_owned())
                .collect(),
        ),
        TypeDescriptor::VarLenAscii => ParamValues::Str(
            ds.read_raw::<VarLenAscii>()
                .at(path, &name)?
                .iter()
                .map(|s| s.as_str().to_owned())
                .collect(),
        ),
        other => {
            return Err(StudyFileError::Format {
                path: path.to_owned(),
                variable: name,
                reason: format!("parameter of type {other}, expected float or string"),
            })
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
