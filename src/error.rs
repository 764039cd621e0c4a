//! Errors, with the offending numbers and paths in their fields: of the physics
//! model ([`ParamError`], [`ModelError`]) and of running studies ([`RunError`]).

/// A parameter is out of its allowed range; names the field, the value and the rule.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid parameter `{field}` = {value}: {allowed}")]
pub struct ParamError {
    /// Dotted name of the parameter, e.g. `bearing.ball_count`.
    pub field: String,
    /// The offending value, as written.
    pub value: String,
    /// What is allowed.
    pub allowed: String,
}

impl ParamError {
    /// Builds the error for `field` holding `value`, where `allowed` says what is allowed.
    /// A number is shown by [`number`].
    pub fn new(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        let value = value.to_string();
        Self {
            field: field.into(),
            value: value.parse().map_or(value, number),
            allowed: allowed.into(),
        }
    }

    /// The message of a refusal: `-0.02 is not allowed: finite and > 0 s`.
    pub fn refusal(&self) -> String {
        format!("{} is not allowed: {}", self.value, self.allowed)
    }
}

/// A number as a message shows it: its shortest exact decimal form (`0.02`, `9570000000`),
/// in powers of ten when that form is long (`1e-300`, `2.5e20`).
pub fn number(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() > 16 {
        format!("{x:e}")
    } else {
        plain
    }
}

/// The model could not be evaluated at some state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// Newton's method on the position constraints did not converge.
    #[error("position constraints not satisfied after {iterations} Newton iterations (residual {residual:e} m)")]
    ConstraintsNotConverged {
        /// Iterations taken.
        iterations: usize,
        /// Max-norm of the residual left (m or rad).
        residual: f64,
    },
    /// The constraint Jacobian of the dependent coordinates is singular
    /// (the mechanism reached a singular configuration).
    #[error("singular constraint Jacobian (mechanism at a singular configuration)")]
    SingularConstraints,
    /// A computed quantity is NaN or infinite.
    #[error("non-finite {what}")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
    },
}

/// Why a study could not be run, merged, inspected or measured: what the library's
/// [`crate::run_study`], [`crate::output::merge`], [`crate::output::inspect`] and
/// [`crate::accuracy`] return. Failed *cases* are not errors: they are recorded in
/// the file with their message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// A file operation failed.
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        /// What was tried: `create`, `remove`, `rename … to`, ….
        action: String,
        /// The file.
        path: std::path::PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// Reading or writing a study file failed (the error names the file).
    #[error("{source}")]
    File {
        /// The study file.
        path: std::path::PathBuf,
        /// What went wrong.
        source: Box<crate::output::StudyFileError>,
    },
    /// The crash journal of an interrupted run cannot be used.
    #[error(transparent)]
    Journal(#[from] crate::run::JournalError),
    /// Another process is writing the same output.
    #[error("{} is in use by another studyrun (pid {pid}, lock {}); wait for it to finish or stop it", output.display(), lock.display())]
    Locked {
        /// The output file.
        output: std::path::PathBuf,
        /// The lock file.
        lock: std::path::PathBuf,
        /// The process holding the lock (as it wrote it; 0 if unknown).
        pid: u32,
    },
    /// What is on disk, or the request itself, does not allow the operation; the
    /// message says why and what to do.
    #[error("{0}")]
    Refused(String),
    /// An ideal-mechanism reference run failed (every case needs its reference).
    #[error("reference (ideal mechanism) {index} at {rpm} rpm: {source}")]
    Reference {
        /// Index of the reference.
        index: usize,
        /// Its crank speed (rev/min).
        rpm: f64,
        /// Why it failed.
        source: crate::simulate::CaseError,
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
    /// An [`RunError::Io`] for `action` on `path`.
    pub(crate) fn io(
        action: impl Into<String>,
        path: &std::path::Path,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let (action, path) = (action.into(), path.to_path_buf());
        move |source| Self::Io {
            action,
            path,
            source,
        }
    }

    /// A [`RunError::File`] for `path`.
    pub(crate) fn file(
        path: &std::path::Path,
    ) -> impl FnOnce(crate::output::StudyFileError) -> Self {
        let path = path.to_path_buf();
        move |source| Self::File {
            path,
            source: Box::new(source),
        }
    }
}
