//! The error type of study files.

use std::path::PathBuf;

use super::dimension_scales::ScaleError;

/// What can go wrong creating, writing or reading a study file. Every message names
/// the file and, where one is concerned, the variable.
#[derive(Debug, thiserror::Error)]
pub enum StudyFileError {
    /// The [`Layout`](super::Layout) is inconsistent (lengths, names, levels).
    #[error("{path}: invalid layout: {reason}")]
    Layout {
        /// The file being created.
        path: PathBuf,
        /// What is wrong, naming the variable.
        reason: String,
    },
    /// An HDF5 call failed.
    #[error("{path}: variable `{variable}`: {source}")]
    Hdf5 {
        /// The file.
        path: PathBuf,
        /// The variable (or attribute, or `/` for the file itself) concerned.
        variable: String,
        /// HDF5's error.
        #[source]
        source: hdf5::Error,
    },
    /// Making or attaching a dimension scale failed.
    #[error("{path}: variable `{variable}`: {source}")]
    Scale {
        /// The file.
        path: PathBuf,
        /// The variable concerned.
        variable: String,
        /// The dimension-scale error.
        #[source]
        source: ScaleError,
    },
    /// A row index beyond the `case` or `reference` dimension.
    #[error("{path}: {dimension} row {row} is out of range (the file has {len})")]
    Row {
        /// The file.
        path: PathBuf,
        /// `case` or `reference`.
        dimension: &'static str,
        /// The row asked for.
        row: usize,
        /// The dimension's length.
        len: usize,
    },
    /// A record passed to the writer does not fit the layout.
    #[error("{path}: variable `{variable}`: {reason}")]
    Record {
        /// The file.
        path: PathBuf,
        /// The variable (or group of variables: `series`, `spectra`, `metrics`).
        variable: String,
        /// What does not fit.
        reason: String,
    },
    /// The path holds no HDF5 file: nothing, a directory, or a file of another kind.
    #[error("{path} {reason}")]
    NotHdf5 {
        /// The path given.
        path: PathBuf,
        /// What is there instead: `does not exist`, `is a directory`, ….
        reason: String,
    },
    /// The file is not a study file of this version, or its content is inconsistent.
    #[error("{path}: variable `{variable}`: not a readable study file: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// The variable (or attribute) concerned.
        variable: String,
        /// What was found.
        reason: String,
    },
}

/// Attaches the file and variable to an HDF5 result.
pub(super) trait AtVariable<T> {
    /// Maps an HDF5 error to [`StudyFileError::Hdf5`] naming `path` and `variable`.
    fn at(self, path: &std::path::Path, variable: &str) -> Result<T, StudyFileError>;
}

impl<T> AtVariable<T> for hdf5::Result<T> {
    fn at(self, path: &std::path::Path, variable: &str) -> Result<T, StudyFileError> {
        self.map_err(|source| StudyFileError::Hdf5 {
            path: path.to_owned(),
            variable: variable.to_owned(),
            source,
        })
    }
}
