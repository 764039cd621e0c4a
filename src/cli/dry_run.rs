//! `studyrun GRID --dry-run`: the case table, the memory estimate, the file size and
//! a time estimate from short calibration runs; as text or as JSON.

use super::*;

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
    /// The run's peak memory (bytes) and its breakdown in words.
    memory: (f64, String),
    /// The calibration: `(case id, estimated seconds for the whole case)` of the runs
    /// that finished, and the messages of those that failed.
    calibration: (Vec<(u64, f64)>, Vec<String>),
}

impl DryRun<'_> {
    /// The mean cost of one case (s) over the calibration runs, if any finished.
    fn per_case(&self) -> Option<f64> {
        let times = &self.calibration.0;
        (!times.is_empty()).then(|| times.iter().map(|t| t.1).sum::<f64>() / times.len() as f64)
    }

    /// The whole run's estimated wall time on `jobs` workers (s).
    fn total(&self, jobs: usize) -> Option<f64> {
        self.per_case()
            .map(|c| c * self.rows.len() as f64 / jobs as f64)
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
    let dry = DryRun {
        study,
        rows,
        series: (n_series, n_time),
        spectra: study.stored_spectra_count(),
        raw_bytes,
        memory: (estimate.total, estimate.to_string()),
        calibration,
    };
    if json {
        print_json(&dry, limits)
    } else {
        print_text(&dry, limits)
    }
}

/// Runs 10 % of the duration of the cases [`calibration_rows`] picks: each finished
/// run's case id and its time scaled to the whole duration (s), and why the others
/// failed.
fn calibrate(study: &Study, rows: &[usize]) -> (Vec<(u64, f64)>, Vec<String>) {
    let short = Sampling {
        duration: 0.1 * study.sampling.duration,
        ..study.sampling
    };
    let (mut times, mut failures) = (Vec::new(), Vec::new());
    for &r in &calibration_rows(study, rows) {
        let case = &study.cases[r];
        match simulate(&case.params, &study.solver, &short) {
            Ok(o) => times.push((case.id, o.wall_time * 10.0)),
            Err(e) => failures.push(format!("case {}: {e}", case.id)),
        }
    }
    (times, failures)
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
        "memory": super::study_run::memory_json(dry.memory.0, limits),
        "time": {
            "estimate_s": dry.total(limits.jobs),
            "per_case_s": dry.per_case(),
            "calibrated_on": dry.calibration.0.iter().map(|t| t.0).collect::<Vec<_>>(),
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
         and {} spectra per case; raw output {:.1} MB before compression (deflate level {}, {})",
        dry.rows.len(),
        study.references.len(),
        dry.series.0,
        dry.series.1,
        study.output.decimate,
        dry.spectra,
        dry.raw_bytes / 1e6,
        study.compression,
        if study.float32 { "float32" } else { "float64" },
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
    let ids: Vec<String> = times.iter().map(|t| t.0.to_string()).collect();
    out!(
        "time: about {} s on {jobs} threads (a case takes {:.3} s on average over cases {}, from runs of 10 % of the duration{})",
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
