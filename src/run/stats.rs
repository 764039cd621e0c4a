//! Where a run's time goes: thread CPU time per activity, summed over the workers and
//! the writer thread, and how often a worker had to wait for the writer.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// CPU time consumed by the calling thread so far (s), from
/// `CLOCK_THREAD_CPUTIME_ID`; time spent blocked or descheduled does not count.
pub fn thread_cpu() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the call; the clock id is a
    // constant every Linux and macOS kernel supports.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return 0.0;
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// What a run spent its CPU time on (s, thread CPU time summed over threads) and how
/// the channel from the workers to the writer behaved.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunStats {
    /// Integrating and sampling the cases (workers), s.
    pub simulate: f64,
    /// Spectra (FFT) and metrics of the cases (workers), s.
    pub analysis: f64,
    /// Encoding chunks and journal records: float32 conversion, shuffle, deflate,
    /// checksum (workers), s.
    pub encode: f64,
    /// Sampling, spectra and metrics of the cases a worker handed over once
    /// integrated, while a core was left over for the writer (writer thread), s.
    pub analysis_writer: f64,
    /// Encoding the cases a worker handed over unencoded, while a core was left over
    /// for the writer (writer thread), s.
    pub encode_writer: f64,
    /// Appending records to the journal (writer thread), s.
    pub journal: f64,
    /// Creating the HDF5 file (layout, coordinates, parameters) and writing the
    /// reference runs (writer thread, while the workers run the first cases of a
    /// fresh run), s.
    pub create: f64,
    /// Writing the cases into the HDF5 file (writer thread), s.
    pub hdf5: f64,
    /// Flushing and closing the HDF5 file at the end (writer thread), s.
    pub finish: f64,
    /// Cases sent from the workers to the writer.
    pub sends: u64,
    /// Sends that found the channel full, so that a worker waited for the writer.
    pub blocked_sends: u64,
    /// Wall-clock time workers spent waiting on a full channel, s.
    pub send_wait: f64,
    /// Bytes of series and spectra as computed (8 per value).
    pub raw_bytes: u64,
    /// Bytes of the chunks written for them (after float32 conversion and deflate).
    pub stored_bytes: u64,
    /// Wall-clock time from the start of the run to the workers' start (s): deciding
    /// how to start and, for a resumed run, making its file and replaying the journal
    /// (a fresh run makes its file while the workers run).
    pub startup: f64,
    /// Wall-clock time the workers sat idle at the end, summed over the workers (s):
    /// from the moment each found no case left to the end of the last case.
    pub tail_idle: f64,
}

impl RunStats {
    /// CPU time of the output side: spectra, metrics, encoding, journal, HDF5 (s).
    pub fn output(&self) -> f64 {
        self.analysis
            + self.encode
            + self.encode_writer
            + self.journal
            + self.create
            + self.hdf5
            + self.finish
    }

    /// CPU time of everything measured (s).
    pub fn total(&self) -> f64 {
        self.simulate + self.output()
    }

    /// Share of the measured CPU time spent on the output side (0–1).
    pub fn output_share(&self) -> f64 {
        self.output() / self.total().max(f64::MIN_POSITIVE)
    }

    /// Share of the measured CPU time spent on the spectra, metrics and the HDF5
    /// file (encoding, creating, writing, closing): the output side without the
    /// crash journal's append (0–1).
    pub fn file_and_spectra_share(&self) -> f64 {
        (self.output() - self.journal) / self.total().max(f64::MIN_POSITIVE)
    }
}

impl std::fmt::Display for RunStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let per_case = |s: f64| 1e3 * s / (self.sends.max(1) as f64);
        writeln!(f, "thread CPU time           total s   ms/case")?;
        for (name, s) in [
            ("simulate (workers)", self.simulate),
            ("spectra+metrics (workers)", self.analysis),
            ("encode (workers)", self.encode),
            ("samples+spectra (writer)", self.analysis_writer),
            ("encode (writer)", self.encode_writer),
            ("journal (writer)", self.journal),
            ("create file (writer)", self.create),
            ("hdf5 (writer)", self.hdf5),
            ("finish (writer)", self.finish),
        ] {
            writeln!(f, "  {name:<26}{s:>9.3} {:>9.3}", per_case(s))?;
        }
        writeln!(
            f,
            "output share of CPU time: {:.1} % ({:.1} % without the journal's append)",
            100.0 * self.output_share(),
            100.0 * self.file_and_spectra_share()
        )?;
        writeln!(
            f,
            "stored {:.1} MB of {:.1} MB raw (ratio {:.2})",
            self.stored_bytes as f64 / 1e6,
            self.raw_bytes as f64 / 1e6,
            self.raw_bytes as f64 / (self.stored_bytes.max(1) as f64)
        )?;
        writeln!(
            f,
            "channel: {} sends, {} found it full ({:.3} s waiting)",
            self.sends, self.blocked_sends, self.send_wait
        )?;
        write!(
            f,
            "wall: workers started after {:.1} ms; idle at the end {:.1} ms (summed over workers)",
            1e3 * self.startup,
            1e3 * self.tail_idle
        )
    }
}

/// Worker-side tallies, shared by every worker thread.
#[derive(Debug, Default)]
pub(super) struct WorkerTally {
    simulate_ns: AtomicU64,
    analysis_ns: AtomicU64,
    encode_ns: AtomicU64,
    writer_analysis_ns: AtomicU64,
    writer_encode_ns: AtomicU64,
    blocked_sends: AtomicU64,
    send_wait_ns: AtomicU64,
    /// Over the workers, the sum and the latest of the moments each found no case
    /// left (ns since the run's start), and the number of workers.
    out_of_cases_ns: AtomicU64,
    last_out_of_cases_ns: AtomicU64,
    workers: AtomicU64,
}

/// Seconds as whole nanoseconds, for the atomic tallies.
fn nanos(seconds: f64) -> u64 {
    (seconds * 1e9).round().max(0.0) as u64
}

impl WorkerTally {
    /// One case computed: simulation, analysis and encoding CPU time (s).
    pub(super) fn case(&self, simulate: f64, analysis: f64, encode: f64) {
        self.simulate_ns
            .fetch_add(nanos(simulate), Ordering::Relaxed);
        self.analysis_ns
            .fetch_add(nanos(analysis), Ordering::Relaxed);
        self.encode_ns.fetch_add(nanos(encode), Ordering::Relaxed);
    }

    /// One case handed over to the writer: its analysis (0 when its worker did it)
    /// and encoding CPU time on the writer (s).
    pub(super) fn finished_by_writer(&self, analysis: f64, encode: f64) {
        self.writer_analysis_ns
            .fetch_add(nanos(analysis), Ordering::Relaxed);
        self.writer_encode_ns
            .fetch_add(nanos(encode), Ordering::Relaxed);
    }

    /// One send found the channel full and waited `waited`.
    pub(super) fn blocked(&self, waited: Duration) {
        self.blocked_sends.fetch_add(1, Ordering::Relaxed);
        self.send_wait_ns
            .fetch_add(waited.as_nanos() as u64, Ordering::Relaxed);
    }

    /// A worker found no case left, `at` after the run's start.
    pub(super) fn out_of_cases(&self, at: Duration) {
        let at = at.as_nanos() as u64;
        self.out_of_cases_ns.fetch_add(at, Ordering::Relaxed);
        self.last_out_of_cases_ns.fetch_max(at, Ordering::Relaxed);
        self.workers.fetch_add(1, Ordering::Relaxed);
    }

    /// Adds the tallies into `stats`.
    pub(super) fn add_to(&self, stats: &mut RunStats) {
        let workers = self.workers.load(Ordering::Relaxed);
        let last = self.last_out_of_cases_ns.load(Ordering::Relaxed);
        let sum = self.out_of_cases_ns.load(Ordering::Relaxed);
        stats.tail_idle += (workers * last).saturating_sub(sum) as f64 * 1e-9;
        let s = |a: &AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
        stats.simulate += s(&self.simulate_ns);
        stats.analysis += s(&self.analysis_ns);
        stats.encode += s(&self.encode_ns);
        stats.analysis_writer += s(&self.writer_analysis_ns);
        stats.encode_writer += s(&self.writer_encode_ns);
        stats.blocked_sends += self.blocked_sends.load(Ordering::Relaxed);
        stats.send_wait += s(&self.send_wait_ns);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tail_idle_sums_each_workers_wait_for_the_last() {
        let tally = WorkerTally::default();
        for ms in [25, 10, 19] {
            tally.out_of_cases(Duration::from_millis(ms));
        }
        let mut stats = RunStats::default();
        tally.add_to(&mut stats);
        // (25 - 25) + (25 - 10) + (25 - 19) ms.
        assert!(
            (stats.tail_idle - 0.021).abs() < 1e-12,
            "{}",
            stats.tail_idle
        );
    }

    #[test]
    fn one_worker_never_waits_at_the_end() {
        let tally = WorkerTally::default();
        tally.out_of_cases(Duration::from_millis(640));
        let mut stats = RunStats::default();
        tally.add_to(&mut stats);
        assert_eq!(stats.tail_idle, 0.0);
    }
}
