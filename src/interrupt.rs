//! What a run stopped by SIGINT, SIGTERM or SIGHUP (Ctrl-C, `kill`, a closed terminal)
//! says on its way out: that the finished cases are kept and how to continue. The
//! process then dies of the signal as it would without the note (exit status 130,
//! 143, 129 in a shell), so job schedulers and scripts see the same thing.

use std::path::Path;
use std::sync::OnceLock;

use studyrun::study::Shard;

/// The note, written by the handler with one `write(2)`.
static NOTE: OnceLock<Vec<u8>> = OnceLock::new();

/// The signals that stop a run and get the note.
const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

/// From now on, a stop by one of [`SIGNALS`] first writes a note on the run of `grid`
/// (shard `shard`) into `output` to standard error. Call once, before the run starts
/// its threads.
pub fn note_on_stop(grid: &Path, output: &Path, shard: Option<Shard>) {
    let text = format!(
        "\nstudyrun: stopped by a signal; the cases finished so far are kept beside {}: \
         `studyrun {} -o {}{} --resume` continues the run\n",
        output.display(),
        grid.display(),
        output.display(),
        shard.map_or(String::new(), |s| format!(" --shard {s}"))
    );
    if NOTE.set(text.into_bytes()).is_err() {
        return;
    }
    for signal in SIGNALS {
        // SAFETY: `on_signal` only calls async-signal-safe functions (write, signal,
        // raise) and reads `NOTE`, which is set before the handler is installed and
        // never changed.
        unsafe { libc::signal(signal, on_signal as *const () as libc::sighandler_t) };
    }
}

/// Writes the note, restores the signal's default action and raises it again.
extern "C" fn on_signal(signal: libc::c_int) {
    if let Some(note) = NOTE.get() {
        // SAFETY: a write of an initialised buffer of its own length to fd 2.
        unsafe { libc::write(2, note.as_ptr().cast(), note.len()) };
    }
    // SAFETY: async-signal-safe calls; the default action ends the process.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        libc::raise(signal);
    }
}
