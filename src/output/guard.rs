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
//! The fork holds hdf5-metno's library lock, so no other thread is inside libhdf5 at
//! that moment (everything the reads initialise lazily is initialised under that lock
//! too); the child does nothing but the reads and leaves with `_exit`, so it flushes
//! and closes nothing of this process's files.
//!
//! The child has [`deadline`] to finish (`STUDYRUN_CHECK_TIMEOUT`, seconds, sets
//! another). Systems without `fork` read without the check.

use std::path::Path;
use std::time::Duration;

/// How a check ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Checked {
    /// The reads got through (or failed with an error, which the caller will meet).
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

/// Runs `reads` in a forked child process and says whether it survived (see the
/// module doc). Its result is not passed back: only whether it crashed. `reads` runs
/// only in the child, never in this process.
#[cfg(unix)]
pub(super) fn check<E>(timeout: Duration, reads: impl FnOnce() -> Result<(), E>) -> Checked {
    use std::time::Instant;

    // The fork holds hdf5-metno's (reentrant) library lock, and the child never
    // releases it: no other thread was inside libhdf5 at the fork, and the child's own
    // libhdf5 calls take the lock again without waiting (releasing it could mean waking
    // a thread that was waiting for it, which the child does not have).
    let pid = hdf5::sync::sync(|| {
        // SAFETY: fork in a process that may have other threads: the child only runs
        // `reads` (libhdf5 calls under the lock it holds, and memory allocation, which
        // glibc makes fork-safe) and leaves with `_exit`, which runs no exit handlers
        // and flushes no stdio or HDF5 buffers.
        let pid = unsafe { libc::fork() };
        if pid == 0 {
            let code = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(reads)) {
                Ok(Ok(())) => 0,
                Ok(Err(_)) => 1,
                Err(_) => 2,
            };
            // SAFETY: ends the child at once, see above.
            unsafe { libc::_exit(code) };
        }
        pid
    });
    if pid < 0 {
        return Checked::Crashed(format!(
            "cannot start the process that checks it ({})",
            std::io::Error::last_os_error()
        ));
    }
    let start = Instant::now();
    let mut status = 0;
    loop {
        // SAFETY: `pid` is our child; `status` is a valid out pointer.
        let r = unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) };
        if r == pid {
            break;
        }
        if r < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return Checked::Crashed(format!("cannot wait for the process that checks it ({e})"));
        }
        if start.elapsed() > timeout {
            // SAFETY: `pid` is our child, not reaped yet.
            unsafe {
                libc::kill(pid, libc::SIGKILL);
                libc::waitpid(pid, &mut status, 0);
            }
            return Checked::Crashed(format!(
                "reading it with libhdf5 did not finish in {} s (set STUDYRUN_CHECK_TIMEOUT to wait longer)",
                timeout.as_secs_f64()
            ));
        }
        let waited = start.elapsed();
        // Short sleeps first: most checks take milliseconds.
        std::thread::sleep(Duration::from_millis(
            if waited < Duration::from_millis(50) {
                1
            } else {
                20
            },
        ));
    }
    if libc::WIFSIGNALED(status) {
        let signal = libc::WTERMSIG(status);
        return Checked::Crashed(format!(
            "reading it crashes libhdf5 ({}, in a process that checked it)",
            signal_name(signal)
        ));
    }
    match libc::WEXITSTATUS(status) {
        0 | 1 => Checked::Survived,
        _ => Checked::Crashed("reading it panicked (in a process that checked it)".into()),
    }
}

/// Without `fork`: no check.
#[cfg(not(unix))]
pub(super) fn check<E>(_timeout: Duration, _reads: impl FnOnce() -> Result<(), E>) -> Checked {
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
    fn a_crashing_child_is_reported_and_a_surviving_one_is_not() {
        let t = Duration::from_secs(30);
        assert_eq!(check(t, || Ok::<(), ()>(())), Checked::Survived);
        assert_eq!(check(t, || Err::<(), _>("an error")), Checked::Survived);
        let crashed = check(t, || {
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
        let hung = check(Duration::from_millis(200), || {
            std::thread::sleep(Duration::from_secs(60));
            Ok::<(), ()>(())
        });
        assert!(
            matches!(&hung, Checked::Crashed(m) if m.contains("did not finish")),
            "{hung:?}"
        );
    }
}
