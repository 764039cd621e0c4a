//! The open per-row datasets of a study file, shared by the writer and the reader,
//! and reading blocks of their rows.

use std::ops::Range;
use std::path::Path;

use hdf5::{Dataset, File};
use ndarray::{Array2, Axis};

use super::error::{AtVariable, StudyFileError};
use super::layout::{
    Layout, VarSpec, ERROR_MESSAGE, REPLICATE_ERROR_MESSAGE, REPLICATE_STATUS, STATUS,
};

/// Handles to every dataset written or read one row at a time, in [`Layout`] order.
pub(super) struct RowDatasets {
    pub(super) series: Vec<Dataset>,
    pub(super) spectra: Vec<Dataset>,
    pub(super) kurtosis: Vec<Dataset>,
    pub(super) metrics: Vec<Dataset>,
    pub(super) replicate_metrics: Vec<Dataset>,
    pub(super) revolution_metrics: Vec<Dataset>,
    pub(super) order_spectra: Vec<Dataset>,
    pub(super) status: Dataset,
    pub(super) error_message: Dataset,
    /// `replicate_status` and `replicate_error_message`, in a file with replicates.
    pub(super) replicates: Option<(Dataset, Dataset)>,
    pub(super) reference_series: Vec<Dataset>,
}

impl RowDatasets {
    /// Opens the datasets `layout` names in `file` (at `path`, for messages).
    pub(super) fn open(file: &File, layout: &Layout, path: &Path) -> Result<Self, StudyFileError> {
        let one = |name: &str| file.dataset(name).at(path, name);
        let all = |specs: &[VarSpec]| -> Result<Vec<Dataset>, StudyFileError> {
            specs.iter().map(|s| one(&s.name)).collect()
        };
        Ok(Self {
            series: all(&layout.series)?,
            spectra: all(&layout.spectra)?,
            kurtosis: all(&layout.kurtosis)?,
            metrics: all(&layout.metrics)?,
            replicate_metrics: all(&layout.replicate_metrics)?,
            revolution_metrics: all(&layout.revolution_metrics)?,
            order_spectra: all(&layout.order_spectra)?,
            status: one(STATUS)?,
            error_message: one(ERROR_MESSAGE)?,
            replicates: if layout.replicates.is_empty() {
                None
            } else {
                Some((one(REPLICATE_STATUS)?, one(REPLICATE_ERROR_MESSAGE)?))
            },
            reference_series: all(&layout.reference_series)?,
        })
    }
}

/// Checks that `row` is below `len`, the length of `dimension`.
pub(super) fn check_row(
    path: &Path,
    dimension: &'static str,
    row: usize,
    len: usize,
) -> Result<(), StudyFileError> {
    if row < len {
        Ok(())
    } else {
        Err(StudyFileError::Row {
            path: path.to_owned(),
            dimension,
            row,
            len,
        })
    }
}

/// Values a reader reads of a block of case rows at a time when it reads every row
/// (8 bytes each: 8 MiB).
pub(super) const READ_VALUES: usize = 1 << 20;

/// Rows `rows` of each dataset of `datasets` (variables `specs`), one read each: a
/// `[rows, values per row]` array per dataset (1-D datasets give one value per row).
pub(super) fn read_blocks(
    datasets: &[Dataset],
    specs: &[VarSpec],
    rows: Range<usize>,
    path: &Path,
) -> Result<Vec<Array2<f64>>, StudyFileError> {
    datasets
        .iter()
        .zip(specs)
        .map(|(ds, spec)| {
            let block = if ds.ndim() == 1 {
                let column = ds.read_slice_1d::<f64, _>(rows.clone());
                column.map(|c| c.insert_axis(Axis(1)))
            } else {
                ds.read_slice_2d::<f64, _>((rows.clone(), ..))
            };
            block.at(path, &spec.name)
        })
        .collect()
}
