//! The errors of study files: [`StudyFileError`] (creating, writing or reading one file)
//! and [`OutputError`] (what the file operations around it, lock, overwrite checks and
//! merge, return).

use std::path::{Path, PathBuf};

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
    /// A study file of another format version than this build reads.
    #[error(
        "{path}: a study file of format version {found}, this build reads version {reads}: \
         run the study again, or read it with the studyrun that wrote it"
    )]
    Version {
        /// The file.
        path: PathBuf,
        /// Its `studyrun_file_format`.
        found: String,
        /// The version this build reads.
        reads: i64,
    },
    /// The file is not a study file, or its content is inconsistent.
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

/// Why an operation on study files (taking the lock, checking what an output would
/// replace, merging shards) could not be done. Failed *cases* are not errors: they
/// are recorded in the file with their message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// A file operation failed.
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        /// What was tried: `create`, `remove`, `rename … to`, ….
        action: String,
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// Reading or writing a study file failed (the error names the file).
    #[error("{source}")]
    File {
        /// The study file.
        path: PathBuf,
        /// What went wrong.
        source: Box<StudyFileError>,
    },
    /// Another process is writing the same output.
    #[error("{} is in use by another studyrun (pid {pid}, lock {}); wait for it to finish or stop it", output.display(), lock.display())]
    Locked {
        /// The output file.
        output: PathBuf,
        /// The lock file.
        lock: PathBuf,
        /// The process holding the lock (as it wrote it; 0 if unknown).
        pid: u32,
    },
    /// What is on disk, or the request itself, does not allow the operation; the
    /// message says why and what to do.
    #[error("{0}")]
    Refused(String),
}

impl OutputError {
    /// An [`OutputError::Io`] for `action` on `path`.
    pub(crate) fn io(
        action: impl Into<String>,
        path: &Path,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let (action, path) = (action.into(), path.to_path_buf());
        move |source| Self::Io {
            action,
            path,
            source,
        }
    }

    /// An [`OutputError::File`] for `path`.
    pub(crate) fn file(path: &Path) -> impl FnOnce(StudyFileError) -> Self {
        let path = path.to_path_buf();
        move |source| Self::File {
            path,
            source: Box::new(source),
        }
    }
}
