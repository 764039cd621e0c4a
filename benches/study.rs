//! Study-level benchmark of the runner, in one run:
//!
//! - (a) wall time of a many-case study with 1 and 2 worker threads, run alternately
//!   for several rounds (a shared host's noise moves one pair by ±10 %), and the
//!   speed-up of the fastest and of the median runs;
//! - (b) peak RSS of the `studyrun` binary on a small and a ten times larger study
//!   (`wait4`'s `ru_maxrss` of the child process), and their ratio. Linux counts in a
//!   child's `ru_maxrss` the memory of the process that spawned it, up to its `exec`,
//!   so these children run first, while this bench is small, and the bench's own peak
//!   at that moment is printed beside them (a child's figure cannot be below it);
//! - (c) where the CPU time goes (thread CPU time: simulation vs spectra, encoding,
//!   journal and HDF5) and the output side's share, in the median run of each;
//! - (d) whether the bounded channel ever made a worker wait for the writer.
//!
//! Grids are generated into a temporary directory: the paper's axes (2 locations × 2
//! speeds × waviness off/on) times as many damping values as the case count needs.
//!
//! Run: `cargo bench --bench study`, or with parameters, e.g.
//! `cargo bench --bench study -- --cases 200 --duration 0.4 --rss-cases 200,2000`.
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `--cases N` | 64 | cases of the scaling and CPU-time study (rounded up to a multiple of 8) |
//! | `--rounds R` | 5 | rounds of that study, each at `-j 1` then `-j 2` |
//! | `--duration S` | 0.05 | simulated time per case of that study (s) |
//! | `--rss-cases A,B` | 200,2000 | case counts of the two memory runs |
//! | `--rss-duration S` | 0.01 | simulated time per case of the memory runs (s) |
//! | `--sample-rate HZ` | 50000 | samples per second of every series |
//! | `--compression L` | 1 | deflate level of the series and spectra (0: none) |
//! | `--dtype T` | float64 | `float64` or `float32` storage |

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use studyrun::run::{run, RunOptions, RunStats, RunSummary};
use studyrun::study::Study;

/// The bench's parameters (see the module documentation).
#[derive(Debug, Clone)]
struct Params {
    cases: usize,
    rounds: usize,
    duration: f64,
    rss_cases: [usize; 2],
    rss_duration: f64,
    sample_rate: f64,
    compression: u8,
    dtype: String,
}

impl Params {
    /// Parses `--name value` pairs; cargo's own `--bench` flag is ignored.
    fn from_args() -> Self {
        let mut p = Self {
            cases: 64,
            rounds: 5,
            duration: 0.05,
            rss_cases: [200, 2000],
            rss_duration: 0.01,
            sample_rate: 50_000.0,
            compression: 1,
            dtype: "float64".to_owned(),
        };
        let args: Vec<String> = std::env::args()
            .skip(1)
            .filter(|a| a != "--bench")
            .collect();
        for pair in args.chunks(2) {
            let [name, value] = pair else {
                panic!("`{}` needs a value", pair[0]);
            };
            match name.as_str() {
                "--cases" => p.cases = parse(name, value),
                "--rounds" => p.rounds = parse::<usize>(name, value).max(1),
                "--duration" => p.duration = parse(name, value),
                "--rss-cases" => {
                    let v: Vec<usize> = value.split(',').map(|s| parse(name, s)).collect();
                    p.rss_cases = v
                        .try_into()
                        .unwrap_or_else(|_| panic!("{name} takes two counts, e.g. 200,2000"));
                }
                "--rss-duration" => p.rss_duration = parse(name, value),
                "--sample-rate" => p.sample_rate = parse(name, value),
                "--compression" => p.compression = parse(name, value),
                "--dtype" => p.dtype = value.clone(),
                other => panic!("unknown parameter {other}; see benches/study.rs"),
            }
        }
        p
    }
}

/// The value of parameter `name`, or a panic naming it.
fn parse<T: std::str::FromStr>(name: &str, value: &str) -> T {
    value
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("bad value `{value}` for {name}"))
}

/// Writes a grid of at least `cases` cases (a multiple of 8) of `duration` seconds
/// into `dir`; returns its path.
fn write_grid(dir: &Path, name: &str, cases: usize, duration: f64, p: &Params) -> PathBuf {
    let dampings: Vec<String> = (0..cases.div_ceil(8).max(1))
        .map(|k| format!("{}", 300 + k))
        .collect();
    let text = format!(
        "name: {name}\n\
         duration: {duration}\n\
         sample_rate: {}\n\
         bearing: {{clearance: \"40 um\", stiffness: 9.57e9, waviness: {{number: 35}}}}\n\
         solver: {{method: dop853, rtol: 1e-8, atol: 1e-12}}\n\
         output: {{dtype: {}, compression: {}}}\n\
         max_cases: 1000000\n\
         grid:\n  location: [crank_ground, crank_rod]\n  rpm: [300, 600]\n  \
         waviness_amplitude: [\"0 um\", \"4 um\"]\n  damping: [{}]\n",
        p.sample_rate,
        p.dtype,
        p.compression,
        dampings.join(", ")
    );
    let path = dir.join(format!("{name}.yaml"));
    std::fs::write(&path, text).expect("write the grid");
    path
}

/// Runs `grid` in this process with `jobs` workers.
fn run_in_process(grid: &Path, output: &Path, jobs: usize) -> RunSummary {
    let study = Study::load(grid).expect("valid grid");
    let opts = RunOptions {
        output: output.to_owned(),
        jobs,
        resume: false,
        force: true,
        shard: None,
        quiet: true,
    };
    run(&study, &opts).expect("the study runs")
}

/// Runs the `studyrun` binary on `grid` with two workers; returns its wall time (s)
/// and peak resident set size (bytes), from `wait4` on the child.
fn run_child(grid: &Path, output: &Path) -> (f64, u64) {
    let start = Instant::now();
    // Reaped by `wait4` below, which also gives its resource usage.
    #[allow(clippy::zombie_processes)]
    let child = Command::new(env!("CARGO_BIN_EXE_studyrun"))
        .arg(grid)
        .args(["-o", output.to_str().expect("UTF-8 path"), "-j", "2", "-q"])
        .arg("--force")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn studyrun");
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value of this plain C struct.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `pid` is our child, not yet reaped (the `Child` is never waited on);
    // `status` and `usage` are valid for writing.
    let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(reaped, pid, "wait4 failed");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "studyrun failed on {}",
        grid.display()
    );
    // Linux reports ru_maxrss in KiB.
    (start.elapsed().as_secs_f64(), usage.ru_maxrss as u64 * 1024)
}

fn main() {
    let p = Params::from_args();
    let dir = tempfile::tempdir().expect("temporary directory");
    let n_time = (p.duration * p.sample_rate).round() as usize + 1;
    println!(
        "studyrun study bench: {} cases of {} s at {} Hz ({} samples x 12 series), {} deflate {}",
        p.cases.div_ceil(8) * 8,
        p.duration,
        p.sample_rate,
        n_time,
        p.dtype,
        p.compression
    );

    // Before anything makes this process large (see the module documentation).
    let floor = own_peak_rss();
    let rss: Vec<(usize, f64, u64)> = p
        .rss_cases
        .iter()
        .map(|&cases| {
            let name = format!("rss{cases}");
            let grid = write_grid(dir.path(), &name, cases, p.rss_duration, &p);
            let (wall, bytes) = run_child(&grid, &dir.path().join(format!("{name}.h5")));
            (cases, wall, bytes)
        })
        .collect();

    let grid = write_grid(dir.path(), "scaling", p.cases, p.duration, &p);
    let out = dir.path().join("scaling.h5");
    let (mut ones, mut twos) = (Vec::new(), Vec::new());
    for _ in 0..p.rounds {
        ones.push(run_in_process(&grid, &out, 1));
        twos.push(run_in_process(&grid, &out, 2));
    }
    let walls = |runs: &[RunSummary]| -> String {
        let w: Vec<String> = runs.iter().map(|r| format!("{:.3}", r.wall_time)).collect();
        w.join(" ")
    };
    println!("\n(a) scaling, {} rounds of -j 1 then -j 2", p.rounds);
    println!("  -j 1 runs (s)   {}", walls(&ones));
    println!("  -j 2 runs (s)   {}", walls(&twos));
    for r in [&mut ones, &mut twos] {
        r.sort_by(|a, b| a.wall_time.total_cmp(&b.wall_time));
    }
    let (one, two) = (&ones[p.rounds / 2], &twos[p.rounds / 2]);
    println!(
        "  speed-up        {:>9.2}   fastest runs ({:.3} / {:.3} s; issue: >= 1.85)",
        ones[0].wall_time / twos[0].wall_time,
        ones[0].wall_time,
        twos[0].wall_time
    );
    println!(
        "  speed-up        {:>9.2}   median runs ({:.3} / {:.3} s)",
        one.wall_time / two.wall_time,
        one.wall_time,
        two.wall_time
    );

    println!(
        "\n(b) peak RSS of the studyrun binary, -j 2, {} s cases",
        p.rss_duration
    );
    for &(cases, wall, bytes) in &rss {
        println!(
            "  {:>6} cases    {:>9.1} MB   ({wall:.1} s)",
            cases.div_ceil(8) * 8,
            bytes as f64 / 1e6
        );
    }
    println!(
        "  ratio           {:>9.3}   (issue: <= 1.25)",
        rss[1].2 as f64 / rss[0].2 as f64
    );
    if let Some(floor) = floor {
        println!(
            "  (this bench's own peak when it spawned them: {:.1} MB)",
            floor as f64 / 1e6
        );
    }

    for (jobs, summary) in [(1, one), (2, two)] {
        println!("\n(c, d) -j {jobs}, the median run: where the CPU time went");
        print_stats(&summary.stats);
    }
}

/// This process's peak resident set size (bytes), from `VmHWM` in
/// `/proc/self/status`; `None` where there is no such file.
fn own_peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// Prints a run's CPU time breakdown and channel counters, indented.
fn print_stats(stats: &RunStats) {
    for line in stats.to_string().lines() {
        println!("  {line}");
    }
}
