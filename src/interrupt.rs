//! What a run stopped by SIGINT, SIGTERM or SIGHUP (Ctrl-C, `kill`, a closed terminal)
//! says on its way out: that the finished cases are kept and how to continue, or, if
//! its journal did not exist yet, that nothing was recorded. The process then dies of
//! the signal as it would without the note (exit status 130, 143, 129 in a shell), so
//! job schedulers and scripts see the same thing.

use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::sync::OnceLock;

use studyrun::output::shell_word;
use studyrun::study::Shard;

/// What the handler needs, prepared before it is installed: the journal's path and
/// the two notes, each written with one `write(2)`.
struct Notes {
    /// The run's journal: once it exists, cases are being recorded.
    journal: CString,
    /// The note once the journal exists.
    resume: Vec<u8>,
    /// The note before it does.
    again: Vec<u8>,
}

static NOTES: OnceLock<Notes> = OnceLock::new();

/// The signals that stop a run and get the note.
const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

/// From now on, a stop by one of [`SIGNALS`] first writes a note on the run of `grid`
/// (shard `shard`) into `output` to standard error. Call once, before the run starts
/// its threads.
pub fn note_on_stop(grid: &Path, output: &Path, shard: Option<Shard>) {
    let resume = format!(
        "\nstudyrun: stopped by a signal; the cases finished so far are kept beside {}: \
         `studyrun {} -o {}{} --resume` continues the run\n",
        output.display(),
        shell_word(&grid.to_string_lossy()),
        shell_word(&output.to_string_lossy()),
        shard.map_or(String::new(), |s| format!(" --shard {s}"))
    );
    let again = "\nstudyrun: stopped by a signal before the run recorded anything; \
                 run the same command again\n";
    let (journal, _) = studyrun::output::side_paths(output);
    let Ok(journal) = CString::new(journal.as_os_str().as_bytes()) else {
        return;
    };
    let notes = Notes {
        journal,
        resume: resume.into_bytes(),
        again: again.as_bytes().to_vec(),
    };
    if NOTES.set(notes).is_err() {
        return;
    }
    for signal in SIGNALS {
        // SAFETY: `on_signal` only calls async-signal-safe functions (access, write,
        // signal, raise) and reads `NOTES`, which is set before the handler is
        // installed and never changed.
        unsafe { libc::signal(signal, on_signal as *const () as libc::sighandler_t) };
    }
}

/// Writes the note that fits (`access(2)` tells whether the journal exists),
/// restores the signal's default action and raises it again.
extern "C" fn on_signal(signal: libc::c_int) {
    if let Some(notes) = NOTES.get() {
        // SAFETY: `access` and `write` are async-signal-safe; the path is a valid C
        // string and the note an initialised buffer of its own length.
        unsafe {
            let recorded = libc::access(notes.journal.as_ptr(), libc::F_OK) == 0;
            let note = if recorded {
                &notes.resume
            } else {
                &notes.again
            };
            libc::write(2, note.as_ptr().cast(), note.len());
        }
    }
    // SAFETY: async-signal-safe calls; the default action ends the process.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        libc::raise(signal);
    }
}
