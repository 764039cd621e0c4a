//! The command line: builds the clap command and dispatches to the library.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::{Args, CommandFactory, Parser, Subcommand};

use studyrun::numeric::simd::Isa;
use studyrun::output;
use studyrun::simulate::CHANNELS;
use studyrun::study::memory::{self, Limits};
use studyrun::study::params::axis_value;
use studyrun::study::Shard;
use studyrun::study::{Study, StudyError};

/// Exit code: every case ran to the end.
const EXIT_OK: u8 = 0;
/// Exit code: an error stopped the run (I/O, HDF5, a worker failure).
const EXIT_ERROR: u8 = 1;
/// Exit code: the input is invalid (grid file, command line, an input file that is
/// missing, a directory or no HDF5 file); nothing ran.
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

mod accuracy;
mod dry_run;
mod study_run;

use accuracy::{accuracy_command, parse_rtol};
use dry_run::dry_run;
use study_run::{run_command, validate_command};

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
  studyrun inspect paper.h5 --json                   the summary as JSON (also validate, --dry-run)
  studyrun completions bash                          a shell completion script (also: studyrun man)

Exit codes: 0 all cases ok (or some failed, with --allow-failed); 1 error (I/O, HDF5,
output in use by another process); 2 invalid input (grid file, options, an input file
missing or not HDF5); 3 finished, some cases or replicates failed.

Environment: STUDYRUN_ISA=baseline runs the hot paths on SSE2 instead of AVX (the
results are the same bits; for speed comparisons); unset, the widest the CPU has.";

/// `studyrun --version`: the package version and the git commit it was built from
/// (`unknown` outside a release build, which alone asks git).
const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("STUDYRUN_GIT_COMMIT"),
    ")"
);

/// Parameter studies of a ball bearing with raceway waviness in a slider-crank.
#[derive(Parser)]
#[command(name = "studyrun", version = VERSION, about, after_help = EXAMPLES, args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
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
        /// Print the result as one JSON object (schema: docs/cli.md).
        #[arg(long)]
        json: bool,
    },
    /// Summarise a result file: grid, design, envelope, sensors, shard, status counts,
    /// failed cases with their errors.
    Inspect {
        /// The result file (HDF5).
        file: PathBuf,
        /// Print the summary as one JSON object (schema: docs/cli.md).
        #[arg(long)]
        json: bool,
        /// Also read every value and check every checksum (exit 1 naming what is
        /// damaged); the text summary ends with the verdict.
        #[arg(long)]
        verify: bool,
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
    /// Print a completion script for a shell, e.g.
    /// `studyrun completions bash > ~/.local/share/bash-completion/completions/studyrun`.
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff), e.g. `studyrun man > studyrun.1 && man ./studyrun.1`.
    Man,
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
    ///
    /// With fewer workers than the cores this process may use, the writer thread
    /// also analyses and encodes cases on a spare core, so `-j 1` can keep two cores
    /// busy.
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
    /// With --dry-run: print it as one JSON object (schema: docs/cli.md).
    #[arg(long, requires = "dry_run")]
    json: bool,
    /// Largest memory the run may need, e.g. 40GiB or 512MiB; a study whose estimate
    /// is larger is refused before anything runs [default: half the memory].
    #[arg(long, value_name = "SIZE", value_parser = parse_size)]
    memory_limit: Option<u64>,
    /// Exit 0 (not 3) when the study finished and some cases or replicates failed:
    /// they are recorded in the file. For job scripts whose next step depends on success.
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
            json,
        }) => validate_command(&grid, limits(jobs, memory_limit), json),
        Some(Command::Inspect { file, json, verify }) => inspect_command(&file, json, verify),
        Some(Command::Completions { shell }) => {
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "studyrun",
                &mut std::io::stdout(),
            );
            Ok(EXIT_OK)
        }
        Some(Command::Man) => clap_mangen::Man::new(Cli::command())
            .render(&mut std::io::stdout())
            .map_err(anyhow::Error::from)
            .map(|()| EXIT_OK),
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
            say!("studyrun: error: {}", describe(&e));
            ExitCode::from(exit_code(&e))
        }
    }
}

/// The exit code of a failure, the same for every command: invalid input (a grid file
/// refused, an input file that is missing, a directory or no HDF5 file) is
/// [`EXIT_INVALID`]; anything else that stopped the command is [`EXIT_ERROR`].
fn exit_code(e: &anyhow::Error) -> u8 {
    let not_a_file =
        |e: &output::StudyFileError| matches!(e, output::StudyFileError::NotHdf5 { .. });
    let invalid = e.chain().any(|cause| {
        cause.downcast_ref::<StudyError>().is_some()
            || cause
                .downcast_ref::<output::StudyFileError>()
                .is_some_and(not_a_file)
            || matches!(
                cause.downcast_ref::<output::OutputError>(),
                Some(output::OutputError::File { source, .. }) if not_a_file(source)
            )
    });
    if invalid {
        EXIT_INVALID
    } else {
        EXIT_ERROR
    }
}

/// `studyrun inspect FILE [--json] [--verify]`.
fn inspect_command(file: &Path, json: bool, verify: bool) -> Result<u8> {
    let summary = output::Summary::read(file)?;
    let verdict = verify.then(|| output::verify(file)).transpose()?;
    if json {
        out!("{}", serde_json::to_string_pretty(&summary)?)?;
    } else {
        out!("{}", summary.text().trim_end_matches('\n'))?;
        if let Some(line) = verdict {
            out!("{line}")?;
        }
    }
    Ok(EXIT_OK)
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

/// The study of `grid` under `limits`, holding only the cases of `part` when given.
fn load(grid: &Path, limits: &Limits, part: Option<Shard>) -> Result<Study> {
    Ok(Study::load_part(grid, limits, part)?)
}
