//! The files that belong to one result file `OUT.h5`: the partial files a run
//! writes before the final rename, and the crash journal.

use std::path::{Path, PathBuf};

/// Which of the two partial files a journal's chunks lie in; a resumed run writes the
/// other one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataFile {
    /// `OUT.h5.partial`, where a fresh run writes.
    Partial,
    /// `OUT.h5.partial.resumed`.
    Resumed,
}

impl DataFile {
    /// What this partial file's name adds to the result file's.
    fn suffix(self) -> &'static str {
        match self {
            Self::Partial => ".partial",
            Self::Resumed => ".partial.resumed",
        }
    }

    /// The partial file of this name for the result file `output`.
    pub fn path(self, output: &Path) -> PathBuf {
        with_suffix(output, self.suffix())
    }

    /// The result file whose partial file `path` is, and which of the two it is;
    /// `None` when `path` names no partial file.
    pub fn output_of(path: &Path) -> Option<(PathBuf, Self)> {
        let name = path.to_str()?;
        [Self::Partial, Self::Resumed].into_iter().find_map(|d| {
            name.strip_suffix(d.suffix())
                .map(|output| (PathBuf::from(output), d))
        })
    }

    /// The other partial file: where a run resumed from this one writes.
    pub fn other(self) -> Self {
        match self {
            Self::Partial => Self::Resumed,
            Self::Resumed => Self::Partial,
        }
    }

    pub(crate) fn code(self) -> u8 {
        match self {
            Self::Partial => 0,
            Self::Resumed => 1,
        }
    }

    pub(crate) fn from_code(code: u8) -> Option<Self> {
        [Self::Partial, Self::Resumed]
            .into_iter()
            .find(|d| d.code() == code)
    }
}

/// `path` with `suffix` appended to its file name.
pub fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

/// The journal and partial-file paths that belong to `output` (the partial file a
/// fresh run writes; a resumed run may write [`DataFile::Resumed`]).
pub fn side_paths(output: &Path) -> (PathBuf, PathBuf) {
    (
        with_suffix(output, ".journal"),
        DataFile::Partial.path(output),
    )
}

/// Where a resume writes the journal that replaces `output`'s (`OUT.h5.journal.new`).
pub fn new_journal_path(output: &Path) -> PathBuf {
    with_suffix(output, ".journal.new")
}

/// Flushes the file at `path` to the disk (`fsync`).
pub fn sync_file(path: &Path) -> std::io::Result<()> {
    std::fs::File::open(path)?.sync_all()
}

/// Flushes the directory that holds `path` to the disk, so that a rename, creation
/// or removal of `path` outlives a power loss.
pub fn sync_parent(path: &Path) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match std::fs::File::open(dir)?.sync_all() {
        // File systems that cannot flush a directory (EINVAL) keep renames in order
        // without it.
        Err(e) if e.raw_os_error() == Some(libc::EINVAL) => Ok(()),
        other => other,
    }
}

/// Renames `from` to `to` so that `to` is whole on the disk before the rename and the
/// rename itself is on the disk when this returns: `fsync` of the file, `rename`,
/// `fsync` of the directory.
pub fn rename_durably(from: &Path, to: &Path) -> std::io::Result<()> {
    sync_file(from)?;
    std::fs::rename(from, to)?;
    sync_parent(to)
}

/// Removes the file at `path` and flushes its directory (a missing file is no error).
pub fn remove_durably(path: &Path) -> std::io::Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
        Ok(()) => sync_parent(path),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_partial_file_names_its_result_file() {
        for d in [DataFile::Partial, DataFile::Resumed] {
            let output = Path::new("runs/my study.h5");
            assert_eq!(
                DataFile::output_of(&d.path(output)),
                Some((output.to_path_buf(), d))
            );
        }
        assert_eq!(DataFile::output_of(Path::new("runs/out.h5")), None);
    }
}
