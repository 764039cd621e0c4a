//! Reading a damaged file must end in an error, never in a crash: a check of the file
//! in a child process before this process reads it.
//!
//! libhdf5 1.10 does not survive every damaged file. Variable-length strings are read
//! without it ([`text`](super::text)), but its own parsing of the file's metadata has
//! crashes of its own: one flipped byte in the root group's attribute storage makes
//! `H5Aiterate` free an attribute it never finished building (SIGSEGV in
//! `H5A__close`), and the same library reads every other structure (object headers,
//! B-trees, heaps) with as little checking. Such a crash takes the whole process with
//! it, and no in-process check can rule them all out.
//!
//! So [`check`] first does the reads in a forked child process: the child's crash or
//! endless loop is this process's error ("reading it crashes libhdf5"), the child's
//! error is left for this process to meet itself (the same calls on the same bytes
//! fail the same way), and a child that got through means the same reads here get
//! through too: the child is a copy of this process at the moment of the fork, so
//! libhdf5 starts from the same state, reads the same bytes and takes the same paths.
//! A child whose reads ended without an error has done what they check (every
//! checksum of the values read), so its caller need not read them again
//! ([`Checked::Passed`]).
//! The fork holds hdf5-metno's library lock, so no other thread is inside libhdf5 at
//! that moment (everything the reads initialise lazily is initialised under that lock
//! too); before the lock is let go the child closes every descriptor it inherited but
//! those on the file it checks (so it holds none of this process's locks on other
//! files when another thread reopens one), then does nothing but the reads, which open
//! their file anew, and leaves with `_exit`, so it flushes and closes nothing of this
//! process's files.
//!
//! The child has [`deadline`] to finish (`STUDYRUN_CHECK_TIMEOUT`, seconds, sets
//! another). Systems without `fork` read without the check.

use std::path::Path;
use std::time::Duration;

/// How a check ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Checked {
    /// The reads got through without an error: what they check holds.
    Passed,
    /// The reads failed with an error, which the caller meets by doing them itself
    /// (or, on a system without `fork`, were not checked).
    Survived,
    /// The reads crashed or did not end: what happened, for the message.
    Crashed(String),
}

/// The time a check of the file at `path` may take: `STUDYRUN_CHECK_TIMEOUT` seconds
/// if set, else 2 minutes plus 1 s per MB of the file when `per_byte` (reads of every
/// case), plain 2 minutes otherwise.
pub(super) fn deadline(path: &Path, per_byte: bool) -> Duration {
    if let Some(s) = std::env::var("STUDYRUN_CHECK_TIMEOUT")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
    {
        return Duration::from_secs_f64(s);
    }
    let mb = if per_byte {
        std::fs::metadata(path).map_or(0, |m| m.len() / 1_000_000)
    } else {
        0
    };
    Duration::from_secs(120 + mb)
}

/// Runs `reads` of `file` in a forked child process and says whether it survived
/// (see the module doc). Its result is not passed back: only whether it crashed.
/// `reads` runs only in the child, never in this process.
#[cfg(unix)]
pub(super) fn check<E>(
    timeout: Duration,
    file: &Path,
    reads: impl FnOnce() -> Result<(), E>,
) -> Checked {
    use std::os::unix::fs::MetadataExt;

    let file = std::fs::metadata(file).ok().map(|m| (m.dev(), m.ino()));
    let pid = spawn(file, reads);
    if pid < 0 {
        return Checked::Crashed(format!(
            "cannot start the process that checks it ({})",
            std::io::Error::last_os_error()
        ));
    }
    let status = match wait(pid, timeout) {
        Ok(status) => status,
        Err(reason) => return Checked::Crashed(reason),
    };
    if libc::WIFSIGNALED(status) {
        let signal = libc::WTERMSIG(status);
        return Checked::Crashed(format!(
            "reading it crashes libhdf5 ({}, in a process that checked it)",
            signal_name(signal)
        ));
    }
    match libc::WEXITSTATUS(status) {
        0 => Checked::Passed,
        1 => Checked::Survived,
        _ => Checked::Crashed("reading it panicked (in a process that checked it)".into()),
    }
}

/// Forks the child that runs `reads` (exit 0 if they succeed, 1 if they fail, 2 if
/// they panic) once it has closed what it inherited but the descriptors on `file`
/// (device, inode); returns its pid, or -1 if it could not be started.
///
/// The fork holds hdf5-metno's (reentrant) library lock, and the child never releases
/// it: no other thread was inside libhdf5 at the fork, and the child's own libhdf5
/// calls take the lock again without waiting (releasing it could mean waking a thread
/// that was waiting for it, which the child does not have).
#[cfg(unix)]
fn spawn<E>(file: Option<(u64, u64)>, reads: impl FnOnce() -> Result<(), E>) -> i32 {
    hdf5::sync::sync(|| {
        // The child says on this pipe when it has closed what it inherited; until then
        // this process keeps the library lock, so no thread of it opens or closes an
        // HDF5 file while the child still shares its descriptors and their locks.
        let mut pipe = [-1; 2];
        // SAFETY: `pipe` is a valid array of two descriptors to fill.
        if unsafe { libc::pipe(pipe.as_mut_ptr()) } != 0 {
            return -1;
        }
        let [r, w] = pipe;
        // SAFETY: fork in a process that may have other threads: the child only runs
        // `reads` (libhdf5 calls under the lock it holds, and memory allocation, which
        // glibc makes fork-safe) and leaves with `_exit`, which runs no exit handlers
        // and flushes no stdio or HDF5 buffers.
        let pid = unsafe { libc::fork() };
        if pid == 0 {
            // SAFETY: closing descriptors and writing to the pipe in the child only.
            unsafe {
                close_inherited(w, file);
                libc::write(w, [1u8].as_ptr().cast(), 1);
                libc::close(w);
            }
            let code = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(reads)) {
                Ok(Ok(())) => 0,
                Ok(Err(_)) => 1,
                Err(_) => 2,
            };
            // SAFETY: ends the child at once, see above.
            unsafe { libc::_exit(code) };
        }
        // SAFETY: our ends of the pipe; the read returns at the child's byte or, if it
        // never writes one (a failed fork, a child killed first), at end of file.
        unsafe {
            libc::close(w);
            if pid > 0 {
                let mut byte = 0u8;
                while libc::read(r, (&mut byte as *mut u8).cast(), 1) < 0
                    && std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted
                {
                }
            }
            libc::close(r);
        }
        pid
    })
}

/// Waits for the child `pid` for at most `timeout`: its wait status, or why there is
/// none (it was killed at the deadline, or waiting failed).
#[cfg(unix)]
fn wait(pid: i32, timeout: Duration) -> Result<i32, String> {
    let start = std::time::Instant::now();
    let mut status = 0;
    loop {
        // SAFETY: `pid` is our child; `status` is a valid out pointer.
        let r = unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) };
        if r == pid {
            return Ok(status);
        }
        if r < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return Err(format!("cannot wait for the process that checks it ({e})"));
        }
        if start.elapsed() > timeout {
            // SAFETY: `pid` is our child, not reaped yet.
            unsafe {
                libc::kill(pid, libc::SIGKILL);
                libc::waitpid(pid, &mut status, 0);
            }
            return Err(format!(
                "reading it with libhdf5 did not finish in {} s (set STUDYRUN_CHECK_TIMEOUT to wait longer)",
                timeout.as_secs_f64()
            ));
        }
        // Short sleeps first: most checks take milliseconds.
        let waited = start.elapsed();
        std::thread::sleep(Duration::from_millis(
            if waited < Duration::from_millis(50) {
                1
            } else {
                20
            },
        ));
    }
}

/// The descriptors [`close_inherited`] looks at one by one; those above are closed
/// whatever they are.
#[cfg(unix)]
const SCANNED_DESCRIPTORS: i32 = 1024;

/// Closes every descriptor the child inherited but `pipe` (and stdin, stdout, stderr)
/// and those open on `file` (device, inode): the others share this process's open
/// files and the HDF5 file locks (flock) on them, which a file this process closes
/// meanwhile would otherwise keep. Those on `file` stay, as libhdf5 reuses its open
/// file for the same inode: were they closed, the child's reads of a file this process
/// has open would fail at once (and check nothing); the locks they share are this
/// process's own on the file being checked. (`fstat`, `close`, `close_range`: all
/// async-signal-safe.)
///
/// # Safety
/// Only for a forked child, which uses none of the descriptors it closes.
#[cfg(unix)]
unsafe fn close_inherited(pipe: i32, file: Option<(u64, u64)>) {
    let close_range = |from: i32, to: i32| {
        if from <= to && libc::syscall(libc::SYS_close_range, from as u32, to as u32, 0u32) != 0 {
            for fd in from..=to.min(4095) {
                libc::close(fd);
            }
        }
    };
    for fd in 3..SCANNED_DESCRIPTORS {
        let mut st: libc::stat = std::mem::zeroed();
        let on_file = libc::fstat(fd, &mut st) == 0
            && file.is_some_and(|(dev, ino)| st.st_dev == dev && st.st_ino == ino);
        if fd != pipe && !on_file {
            libc::close(fd);
        }
    }
    let above = SCANNED_DESCRIPTORS;
    if pipe >= above {
        close_range(above, pipe - 1);
        close_range(pipe + 1, i32::MAX);
    } else {
        close_range(above, i32::MAX);
    }
}

/// Without `fork`: no check.
#[cfg(not(unix))]
pub(super) fn check<E>(
    _timeout: Duration,
    _file: &Path,
    _reads: impl FnOnce() -> Result<(), E>,
) -> Checked {
    Checked::Survived
}

#[cfg(unix)]
fn signal_name(signal: i32) -> String {
    let name = match signal {
        libc::SIGSEGV => "SIGSEGV",
        libc::SIGBUS => "SIGBUS",
        libc::SIGABRT => "SIGABRT",
        libc::SIGFPE => "SIGFPE",
        libc::SIGILL => "SIGILL",
        libc::SIGKILL => "SIGKILL",
        _ => "",
    };
    if name.is_empty() {
        format!("signal {signal}")
    } else {
        format!("signal {signal}, {name}")
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn a_crashing_child_is_reported_and_a_failing_one_told_from_a_passing_one() {
        let t = Duration::from_secs(30);
        assert_eq!(
            check(t, Path::new("/nonexistent"), || Ok::<(), ()>(())),
            Checked::Passed
        );
        assert_eq!(
            check(t, Path::new("/nonexistent"), || Err::<(), _>("an error")),
            Checked::Survived
        );
        let crashed = check(t, Path::new("/nonexistent"), || {
            // SAFETY: ends the (child) process with the signal a segfault gives (the
            // default action: Rust's stack-overflow handler would return from a raised
            // SIGSEGV, unlike from a real fault, which it hands back to the default).
            unsafe {
                libc::signal(libc::SIGSEGV, libc::SIG_DFL);
                libc::raise(libc::SIGSEGV);
            }
            Ok::<(), ()>(())
        });
        assert!(
            matches!(&crashed, Checked::Crashed(m) if m.contains("SIGSEGV")),
            "{crashed:?}"
        );
        let hung = check(
            Duration::from_millis(200),
            Path::new("/nonexistent"),
            || {
                std::thread::sleep(Duration::from_secs(60));
                Ok::<(), ()>(())
            },
        );
        assert!(
            matches!(&hung, Checked::Crashed(m) if m.contains("did not finish")),
            "{hung:?}"
        );
    }

    #[test]
    fn the_child_reads_a_file_this_process_holds_open() {
        // libhdf5 in the child reuses this process's open file for the same inode: its
        // descriptor must still be there, or the reads would fail and check nothing.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("held.h5");
        let values = [1.5, -2.0, 3.25];
        hdf5::File::create(&path)
            .and_then(|f| {
                f.new_dataset_builder()
                    .with_data(&values)
                    .create("x")
                    .map(|_| ())
            })
            .unwrap();
        let held = hdf5::File::open(&path).unwrap();
        let read = check(Duration::from_secs(30), &path, || {
            let got = hdf5::File::open(&path)
                .and_then(|f| f.dataset("x"))
                .and_then(|d| d.read_raw::<f64>())
                .expect("the child reads the file"); // a panic: Crashed
            assert_eq!(got, values);
            Ok::<(), ()>(())
        });
        assert_eq!(read, Checked::Passed);
        drop(held);
    }
}
