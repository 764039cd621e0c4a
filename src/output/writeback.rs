//! A study file's bytes sent on to the disk while the run goes on.
//!
//! A run publishes its file only once every byte of it is on the disk: an `fsync`,
//! then the rename (`paths::rename_durably`). That `fsync` waits for every byte still
//! in the page cache, which for a short study is most of what its file costs (18 ms of
//! a 0.28 s run of 16 cases writing 25 MB, on this project's host, when all of it is
//! left to the end). So the writer starts the write-out of each case's chunks as soon
//! as they are in the file
//! (`sync_file_range(SYNC_FILE_RANGE_WRITE)`, which queues the dirty pages and
//! returns): the disk writes them while the next cases are computed, and the final
//! `fsync` waits for what is left, the last case and the file's metadata.
//!
//! Only a hint: it promises nothing (the `fsync` does), and where the call is missing
//! or refused nothing else changes.

use std::fs::File;
use std::path::Path;

/// Starts the write-out of ranges of one file.
#[derive(Debug)]
pub(super) struct Writeback {
    /// The file, opened for reading (none where it could not be).
    file: Option<File>,
}

impl Writeback {
    /// For the file at `path`, which must exist.
    pub(super) fn new(path: &Path) -> Self {
        Self {
            file: File::open(path).ok(),
        }
    }

    /// Starts writing `[offset, offset + len)` of the file to the disk, without
    /// waiting for it.
    pub(super) fn start(&self, offset: u64, len: u64) {
        if let Some(file) = &self.file {
            sync_range(file, offset, len);
        }
    }
}

/// Queues the dirty pages of `[offset, offset + len)` of `file` for writing.
#[cfg(target_os = "linux")]
fn sync_range(file: &File, offset: u64, len: u64) {
    use std::os::fd::AsRawFd;
    let (Ok(offset), Ok(len)) = (
        libc::off64_t::try_from(offset),
        libc::off64_t::try_from(len),
    ) else {
        return;
    };
    // SAFETY: the descriptor is open for the duration of the call, which only reads
    // its integer arguments. A failure leaves the pages to the final `fsync`.
    unsafe {
        libc::sync_file_range(file.as_raw_fd(), offset, len, libc::SYNC_FILE_RANGE_WRITE);
    }
}

/// No `sync_file_range` here: the final `fsync` writes everything.
#[cfg(not(target_os = "linux"))]
fn sync_range(_: &File, _: u64, _: u64) {}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// Starting the write-out of written, unwritten and out-of-range parts of a file
    /// leaves its contents and size as they are.
    #[test]
    fn starting_the_write_out_changes_nothing_in_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.bin");
        let mut f = File::create(&path).unwrap();
        f.write_all(&[7; 10_000]).unwrap();
        let w = Writeback::new(&path);
        assert!(w.file.is_some());
        w.start(0, 10_000);
        w.start(4_000, 100_000);
        w.start(u64::MAX - 1, 10);
        f.write_all(&[8; 10]).unwrap();
        w.start(10_000, 10);
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 10_010);
        assert!(bytes[..10_000].iter().all(|&b| b == 7) && bytes[10_000..].iter().all(|&b| b == 8));
        Writeback::new(&dir.path().join("missing.bin")).start(0, 10);
    }
}
