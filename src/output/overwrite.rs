//! Nothing replaced that is not ours: the checks every command makes before it
//! writes, replaces or removes a file at a path the user named.
//!
//! - an output (and its side files: journal, partial files, lock) is a regular file
//!   or nothing: never a directory, a FIFO, a device, a socket or a symbolic link
//!   (whatever it points to), with or without `--force`; a side file is no hard link
//!   either (it is written in place);
//! - it is none of the command's inputs (the grid file, a shard), compared by device
//!   and inode, so another spelling of the same path is caught;
//! - `--force` replaces only a studyrun study file (an HDF5 file with the
//!   `studyrun_file_format` root attribute, of any format version, read as
//!   [`StudyReader::open`](crate::output::StudyReader::open) reads it: first in a
//!   child process, so that a file that crashes libhdf5 is refused, not the command);
//!   anything else is refused and left as it is. Nothing else of the file is read: the
//!   check costs the same for a file of any size.

use std::fs::Metadata;
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::Path;

use super::guard::{self, Checked};
use super::reader::{check_format_version, damaged, open_hdf5};
use super::OutputError;
use crate::output::StudyFileError;

/// What kind of thing `m` is, for messages.
fn kind(m: &Metadata) -> &'static str {
    let t = m.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "a regular file"
    }
}

/// Checks what is at `path`, a file a command is about to create, replace or remove:
/// nothing, or a regular file that is none of `inputs`. Returns whether a regular file
/// is there. `what` names the path's role in messages (`the output`, `the journal`).
pub fn check_path(path: &Path, what: &str, inputs: &[&Path]) -> Result<bool, OutputError> {
    let m = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(OutputError::io("inspect", path)(e)),
    };
    let t = m.file_type();
    if t.is_symlink() {
        let target = std::fs::read_link(path)
            .map(|t| format!(" to {}", t.display()))
            .unwrap_or_default();
        return Err(OutputError::Refused(format!(
            "{} ({what}) is a symbolic link{target}; studyrun neither writes through nor \
             replaces links: give the path of a regular file",
            path.display()
        )));
    }
    if !t.is_file() {
        return Err(OutputError::Refused(format!(
            "{} ({what}) is {}, not a regular file; studyrun writes regular files only and \
             replaces nothing else{}",
            path.display(),
            kind(&m),
            if t.is_dir() {
                ": give the result file's path"
            } else {
                ""
            }
        )));
    }
    for input in inputs {
        if let Ok(i) = std::fs::metadata(input) {
            if i.dev() == m.dev() && i.ino() == m.ino() {
                return Err(OutputError::Refused(format!(
                    "{} ({what}) is the input {} itself; choose another output",
                    path.display(),
                    input.display()
                )));
            }
        }
    }
    Ok(true)
}

/// Checks that the regular file at `output` is a studyrun study file, the only kind
/// `--force` replaces.
pub fn check_replaceable(output: &Path) -> Result<(), OutputError> {
    match identify(output) {
        // One of an older or newer studyrun is a study file too.
        Ok(_) | Err(StudyFileError::Version { .. }) => Ok(()),
        Err(e) => Err(OutputError::Refused(format!(
            "{} is not a studyrun result file, and --force replaces only those ({}); \
             nothing was changed: remove it yourself if you mean to, or choose another output",
            output.display(),
            first_line(&e.to_string())
        ))),
    }
}

/// [`check_path`] for a file beside an output that a command writes in place (journal,
/// partial files, lock): also refuses a hard link, whose other names would see the
/// writes.
pub fn check_side_path(path: &Path, what: &str, inputs: &[&Path]) -> Result<bool, OutputError> {
    let exists = check_path(path, what, inputs)?;
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.nlink() > 1 => Err(OutputError::Refused(format!(
            "{} ({what}) is a hard link ({} names share the file); studyrun writes through \
             no links: remove it or give another output",
            path.display(),
            m.nlink()
        ))),
        _ => Ok(exists),
    }
}

/// Checks `output` for a command that writes it from scratch (`merge`, `accuracy`):
/// refuses what [`check_path`] refuses, an existing file without `force`, and with
/// `force` anything but a study file. Returns whether a file is there to replace.
pub fn check_output(output: &Path, force: bool, inputs: &[&Path]) -> Result<bool, OutputError> {
    let exists = check_path(output, "the output", inputs)?;
    for (side, what) in side_files(output) {
        check_side_path(&side, what, inputs)?;
    }
    if exists {
        if !force {
            return Err(OutputError::Refused(format!(
                "{} exists; use --force to overwrite it",
                output.display()
            )));
        }
        check_replaceable(output)?;
    }
    Ok(exists)
}

/// The files that belong to the result file `output`, with their roles.
pub fn side_files(output: &Path) -> [(std::path::PathBuf, &'static str); 5] {
    use super::{new_journal_path, side_paths, with_suffix, DataFile};
    let (journal, _) = side_paths(output);
    [
        (journal, "the journal"),
        (new_journal_path(output), "the new journal"),
        (DataFile::Partial.path(output), "the partial file"),
        (DataFile::Resumed.path(output), "the resumed partial file"),
        (with_suffix(output, ".lock"), "the lock file"),
    ]
}

/// Whether `path` is a study file of this format version (a study file of another
/// gives [`StudyFileError::Version`]): its format attribute read in a child process
/// ([`guard::check`]), and here only if the child's read failed, for the error.
fn identify(path: &Path) -> Result<(), StudyFileError> {
    let read = || open_hdf5(path).and_then(|file| check_format_version(&file, path));
    match guard::check(guard::deadline(path, false), path, read) {
        Checked::Passed => Ok(()),
        Checked::Survived => read(),
        Checked::Crashed(reason) => Err(damaged(path, reason)),
    }
}

/// The first line of `text` (HDF5 errors can run over several).
fn first_line(text: &str) -> &str {
    text.lines().next().unwrap_or(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_that_are_not_inputs_pass() {
        let dir = tempfile::tempdir().unwrap();
        let grid = dir.path().join("g.yaml");
        std::fs::write(&grid, "x").unwrap();
        assert!(!check_path(&dir.path().join("new.h5"), "the output", &[&grid]).unwrap());
        assert!(check_path(&dir.path().join("g.yaml"), "the output", &[]).unwrap());
        let e = check_path(&dir.path().join("./g.yaml"), "the output", &[&grid]).unwrap_err();
        assert!(e.to_string().contains("is the input"), "{e}");
        let e = check_path(dir.path(), "the output", &[]).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        std::os::unix::fs::symlink(&grid, dir.path().join("link.h5")).unwrap();
        let e = check_path(&dir.path().join("link.h5"), "the output", &[]).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        let e = check_replaceable(&grid).unwrap_err();
        assert!(e.to_string().contains("not a studyrun result file"), "{e}");
        assert_eq!(std::fs::read_to_string(&grid).unwrap(), "x");
    }
}
