//! Progress of a running study: an indicatif bar on a terminal, plain log lines
//! (every 5 s and at the end) when stderr is not a terminal.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Reports cases done, rate, ETA and failures.
pub struct Progress {
    bar: Option<ProgressBar>,
    total: u64,
    done: u64,
    /// Cases done before this run started (resumed from the journal).
    already: u64,
    failed: u64,
    quiet: bool,
    start: Instant,
    last_log: Instant,
}

impl Progress {
    /// Starts reporting on `total` cases, `already` of them done before (resume).
    pub fn new(total: u64, already: u64, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template(
                    "{bar:40} {pos}/{len} cases  {per_sec}  ETA {eta}  {msg}",
                )
                .expect("valid template"),
            );
            bar.set_position(already);
            bar.reset_eta();
            bar
        });
        Self {
            bar,
            total,
            done: already,
            already,
            failed: 0,
            quiet,
            start: Instant::now(),
            last_log: Instant::now(),
        }
    }

    /// One more case finished (`failed` if it did not run to the end).
    pub fn case_done(&mut self, failed: bool) {
        self.done += 1;
        self.failed += u64::from(failed);
        match &self.bar {
            Some(bar) => {
                bar.set_position(self.done);
                if self.failed > 0 {
                    bar.set_message(format!("{} failed", self.failed));
                }
            }
            None if !self.quiet && self.last_log.elapsed() >= Duration::from_secs(5) => {
                self.last_log = Instant::now();
                self.log();
            }
            None => {}
        }
    }

    fn log(&self) {
        let secs = self.start.elapsed().as_secs_f64();
        let rate = (self.done - self.already) as f64 / secs.max(1e-9);
        let eta = (self.total - self.done) as f64 / rate.max(1e-9);
        // A full disk or a closed stderr must not stop the run: the line is dropped.
        let _ = writeln!(
            std::io::stderr(),
            "studyrun: {}/{} cases, {:.1} cases/s, ETA {:.0} s, {} failed, {:.1} s elapsed",
            self.done,
            self.total,
            rate,
            eta,
            self.failed,
            secs
        );
    }

    /// Ends the report.
    pub fn finish(&self) {
        match &self.bar {
            Some(bar) => bar.finish(),
            None if !self.quiet => self.log(),
            None => {}
        }
    }
}
