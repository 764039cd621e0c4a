//! `studyrun GRID --dry-run`: the case table, the memory estimate, and the file size
//! and time estimated from a few cases run whole; as text or as JSON.

use super::*;
use studyrun::run::{measure_case, Measured};

/// Cases the dry run's time estimate is calibrated on: up to [`CALIBRATION_CASES`]
/// spread evenly over `rows`, bearing cases only when there are any (an ideal case
/// costs next to nothing and would make the estimate far too low).
pub(super) const CALIBRATION_CASES: usize = 5;

pub(super) fn calibration_rows(study: &Study, rows: &[usize]) -> Vec<usize> {
    let bearing: Vec<usize> = rows
        .iter()
        .copied()
        .filter(|&r| study.cases[r].params.location != studyrun::mechanism::Location::Ideal)
        .collect();
    let pool = if bearing.is_empty() { rows } else { &bearing };
    let n = pool.len().min(CALIBRATION_CASES);
    let mut picked: Vec<usize> = (0..n)
        .map(|k| {
            pool[if n > 1 {
                k * (pool.len() - 1) / (n - 1)
            } else {
                0
            }]
        })
        .collect();
    picked.dedup();
    picked
}

/// What a dry run finds: the cases, the file's shape, the memory estimate and the
/// calibrated time estimate.
struct DryRun<'a> {
    study: &'a Study,
    /// Rows of `study.cases` the run (or shard) holds.
    rows: Vec<usize>,
    /// Stored series per case, and samples per series.
    series: (usize, usize),
    /// Spectra per case.
    spectra: usize,
    /// The output's size before compression (bytes).
    raw_bytes: f64,
    /// Bytes per case of the file beside its series and spectra (its metrics,
    /// parameters and status), and of the file beside its cases (references'
    /// series, coordinates, metadata), uncompressed.
    overhead: (f64, f64),
    /// The run's peak memory (bytes) and its breakdown in words.
    memory: (f64, String),
    /// The calibration: the cases run whole, and the messages of those that failed.
    calibration: (Vec<Measured>, Vec<String>),
}

impl DryRun<'_> {
    /// The mean of `f` over the calibration runs, if any finished.
    fn mean(&self, f: impl Fn(&Measured) -> f64) -> Option<f64> {
        let runs = &self.calibration.0;
        (!runs.is_empty()).then(|| runs.iter().map(f).sum::<f64>() / runs.len() as f64)
    }

    /// The mean CPU time of one case (s) over the calibration runs.
    fn per_case(&self) -> Option<f64> {
        self.mean(|m| m.case_s)
    }

    /// The whole run's estimated wall time on `jobs` workers (s): the start
    /// ([`STARTUP_S`]); every case, and every reference twice (made when the file is
    /// created, and again by the workers, whose cache of them is bounded), shared by
    /// the workers; the last case, which one worker finishes alone; and the file's
    /// flush to the disk at the end ([`FLUSH_BYTES_PER_S`]).
    fn total(&self, jobs: usize) -> Option<f64> {
        let jobs = jobs.max(1) as f64;
        let per_case = self.per_case()?;
        let reference = self.mean(|m| m.reference_s)?;
        let cpu = per_case * self.rows.len() as f64
            + 2.0 * reference * self.study.references.len() as f64;
        let tail = per_case * (1.0 - 1.0 / jobs);
        Some(STARTUP_S + cpu / jobs + tail + self.file_bytes()? / FLUSH_BYTES_PER_S)
    }

    /// The file's estimated size (bytes): each case's series and spectra as the
    /// calibration runs stored them (compressed), plus the overheads.
    fn file_bytes(&self) -> Option<f64> {
        let stored = self.mean(|m| m.stored_bytes as f64)?;
        Some(self.rows.len() as f64 * (stored + self.overhead.0) + self.overhead.1)
    }
}

/// The case table, the memory estimate, the file size and a time estimate from short
/// calibration runs (10 % of the duration) of up to five cases spread over the table,
/// as text or (`json`) one JSON object. Never fails for want of an estimate: a
/// calibration that cannot run says so.
pub(super) fn dry_run(
    study: &Study,
    shard: Option<Shard>,
    limits: &Limits,
    json: bool,
) -> Result<()> {
    let rows: Vec<usize> = match shard {
        Some(s) => study.shard(s.k, s.n),
        None => (0..study.cases.len()).collect(),
    };
    let n_time = study.stored_times().len();
    let n_series = study.stored_series_count();
    let n_freq = study.stored_bins();
    let width = if study.float32 { 4.0 } else { 8.0 };
    let raw_bytes = rows.len() as f64
        * (n_series as f64 * n_time as f64 + study.stored_spectra_count() as f64 * n_freq as f64)
        * width;
    let estimate = study.memory_estimate(limits.jobs);
    let calibration = calibrate(study, &rows);
    let layout = studyrun::study::study_layout(study, &rows[..rows.len().min(1)], shard);
    let per_case = 8.0 * (layout.n_metric_values() + layout.parameters.len()) as f64 + 64.0;
    let references =
        width * (layout.reference_series.len() * n_time) as f64 * study.references.len() as f64;
    let dry = DryRun {
        study,
        rows,
        series: (n_series, n_time),
        spectra: study.stored_spectra_count(),
        raw_bytes,
        overhead: (per_case, references + FILE_METADATA_BYTES),
        memory: (estimate.total, estimate.to_string()),
        calibration,
    };
    if json {
        print_json(&dry, limits)
    } else {
        print_text(&dry, limits)
    }
}

/// Bytes of a study file beside its variables' values: the root and variable
/// attributes, dimension scales, chunk indices and HDF5's own structures (about what
/// a one-case file of the smoke study holds beside its values).
const FILE_METADATA_BYTES: f64 = 120e3;

/// Seconds a run takes beside its cases: the process's start, the grid's expansion
/// and the file's creation (about what `--timings` shows before the workers start on a
/// small study).
const STARTUP_S: f64 = 0.05;

/// Bytes per second at which the finished file reaches the disk (its `fsync`; about
/// what docs/performance.md measures).
const FLUSH_BYTES_PER_S: f64 = 1e9;

/// CPU time after which the calibration runs no further case (s): a dry run stays
/// quick however long a case is, and still runs at least one.
const CALIBRATION_BUDGET_S: f64 = 3.0;

/// Runs whole, as a worker does ([`measure_case`]), the cases [`calibration_rows`]
/// picks, until [`CALIBRATION_BUDGET_S`] is spent: what each cost, and why the others
/// failed.
fn calibrate(study: &Study, rows: &[usize]) -> (Vec<Measured>, Vec<String>) {
    let (mut runs, mut failures) = (Vec::new(), Vec::new());
    let mut spent = 0.0;
    for &r in &calibration_rows(study, rows) {
        if spent > CALIBRATION_BUDGET_S {
            break;
        }
        let start = std::time::Instant::now();
        match measure_case(study, r) {
            Ok(m) => runs.push(m),
            Err(e) => failures.push(format!("case {}: {e}", study.cases[r].id)),
        }
        spent += start.elapsed().as_secs_f64();
    }
    (runs, failures)
}

/// The dry run as one JSON object (docs/cli.md).
fn print_json(dry: &DryRun<'_>, limits: &Limits) -> Result<()> {
    let study = dry.study;
    let varied = study.varied();
    let cases: Vec<serde_json::Value> = dry
        .rows
        .iter()
        .map(|&r| {
            let c = &study.cases[r];
            let mut row = serde_json::Map::new();
            row.insert("case".into(), c.id.into());
            for axis in &varied {
                row.insert(axis.to_string(), axis_value(axis, &c.params).into());
            }
            serde_json::Value::Object(row)
        })
        .collect();
    let report = serde_json::json!({
        "name": study.name,
        "cases": cases,
        "references": study.references.len(),
        "stored_series": dry.series.0,
        "samples": dry.series.1,
        "decimate": study.output.decimate,
        "spectra": dry.spectra,
        "raw_bytes": dry.raw_bytes.round(),
        "file_bytes": dry.file_bytes().map(f64::round),
        "memory": super::study_run::memory_json(dry.memory.0, limits),
        "time": {
            "estimate_s": dry.total(limits.jobs),
            "per_case_s": dry.per_case(),
            "calibrated_on": dry.calibration.0.iter().map(|m| m.id).collect::<Vec<_>>(),
            "failures": dry.calibration.1,
        },
    });
    out!("{}", serde_json::to_string_pretty(&report)?)
}

/// The dry run as text: a tab-separated case table, then the file, memory and time.
fn print_text(dry: &DryRun<'_>, limits: &Limits) -> Result<()> {
    let study = dry.study;
    let varied = study.varied();
    let mut header = vec!["case".to_string()];
    header.extend(varied.iter().map(|v| v.to_string()));
    out!("{}", header.join("\t"))?;
    for &r in &dry.rows {
        let c = &study.cases[r];
        let mut line = vec![c.id.to_string()];
        line.extend(varied.iter().map(|axis| axis_value(axis, &c.params)));
        out!("{}", line.join("\t"))?;
    }
    out!(
        "\n{} cases ({} ideal references); {} stored series x {} samples (output.decimate {}) \
         and {} spectra per case; raw output {:.1} MB before compression (deflate level {}, {}){}",
        dry.rows.len(),
        study.references.len(),
        dry.series.0,
        dry.series.1,
        study.output.decimate,
        dry.spectra,
        dry.raw_bytes / 1e6,
        study.compression,
        if study.float32 { "float32" } else { "float64" },
        dry.file_bytes().map_or(String::new(), |b| format!(
            "; the file about {:.1} MB",
            b / 1e6
        )),
    )?;
    out!(
        "memory: about {} of the limit {}: {}",
        memory::bytes(dry.memory.0),
        limits.describe(),
        dry.memory.1
    )?;
    if dry.rows.is_empty() {
        return out!("no cases in this shard: the run writes a file with the references only");
    }
    print_time(dry, limits.jobs)
}

/// The time line of the text dry run.
fn print_time(dry: &DryRun<'_>, jobs: usize) -> Result<()> {
    let (times, failures) = &dry.calibration;
    let (Some(mean), Some(total)) = (dry.per_case(), dry.total(jobs)) else {
        return out!(
            "time: estimate unavailable: no calibration run finished ({})",
            if failures.is_empty() {
                "no case to calibrate on".to_string()
            } else {
                failures.join("; ")
            }
        );
    };
    let ids: Vec<String> = times.iter().map(|m| m.id.to_string()).collect();
    out!(
        "time: about {} s on {jobs} threads (a case takes {:.3} s of CPU on average over cases {}, run whole{})",
        if total < 10.0 {
            format!("{total:.1}")
        } else {
            format!("{total:.0}")
        },
        mean,
        ids.join(", "),
        if failures.is_empty() {
            String::new()
        } else {
            format!(
                "; {} of {} calibration runs failed: {}",
                failures.len(),
                times.len() + failures.len(),
                failures.join("; ")
            )
        }
    )
}
