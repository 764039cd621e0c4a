//! One writer per output: every command that creates, replaces or removes the files
//! of a result file `OUT.h5` first holds an exclusive lock on `OUT.h5.lock`.
//!
//! The lock is the standard library's [`File::try_lock`] (`flock(2)` on Linux), which the kernel releases when the process dies, however
//! it dies, so a killed run never leaves a stale lock. The holder writes its pid
//! into the lock file for the message a second process prints. The lock file is
//! removed when the lock is released; a process that locked a file another process
//! removed meanwhile notices (the path no longer names the file it locked) and tries
//! again, so two processes never both believe they hold the lock.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use super::with_suffix;
use super::OutputError;

/// An exclusive hold on an output's files, released on drop.
#[derive(Debug)]
pub struct OutputLock {
    file: File,
    path: PathBuf,
}

impl OutputLock {
    /// Takes the lock of `output` (`OUT.h5.lock`) without waiting; refuses with
    /// [`OutputError::Locked`] naming the holder's pid when another process has it.
    pub fn acquire(output: &Path) -> Result<Self, OutputError> {
        let path = with_suffix(output, ".lock");
        loop {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(OutputError::io("create the lock file", &path))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let mut text = String::new();
                    let _ = file.read_to_string(&mut text);
                    return Err(OutputError::Locked {
                        output: output.to_path_buf(),
                        lock: path,
                        pid: text.trim().parse().unwrap_or(0),
                    });
                }
                Err(std::fs::TryLockError::Error(err)) => {
                    return Err(OutputError::io("lock", &path)(err))
                }
            }
            // The holder before us may have removed the file after we opened it.
            let same = match (file.metadata(), std::fs::metadata(&path)) {
                (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
                _ => false,
            };
            if !same {
                continue;
            }
            // A hard link would have the pid written into the file it shares.
            if file.metadata().is_ok_and(|m| m.nlink() > 1) {
                return Err(OutputError::Refused(format!(
                    "{} (the lock file) is a hard link to another file; studyrun writes \
                     through no links: remove it",
                    path.display()
                )));
            }
            let pid = format!("{}\n", std::process::id());
            file.set_len(0)
                .and_then(|()| file.seek(SeekFrom::Start(0)))
                .and_then(|_| file.write_all(pid.as_bytes()))
                .map_err(OutputError::io("write the lock file", &path))?;
            return Ok(Self { file, path });
        }
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Removed while still locked, so no other process can lock this file after
        // it is gone from the directory without noticing.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_the_same_output_is_refused_until_the_first_is_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.h5");
        let first = OutputLock::acquire(&out).unwrap();
        match OutputLock::acquire(&out) {
            Err(OutputError::Locked { pid, .. }) => assert_eq!(pid, std::process::id()),
            other => panic!("expected Locked, got {other:?}"),
        }
        drop(first);
        assert!(!with_suffix(&out, ".lock").exists());
        let again = OutputLock::acquire(&out).unwrap();
        drop(again);
    }

    #[test]
    fn a_hard_linked_lock_file_is_refused_and_its_file_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.h5");
        let mine = dir.path().join("mine.txt");
        std::fs::write(&mine, "my notes\n").unwrap();
        std::fs::hard_link(&mine, with_suffix(&out, ".lock")).unwrap();
        let e = OutputLock::acquire(&out).unwrap_err();
        assert!(e.to_string().contains("hard link"), "{e}");
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "my notes\n");
        let e = crate::output::overwrite::check_side_path(
            &with_suffix(&out, ".lock"),
            "the lock file",
            &[],
        )
        .unwrap_err();
        assert!(e.to_string().contains("hard link"), "{e}");
    }
}
