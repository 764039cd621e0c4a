//! Running a study: cases in parallel (rayon), one writer (the HDF5 library is not
//! thread-safe), bounded memory, a crash journal, resume, shards and merging.
//!
//! Data flow: workers (a rayon pool) take cases one at a time, the costliest first
//! ([`order`]), simulate them, compute spectra and metrics, encode the series
//! and spectra into the chunks the file stores (float32 conversion, shuffle, deflate)
//! with their checksums ([`JournalRecord::encode`]), and send the records through a
//! bounded channel; the calling thread copies each case's chunks into `OUT.h5.partial`
//! (HDF5 direct chunk write), appends to the journal where they went, and reports
//! progress. At the end the partial file is renamed to `OUT.h5` (atomic) and the
//! journal removed. A resumed run replays the journal into the other partial file
//! ([`DataFile`]). Case data do not depend on the number of threads: each case is simulated
//! and encoded on its own, in one thread. [`RunStats`] says where the time went.

mod case;
mod journal;
mod order;
mod progress;
mod stats;

pub use case::{run_case, CaseCost, CaseResult};
pub use journal::{
    JournalEntry, JournalError, JournalHeader, JournalReader, JournalRecord, JournalWriter,
};
pub use stats::RunStats;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, SendError, SyncSender, TrySendError};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rayon::prelude::*;

use crate::output::{
    new_journal_path, side_paths, study_layout, ChunkEncoder, DataFile, Status, StudyFingerprint,
    StudyWriter, REFERENCE_CHANNELS,
};
use crate::signal::spectrum::{SpectrumPlan, Window};
use crate::simulate::{simulate, CaseOutput};
use crate::study::Shard;
use crate::study::Study;

/// How to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The result file.
    pub output: PathBuf,
    /// Worker threads (≥ 1).
    pub jobs: usize,
    /// Continue an interrupted run from its journal.
    pub resume: bool,
    /// Overwrite an existing result file (and discard a journal).
    pub force: bool,
    /// Run only this shard.
    pub shard: Option<Shard>,
    /// No progress output.
    pub quiet: bool,
}

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Cases in this run (the shard, or the whole study).
    pub cases: usize,
    /// Cases that ran to the end.
    pub ok: usize,
    /// Cases that failed (recorded in the file with their message).
    pub failed: usize,
    /// Cases taken from the journal of an interrupted run.
    pub resumed: usize,
    /// Cases the journal of an interrupted run recorded but whose chunks were not
    /// found intact in its partial file: run again.
    pub rerun: usize,
    /// Wall-clock time (s).
    pub wall_time: f64,
    /// Where the CPU time went and whether the workers waited for the writer.
    pub stats: RunStats,
}

/// What a scoped thread returned; its panic goes on in this thread.
fn joined<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

/// Removes the file at `path` if there is one.
fn remove_if_exists(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("cannot remove {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// The ideal-mechanism runs every case is compared with.
pub fn run_references(study: &Study) -> Result<Vec<CaseOutput>> {
    study
        .references
        .par_iter()
        .enumerate()
        .map(|(k, r)| {
            simulate(r, &study.solver, &study.sampling)
                .with_context(|| format!("reference (ideal mechanism) {k} at {} rpm", r.rpm))
        })
        .collect()
}

/// The spectrum window of a study.
pub fn window_of(study: &Study) -> Window {
    if study.window == "rectangular" {
        Window::Rectangular
    } else {
        Window::Hann
    }
}

/// Runs `study` (or a shard of it) into `opts.output`.
pub fn run(study: &Study, opts: &RunOptions) -> Result<RunSummary> {
    let start = Instant::now();
    let rows: Vec<usize> = match opts.shard {
        Some(s) => study.shard(s.k, s.n),
        None => (0..study.cases.len()).collect(),
    };
    if rows.is_empty() {
        bail!(
            "shard {} of a {}-case study has no cases",
            opts.shard.map_or(String::new(), |s| s.to_string()),
            study.cases.len()
        );
    }
    let (journal_path, _) = side_paths(&opts.output);
    let new_journal_path = new_journal_path(&opts.output);
    if opts.output.is_dir() {
        bail!(
            "{} is a directory; give the result file's path",
            opts.output.display()
        );
    }
    // With `--force` the old result file is removed while the file is created (below).
    if opts.force {
        let partials = [DataFile::Partial, DataFile::Resumed].map(|d| d.path(&opts.output));
        for p in [&journal_path, &new_journal_path]
            .into_iter()
            .chain(&partials)
        {
            remove_if_exists(p)?;
        }
    } else if opts.output.exists() {
        bail!(
            "{} exists; use --force to overwrite it",
            opts.output.display()
        );
    } else if journal_path.exists() && !opts.resume {
        bail!(
            "{} holds an interrupted run; use --resume to continue it or --force to start over",
            journal_path.display()
        );
    } else if opts.resume && !journal_path.exists() {
        bail!(
            "nothing to resume: {} does not exist",
            journal_path.display()
        );
    }

    let layout = study_layout(study, &rows)?;
    let header = JournalHeader {
        fingerprint: StudyFingerprint::of(study, opts.shard).0,
        n_time: layout.times.len() as u64,
        n_series: layout.series.len() as u64,
        n_freq: layout.frequencies.len() as u64,
        n_spectra: layout.spectra.len() as u64,
        n_metrics: layout.metrics.len() as u64,
        storage: layout.storage,
    };
    let raw_per_case = 8 * (header.n_series * header.n_time + header.n_spectra * header.n_freq);
    let mut stats = RunStats::default();
    let reader = if opts.resume {
        Some(JournalReader::open(&journal_path, &header)?)
    } else {
        None
    };
    // A resumed run writes the other partial file than the one the journal's cases
    // are in.
    let data = reader
        .as_ref()
        .map_or(DataFile::Partial, |r| r.data_file().other());
    let partial_path = data.path(&opts.output);
    // The ideal references run, and with `--force` the old result file is unlinked
    // (milliseconds for a large file), while the file is created; both are done
    // before the journal exists, so a kill cannot leave a journal beside an old result.
    let cpu = thread_cpu();
    let (references, writer, removed) = std::thread::scope(|scope| {
        let references = scope.spawn(|| run_references(study));
        let removed = opts
            .force
            .then(|| scope.spawn(|| remove_if_exists(&opts.output)));
        let writer = StudyWriter::create(&partial_path, &layout)
            .with_context(|| format!("cannot create {}", partial_path.display()));
        (joined(references), writer, removed.map_or(Ok(()), joined))
    });
    removed?;
    let (references, mut writer) = (references?, writer?);
    for (k, r) in references.iter().enumerate() {
        let series: Vec<&[f64]> = REFERENCE_CHANNELS
            .iter()
            .map(|c| r.channel(c).expect("reference channel"))
            .collect();
        writer.write_reference(k, &series)?;
    }
    stats.create = thread_cpu() - cpu;

    // Replay what an interrupted run finished.
    let (mut journal, replayed) = match reader {
        Some(reader) => replay(reader, &opts.output, &header, &mut writer, rows.len())?,
        None => (
            JournalWriter::create(&journal_path, &header, data)
                .with_context(|| format!("cannot create {}", journal_path.display()))?,
            Replayed::default(),
        ),
    };
    let Replayed {
        done,
        journaled,
        mut ok,
        mut failed,
    } = replayed;
    let resumed = done.len();
    let mut pending: Vec<usize> = (0..rows.len()).filter(|r| !done.contains(r)).collect();
    dispatch_order(study, &rows, &mut pending);

    let mut progress = Progress::new(rows.len() as u64, resumed as u64, opts.quiet);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs.max(1))
        .build()?;
    let n_window = study.analysis_window().len();
    let window = window_of(study);
    let storage = layout.storage;
    // At most two records per worker wait for the writer: memory stays bounded.
    let (tx, rx) = sync_channel::<Box<JournalRecord>>(2 * opts.jobs.max(1));
    let tally = WorkerTally::default();
    let n_pending = pending.len();
    let (rows_ref, refs, tally_ref) = (&rows, &references, &tally);
    stats.startup = start.elapsed().as_secs_f64();
    let received = std::thread::scope(|scope| -> Result<usize> {
        // The workers own the sender: when they end, normally or not, the channel closes.
        scope.spawn(move || {
            // Every worker takes the next case of `pending` until none is left or the
            // writer is gone.
            let next = AtomicUsize::new(0);
            pool.broadcast(|_| {
                let mut plan = SpectrumPlan::new(n_window, window)
                    .expect("window length checked by the layout");
                let mut encoder = ChunkEncoder::new(storage);
                while let Some(&row) = pending.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let case = &study.cases[rows_ref[row]];
                    let result =
                        run_case(study, row, &case.params, &refs[case.reference], &mut plan);
                    let cpu = thread_cpu();
                    let record = Box::new(JournalRecord::encode(&result, &mut encoder));
                    tally_ref.case(
                        result.cost.simulate,
                        result.cost.analysis,
                        thread_cpu() - cpu,
                    );
                    if send(&tx, record, tally_ref).is_err() {
                        break;
                    }
                }
                tally_ref.out_of_cases(start.elapsed());
            });
        });
        let mut received = 0;
        // `rx` is consumed: if this loop stops early (an error), the channel closes and
        // the workers stop instead of waiting for a writer that is gone.
        for rec in rx {
            let cpu = thread_cpu();
            let before = rec.write_to(&mut writer)?;
            let cpu_hdf5 = thread_cpu();
            journal
                .write(&rec, before)
                .with_context(|| format!("cannot append to {}", journal_path.display()))?;
            stats.hdf5 += cpu_hdf5 - cpu;
            stats.journal += thread_cpu() - cpu_hdf5;
            stats.stored_bytes += rec.chunk_bytes() as u64;
            if rec.status() == Status::Ok {
                ok += 1;
                stats.raw_bytes += raw_per_case;
            } else {
                failed += 1
            }
            progress.case_done(rec.status() != Status::Ok);
            received += 1;
        }
        Ok(received)
    })?;
    if received != n_pending {
        bail!("a worker thread stopped after {received} of {n_pending} cases; rerun with --resume");
    }
    progress.finish();
    let cpu = thread_cpu();
    writer
        .finish()
        .with_context(|| format!("cannot finish {}", partial_path.display()))?;
    stats.finish = thread_cpu() - cpu;
    stats.sends = received as u64;
    tally.add_to(&mut stats);
    std::fs::rename(&partial_path, &opts.output).with_context(|| {
        format!(
            "cannot rename {} to {}",
            partial_path.display(),
            opts.output.display()
        )
    })?;
    drop(journal);
    std::fs::remove_file(&journal_path)
        .with_context(|| format!("cannot remove {}", journal_path.display()))?;
    Ok(RunSummary {
        cases: rows.len(),
        ok,
        failed,
        resumed,
        rerun: journaled - resumed,
        wall_time: start.elapsed().as_secs_f64(),
        stats,
    })
}

/// What a resumed run took over from the journal of the interrupted one.
#[derive(Debug, Default)]
struct Replayed {
    /// Rows replayed into the new partial file.
    done: HashSet<usize>,
    /// Rows the journal recorded (some may not have been found intact).
    journaled: usize,
    /// Replayed cases that ran to the end.
    ok: usize,
    /// Replayed cases that failed.
    failed: usize,
}

/// Replays the cases `reader`'s journal recorded below row `n_rows` into `writer` (the
/// other partial file than the journal's, see [`DataFile`]) under a new journal, which
/// then replaces the old one by an atomic rename; the old partial file is removed
/// last. The old files are only read, so a kill at any moment leaves a journal whose
/// partial file holds its cases. Returns the new journal, open for appending.
fn replay(
    mut reader: JournalReader,
    output: &Path,
    header: &JournalHeader,
    writer: &mut StudyWriter,
    n_rows: usize,
) -> Result<(JournalWriter, Replayed)> {
    let (journal_path, _) = side_paths(output);
    let new_journal_path = new_journal_path(output);
    let old = reader.data_file().path(output);
    let old_data = std::fs::File::open(&old).with_context(|| {
        format!(
            "cannot open {}, the partial file that holds the journal's cases; \
             run with --force to start over",
            old.display()
        )
    })?;
    let mut journal = JournalWriter::create(&new_journal_path, header, reader.data_file().other())
        .with_context(|| format!("cannot create {}", new_journal_path.display()))?;
    let mut journaled = HashSet::new();
    let mut replayed = Replayed::default();
    while let Some(entry) = reader.next_entry() {
        if entry.row() >= n_rows || replayed.done.contains(&entry.row()) {
            continue;
        }
        journaled.insert(entry.row());
        // A case whose chunks are not intact in the old file is run again.
        let Some(rec) = entry.load(&old_data) else {
            continue;
        };
        let before = rec.write_to(writer)?;
        journal
            .write(&rec, before)
            .with_context(|| format!("cannot append to {}", new_journal_path.display()))?;
        replayed.done.insert(rec.row());
        if rec.status() == Status::Ok {
            replayed.ok += 1
        } else {
            replayed.failed += 1
        }
    }
    replayed.journaled = journaled.len();
    std::fs::rename(&new_journal_path, &journal_path).with_context(|| {
        format!(
            "cannot rename {} to {}",
            new_journal_path.display(),
            journal_path.display()
        )
    })?;
    drop(old_data);
    std::fs::remove_file(&old).with_context(|| format!("cannot remove {}", old.display()))?;
    Ok((journal, replayed))
}

/// Sends `record` to the writer; a send that finds the channel full (the writer is
/// behind, so the worker waits) is counted in `tally` with its waiting time.
fn send<T>(tx: &SyncSender<T>, record: T, tally: &WorkerTally) -> Result<(), SendError<T>> {
    match tx.try_send(record) {
        Ok(()) => Ok(()),
        Err(TrySendError::Disconnected(record)) => Err(SendError(record)),
        Err(TrySendError::Full(record)) => {
            let waiting = Instant::now();
            let sent = tx.send(record);
            tally.blocked(waiting.elapsed());
            sent
        }
    }
}

use order::dispatch_order;
use progress::Progress;
use stats::{thread_cpu, WorkerTally};
