//! The error of running a study.

use crate::output::OutputError;
use crate::simulate::CaseError;

use super::JournalError;

/// Why a study could not be run or measured: what [`crate::run_study`] and
/// [`crate::accuracy`] return. Failed *cases* are not errors: they are recorded in the
/// file with their message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// A file operation, the lock or a refusal of what is on disk.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The crash journal of an interrupted run cannot be used.
    #[error(transparent)]
    Journal(#[from] JournalError),
    /// An ideal-mechanism reference run failed (every case needs its reference).
    #[error("reference (ideal mechanism) {index} at {rpm} rpm: {source}")]
    Reference {
        /// Index of the reference.
        index: usize,
        /// Its crank speed (rev/min).
        rpm: f64,
        /// Why it failed.
        source: CaseError,
    },
    /// A worker thread stopped before every case was done; the partial file and its
    /// journal are kept for `--resume`.
    #[error("a worker thread stopped after {received} of {pending} cases; rerun with --resume")]
    WorkerStopped {
        /// Cases the writer received.
        received: usize,
        /// Cases there were to run.
        pending: usize,
    },
    /// The worker pool could not be built.
    #[error("cannot start the worker threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
}

impl RunError {
    /// A refusal: what is on disk, or the request itself, does not allow the run.
    pub(crate) fn refused(message: String) -> Self {
        Self::Output(OutputError::Refused(message))
    }
}
