//! The command line: builds the clap command and dispatches to the library.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use studyrun::numeric::simd::Isa;
use studyrun::output;
use studyrun::run::{self, RunOptions};
use studyrun::simulate::{simulate, Sampling, CHANNELS};
use studyrun::study::params::lookup;
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
    /// Check a grid file and print its cases' count; runs nothing.
    Validate {
        /// The grid file (YAML).
        grid: PathBuf,
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
        /// Worker threads [default: all cores].
        #[arg(short, long)]
        jobs: Option<usize>,
        /// Overwrite OUTPUT if it exists.
        #[arg(long)]
        force: bool,
        /// Only these integrators of the ladder, comma-separated [default: all].
        #[arg(long, value_delimiter = ',', value_parser = clap::builder::PossibleValuesParser::new(studyrun::accuracy::METHOD_NAMES))]
        methods: Vec<String>,
        /// Relative tolerances for the adaptive methods instead of the decades 1e-3 …
        /// 1e-9 (SDIRK4: … 1e-8), comma-separated, e.g. 1e-7,5e-8,2e-8,1e-8; each
        /// above 1e-10 and below 1, with atol = 1e-4 rtol. RK4 keeps its steps.
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
        /// Overwrite OUTPUT if it exists.
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
    /// Worker threads [default: all cores].
    #[arg(short, long)]
    jobs: Option<usize>,
    /// Continue an interrupted run from its journal (OUTPUT.journal).
    #[arg(long, conflicts_with = "force")]
    resume: bool,
    /// Overwrite an existing result file and discard any journal.
    #[arg(long)]
    force: bool,
    /// Run only shard K of N (cases whose id % N == K - 1).
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Print the case table and the estimated size and time; run nothing.
    #[arg(long)]
    dry_run: bool,
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
        eprintln!("studyrun: error: {e}");
        return ExitCode::from(EXIT_INVALID);
    }
    let outcome = match cli.command {
        Some(Command::Run(args)) => run_command(args),
        None => run_command(cli.run),
        Some(Command::Validate { grid }) => load(&grid).map(|study| {
            println!(
                "{}: ok, {} cases ({} ideal references), axes: {}",
                grid.display(),
                study.cases.len(),
                study.references.len(),
                study.axes.join(", ")
            );
            EXIT_OK
        }),
        Some(Command::Inspect { file }) => output::inspect(&file).map(|text| {
            print!("{text}");
            EXIT_OK
        }),
        Some(Command::Accuracy {
            grid,
            output,
            jobs,
            force,
            methods,
            rtols,
        }) => accuracy_command(&grid, output, jobs, force, (&methods, &rtols)),
        Some(Command::Merge {
            output,
            shards,
            force,
        }) => output::merge(&output, &shards, force)
            .map_err(anyhow::Error::from)
            .map(|n| {
                println!(
                    "merged {} shard files into {} ({n} cases)",
                    shards.len(),
                    output.display()
                );
                EXIT_OK
            }),
    };
    match outcome {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            let code = if e.downcast_ref::<StudyError>().is_some() {
                EXIT_INVALID
            } else {
                EXIT_ERROR
            };
            eprintln!("studyrun: error: {}", describe(&e));
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

fn load(grid: &Path) -> Result<Study> {
    Ok(Study::load(grid)?)
}

fn run_command(args: RunArgs) -> Result<u8> {
    let grid = args.grid.expect("clap requires the grid");
    let study = load(&grid)?;
    let output = args
        .output
        .unwrap_or_else(|| PathBuf::from(format!("{}.h5", study.name)));
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    if args.dry_run {
        dry_run(&study, args.shard, jobs)?;
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
    let summary = run::run(&study, &opts)?;
    if summary.complete_before {
        eprintln!(
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
        eprintln!("{}", summary.stats);
    }
    if !args.quiet {
        eprintln!(
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
        eprintln!(
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

/// The case table, the file size and a time estimate from a short calibration run.
fn dry_run(study: &Study, shard: Option<Shard>, jobs: usize) -> Result<()> {
    let rows: Vec<usize> = match shard {
        Some(s) => study.shard(s.k, s.n),
        None => (0..study.cases.len()).collect(),
    };
    let mut header = vec!["case".to_string()];
    header.extend(study.axes.iter().cloned());
    println!("{}", header.join("\t"));
    for &r in &rows {
        let c = &study.cases[r];
        let mut line = vec![c.id.to_string()];
        for axis in &study.axes {
            line.push(match lookup(axis) {
                Some(p) => format!("{}", p.get(&c.params)),
                None => c.params.location.to_string(),
            });
        }
        println!("{}", line.join("\t"));
    }
    let n_time = study.sampling.len() as f64;
    let n_freq = (study.analysis_window().len() / 2 + 1) as f64;
    let width = if study.float32 { 4.0 } else { 8.0 };
    let raw = rows.len() as f64
        * (CHANNELS.len() as f64 * n_time + study.spectrum_channels.len() as f64 * n_freq)
        * width;
    if rows.is_empty() {
        println!("\nno cases in this shard: the run writes a file with the references only");
        return Ok(());
    }
    // Calibrate on 10 % of the first case's duration.
    let probe = &study.cases[rows[0]].params;
    let short = Sampling {
        duration: 0.1 * study.sampling.duration,
        ..study.sampling
    };
    let t = simulate(probe, &study.solver, &short)
        .context("calibration run")?
        .wall_time
        * 10.0;
    println!(
        "\n{} cases ({} ideal references); raw output {:.1} MB before compression (deflate level {}, {}); estimated time ~{:.0} s on {jobs} threads (from {:.3} s for case {})",
        rows.len(),
        study.references.len(),
        raw / 1e6,
        study.compression,
        if study.float32 { "float32" } else { "float64" },
        t * rows.len() as f64 / jobs as f64,
        t,
        study.cases[rows[0]].id
    );
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
    jobs: Option<usize>,
    force: bool,
    (methods, rtols): (&[String], &[f64]),
) -> Result<u8> {
    use studyrun::accuracy::{self, describe, ERROR_CHANNELS};
    let study = load(grid)?;
    let output = output.unwrap_or_else(|| PathBuf::from(format!("{}_accuracy.h5", study.name)));
    if output.exists() && !force {
        anyhow::bail!("{} exists; use --force to overwrite it", output.display());
    }
    let jobs = jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build()?;
    let mut ladder = if rtols.is_empty() {
        accuracy::default_ladder()
    } else {
        accuracy::ladder_at(rtols)
    };
    if !methods.is_empty() {
        ladder.retain(|m| methods.iter().any(|name| name == describe(m).0));
    }
    eprintln!(
        "studyrun: accuracy of {} settings on {} cases (+2 reference runs each)",
        ladder.len(),
        study.cases.len()
    );
    let (refs, ms) = pool.install(|| accuracy::run(&study, &ladder))?;
    for r in &refs {
        let c = &study.cases[r.case];
        let labels: Vec<String> = study
            .axes
            .iter()
            .map(|a| match lookup(a) {
                Some(p) => format!("{a}={}", p.get(&c.params)),
                None => format!("{a}={}", c.params.location),
            })
            .collect();
        println!(
            "\ncase {} ({}): horizon {:.3} s of {} s{}; reference metric uncertainty {:.1e} / {:.1e} / {:.1e}",
            c.id,
            labels.join(", "),
            r.horizon,
            study.sampling.duration,
            if r.horizon < study.sampling.duration { " (chaotic: pointwise errors up to the horizon only)" } else { "" },
            r.metric_uncertainty[0],
            r.metric_uncertainty[1],
            r.metric_uncertainty[2]
        );
        println!("| method | setting | max err {0} | rms err {0} | metric err {0} | metric err {1} | metric err {2} | wall (s) | steps | rejected | RHS |", ERROR_CHANNELS[0], ERROR_CHANNELS[1], ERROR_CHANNELS[2]);
        println!("|---|---|---|---|---|---|---|---|---|---|---|");
        for m in ms.iter().filter(|m| m.case == r.case) {
            let (name, setting) = describe(&m.method);
            match &m.error {
                Some(e) => println!("| {name} | {setting:.0e} | failed: {e} |"),
                None => println!(
                    "| {name} | {setting:.0e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.3} | {} | {} | {} |",
                    m.max_error[0], m.rms_error[0], m.metric_error[0], m.metric_error[1], m.metric_error[2], m.wall_time, m.steps, m.rejected, m.rhs_evals
                ),
            }
        }
    }
    println!("\nover all cases (metric error: worst channel, worst case):");
    println!("| method | setting | worst metric error | median metric error | total wall (s) | total RHS |");
    println!("|---|---|---|---|---|---|");
    for method in &ladder {
        let rows: Vec<_> = ms.iter().filter(|m| m.method == *method).collect();
        let mut errs: Vec<f64> = rows
            .iter()
            .map(|m| m.metric_error.iter().copied().fold(0.0, f64::max))
            .collect();
        errs.sort_by(f64::total_cmp);
        let (name, setting) = describe(method);
        println!(
            "| {name} | {setting:.0e} | {:.1e} | {:.1e} | {:.2} | {} |",
            errs.last().copied().unwrap_or(f64::NAN),
            errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN),
            rows.iter().map(|m| m.wall_time).sum::<f64>(),
            rows.iter().map(|m| m.rhs_evals).sum::<u64>()
        );
    }
    let chaotic: Vec<String> = refs
        .iter()
        .filter(|r| r.horizon < study.sampling.duration)
        .map(|r| study.cases[r.case].id.to_string())
        .collect();
    println!(
        "\nchaotic cases (the two references part before the end; horizon < {} s): {} of {}: {}",
        study.sampling.duration,
        chaotic.len(),
        refs.len(),
        chaotic.join(", ")
    );
    match accuracy::cheapest_within(&ms, &refs, &ladder, 0.01, study.sampling.duration) {
        Some((m, judged)) => println!(
            "cheapest setting with metric error < 1 % on the {judged} non-chaotic cases: {m:?}"
        ),
        None => println!("no setting keeps the metric error below 1 % on every non-chaotic case"),
    }
    accuracy::write_file(&output, &study, &refs, &ms)?;
    eprintln!("studyrun: wrote {}", output.display());
    Ok(EXIT_OK)
}
