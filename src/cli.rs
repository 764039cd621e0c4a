//! The command line: builds the clap command and dispatches to the library.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};

use studyrun::numeric::simd::Isa;
use studyrun::output;
use studyrun::run::{self, RunOptions};
use studyrun::simulate::{simulate, Sampling, CHANNELS};
use studyrun::study::memory::{self, Limits};
use studyrun::study::params::axis_value;
use studyrun::study::Shard;
use studyrun::study::{Study, StudyError};

/// Exit code: every case ran to the end.
const EXIT_OK: u8 = 0;
/// Exit code: an error stopped the run (I/O, HDF5, a worker failure).
const EXIT_ERROR: u8 = 1;
/// Exit code: the input is invalid (grid file or command line); nothing ran.
const EXIT_INVALID: u8 = 2;
/// Exit code: the study finished and its file is complete, but some cases failed.
const EXIT_CASES_FAILED: u8 = 3;

/// Writes a line to stderr, ignoring failure (a full disk or closed stderr must not
/// turn a message into a panic).
macro_rules! say {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// Writes to stdout; a failure becomes an error of the command ([`StdoutClosed`] for
/// a reader that went away, e.g. `| head`).
macro_rules! out {
    ($($arg:tt)*) => {
        write_stdout(format_args!($($arg)*))
    };
}

/// Stdout is a pipe whose reader has gone: stop quietly.
#[derive(Debug)]
struct StdoutClosed;

impl fmt::Display for StdoutClosed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("standard output closed")
    }
}

impl std::error::Error for StdoutClosed {}

fn write_stdout(args: fmt::Arguments<'_>) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_fmt(args)
        .and_then(|()| stdout.write_all(b"\n"))
    {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(StdoutClosed.into()),
        Err(e) => Err(anyhow::Error::new(e).context("cannot write to standard output")),
    }
}

const EXAMPLES: &str = "\
Examples:
  studyrun studies/paper.yaml                        run the paper's study into paper.h5
  studyrun studies/paper.yaml -o out.h5 -j 2         two worker threads, chosen output
  studyrun studies/showcase.yaml --dry-run           list the cases, estimate size and time
  studyrun studies/showcase.yaml --resume            start, continue a killed run, or confirm it is done
  studyrun studies/showcase.yaml --shard 3/8 -o part3.h5 --resume
                                                     one of 8 shards (e.g. a Slurm array task)
  studyrun merge showcase.h5 part*.h5                combine the shards
  studyrun inspect paper.h5                          summary, status counts, failed cases
  studyrun validate studies/showcase.yaml            check a grid file without running it
  studyrun accuracy studies/accuracy_smoke.yaml      error and cost of every integrator setting
  studyrun accuracy studies/paper.yaml --methods tsit5   only one integrator's settings
  studyrun accuracy studies/paper.yaml --rtols 1e-7,5e-8 the adaptive methods at these rtols

Exit codes: 0 all cases ok (or some failed, with --allow-failed); 1 error (I/O, HDF5,
output in use by another process); 2 invalid input; 3 finished, some cases failed.

Environment: STUDYRUN_ISA=baseline runs the hot paths on SSE2 instead of AVX (the
results are the same bits; for speed comparisons); unset, the widest the CPU has.";

/// Parameter studies of a ball bearing with raceway waviness in a slider-crank.
#[derive(Parser)]
#[command(name = "studyrun", version, about, after_help = EXAMPLES, args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Run a study (the default command).
    Run(RunArgs),
    /// Check a grid file and print its cases' count and memory estimate; runs nothing.
    Validate {
        /// The grid file (YAML).
        grid: PathBuf,
        /// Worker threads the memory estimate is made for [default: all cores].
        #[arg(short, long, value_parser = clap::value_parser!(u64).range(1..))]
        jobs: Option<u64>,
        /// Largest memory a run may need, e.g. 40GiB [default: half the memory].
        #[arg(long, value_name = "SIZE", value_parser = parse_size)]
        memory_limit: Option<u64>,
    },
    /// Summarise a result file: grid, status counts, failed cases with their errors.
    Inspect {
        /// The result file (HDF5).
        file: PathBuf,
    },
    /// Measure what accuracy costs: every integrator over a ladder of settings against
    /// a tight reference, for each case of the grid; prints a table and the cheapest
    /// setting whose metric error stays below 1 %.
    Accuracy {
        /// The grid file (YAML); its solver settings are ignored.
        grid: PathBuf,
        /// Result file [default: <grid name>_accuracy.h5].
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Worker threads [default: all cores; at most 4 per core].
        #[arg(short, long, value_parser = clap::value_parser!(u64).range(1..))]
        jobs: Option<u64>,
        /// Overwrite OUTPUT if it exists (only a studyrun result file).
        #[arg(long)]
        force: bool,
        /// Largest memory the grid's run may need, e.g. 40GiB [default: half the memory].
        #[arg(long, value_name = "SIZE", value_parser = parse_size)]
        memory_limit: Option<u64>,
        /// Only these integrators of the ladder, comma-separated [default: all].
        #[arg(long, value_delimiter = ',', value_parser = clap::builder::PossibleValuesParser::new(studyrun::accuracy::METHOD_NAMES))]
        methods: Vec<String>,
        /// Relative tolerances for the adaptive methods instead of the decades 1e-3 …
        /// 1e-9 (SDIRK4: … 1e-8), comma-separated, e.g. 1e-7,5e-8,2e-8,1e-8; each
        /// above 1e-10 and below 0.1, with atol = 1e-4 rtol. RK4 keeps its steps up to the sample spacing.
        #[arg(long, value_delimiter = ',', value_parser = parse_rtol)]
        rtols: Vec<f64>,
    },
    /// Combine the shard files of one study into one file.
    Merge {
        /// The merged file to write.
        output: PathBuf,
        /// The shard files (any order).
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Overwrite OUTPUT if it exists (only a studyrun result file).
        #[arg(long)]
        force: bool,
    },
}

#[derive(Args)]
struct RunArgs {
    /// The grid file (YAML).
    #[arg(required = true)]
    grid: Option<PathBuf>,
    /// Result file [default: <grid name>.h5 in the current directory].
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Worker threads [default: all cores; at most 4 per core].
    #[arg(short, long, value_parser = clap::value_parser!(u64).range(1..))]
    jobs: Option<u64>,
    /// Continue an interrupted run from its journal (OUTPUT.journal).
    #[arg(long, conflicts_with = "force")]
    resume: bool,
    /// Overwrite an existing result file (only a studyrun result file) and discard any
    /// journal.
    #[arg(long)]
    force: bool,
    /// Run only shard K of N (cases whose id % N == K - 1).
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Print the case table, the memory estimate and the estimated size and time; run
    /// nothing.
    #[arg(long)]
    dry_run: bool,
    /// Largest memory the run may need, e.g. 40GiB or 512MiB; a study whose estimate
    /// is larger is refused before anything runs [default: half the memory].
    #[arg(long, value_name = "SIZE", value_parser = parse_size)]
    memory_limit: Option<u64>,
    /// Exit 0 (not 3) when the study finished and some cases failed: they are
    /// recorded in the file. For job scripts whose next step depends on success.
    #[arg(long)]
    allow_failed: bool,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
    /// After the run, print where the CPU time went (simulation, spectra, encoding,
    /// journal, HDF5) and whether the workers ever waited for the writer.
    #[arg(long)]
    timings: bool,
}

/// Parses the command line, runs the command and maps the outcome to an exit code.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(e) = Isa::requested() {
        say!("studyrun: error: {e}");
        return ExitCode::from(EXIT_INVALID);
    }
    let outcome = match cli.command {
        Some(Command::Run(args)) => run_command(args),
        None => run_command(cli.run),
        Some(Command::Validate {
            grid,
            jobs,
            memory_limit,
        }) => validate_command(&grid, jobs, memory_limit),
        Some(Command::Inspect { file }) => output::inspect(&file).and_then(|text| {
            out!("{}", text.trim_end_matches('\n'))?;
            Ok(EXIT_OK)
        }),
        Some(Command::Accuracy {
            grid,
            output,
            jobs,
            force,
            memory_limit,
            methods,
            rtols,
        }) => accuracy_command(
            &grid,
            output,
            limits(jobs, memory_limit),
            force,
            (&methods, &rtols),
        ),
        Some(Command::Merge {
            output,
            shards,
            force,
        }) => output::merge(&output, &shards, force)
            .map_err(anyhow::Error::from)
            .and_then(|n| {
                out!(
                    "merged {} shard files into {} ({n} cases)",
                    shards.len(),
                    output.display()
                )?;
                Ok(EXIT_OK)
            }),
    };
    match outcome {
        Ok(code) => ExitCode::from(code),
        Err(e) if e.downcast_ref::<StdoutClosed>().is_some() => ExitCode::from(EXIT_OK),
        Err(e) => {
            let code = if e.downcast_ref::<StudyError>().is_some() {
                EXIT_INVALID
            } else {
                EXIT_ERROR
            };
            say!("studyrun: error: {}", describe(&e));
            ExitCode::from(code)
        }
    }
}

/// The error and its causes on one line, each cause once: a cause whose text the
/// message already holds is not repeated.
fn describe(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

/// One `--memory-limit` value.
fn parse_size(text: &str) -> Result<u64, String> {
    memory::parse_size(text)
}

/// The worker threads to run: `requested` (at least 1), or all cores; more than
/// [`memory::max_jobs`] (4 per core, at most 1024) only adds threads that wait, so
/// such a request is lowered with a warning.
fn jobs(requested: Option<u64>) -> usize {
    let max = memory::max_jobs();
    match requested {
        None => memory::available_cores(),
        Some(j) if j as u128 > max as u128 => {
            say!(
                "studyrun: warning: -j {j} is more than 4 workers per available core ({} cores) \
                 or {}; using -j {max}",
                memory::available_cores(),
                memory::MAX_JOBS
            );
            max
        }
        Some(j) => j.max(1) as usize,
    }
}

/// The limits a grid is validated under: the workers and the memory limit.
fn limits(jobs_requested: Option<u64>, memory_limit: Option<u64>) -> Limits {
    Limits::new(memory_limit, Some(jobs(jobs_requested)))
}

fn load(grid: &Path, limits: &Limits) -> Result<Study> {
    Ok(Study::load_with(grid, limits)?)
}

fn validate_command(grid: &Path, jobs: Option<u64>, memory_limit: Option<u64>) -> Result<u8> {
    let limits = limits(jobs, memory_limit);
    let study = load(grid, &limits)?;
    let estimate = study.memory_estimate(limits.jobs);
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

fn run_command(args: RunArgs) -> Result<u8> {
    let grid = args.grid.expect("clap requires the grid");
    let limits = limits(args.jobs, args.memory_limit);
    let study = load(&grid, &limits)?;
    let output = args
        .output
        .unwrap_or_else(|| PathBuf::from(format!("{}.h5", study.name)));
    let jobs = limits.jobs;
    if args.dry_run {
        dry_run(&study, args.shard, &limits)?;
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
        return Ok(if summary.failed > 0 && !args.allow_failed {
            EXIT_CASES_FAILED
        } else {
            EXIT_OK
        });
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
    Ok(if summary.failed > 0 && !args.allow_failed {
        EXIT_CASES_FAILED
    } else {
        EXIT_OK
    })
}

/// Cases the dry run's time estimate is calibrated on: up to [`CALIBRATION_CASES`]
/// spread evenly over `rows`, bearing cases only when there are any (an ideal case
/// costs next to nothing and would make the estimate far too low).
const CALIBRATION_CASES: usize = 5;

fn calibration_rows(study: &Study, rows: &[usize]) -> Vec<usize> {
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

/// The case table, the memory estimate, the file size and a time estimate from short
/// calibration runs (10 % of the duration) of up to five cases spread over the table.
/// Never fails for want of an estimate: a calibration that cannot run says so.
fn dry_run(study: &Study, shard: Option<Shard>, limits: &Limits) -> Result<()> {
    let jobs = limits.jobs;
    let rows: Vec<usize> = match shard {
        Some(s) => study.shard(s.k, s.n),
        None => (0..study.cases.len()).collect(),
    };
    let mut header = vec!["case".to_string()];
    let varied = study.varied();
    header.extend(varied.iter().map(|v| v.to_string()));
    out!("{}", header.join("\t"))?;
    for &r in &rows {
        let c = &study.cases[r];
        let mut line = vec![c.id.to_string()];
        for axis in &varied {
            line.push(axis_value(axis, &c.params));
        }
        out!("{}", line.join("\t"))?;
    }
    let n_time = study.stored_times().len() as f64;
    let n_series = study.stored_series_count() as f64;
    let n_freq = (study.analysis_window().len() / 2 + 1) as f64;
    let width = if study.float32 { 4.0 } else { 8.0 };
    let raw = rows.len() as f64
        * (n_series * n_time + study.spectrum_channels.len() as f64 * n_freq)
        * width;
    let estimate = study.memory_estimate(jobs);
    out!(
        "\n{} cases ({} ideal references); {} stored series x {} samples (output.decimate {}) \
         and {} spectra per case; raw output {:.1} MB before compression (deflate level {}, {})",
        rows.len(),
        study.references.len(),
        n_series,
        n_time,
        study.output.decimate,
        study.spectrum_channels.len(),
        raw / 1e6,
        study.compression,
        if study.float32 { "float32" } else { "float64" },
    )?;
    out!(
        "memory: about {} of the limit {}: {}",
        memory::bytes(estimate.total),
        limits.describe(),
        estimate
    )?;
    if rows.is_empty() {
        out!("no cases in this shard: the run writes a file with the references only")?;
        return Ok(());
    }
    // Calibrate on 10 % of the duration of a few cases spread over the table.
    let short = Sampling {
        duration: 0.1 * study.sampling.duration,
        ..study.sampling
    };
    let mut times = Vec::new();
    let mut ids = Vec::new();
    let mut failures = Vec::new();
    let picked = calibration_rows(study, &rows);
    for &r in &picked {
        let case = &study.cases[r];
        match simulate(&case.params, &study.solver, &short) {
            Ok(o) => {
                times.push(o.wall_time * 10.0);
                ids.push(case.id.to_string());
            }
            Err(e) => failures.push(format!("case {}: {e}", case.id)),
        }
    }
    if times.is_empty() {
        out!(
            "time: estimate unavailable: no calibration run finished ({})",
            if failures.is_empty() {
                "no case to calibrate on".to_string()
            } else {
                failures.join("; ")
            }
        )?;
        return Ok(());
    }
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    out!(
        "time: about {} s on {jobs} threads (a case takes {:.3} s on average over cases {}, from runs of 10 % of the duration{})",
        {
            let total = mean * rows.len() as f64 / jobs as f64;
            if total < 10.0 {
                format!("{total:.1}")
            } else {
                format!("{total:.0}")
            }
        },
        mean,
        ids.join(", "),
        if failures.is_empty() {
            String::new()
        } else {
            format!(
                "; {} of {} calibration runs failed: {}",
                failures.len(),
                picked.len(),
                failures.join("; ")
            )
        }
    )?;
    Ok(())
}

/// One value of `accuracy --rtols`: a number the accuracy study can judge
/// ([`studyrun::accuracy::check_rtol`]).
fn parse_rtol(text: &str) -> Result<f64, String> {
    let rtol: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    studyrun::accuracy::check_rtol(rtol)?;
    Ok(rtol)
}

fn accuracy_command(
    grid: &Path,
    output: Option<PathBuf>,
    limits: Limits,
    force: bool,
    (methods, rtols): (&[String], &[f64]),
) -> Result<u8> {
    use studyrun::accuracy::{self, describe, setting_label, ERROR_CHANNELS};
    if let Some(twice) = rtols
        .iter()
        .enumerate()
        .find_map(|(k, r)| rtols[..k].contains(r).then_some(r))
    {
        clap::Error::raw(
            clap::error::ErrorKind::ValueValidation,
            format!("--rtols: {twice:e} is given twice; give each rtol once\n"),
        )
        .exit();
    }
    let study = load(grid, &limits)?;
    // The accuracy study keeps every case's reference run (all channels) to the end,
    // and each worker two more runs.
    let run_bytes = (CHANNELS.len() + 1) as f64 * 8.0 * study.sampling.len() as f64;
    let need = (study.cases.len() + study.references.len() + 3 * limits.jobs) as f64 * run_bytes
        + 64.0 * 1024.0 * 1024.0;
    if need > limits.memory as f64 {
        return Err(StudyError {
            path: grid.to_path_buf(),
            location: None,
            field: "grid".into(),
            message: format!(
                "the accuracy study keeps the reference run of each of its {} cases ({} each): \
                 about {} of memory, more than the limit of {}; fewer cases, a lower \
                 sample_rate or a shorter duration",
                study.cases.len(),
                memory::bytes(run_bytes),
                memory::bytes(need),
                limits.describe()
            ),
        }
        .into());
    }
    let output = output.unwrap_or_else(|| PathBuf::from(format!("{}_accuracy.h5", study.name)));
    // The output first, before all the work: nothing there that is not ours, no
    // replacing without --force, only a study file with it, and the lock held to the end.
    output::overwrite::check_output(&output, force, &[grid])?;
    let _lock = output::OutputLock::acquire(&output)?;
    output::overwrite::check_output(&output, force, &[grid])?;
    let jobs = limits.jobs;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build()?;
    let mut ladder = if rtols.is_empty() {
        accuracy::default_ladder()
    } else {
        accuracy::ladder_at(rtols)
    };
    if !methods.is_empty() {
        ladder.retain(|m| methods.iter().any(|name| name == describe(m).0));
    }
    // Only settings a grid file could run: RK4 steps up to the sample spacing.
    let spacing = 1.0 / study.sampling.sample_rate;
    ladder.retain(|m| accuracy::runnable(m, spacing));
    say!(
        "studyrun: accuracy of {} settings on {} cases (+2 reference runs each)",
        ladder.len(),
        study.cases.len()
    );
    let (refs, ms) = pool.install(|| accuracy::run(&study, &ladder))?;
    for r in &refs {
        let c = &study.cases[r.case];
        let labels: Vec<String> = study
            .varied()
            .iter()
            .map(|a| format!("{a}={}", axis_value(a, &c.params)))
            .collect();
        out!(
            "\ncase {} ({}): horizon {:.3} s of {} s{}; reference metric uncertainty {:.1e} / {:.1e} / {:.1e}",
            c.id,
            labels.join(", "),
            r.horizon,
            study.sampling.duration,
            if r.horizon < study.sampling.duration { " (chaotic: pointwise errors up to the horizon only)" } else { "" },
            r.metric_uncertainty[0],
            r.metric_uncertainty[1],
            r.metric_uncertainty[2]
        )?;
        out!("| method | setting | max err {0} | rms err {0} | metric err {0} | metric err {1} | metric err {2} | wall (s) | steps | rejected | RHS |", ERROR_CHANNELS[0], ERROR_CHANNELS[1], ERROR_CHANNELS[2])?;
        out!("|---|---|---|---|---|---|---|---|---|---|---|")?;
        for m in ms.iter().filter(|m| m.case == r.case) {
            let (name, setting) = describe(&m.method);
            match &m.error {
                Some(e) => out!("| {name} | {} | failed: {e} |", setting_label(setting))?,
                None => out!(
                    "| {name} | {} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.3} | {} | {} | {} |",
                    setting_label(setting),
                    m.max_error[0], m.rms_error[0], m.metric_error[0], m.metric_error[1], m.metric_error[2], m.wall_time, m.steps, m.rejected, m.rhs_evals
                )?,
            }
        }
    }
    out!("\nover all cases (metric error: worst channel, worst case):")?;
    out!("| method | setting | worst metric error | median metric error | total wall (s) | total RHS |")?;
    out!("|---|---|---|---|---|---|")?;
    for method in &ladder {
        let rows: Vec<_> = ms.iter().filter(|m| m.method == *method).collect();
        let mut errs: Vec<f64> = rows
            .iter()
            .map(|m| m.metric_error.iter().copied().fold(0.0, f64::max))
            .collect();
        errs.sort_by(f64::total_cmp);
        let (name, setting) = describe(method);
        out!(
            "| {name} | {} | {:.1e} | {:.1e} | {:.2} | {} |",
            setting_label(setting),
            errs.last().copied().unwrap_or(f64::NAN),
            errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN),
            rows.iter().map(|m| m.wall_time).sum::<f64>(),
            rows.iter().map(|m| m.rhs_evals).sum::<u64>()
        )?;
    }
    let chaotic: Vec<String> = refs
        .iter()
        .filter(|r| r.horizon < study.sampling.duration)
        .map(|r| study.cases[r.case].id.to_string())
        .collect();
    out!(
        "\nchaotic cases (the two references part before the end; horizon < {} s): {} of {}: {}",
        study.sampling.duration,
        chaotic.len(),
        refs.len(),
        chaotic.join(", ")
    )?;
    match accuracy::cheapest_within(&ms, &refs, &ladder, 0.01, study.sampling.duration) {
        Some((m, judged)) => {
            out!("cheapest setting with metric error < 1 % on the {judged} non-chaotic cases: {m}")?
        }
        None => out!("no setting keeps the metric error below 1 % on every non-chaotic case")?,
    }
    accuracy::write_file(&output, &study, &refs, &ms)?;
    say!("studyrun: wrote {}", output.display());
    Ok(EXIT_OK)
}
