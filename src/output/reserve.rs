//! Disk blocks reserved ahead of the chunks a writer appends.
//!
//! A buffered write into blocks the file does not have yet costs the kernel more than
//! one into blocks already allocated: ext4 (like other delayed-allocation file systems)
//! accounts for every new block at write time. On this project's host, writing 100 kB
//! pieces cost 0.30 ms of CPU per MB into a growing file and 0.23 ms per MB into
//! blocks allocated beforehand (1 MB pieces: 0.20 and 0.14 ms). The study writer's
//! thread is the one serial part of a run, so it reserves the blocks its next chunks
//! will go to, [`STEP`] at a time, with `fallocate(FALLOC_FL_KEEP_SIZE)`: the blocks
//! are allocated past the end of the file, which keeps its size (the size is what a
//! crash journal records, and what readers see). Blocks left over past the end are
//! released when the file is finished.
//!
//! A reservation is only a hint: where `fallocate` is missing or refuses (another
//! operating system, a file system without it, a full disk), nothing is reserved and
//! the writes that follow allocate their blocks, or report the full disk, as before.

use std::fs::{File, OpenOptions};
use std::path::Path;

/// Bytes reserved at a time (past the end of what the chunks about to be written
/// need).
pub const STEP: u64 = 64 << 20;

/// Blocks reserved past the end of one file.
#[derive(Debug)]
pub(super) struct Reservation {
    /// The file, opened for writing (none where it could not be).
    file: Option<File>,
    /// End of the space reserved so far (bytes from the start of the file).
    end: u64,
}

impl Reservation {
    /// No reservation yet for the file at `path`, which must exist.
    pub(super) fn new(path: &Path) -> Self {
        Self {
            file: OpenOptions::new().write(true).open(path).ok(),
            end: 0,
        }
    }

    /// Makes sure the blocks of `[len, len + bytes)` are reserved, `len` being the
    /// file's size now: if they are not, reserves them and [`STEP`] beyond.
    pub(super) fn ahead(&mut self, len: u64, bytes: u64) {
        let need = len + bytes;
        if need <= self.end {
            return;
        }
        let from = self.end.max(len);
        if let Some(file) = &self.file {
            if keep_size_fallocate(file, from, need - from + STEP) {
                self.end = need + STEP;
                return;
            }
        }
        // Never ask again.
        self.file = None;
        self.end = u64::MAX;
    }

    /// Releases the blocks reserved past the end of the file, once it is closed:
    /// truncating a file to its own size frees the blocks past its end.
    pub(super) fn release(self) -> std::io::Result<()> {
        match self.file {
            Some(file) => file.set_len(file.metadata()?.len()),
            None => Ok(()),
        }
    }
}

/// Allocates `[offset, offset + len)` of `file` without changing its size; false
/// where that is not possible.
#[cfg(target_os = "linux")]
fn keep_size_fallocate(file: &File, offset: u64, len: u64) -> bool {
    use std::os::fd::AsRawFd;
    let (Ok(offset), Ok(len)) = (i64::try_from(offset), i64::try_from(len)) else {
        return false;
    };
    // SAFETY: the descriptor is open for writing for the duration of the call, which
    // only reads its integer arguments.
    unsafe { libc::fallocate(file.as_raw_fd(), libc::FALLOC_FL_KEEP_SIZE, offset, len) == 0 }
}

/// No `fallocate` here: nothing is reserved.
#[cfg(not(target_os = "linux"))]
fn keep_size_fallocate(_: &File, _: u64, _: u64) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use std::os::unix::fs::MetadataExt;

    /// Bytes the file's blocks take on disk.
    fn allocated(path: &Path) -> u64 {
        std::fs::metadata(path).unwrap().blocks() * 512
    }

    #[test]
    fn reserves_past_the_end_keeps_the_size_and_releases_what_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.bin");
        let mut f = File::create(&path).unwrap();
        f.write_all(&[7; 1000]).unwrap();
        let mut r = Reservation::new(&path);
        r.ahead(1000, 5000);
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 1000, "size kept");
        if cfg!(target_os = "linux") && r.file.is_some() {
            assert!(allocated(&path) >= 6000 + STEP, "{}", allocated(&path));
        }
        // Within the reservation: nothing more is asked.
        let end = r.end;
        r.ahead(4000, 1000);
        assert_eq!(r.end, end);
        f.write_all(&[8; 5000]).unwrap();
        drop(f);
        r.release().unwrap();
        assert_eq!(std::fs::read(&path).unwrap().len(), 6000, "data kept");
        assert!(
            allocated(&path) < 1 << 20,
            "released: {} bytes allocated",
            allocated(&path)
        );
    }

    #[test]
    fn a_file_that_cannot_be_opened_reserves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = Reservation::new(&dir.path().join("missing.bin"));
        r.ahead(0, 100);
        assert_eq!(r.end, u64::MAX);
        r.ahead(1 << 40, 100);
        r.release().unwrap();
    }
}
