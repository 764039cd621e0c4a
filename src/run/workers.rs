//! The workers and the one writer of a run: the workers take cases one at a time and
//! send their records through a bounded channel; the calling thread stores them.
//!
//! Workers analyse their cases and encode the chunks themselves, so neither holds up
//! the writer. When a core is left over for the writer (fewer workers than cores)
//! and the writer has nothing in hand, a worker hands its case over as soon as it is
//! integrated ([`Handover`]): the writer samples its outputs (when they are pure,
//! [`crate::simulate::Integrated`]), analyses and encodes it while the worker runs
//! the next case. A case with replicates (which simulate more) keeps its
//! analysis, and hands over only its encoding. The bytes are the same either way.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, SendError, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::case::{simulate_case, Analyses, CaseResult, Simulated};
use super::journal::JournalRecord;
use super::references::ReferenceCache;
use super::stats::{thread_cpu, WorkerTally};
use super::RunError;
use crate::output::{ChunkEncoder, Storage};
use crate::simulate::CaseOutput;
use crate::study::Study;

/// What the workers need to run cases.
pub(super) struct Work<'a> {
    pub(super) study: &'a Study,
    /// The study's case index of every file row.
    pub(super) rows: &'a [usize],
    /// The ideal references, by index, made where a case needs one.
    pub(super) references: &'a ReferenceCache<'a>,
    pub(super) storage: Storage,
    pub(super) jobs: usize,
    /// When the run started (for the workers' idle time at the end).
    pub(super) start: Instant,
}

/// A case on its way to the writer.
enum Delivery<'a> {
    /// Analysed and encoded by its worker.
    Encoded(Box<JournalRecord>),
    /// Analysed by its worker, handed over unencoded ([`Handover`]).
    Unencoded(Box<CaseResult>),
    /// Handed over once simulated ([`Handover`]), with its ideal reference: the
    /// writer analyses and encodes it.
    Simulated(Box<Simulated<'a>>, Arc<CaseOutput>),
}

/// What the writer needs to finish the cases handed over to it: made at the first.
struct Finisher {
    analyses: Analyses,
    encoder: ChunkEncoder,
}

impl Finisher {
    /// The writer's finisher in `slot`, made at the first case handed over.
    fn of<'f>(slot: &'f mut Option<Self>, work: &Work<'_>) -> &'f mut Self {
        slot.get_or_insert_with(|| Finisher {
            analyses: Analyses::new(work.study).expect("window length checked by the layout"),
            encoder: ChunkEncoder::new(work.storage),
        })
    }

    /// The record of `delivery`, finished here if its worker handed it over; the CPU
    /// time of the analysis and encoding done here goes to `tally`.
    fn record(
        slot: &mut Option<Self>,
        work: &Work<'_>,
        delivery: Delivery<'_>,
        tally: &WorkerTally,
    ) -> Box<JournalRecord> {
        let (result, analysis) = match delivery {
            Delivery::Encoded(record) => return record,
            Delivery::Unencoded(result) => (*result, 0.0),
            Delivery::Simulated(simulated, reference) => {
                let cpu = thread_cpu();
                let analyses = &mut Self::of(slot, work).analyses;
                let result = analyses.finish(work.study, *simulated, &reference);
                (result, thread_cpu() - cpu)
            }
        };
        let cpu = thread_cpu();
        let encoder = &mut Self::of(slot, work).encoder;
        let record = Box::new(JournalRecord::encode(&result, encoder));
        tally.finished_by_writer(analysis, thread_cpu() - cpu);
        record
    }
}

/// Whether a worker hands its case to the writer to finish (once simulated, or
/// analysed but unencoded): only while a core is left over for the writer and the
/// writer has no case in hand (none sent and not yet stored), so the writer never
/// falls behind the workers for it, and at most one such case waits per worker.
struct Handover {
    /// Fewer workers than the cores this process may use.
    spare_core: bool,
    /// Cases sent and not yet stored.
    in_hand: AtomicUsize,
}

impl Handover {
    /// The hand-over of a run of `jobs` workers on `cores` cores.
    fn new(jobs: usize, cores: usize) -> Self {
        Self {
            spare_core: jobs.max(1) < cores,
            in_hand: AtomicUsize::new(0),
        }
    }

    /// Whether the writer is free to finish the case about to be sent.
    fn writer_free(&self) -> bool {
        self.spare_core && self.in_hand.load(Ordering::Acquire) == 0
    }
}

/// Runs the `pending` rows on `work.jobs` workers, the costliest first, and hands
/// each finished case's record to `store` on this thread (the one writer), with the
/// output `open` makes here while the workers run their first cases. Returns the
/// output and the workers' tally.
///
/// When `open` or `store` fails the channel closes: each worker stops once its case
/// in hand is done, and the error is returned then.
pub(super) fn run_pending<O>(
    work: &Work<'_>,
    pending: &[usize],
    open: impl FnOnce() -> Result<O, RunError>,
    store: impl FnMut(&mut O, &JournalRecord) -> Result<(), RunError>,
) -> Result<(O, WorkerTally), RunError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let handover = Handover::new(work.jobs, cores);
    run_with(work, pending, &handover, open, store)
}

/// [`run_pending`] with the hand-over `handover`.
fn run_with<O>(
    work: &Work<'_>,
    pending: &[usize],
    handover: &Handover,
    open: impl FnOnce() -> Result<O, RunError>,
    mut store: impl FnMut(&mut O, &JournalRecord) -> Result<(), RunError>,
) -> Result<(O, WorkerTally), RunError> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(work.jobs.max(1))
        .build()?;
    // At most two records per worker wait for the writer: memory stays bounded.
    let (tx, rx) = sync_channel::<Delivery>(2 * work.jobs.max(1));
    let tally = WorkerTally::default();
    // The first reference a worker could not make; the workers then stop.
    let failed_reference = Mutex::new(None);
    let outcome = std::thread::scope(|scope| -> Result<(O, usize), RunError> {
        // The workers own the sender: when they end, normally or not, the channel closes.
        let shared = Shared {
            work,
            pending,
            tally: &tally,
            handover,
            failed_reference: &failed_reference,
        };
        scope.spawn(move || {
            let next = AtomicUsize::new(0);
            pool.broadcast(|_| shared.work_cases(&next, &tx));
        });
        // `rx` is owned here: if this closure returns early (an error), the channel
        // closes and the workers stop instead of waiting for a writer that is gone.
        let rx = rx;
        let mut output = open()?;
        let mut finisher = None;
        let mut received = 0;
        for delivery in rx {
            let record = Finisher::record(&mut finisher, work, delivery, &tally);
            store(&mut output, &record)?;
            handover.in_hand.fetch_sub(1, Ordering::AcqRel);
            received += 1;
        }
        Ok((output, received))
    });
    if let Some(e) = failed_reference
        .into_inner()
        .unwrap_or_else(|p| p.into_inner())
    {
        return Err(e);
    }
    let (output, received) = outcome?;
    if received != pending.len() {
        return Err(RunError::WorkerStopped {
            received,
            pending: pending.len(),
        });
    }
    Ok((output, tally))
}

/// What every worker of [`run_pending`] shares.
#[derive(Clone, Copy)]
struct Shared<'a> {
    work: &'a Work<'a>,
    pending: &'a [usize],
    tally: &'a WorkerTally,
    handover: &'a Handover,
    failed_reference: &'a Mutex<Option<RunError>>,
}

impl<'a> Shared<'a> {
    /// One worker's loop: takes the next case of `pending` (`next` counts them out)
    /// until none is left, the writer is gone, or a reference cannot be made (kept in
    /// `failed_reference`).
    fn work_cases(&self, next: &AtomicUsize, tx: &SyncSender<Delivery<'a>>) {
        let study = self.work.study;
        let mut analyses = Analyses::new(study).expect("window length checked by the layout");
        let mut encoder = ChunkEncoder::new(self.work.storage);
        while let Some(&row) = self.pending.get(next.fetch_add(1, Ordering::Relaxed)) {
            let case = &study.cases[self.work.rows[row]];
            // A measured recording has no reference.
            let reference = match study.recordings {
                Some(_) => None,
                None => match self.work.references.get(case.reference) {
                    Ok(reference) => Some(reference),
                    Err(e) => {
                        let first = self.failed_reference.lock();
                        first.unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
                        break;
                    }
                },
            };
            let delivery = match reference {
                Some(reference) => self.simulated(study, row, case, reference, &mut analyses),
                None => Delivery::Unencoded(Box::new(analyses.run(study, row, case, None))),
            };
            let delivery = match delivery {
                Delivery::Unencoded(result) if !self.handover.writer_free() => {
                    let cpu = thread_cpu();
                    let record = Box::new(JournalRecord::encode(&result, &mut encoder));
                    self.tally.case(
                        result.cost.simulate,
                        result.cost.analysis,
                        thread_cpu() - cpu,
                    );
                    Delivery::Encoded(record)
                }
                Delivery::Unencoded(result) => {
                    self.tally
                        .case(result.cost.simulate, result.cost.analysis, 0.0);
                    Delivery::Unencoded(result)
                }
                handed_over => handed_over,
            };
            self.handover.in_hand.fetch_add(1, Ordering::AcqRel);
            if send(tx, delivery, self.tally).is_err() {
                break;
            }
        }
        self.tally.out_of_cases(self.work.start.elapsed());
    }
}

impl<'a> Shared<'a> {
    /// Simulates `case` at file row `row` and hands it to the writer if the writer is
    /// free and the case has no replicates; otherwise analyses it against `reference`
    /// here, to be encoded by whoever is free.
    fn simulated(
        &self,
        study: &'a Study,
        row: usize,
        case: &'a crate::study::Case,
        reference: Arc<CaseOutput>,
        analyses: &mut Analyses,
    ) -> Delivery<'a> {
        let result = match simulate_case(study, row, case) {
            Ok(simulated) if study.replicates.is_none() && self.handover.writer_free() => {
                self.tally.case(simulated.cost().simulate, 0.0, 0.0);
                return Delivery::Simulated(Box::new(simulated), reference);
            }
            Ok(simulated) => Box::new(analyses.finish(study, simulated, &reference)),
            Err(failed) => failed,
        };
        Delivery::Unencoded(result)
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::RunStats;

    /// A study of four short cases of the bearing at the crank, with `extra` lines.
    fn study(extra: &str) -> Study {
        let text = format!(
            "name: handover\nduration: 0.02\nsample_rate: 2000\n{extra}\
             grid:\n  rpm: [300, 600]\n  damping: [300, 400]\n"
        );
        Study::from_yaml(&text, std::path::Path::new("handover.yaml")).expect("valid grid")
    }

    /// Every case's record as the writer stores it, in row order, and the run's tally,
    /// with a core left over for the writer or not.
    fn records(study: &Study, spare_core: bool) -> (Vec<JournalRecord>, RunStats) {
        let rows: Vec<usize> = (0..study.cases.len()).collect();
        let references = ReferenceCache::new(study, 1);
        let layout = crate::study::study_layout(study, &rows, None);
        let work = Work {
            study,
            rows: &rows,
            references: &references,
            storage: layout.storage,
            jobs: 1,
            start: Instant::now(),
        };
        let handover = Handover::new(1, if spare_core { 2 } else { 1 });
        let store = |out: &mut Vec<JournalRecord>, rec: &JournalRecord| {
            out.push(rec.clone());
            Ok(())
        };
        let (mut out, tally) =
            run_with(&work, &rows, &handover, || Ok(Vec::new()), store).expect("run");
        out.sort_by_key(JournalRecord::row);
        let mut stats = RunStats::default();
        tally.add_to(&mut stats);
        (out, stats)
    }

    /// The writer's records of `study` with a spare core are its workers' alone,
    /// but for each case's wall time; returns the tally with the spare core.
    fn same_records_with_a_spare_core(study: &Study) -> RunStats {
        let (by_workers, stats) = records(study, false);
        assert_eq!((stats.analysis_writer, stats.encode_writer), (0.0, 0.0));
        let (handed_over, stats) = records(study, true);
        assert_eq!(by_workers.len(), study.cases.len());
        let specs = crate::study::study_metric_specs(study);
        let wall_time = specs.iter().position(|s| s.name == "wall_time");
        let at = wall_time.expect("a wall_time metric");
        for (handed, worker) in handed_over.iter().zip(&by_workers) {
            assert_eq!(handed.data_bits(at), worker.data_bits(at));
        }
        stats
    }

    #[test]
    fn cases_the_writer_finishes_are_the_same_records() {
        let stats = same_records_with_a_spare_core(&study(""));
        // The writer holds nothing when the first case is simulated: it analyses and
        // encodes that one.
        assert!(stats.analysis_writer > 0.0, "{stats:?}");
        assert!(stats.encode_writer > 0.0, "{stats:?}");
    }

    #[test]
    fn a_case_with_replicates_hands_over_only_its_encoding() {
        let replicates = "replicates: {count: 2, perturbation: \"1 nm\"}\n";
        let stats = same_records_with_a_spare_core(&study(replicates));
        assert_eq!(stats.analysis_writer, 0.0);
        assert!(stats.encode_writer > 0.0, "{stats:?}");
    }

    #[test]
    fn a_writer_that_cannot_open_its_output_stops_the_workers() {
        let study = study("");
        let rows: Vec<usize> = (0..study.cases.len()).collect();
        let references = ReferenceCache::new(&study, 1);
        let work = Work {
            study: &study,
            rows: &rows,
            references: &references,
            storage: crate::study::study_layout(&study, &rows, None).storage,
            jobs: 1,
            start: Instant::now(),
        };
        let open = || -> Result<(), RunError> { Err(RunError::refused("no output".into())) };
        let outcome = run_pending(&work, &rows, open, |_, _| Ok(()));
        let message = outcome.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(message.contains("no output"), "{message}");
    }
}
