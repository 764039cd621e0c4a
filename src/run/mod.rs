//! Running a study: cases in parallel (rayon), one writer (the HDF5 library is not
//! thread-safe), bounded memory, a crash journal, resume, shards and merging.
//!
//! Data flow: workers (a rayon pool) take cases one at a time, the costliest first
//! (`order`), simulate them, compute spectra and metrics, encode the series
//! and spectra into the chunks the file stores (float32 conversion, shuffle, deflate)
//! with their checksums (`JournalRecord::encode`), and send the records through a
//! bounded channel; the calling thread copies each case's chunks into `OUT.h5.partial`
//! (HDF5 direct chunk write), appends to the journal where they went, and reports
//! progress. At the end the partial file is renamed to `OUT.h5` (atomic) and the
//! journal removed. A resumed run replays the journal into the other partial file
//! ([`DataFile`]). Case data do not depend on the number of threads: each case is simulated
//! and encoded on its own, in one thread. [`RunStats`] says where the time went.

mod calibrate;
mod case;
mod error;
mod journal;
mod order;
mod progress;
mod recording;
mod references;
mod stats;
mod workers;

pub use calibrate::{measure_case, Measured};
pub use case::check_eccentricity;
pub use error::RunError;
pub use journal::JournalError;
use journal::{JournalHeader, JournalReader, JournalRecord, JournalWriter};
pub(crate) use references::run_references;
use references::{each_reference, ReferenceCache};
pub use stats::RunStats;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::output::OutputError;
use crate::output::{
    new_journal_path, overwrite, remove_durably, rename_durably, side_paths, DataFile, Layout,
    OutputLock, Status, StudyReader, StudyWriter,
};
use crate::signal::spectrum::Window;
use crate::study::Shard;
use crate::study::{stored_reference_channels, study_layout, Study, StudyFingerprint};

/// How to run. The default writes `study.h5` in the working directory with one
/// worker per core, refusing to replace anything, with progress on stderr.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The result file.
    pub output: PathBuf,
    /// Worker threads (≥ 1; 0 counts as 1).
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

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            output: PathBuf::from("study.h5"),
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            resume: false,
            force: false,
            shard: None,
            quiet: false,
        }
    }
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
    /// Perturbed replicates of ok cases that failed (recorded in the file with their
    /// message, `replicate_error_message`).
    pub failed_replicates: usize,
    /// Cases taken from the journal of an interrupted run.
    pub resumed: usize,
    /// Cases the journal of an interrupted run recorded but whose chunks were not
    /// found intact in its partial file: run again.
    pub rerun: usize,
    /// The output already held this study's complete result (a `--resume` of a
    /// finished run): nothing ran.
    pub complete_before: bool,
    /// Wall-clock time (s).
    pub wall_time: f64,
    /// Where the CPU time went and whether the workers waited for the writer.
    pub stats: RunStats,
}

/// Renames `from` to `to` (atomic within a file system), both on the disk when it
/// returns ([`rename_durably`]).
fn rename(from: &Path, to: &Path) -> Result<(), OutputError> {
    rename_durably(from, to).map_err(OutputError::io(format!("rename {} to", from.display()), to))
}

/// The spectrum window of a study.
pub(crate) fn window_of(study: &Study) -> Window {
    if study.window == "rectangular" {
        Window::Rectangular
    } else {
        Window::Hann
    }
}

/// How a run begins, decided from what is on disk and the options.
enum Start {
    /// No earlier run to take over: create the file from scratch.
    Fresh,
    /// Continue the interrupted run this journal recorded.
    Resume(JournalReader),
    /// The output already holds this study's (or shard's) complete result.
    Complete(RunSummary),
}

/// Runs `study` (or a shard of it) into `opts.output`: refuses a study holding one
/// shard's cases ([`Study::part`]) run as another part; takes the output's lock,
/// decides how to start, creates the file (references first), replays an
/// interrupted run, runs the pending cases on the workers and finishes the file.
pub fn run(study: &Study, opts: &RunOptions) -> Result<RunSummary, RunError> {
    let start = Instant::now();
    if let Some(part) = study.part.filter(|&p| Some(p) != opts.shard) {
        return Err(RunError::refused(format!(
            "the study holds only the cases of shard {part}; run it as that shard \
             (`--shard {part}`), or load the whole study"
        )));
    }
    let rows: Vec<usize> = match opts.shard {
        Some(s) => study.shard(s.k, s.n),
        None => (0..study.cases.len()).collect(),
    };
    // Nothing that is not ours is written over: checked before the lock file is
    // made, and again (with the study-file check of --force) under the lock.
    check_paths(study, &opts.output)?;
    let _lock = OutputLock::acquire(&opts.output)?;
    let layout = study_layout(study, &rows, opts.shard);
    let header = journal_header(study, opts.shard, &layout);
    let (journal_path, _) = side_paths(&opts.output);
    let begin = match decide_start(study, opts, &header, rows.len(), start)? {
        Start::Complete(summary) => return Ok(summary),
        // A fresh run's journal comes first, so that every partial file of a run has
        // its journal beside it: a partial file without one is not studyrun's.
        Start::Fresh => Begin::Fresh(
            JournalWriter::create(&journal_path, &header, DataFile::Partial)
                .map_err(OutputError::io("create", &journal_path))?,
        ),
        Start::Resume(reader) => Begin::Resume(reader),
    };
    // A resumed run's pending cases are those its replay does not recover, so its
    // file is made and replayed first. A fresh run's workers start at once, and this
    // thread makes the file while they run the first cases.
    let (output, replayed) = match begin {
        Begin::Resume(reader) => {
            resume_output(study, opts, (&layout, &header), reader, rows.len())?
        }
        Begin::Fresh(journal) => (Output::Journal(journal), Replayed::default()),
    };
    let references = ReferenceCache::new(study, opts.jobs);
    let resumed = replayed.done.len();
    let mut pending: Vec<usize> = (0..rows.len())
        .filter(|r| !replayed.done.contains(r))
        .collect();
    dispatch_order(study, &rows, &mut pending);
    let mut tally = Tally::after(&replayed);
    let rerun = replayed.journaled - resumed;
    let mut progress = Progress::new(rows.len() as u64, resumed as u64, opts.quiet);
    let work = Work {
        study,
        rows: &rows,
        references: &references,
        storage: layout.storage,
        jobs: opts.jobs,
        start,
    };
    tally.stats.startup = start.elapsed().as_secs_f64();
    let (opened, worker_stats) = run_pending(
        &work,
        &pending,
        || output.open(study, opts, &layout),
        |file, rec| {
            let (cpu, cpu_hdf5) = file.store(rec, &journal_path)?;
            tally.record(rec, cpu, cpu_hdf5, &layout);
            progress.case_done(rec.status() != Status::Ok);
            Ok(())
        },
    )?;
    worker_stats.add_to(&mut tally.stats);
    tally.stats.create = opened.create;
    progress.finish();
    tally.stats.finish = finish_file(opened, &opts.output)?;
    Ok(tally.summary(rows.len(), (resumed, rerun), start))
}

/// The journal header of `study` run as `shard` into a file of `layout`: the study's
/// fingerprint and the sizes of a case's record.
fn journal_header(study: &Study, shard: Option<Shard>, layout: &Layout) -> JournalHeader {
    JournalHeader {
        fingerprint: StudyFingerprint::of(study, shard).0,
        n_time: layout.times.len() as u64,
        n_series: layout.series.len() as u64,
        n_freq: layout.spectrum_rows().map(|(_, n)| n).max().unwrap_or(0) as u64,
        n_spectra: layout.spectrum_rows().count() as u64,
        n_metrics: layout.n_metric_values() as u64,
        storage: layout.storage,
    }
}

/// Finishes the partial file of `opened` and declares it the result at `output`: on
/// the disk before it is renamed, the file, then its new name; then the journal goes.
/// Returns the CPU time the file's finish took (s).
fn finish_file(opened: Opened, output: &Path) -> Result<f64, RunError> {
    let Opened {
        writer,
        data,
        journal,
        ..
    } = opened;
    let (journal_path, _) = side_paths(output);
    let partial_path = data.path(output);
    let cpu = thread_cpu();
    writer.finish().map_err(OutputError::file(&partial_path))?;
    let finish = thread_cpu() - cpu;
    rename(&partial_path, output)?;
    drop(journal);
    remove_durably(&journal_path).map_err(OutputError::io("remove", &journal_path))?;
    Ok(finish)
}

/// The journal a run starts with: its own (fresh), or an interrupted run's.
enum Begin {
    Fresh(JournalWriter),
    Resume(JournalReader),
}

/// Where a run stores its cases: the partial file and journal, or a fresh run's
/// journal alone until the file is made.
enum Output {
    Open(Box<Opened>),
    Journal(JournalWriter),
}

impl Output {
    /// The partial file, made now for a fresh run ([`create_file`]).
    fn open(self, study: &Study, opts: &RunOptions, layout: &Layout) -> Result<Opened, RunError> {
        match self {
            Output::Open(opened) => Ok(*opened),
            Output::Journal(journal) => {
                let (writer, data, create) = create_file(study, opts, layout, None)?;
                Ok(Opened {
                    writer,
                    data,
                    journal,
                    create,
                })
            }
        }
    }
}

impl Opened {
    /// Copies `rec`'s chunks into the file and appends where they went to the journal
    /// at `journal_path`. Returns this thread's CPU time (s) before and after the copy.
    fn store(&mut self, rec: &JournalRecord, journal_path: &Path) -> Result<(f64, f64), RunError> {
        let cpu = thread_cpu();
        let before = rec
            .write_to(&mut self.writer)
            .map_err(OutputError::file(self.writer.path()))?;
        let cpu_hdf5 = thread_cpu();
        self.journal
            .write(rec, before)
            .map_err(OutputError::io("append to", journal_path))?;
        Ok((cpu, cpu_hdf5))
    }
}

/// The output of a resumed run: its partial file made ([`create_file`]) and the
/// journal `reader` read replayed into it ([`replay`]), with what the replay took over.
fn resume_output(
    study: &Study,
    opts: &RunOptions,
    (layout, header): (&Layout, &JournalHeader),
    reader: JournalReader,
    n_rows: usize,
) -> Result<(Output, Replayed), RunError> {
    let (mut writer, data, create) = create_file(study, opts, layout, Some(&reader))?;
    let (journal, replayed) = replay(reader, &opts.output, header, &mut writer, n_rows)?;
    let opened = Opened {
        writer,
        data,
        journal,
        create,
    };
    Ok((Output::Open(Box::new(opened)), replayed))
}

/// A run's partial file, open for its cases, with its journal.
struct Opened {
    writer: StudyWriter,
    /// Which partial file `writer` writes.
    data: DataFile,
    journal: JournalWriter,
    /// CPU time making the file took (s): its layout and the references.
    create: f64,
}

/// Decides how a run starts from the journal and result file on disk:
///
/// - a journal of an interrupted run: continue it with `--resume` (it must belong to
///   this study and shard), discard it with `--force`, refuse otherwise;
/// - a journal of this study whose partial file is gone: its run was stopped after it
///   renamed that file to the output and before it removed the journal (the output
///   then holds the complete result, checked: the journal is removed and the run goes
///   on as without it), or right after it created the journal (nothing recorded: the
///   journal is discarded); anything else is refused;
/// - no journal and a result file: with `--resume`, a complete result of this study
///   and shard is left as it is ([`Start::Complete`]) and anything else refused;
///   replaced with `--force`; refused otherwise;
/// - neither: a fresh run (also with `--resume`, so a job script can always pass it).
///
/// Partial files and a new journal beside a journal belong to its run and go with
/// it; without a journal they are not studyrun's and are refused, never removed.
/// Nothing that is not ours is replaced or removed: the output and its side files
/// must be regular files (or absent) and none of them the grid file, and `--force`
/// replaces only a study file ([`overwrite`]).
fn decide_start(
    study: &Study,
    opts: &RunOptions,
    header: &JournalHeader,
    n_rows: usize,
    start: Instant,
) -> Result<Start, RunError> {
    let output = &opts.output;
    let (journal_path, _) = side_paths(output);
    let exists = check_paths(study, output)?;
    if journal_path.exists() {
        match JournalReader::open(&journal_path, header) {
            Ok(reader) if !reader.data_file().path(output).exists() && !opts.force => {
                let finished = exists && complete_result(study, opts, n_rows, start).is_ok();
                if !finished && !recorded_nothing(&journal_path, header) {
                    return Err(RunError::refused(format!(
                        "{} records finished cases of this study, but {}, the partial file \
                         that holds them, is gone; run with --force to start over",
                        journal_path.display(),
                        reader.data_file().path(output).display()
                    )));
                }
                remove_durably(&journal_path).map_err(OutputError::io("remove", &journal_path))?;
            }
            Ok(reader) if opts.resume => return Ok(Start::Resume(reader)),
            // Its run stopped before it recorded a case: start afresh, as without a
            // journal.
            Err(JournalError::Unstarted { .. }) if opts.resume => {}
            Err(e) if opts.resume => return Err(e.into()),
            _ if opts.force => {}
            _ => {
                return Err(RunError::refused(format!(
                    "{} holds an interrupted run; use --resume to continue it or --force to \
                     start over",
                    journal_path.display()
                )))
            }
        }
    }
    let journal = journal_path.exists();
    let strays = [
        DataFile::Partial.path(output),
        DataFile::Resumed.path(output),
        new_journal_path(output),
    ];
    if !journal {
        if let Some(stray) = strays.iter().find(|p| p.exists()) {
            return Err(RunError::refused(format!(
                "{} is in the way: no journal {} says that a studyrun run wrote it, and \
                 studyrun removes only its own files; move or remove it yourself",
                stray.display(),
                journal_path.display()
            )));
        }
    }
    if exists && !opts.force {
        if !opts.resume {
            return Err(RunError::refused(format!(
                "{} exists; use --force to overwrite it",
                output.display()
            )));
        }
        let summary = complete_result(study, opts, n_rows, start)?;
        return Ok(Start::Complete(summary));
    }
    if exists {
        // --force replaces a study result, nothing else.
        overwrite::check_replaceable(output)?;
    }
    // The discarded run's files, its journal last: a stop on the way leaves a
    // journal beside whatever of them is left.
    for p in strays.iter().chain([&journal_path]) {
        remove_durably(p).map_err(OutputError::io("remove", p))?;
    }
    Ok(Start::Fresh)
}

/// Whether the journal at `path` (whose header matches `header`) records no case.
fn recorded_nothing(path: &Path, header: &JournalHeader) -> bool {
    JournalReader::open(path, header).is_ok_and(|mut r| r.next_entry().is_none())
}

/// Refuses an output, or a file beside it the run would write or remove, that is not
/// a regular file or is the grid file itself ([`overwrite::check_path`]). Returns whether
/// the output exists.
fn check_paths(study: &Study, output: &Path) -> Result<bool, RunError> {
    let grid = [study.path.as_path()];
    let exists = overwrite::check_path(output, "the output", &grid)?;
    for (side, what) in overwrite::side_files(output) {
        overwrite::check_side_path(&side, what, &grid)?;
    }
    Ok(exists)
}

/// The summary of `opts.output` when it is a complete result of `study` run as
/// `opts.shard`; refused when it is anything else.
fn complete_result(
    study: &Study,
    opts: &RunOptions,
    n_rows: usize,
    start: Instant,
) -> Result<RunSummary, RunError> {
    let output = &opts.output;
    let other = |why: &str| {
        RunError::refused(format!(
            "{} is not a complete result of this study{}: {why}; \
             use --force to replace it or choose another output",
            output.display(),
            opts.shard
                .map_or(String::new(), |s| format!(" (shard {s})")),
        ))
    };
    let reader = StudyReader::open(output).map_err(|e| other(&e.to_string()))?;
    let text = |name: &str| {
        reader
            .attribute(name)
            .and_then(|v| v.as_text().map(str::to_owned))
    };
    if text("study_fingerprint") != Some(StudyFingerprint::of(study, None).hex()) {
        return Err(other("it was written for another grid or studyrun version"));
    }
    if text("shard").unwrap_or_default() != opts.shard.map_or(String::new(), |s| s.to_string()) {
        return Err(other("it holds another shard"));
    }
    let statuses = reader.statuses().map_err(OutputError::file(output))?;
    if statuses.len() != n_rows || statuses.contains(&Status::Pending) {
        return Err(other("it has pending cases"));
    }
    reader
        .verify()
        .map_err(|e| other(&format!("it is damaged: {e}")))?;
    let failed = statuses.iter().filter(|&&s| s == Status::Failed).count();
    let failed_replicates = reader
        .failed_replicates()
        .map_err(OutputError::file(output))?;
    Ok(RunSummary {
        cases: n_rows,
        ok: n_rows - failed,
        failed,
        failed_replicates,
        resumed: 0,
        rerun: 0,
        complete_before: true,
        wall_time: start.elapsed().as_secs_f64(),
        stats: RunStats::default(),
    })
}

/// Creates the partial file and writes the ideal references into it, made `jobs` at a
/// time. A result file already at the output (`--force`) stays until the finished
/// run's file is renamed over it, so a run stopped on the way loses nothing: its
/// journal beside the old result resumes the new run. Returns the writer, which
/// partial file it writes (a resumed run writes the other one than its journal's
/// cases are in) and the CPU time this took (s).
fn create_file(
    study: &Study,
    opts: &RunOptions,
    layout: &Layout,
    reader: Option<&JournalReader>,
) -> Result<(StudyWriter, DataFile, f64), RunError> {
    let data = reader.map_or(DataFile::Partial, |r| r.data_file().other());
    let partial_path = data.path(&opts.output);
    let cpu = thread_cpu();
    let mut writer =
        StudyWriter::create(&partial_path, layout).map_err(OutputError::file(&partial_path))?;
    let stored = stored_reference_channels(study);
    let indices: Vec<usize> = layout.reference_ids.iter().map(|&id| id as usize).collect();
    each_reference(study, &indices, opts.jobs, |k, r| {
        let series: Vec<Vec<f64>> = stored
            .iter()
            .map(|c| study.keep_stored_samples(r.channel(c).expect("reference channel").to_vec()))
            .collect();
        let series: Vec<&[f64]> = series.iter().map(Vec::as_slice).collect();
        writer
            .write_reference(k, &series)
            .map_err(OutputError::file(&partial_path))?;
        Ok(())
    })?;
    Ok((writer, data, thread_cpu() - cpu))
}

/// Counts what the writer stored.
struct Tally {
    ok: usize,
    failed: usize,
    failed_replicates: usize,
    stats: RunStats,
}

impl Tally {
    /// The tally of a run that took over `replayed` from an interrupted one.
    fn after(replayed: &Replayed) -> Self {
        Self {
            ok: replayed.ok,
            failed: replayed.failed,
            failed_replicates: replayed.failed_replicates,
            stats: RunStats::default(),
        }
    }

    /// The summary of a run of `cases` cases that started at `start`, `resumed` of
    /// them from the journal and `rerun` run again.
    fn summary(self, cases: usize, (resumed, rerun): (usize, usize), start: Instant) -> RunSummary {
        RunSummary {
            cases,
            ok: self.ok,
            failed: self.failed,
            failed_replicates: self.failed_replicates,
            resumed,
            rerun,
            complete_before: false,
            wall_time: start.elapsed().as_secs_f64(),
            stats: self.stats,
        }
    }

    /// Counts `rec`, written between the CPU times `cpu` (start) and `cpu_hdf5`
    /// (HDF5 done; the journal's append followed).
    fn record(&mut self, rec: &JournalRecord, cpu: f64, cpu_hdf5: f64, layout: &Layout) {
        self.stats.hdf5 += cpu_hdf5 - cpu;
        self.stats.journal += thread_cpu() - cpu_hdf5;
        self.stats.stored_bytes += rec.chunk_bytes() as u64;
        self.stats.sends += 1;
        self.failed_replicates += rec.failed_replicates();
        if rec.status() == Status::Ok {
            self.ok += 1;
            let values = layout.series.len() * layout.times.len()
                + layout.spectrum_rows().map(|(_, n)| n).sum::<usize>();
            self.stats.raw_bytes += 8 * values as u64;
        } else {
            self.failed += 1
        }
    }
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
    /// Failed replicates of the replayed cases.
    failed_replicates: usize,
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
) -> Result<(JournalWriter, Replayed), RunError> {
    let (journal_path, _) = side_paths(output);
    let new_journal_path = new_journal_path(output);
    let old = reader.data_file().path(output);
    let old_data = std::fs::File::open(&old).map_err(|e| {
        RunError::refused(format!(
            "cannot open {}, the partial file that holds the journal's cases ({e}); \
             run with --force to start over",
            old.display()
        ))
    })?;
    let mut journal = JournalWriter::create(&new_journal_path, header, reader.data_file().other())
        .map_err(OutputError::io("create", &new_journal_path))?;
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
        let before = rec
            .write_to(writer)
            .map_err(OutputError::file(writer.path()))?;
        journal
            .write(&rec, before)
            .map_err(OutputError::io("append to", &new_journal_path))?;
        replayed.done.insert(rec.row());
        replayed.failed_replicates += rec.failed_replicates();
        if rec.status() == Status::Ok {
            replayed.ok += 1
        } else {
            replayed.failed += 1
        }
    }
    replayed.journaled = journaled.len();
    rename(&new_journal_path, &journal_path)?;
    drop(old_data);
    remove_durably(&old).map_err(OutputError::io("remove", &old))?;
    Ok((journal, replayed))
}

use order::dispatch_order;
use progress::Progress;
use stats::thread_cpu;
use workers::{run_pending, Work};
