//! The open per-row datasets of a study file, shared by the writer and the reader.

use std::path::Path;

use hdf5::{Dataset, File};

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
