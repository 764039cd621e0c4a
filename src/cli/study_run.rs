//! `studyrun GRID` and `studyrun validate GRID`: run a study, or check its grid file.

use super::*;
use studyrun::run::{self, RunOptions, RunSummary};

/// `studyrun validate GRID [--json]`: the grid file checked under `limits`, with its
/// case count and memory estimate. With `json`, a refused grid file is a JSON object
/// too (`valid: false` and where it is wrong), and the exit code is the same.
pub(super) fn validate_command(grid: &Path, limits: Limits, json: bool) -> Result<u8> {
    let study = match Study::load_with(grid, &limits) {
        Ok(study) => study,
        Err(e) if json => {
            let (line, column) = e.location.unzip();
            let refusal = serde_json::json!({
                "grid": grid.display().to_string(),
                "valid": false,
                "error": {"line": line, "column": column, "field": e.field, "message": e.message},
            });
            out!("{}", serde_json::to_string_pretty(&refusal)?)?;
            say!("studyrun: error: {e}");
            return Ok(EXIT_INVALID);
        }
        Err(e) => return Err(e.into()),
    };
    let estimate = study.memory_estimate(limits.jobs);
    if json {
        let report = serde_json::json!({
            "grid": grid.display().to_string(),
            "valid": true,
            "name": study.name,
            "cases": study.cases.len(),
            "references": study.references.len(),
            "axes": study.axes,
            "design": study.design.as_ref().map(|d| serde_json::json!({
                "method": d.method.name(),
                "samples": d.samples,
                "rows": d.rows,
                "parameters": d.parameters,
            })),
            "memory": memory_json(estimate.total, &limits),
        });
        out!("{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(EXIT_OK);
    }
    out!(
        "{}: ok, {} cases ({} ideal references), axes: {}{}; memory about {} on {} workers (limit {})",
        grid.display(),
        study.cases.len(),
        study.references.len(),
        if study.axes.is_empty() {
            "none".to_string()
        } else {
            study.axes.join(", ")
        },
        study.design.as_ref().map_or(String::new(), |d| format!(
            "; design: {} of {} samples ({} rows) over {}",
            d.method.name(),
            d.samples,
            d.rows,
            d.parameters.join(", ")
        )),
        memory::bytes(estimate.total),
        limits.jobs,
        memory::bytes(limits.memory as f64)
    )?;
    Ok(EXIT_OK)
}

/// The `memory` object of `validate --json` and `--dry-run --json`: the estimate of
/// the run's peak (bytes), the limit it was judged against (bytes) and the workers.
pub(super) fn memory_json(estimate: f64, limits: &Limits) -> serde_json::Value {
    serde_json::json!({
        "estimate_bytes": estimate.round(),
        "limit_bytes": limits.memory,
        "jobs": limits.jobs,
    })
}

pub(super) fn run_command(args: RunArgs) -> Result<u8> {
    let grid = args.grid.expect("clap requires the grid");
    let limits = limits(args.jobs, args.memory_limit);
    let study = load(&grid, &limits, args.shard)?;
    let output = args
        .output
        .unwrap_or_else(|| PathBuf::from(format!("{}.h5", study.name)));
    let jobs = limits.jobs;
    if args.dry_run {
        dry_run(&study, args.shard, &limits, args.json)?;
        return Ok(EXIT_OK);
    }
    let opts = RunOptions {
        output: output.clone(),
        jobs,
        resume: args.resume,
        force: args.force,
        shard: args.shard,
        quiet: args.quiet,
    };
    crate::interrupt::note_on_stop(&grid, &output, args.shard);
    let summary = run::run(&study, &opts)?;
    if summary.complete_before {
        say!(
            "studyrun: {} already holds this study's complete result ({} cases: {} ok, {} failed); nothing to do",
            output.display(),
            summary.cases,
            summary.ok,
            summary.failed
        );
        return Ok(exit_code(&summary, args.allow_failed));
    }
    if args.timings {
        say!("{}", summary.stats);
    }
    if !args.quiet {
        say!(
            "studyrun: {} cases into {} in {:.2} s ({} ok, {} failed{})",
            summary.cases,
            output.display(),
            summary.wall_time,
            summary.ok,
            summary.failed,
            if summary.resumed > 0 {
                format!(", {} from the journal", summary.resumed)
            } else {
                String::new()
            }
        );
    }
    if summary.rerun > 0 {
        say!(
            "studyrun: warning: {} cases of the journal were run again: their data were not \
             found intact in the partial file",
            summary.rerun
        );
    }
    if summary.failed_replicates > 0 {
        say!(
            "studyrun: {} perturbed replicates failed (their metrics are NaN; why is in \
             replicate_error_message)",
            summary.failed_replicates
        );
    }
    Ok(exit_code(&summary, args.allow_failed))
}

/// [`EXIT_CASES_FAILED`] when a case or a replicate failed (unless `allow_failed`),
/// else [`EXIT_OK`].
fn exit_code(summary: &RunSummary, allow_failed: bool) -> u8 {
    if (summary.failed > 0 || summary.failed_replicates > 0) && !allow_failed {
        EXIT_CASES_FAILED
    } else {
        EXIT_OK
    }
}
