//! Loading one recording's samples from a file: [`read_samples`].
//!
//! The format follows the file's extension (case-insensitive, [`EXTENSIONS`]):
//!
//! | extension | format | [`Selector`] |
//! |---|---|---|
//! | `.npy` | NumPy array, format versions 1.0–3.0 | [`Selector::None`] |
//! | `.npz` | ZIP archive of `.npy` members, stored or deflated | member name, with or without `.npy` |
//! | `.wav` | RIFF WAVE: integer PCM 8/16/24/32 bits, IEEE float 32/64, extensible | channel index |
//! | `.csv` | delimited text (`,`, or `;` or tab), optional header row | column name or index |
//! | `.h5`, `.hdf5`, `.nc` | HDF5 and netCDF-4 | dataset path, `DE` or `group/DE` |
//! | `.mat` | MATLAB Level 5 MAT-file (v6/v7; v7.3 is HDF5 and read as such) | variable or struct field path, `bearing.gs` |
//!
//! Each reader is a small parser of its own over the file's bytes (HDF5 goes through
//! libhdf5). Every length a file declares is checked against the bytes that are
//! there before anything is allocated from it, so a truncated or corrupt file gives
//! a [`ReadError`] naming the file, never a panic. The samples must be one column,
//! not empty, and finite.

mod bytes;
mod csv;
#[cfg(test)]
mod fixtures;
mod hdf5;
mod mat;
mod npy;
#[cfg(test)]
mod tests;
mod wav;
mod zip;

use std::path::{Path, PathBuf};

/// Where in a file the samples are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Selector {
    /// An `.npz` member name (with or without `.npy`), an HDF5 / netCDF-4 dataset
    /// path (`DE`, `group/DE`), or a MAT-file variable or scalar-struct field path
    /// (`bearing.gs`).
    Variable(String),
    /// A WAV channel, 0-based.
    ChannelIndex(usize),
    /// A CSV column.
    Column(ColumnRef),
    /// Nothing: an `.npy` file, or a file holding exactly one candidate (one `.npz`
    /// member, one WAV channel, one CSV column, one numeric HDF5 dataset, one numeric
    /// top-level MAT variable).
    None,
}

/// A CSV column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ColumnRef {
    /// The column whose header-row field is this name (trimmed, unquoted).
    Name(String),
    /// The column at this 0-based index.
    Index(usize),
}

/// One recording's samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    /// The samples in file order, all finite. Integer WAV PCM is scaled to [-1, 1);
    /// every other format's values are as stored (integers converted exactly up to
    /// 2^53).
    pub values: Vec<f64>,
    /// The sample rate in Hz from a WAV file's header; `None` for the other formats,
    /// which do not carry one in a standard place.
    pub sample_rate: Option<f64>,
}

/// The file extensions [`read_samples`] knows, lower case, without the dot.
pub const EXTENSIONS: [&str; 8] = ["npy", "npz", "wav", "csv", "h5", "hdf5", "nc", "mat"];

/// The shapes a recording's array may have, as the errors name them.
const ONE_COLUMN: &str = "an (N,) or (N, 1) array (or (1, N))";

/// What can go wrong reading a recording. Every message names the file, what is
/// wrong and, where there is a choice, what the file holds or what is allowed.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file does not exist.
    #[error("{}: no such file", path.display())]
    Missing {
        /// The file.
        path: PathBuf,
    },
    /// The file exists but cannot be read (permissions, a directory, a FIFO, I/O).
    #[error("{}: cannot be read: {reason}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The extension is none of [`EXTENSIONS`].
    #[error("{}: unknown extension {extension}; allowed: .npy, .npz, .wav, .csv, .h5, .hdf5, .nc, .mat", path.display())]
    Extension {
        /// The file.
        path: PathBuf,
        /// The extension found, `` `.txt` `` or `no extension`.
        extension: String,
    },
    /// The selector names nothing in the file, is of the wrong kind for the format,
    /// or is missing where the file holds several candidates.
    #[error("{}: {reason}", path.display())]
    Selection {
        /// The file.
        path: PathBuf,
        /// What was asked for and what the file holds.
        reason: String,
    },
    /// The selected array is not one column.
    #[error("{}: `{name}` has shape {shape}; expected {ONE_COLUMN}", path.display())]
    Shape {
        /// The file.
        path: PathBuf,
        /// The array.
        name: String,
        /// Its shape as the format writes it, `(2, 3)` or `2x3`.
        shape: String,
    },
    /// The selected array holds no samples.
    #[error("{}: `{name}` is empty (no samples)", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
        /// The array.
        name: String,
    },
    /// The file is truncated, corrupt, or not of the format its extension says.
    #[error("{}: {reason}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where.
        reason: String,
    },
    /// The file is valid but holds something this reader does not read (a complex
    /// or cell array, a compressed WAV, a dtype outside the list).
    #[error("{}: {reason}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What it holds and what is allowed.
        reason: String,
    },
    /// A sample is NaN or infinite.
    #[error("{}: `{name}`: sample {index} is {value}; every sample must be finite", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The array.
        name: String,
        /// The 0-based index of the first non-finite sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// libhdf5 failed on an HDF5 or netCDF-4 file.
    #[error("{}: `{name}`: {source}", path.display())]
    Hdf5 {
        /// The file.
        path: PathBuf,
        /// The dataset (or `/` for the file).
        name: String,
        /// HDF5's error.
        #[source]
        source: ::hdf5::Error,
    },
}

/// Loads the samples `selector` picks from the file at `path`, the format chosen by
/// the file's extension ([`EXTENSIONS`]; the module docs list what each selects).
///
/// # Errors
///
/// [`ReadError`] naming the file: missing or unreadable, unknown extension, nothing
/// matching the selector (the message lists what the file holds), an array that is
/// not one column or is empty, truncated or corrupt data, or a non-finite sample.
pub fn read_samples(path: &Path, selector: &Selector) -> Result<Samples, ReadError> {
    let format = Format::of(path)?;
    check_regular_file(path)?;
    let loaded = load(format, path, selector)?;
    checked(path, loaded)
}

/// The file formats, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Npy,
    Npz,
    Wav,
    Csv,
    Hdf5,
    Mat,
}

impl Format {
    /// The format of `path` from its extension, case-insensitive.
    fn of(path: &Path) -> Result<Self, ReadError> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        Ok(match ext.as_deref() {
            Some("npy") => Self::Npy,
            Some("npz") => Self::Npz,
            Some("wav") => Self::Wav,
            Some("csv") => Self::Csv,
            Some("h5" | "hdf5" | "nc") => Self::Hdf5,
            Some("mat") => Self::Mat,
            other => {
                return Err(ReadError::Extension {
                    path: path.to_owned(),
                    extension: other.map_or("(none)".into(), |e| format!("`.{e}`")),
                })
            }
        })
    }
}

/// Refuses a path that is missing, a directory, or not a regular file (reading a
/// FIFO would wait for its writer for ever).
fn check_regular_file(path: &Path) -> Result<(), ReadError> {
    let unreadable = |reason: String| ReadError::Unreadable {
        path: path.to_owned(),
        reason,
    };
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(ReadError::Missing {
            path: path.to_owned(),
        }),
        Err(e) => Err(unreadable(e.to_string())),
        Ok(m) if m.is_dir() => Err(unreadable("is a directory".into())),
        Ok(m) if !m.is_file() => Err(unreadable(
            "is not a regular file (a FIFO, device or socket)".into(),
        )),
        Ok(_) => Ok(()),
    }
}

/// Checks that `selector` is of the kind `format` selects by, then runs its reader.
fn load(format: Format, path: &Path, selector: &Selector) -> Result<Loaded, ReadError> {
    let at = |f: Fault| f.at(path);
    match format {
        Format::Hdf5 => hdf5::read(path, variable(selector, "an HDF5 or netCDF-4").map_err(at)?),
        Format::Npy => {
            if *selector != Selector::None {
                let nothing = "nothing (Selector::None)";
                return Err(at(wrong_selector("an .npy", nothing, selector)));
            }
            npy::read(&contents(path)?, "the array").map_err(at)
        }
        Format::Npz => {
            let member = variable(selector, "an .npz").map_err(at)?;
            npy::read_npz(&contents(path)?, member).map_err(at)
        }
        Format::Wav => {
            let channel = match selector {
                Selector::ChannelIndex(i) => Some(*i),
                Selector::None => None,
                other => return Err(at(wrong_selector("a WAV", "a channel index", other))),
            };
            wav::read(&contents(path)?, channel).map_err(at)
        }
        Format::Csv => {
            let column = match selector {
                Selector::Column(c) => Some(c),
                Selector::None => None,
                other => return Err(at(wrong_selector("a CSV", "a column name or index", other))),
            };
            csv::read(&contents(path)?, column).map_err(at)
        }
        Format::Mat => {
            let name = variable(selector, "a MAT").map_err(at)?;
            let bytes = contents(path)?;
            if mat::is_hdf5(&bytes) {
                // MAT v7.3 is HDF5: a struct is a group, its fields are members.
                let dataset = name.map(|v| v.replace('.', "/"));
                hdf5::read(path, dataset.as_deref())
            } else {
                mat::read(&bytes, name).map_err(at)
            }
        }
    }
}

/// The whole file's bytes.
fn contents(path: &Path) -> Result<Vec<u8>, ReadError> {
    std::fs::read(path).map_err(|e| ReadError::Unreadable {
        path: path.to_owned(),
        reason: e.to_string(),
    })
}

/// The variable name of a selector for a format that selects by name.
fn variable<'s>(selector: &'s Selector, file: &str) -> Result<Option<&'s str>, Fault> {
    match selector {
        Selector::Variable(v) => Ok(Some(v)),
        Selector::None => Ok(None),
        other => Err(wrong_selector(file, "a variable name", other)),
    }
}

/// The error for a selector of the wrong kind.
fn wrong_selector(file: &str, wants: &str, got: &Selector) -> Fault {
    let got = match got {
        Selector::Variable(v) => format!("variable `{v}`"),
        Selector::ChannelIndex(i) => format!("channel index {i}"),
        Selector::Column(ColumnRef::Name(n)) => format!("column `{n}`"),
        Selector::Column(ColumnRef::Index(i)) => format!("column index {i}"),
        Selector::None => "nothing".into(),
    };
    Fault::Select(format!("{file} file is selected by {wants}, not by {got}"))
}

/// Refuses empty or non-finite samples.
fn checked(path: &Path, loaded: Loaded) -> Result<Samples, ReadError> {
    if loaded.values.is_empty() {
        return Err(Fault::Empty(loaded.name).at(path));
    }
    if let Some(index) = loaded.values.iter().position(|v| !v.is_finite()) {
        return Err(ReadError::NonFinite {
            path: path.to_owned(),
            name: loaded.name,
            index,
            value: loaded.values[index],
        });
    }
    Ok(Samples {
        values: loaded.values,
        sample_rate: loaded.sample_rate,
    })
}

/// What a format's reader found: the samples and a name for them in messages.
#[derive(Debug)]
struct Loaded {
    /// The array, member, variable, column or channel, as messages name it.
    name: String,
    /// The samples, not yet checked for emptiness or finiteness.
    values: Vec<f64>,
    /// Hz, where the format records it.
    sample_rate: Option<f64>,
}

/// A reader's error before the file's path is attached ([`Fault::at`]).
#[derive(Debug, Clone, PartialEq)]
enum Fault {
    /// [`ReadError::Selection`].
    Select(String),
    /// [`ReadError::Shape`]: the array's name and shape.
    Shape(String, String),
    /// [`ReadError::Empty`]: the array's name.
    Empty(String),
    /// [`ReadError::Corrupt`].
    Corrupt(String),
    /// [`ReadError::Unsupported`].
    Unsupported(String),
}

impl Fault {
    /// The [`ReadError`] for the file at `path`.
    fn at(self, path: &Path) -> ReadError {
        let path = path.to_owned();
        match self {
            Self::Select(reason) => ReadError::Selection { path, reason },
            Self::Shape(name, shape) => ReadError::Shape { path, name, shape },
            Self::Empty(name) => ReadError::Empty { path, name },
            Self::Corrupt(reason) => ReadError::Corrupt { path, reason },
            Self::Unsupported(reason) => ReadError::Unsupported { path, reason },
        }
    }
}

/// `a, b, c`, or `nothing` for no names.
fn listed(names: &[String]) -> String {
    if names.is_empty() {
        "nothing".into()
    } else {
        names.join(", ")
    }
}
