//! Bounded memory, decided before anything runs: what a study's run holds in memory
//! ([`MemoryEstimate`]), the limit it must fit ([`Limits`]) and the size cap of a
//! grid file ([`MAX_GRID_BYTES`]).
//!
//! A run holds, at its peak (docs/model.md leaves this to the engine; the figures are
//! upper bounds, series are float64 in memory whatever the file stores):
//!
//! - per worker, the case it is computing: its samples × (channels + time) as
//!   float64, the spectra with their FFT buffers, and the case's encoded record
//!   (stored samples × stored series + spectra bins, at the stored width) with the
//!   encoder's scratch;
//! - the records waiting for the writer: at most two per worker, and the one it writes;
//! - the ideal references a run keeps, every channel of each: at most
//!   [`reference_cache_entries`] of them, whatever the number of distinct references;
//! - the case table: every case's parameters, their copy in the file's layout and the
//!   run's bookkeeping;
//! - a fixed part for the program, the HDF5 library and thread stacks.

use std::fmt;
use std::path::Path;

use crate::simulate::CHANNELS;
use crate::study::params::PARAMETERS;

/// Largest grid file read (bytes): a grid of this size already expands to more cases
/// than any memory holds; larger files (and endless ones such as `/dev/zero`) are
/// refused before parsing.
pub const MAX_GRID_BYTES: u64 = 4 << 20;

/// Most worker threads accepted in any case (`-j`); see [`max_jobs`].
pub const MAX_JOBS: usize = 1024;

/// Memory of the program itself: code, the HDF5 library, allocator arenas (bytes).
const FIXED_BYTES: f64 = 64.0 * 1024.0 * 1024.0;
/// One design value while a study expands: the unit draw and the resolved value
/// with its place in the grid file.
const DESIGN_VALUE_BYTES: f64 = 8.0 + 40.0;
/// One entry of the table that numbers the whole study's distinct references while it
/// is expanded: a 16-byte key (body set, speed) and its id and first case (16 bytes)
/// and the table's control byte, in a hash table at most 7/8 full that doubles when it
/// grows.
pub const REFERENCE_ID_BYTES: f64 = 2.0 * 33.0 * 8.0 / 7.0;
/// Per worker beyond its case's data: thread stack, deflate state, FFT twiddles.
const WORKER_BYTES: f64 = 4.0 * 1024.0 * 1024.0;

/// Bytes of ideal references a run keeps for its workers (at least two per worker):
/// a study with more distinct references makes them again where a case needs one.
pub const REFERENCE_CACHE_BYTES: f64 = 64.0 * 1024.0 * 1024.0;

/// The ideal references a run keeps at once, of `references` of `bytes` each on `jobs`
/// workers: all of them when they fit in [`REFERENCE_CACHE_BYTES`], else what fits
/// there, and never fewer than two per worker.
pub fn reference_cache_entries(references: u64, jobs: usize, bytes: f64) -> u64 {
    let fit = (REFERENCE_CACHE_BYTES / bytes.max(1.0)).floor() as u64;
    references.min(fit.max(2 * jobs.max(1) as u64))
}

/// The most worker threads a run may start: four per available core, at most
/// [`MAX_JOBS`]. More only adds threads that wait (and memory for their buffers).
pub fn max_jobs() -> usize {
    (4 * available_cores()).clamp(1, MAX_JOBS)
}

/// The cores this process may run on (1 if unknown).
pub fn available_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Values the writer holds per case for `replicates` runs per case (0: none): each
/// replicated metric per replicate, its mean, deviation and interval, the horizon
/// and the chaotic flag. In floating point, as every count here: a count from an
/// absurd input (10^300 rpm) must give an absurd estimate, not overflow.
fn replicate_values(replicates: u64) -> f64 {
    if replicates == 0 {
        return 0.0;
    }
    let metrics = crate::signal::replicates::replicated_metrics().len() as f64;
    replicates as f64 * metrics + 3.0 * metrics + 2.0
}

/// Values the writer holds per case for `revolutions` revolutions: each
/// per-revolution metric per revolution.
fn revolution_values(revolutions: u64) -> f64 {
    revolutions as f64 * crate::signal::revolutions::revolution_metric_specs().len() as f64
}

/// Bytes one case takes in the case table of a run: its parameters (with the
/// waviness harmonics on the heap), their copy in the file's layout (one f64 per
/// parameter, the location label, case id and reference index), the copies the file
/// writer makes of them while it creates the file, and the run's per-case
/// bookkeeping (row, dispatch order, journal index). Measured: a run of 200 000 cases
/// of 11 samples peaks at 232 MB, 1.1 kB per case.
pub fn case_table_bytes() -> f64 {
    let case = std::mem::size_of::<super::Case>() as f64;
    let harmonics = 2.0 * 32.0;
    let layout = 8.0 * PARAMETERS.len() as f64 + (24.0 + 32.0) + 16.0;
    let writer = 8.0 * PARAMETERS.len() as f64 + (24.0 + 32.0) + 16.0 + 256.0;
    let bookkeeping = 64.0;
    case + harmonics + layout + writer + bookkeeping
}

/// What determines a study's memory, known before its cases are expanded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    /// Samples per case, both ends included.
    pub samples: u64,
    /// Samples in the analysed window (the spectra's length).
    pub window: u64,
    /// Spectrum channels.
    pub spectra: usize,
    /// Series per case beyond the simulated channels: two per sensor.
    pub sensor_series: usize,
    /// Series per case the file stores (`output.series`): channels and sensor series.
    pub stored_series: usize,
    /// Samples per stored series (`output.decimate` applied).
    pub stored_samples: u64,
    /// Series and spectra stored as float32.
    pub float32: bool,
    /// Cases the run holds: the study's, or one shard's.
    pub cases: u64,
    /// Ideal references the run's cases use (an upper bound before expansion).
    pub references: u64,
    /// Distinct ideal references of the whole study, numbered while it is expanded
    /// (0 before they are known): an entry of [`REFERENCE_ID_BYTES`] each, whatever
    /// part of the study the run holds.
    pub study_references: u64,
    /// Values a sampled design holds while the study is expanded (rows × parameters).
    pub design_values: u64,
    /// Runs per case with `replicates:` (0 without).
    pub replicates: u64,
    /// Length of the `revolution` dimension (most whole revolutions of a case).
    pub revolutions: u64,
    /// Order spectra per case (docs/model.md §7.9), `window / 2 + 1` values each,
    /// held with the case table like the per-revolution values.
    pub order_spectra: usize,
    /// Knots of the longest `speed:` table a case holds (0 without one): a time and
    /// a speed each, in every case that has the table.
    pub speed_knots: u64,
}

impl Shape {
    /// Bytes one case takes in the run's case table: its parameters and bookkeeping
    /// ([`case_table_bytes`]), its replicate and per-revolution values and its order
    /// spectra.
    pub fn case_bytes(&self) -> f64 {
        let n_f = (self.window / 2 + 1) as f64;
        case_table_bytes()
            + (replicate_values(self.replicates) + revolution_values(self.revolutions)) * 8.0
            + self.order_spectra as f64 * n_f * 8.0
            + self.speed_knots as f64 * 16.0
    }
}

/// The memory a run of a study needs at its peak, by part (bytes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryEstimate {
    /// What it was estimated for.
    pub shape: Shape,
    /// Worker threads.
    pub jobs: usize,
    /// One case in a worker: series as float64, spectra and FFT buffers, its
    /// encoded record and the encoder's scratch.
    pub per_case: f64,
    /// One encoded record (series and spectra at the stored width).
    pub record: f64,
    /// Records waiting for the writer (two per worker) and the one it writes.
    pub queued: f64,
    /// The ideal references' series the run keeps ([`reference_cache_entries`] of them).
    pub references: f64,
    /// The case table: parameters, their copy in the file layout, bookkeeping.
    pub case_table: f64,
    /// The program, libraries, thread stacks, the time and frequency coordinates.
    pub fixed: f64,
    /// Everything.
    pub total: f64,
}

impl MemoryEstimate {
    /// The estimate for a study of `shape` run on `jobs` workers.
    pub fn of(shape: Shape, jobs: usize) -> Self {
        let n = shape.samples as f64;
        let n_w = shape.window as f64;
        let n_f = (shape.window / 2 + 1) as f64;
        let s = shape.spectra as f64;
        let simulated = CHANNELS.len() as f64;
        let width = if shape.float32 { 4.0 } else { 8.0 };
        let jobs_f = jobs.max(1) as f64;
        // The case's series (every channel is simulated) and their times, float64.
        let series = (simulated + shape.sensor_series as f64 + 1.0) * n * 8.0;
        // Spectra, the FFT's window, input, output and scratch, the metrics' temporaries.
        // A sensor's noise draws are held while its noisy series is made.
        let draws = if shape.sensor_series > 0 {
            n * 8.0
        } else {
            0.0
        };
        let analysis = s * n_f * 8.0 + 3.0 * n_w * 8.0 + 2.0 * n_f * 16.0 + draws;
        // Only the stored series outlive the analysis, at the stored rate.
        let n_s = shape.stored_samples as f64;
        let record =
            (shape.stored_series as f64 * n_s + s * n_f) * width * (1.0 + 1.0 / 64.0) + 4096.0;
        // The encoder shuffles one series at a time.
        let scratch = n_s.max(n_f) * width + WORKER_BYTES;
        // A perturbed replicate's series beside replicate 0's, kept for its horizon.
        let replicate_series = if shape.replicates > 1 { series } else { 0.0 };
        let per_case = series + replicate_series + analysis + record + scratch;
        let queued = (2.0 * jobs_f + 1.0) * record;
        // The references have the simulated channels only.
        let reference = (simulated + 1.0) * n * 8.0;
        let references =
            reference_cache_entries(shape.references, jobs, reference) as f64 * reference;
        let case_table = shape.cases as f64 * shape.case_bytes()
            + shape.design_values as f64 * DESIGN_VALUE_BYTES
            + shape.study_references as f64 * REFERENCE_ID_BYTES;
        let fixed = FIXED_BYTES + (n + n_s + n_f) * 8.0;
        let total = jobs_f * per_case + queued + references + case_table + fixed;
        Self {
            shape,
            jobs: jobs.max(1),
            per_case,
            record,
            queued,
            references,
            case_table,
            fixed,
            total,
        }
    }

    /// The parts of a lower bound ([`Shape`] with only the samples, cases, design
    /// values, references and revolutions known), e.g. `2 workers x 9.8 GiB for one
    /// case's 1000001 samples x 15 channels as float64, …`.
    pub fn lower_bound_parts(&self) -> String {
        format!(
            "{} for one case's {} samples x {} channels as float64, {} ({} revolutions \
             per case), fixed {}",
            self.workers(),
            self.shape.samples,
            CHANNELS.len(),
            self.held_parts(),
            count(self.shape.revolutions),
            bytes(self.fixed),
        )
    }

    /// `2 workers x 9.8 GiB`: the workers and what each holds for its case.
    fn workers(&self) -> String {
        let plural = if self.jobs == 1 { "" } else { "s" };
        format!("{} worker{plural} x {}", self.jobs, bytes(self.per_case))
    }

    /// The parts held for the whole run: `3 references x 2.75 MiB, case table 12
    /// cases x 2.19 KiB and the study's 3 reference ids = 26.4 KiB` (`58 of 16384
    /// references x …` when the run keeps only some of them; the design's values
    /// named too when it has one).
    fn held_parts(&self) -> String {
        let s = &self.shape;
        let reference = (CHANNELS.len() as f64 + 1.0) * s.samples as f64 * 8.0;
        let kept = reference_cache_entries(s.references, self.jobs, reference);
        let study = match (s.design_values, s.study_references) {
            (0, 0) => String::new(),
            (0, r) => format!(" and the study's {r} reference ids"),
            (d, 0) => format!(" and the study's {d} design values"),
            (d, r) => format!(" and the study's {d} design values and {r} reference ids"),
        };
        format!(
            "{}{} reference{} x {}, case table {} cases x {}{study} = {}",
            if kept < s.references {
                format!("{kept} of ")
            } else {
                String::new()
            },
            s.references,
            if s.references == 1 { "" } else { "s" },
            bytes(reference),
            s.cases,
            bytes(s.case_bytes()),
            bytes(self.case_table),
        )
    }

    /// The part that weighs most, and so what to lower.
    pub fn largest(&self) -> Largest {
        let workers = self.jobs as f64 * self.per_case + self.queued;
        if self.case_table >= workers.max(self.references) {
            Largest::CaseTable
        } else if self.references > workers {
            Largest::References
        } else {
            Largest::Samples
        }
    }
}

/// The largest part of a [`MemoryEstimate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Largest {
    /// The cases in the workers and the records queued: lower the samples per case.
    Samples,
    /// The ideal references the run keeps (two per worker at least): fewer samples.
    References,
    /// The case table: fewer cases, or fewer values per case.
    CaseTable,
}

/// `n` as written, or in powers of ten above 10^12 (`1.8e19`).
fn count(n: u64) -> String {
    if n < 1_000_000_000_000 {
        n.to_string()
    } else {
        format!("{:.1e}", n as f64)
    }
}

impl fmt::Display for MemoryEstimate {
    /// The breakdown, e.g. `2 workers x 9.8 GiB per case (…), …`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.shape;
        write!(
            f,
            "{} per case ({} samples x {} channels as float64, {} spectr{}, the encoded \
             record of {} stored series x {} samples), {} records queued for the writer \
             x {}, {}, fixed {}",
            self.workers(),
            s.samples,
            CHANNELS.len(),
            s.spectra,
            if s.spectra == 1 { "um" } else { "a" },
            s.stored_series,
            s.stored_samples,
            2 * self.jobs + 1,
            bytes(self.record),
            self.held_parts(),
            bytes(self.fixed),
        )
    }
}

/// How much memory a study may need and how many workers it runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest memory estimate accepted (bytes).
    pub memory: u64,
    /// Where [`Limits::memory`] came from.
    pub memory_source: LimitSource,
    /// Worker threads the estimate is made for.
    pub jobs: usize,
}

/// Where a memory limit came from, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitSource {
    /// Half of the physical memory (or of the control group's limit, if lower).
    Default {
        /// The memory it is half of (bytes).
        physical: u64,
    },
    /// Given by the caller (`--memory-limit`).
    Explicit,
}

impl Default for Limits {
    /// Half of the memory this process may use, all available cores.
    fn default() -> Self {
        let physical = physical_memory().unwrap_or(8 << 30);
        Self {
            memory: physical / 2,
            memory_source: LimitSource::Default { physical },
            jobs: available_cores(),
        }
    }
}

impl Limits {
    /// The default limits with the caller's memory limit (bytes) and workers, where given.
    pub fn new(memory: Option<u64>, jobs: Option<usize>) -> Self {
        let mut limits = Self::default();
        if let Some(m) = memory {
            limits.memory = m;
            limits.memory_source = LimitSource::Explicit;
        }
        if let Some(j) = jobs {
            limits.jobs = j.max(1);
        }
        limits
    }

    /// The limit and where it came from, for messages: `11.6 GiB (half of the 23.3 GiB
    /// of physical memory)`.
    pub fn describe(&self) -> String {
        match self.memory_source {
            LimitSource::Default { physical } => format!(
                "{} (half of the {} of memory; raise it with --memory-limit SIZE, e.g. --memory-limit {}GiB)",
                bytes(self.memory as f64),
                bytes(physical as f64),
                (physical as f64 / (1u64 << 30) as f64 * 0.8).max(1.0).round()
            ),
            LimitSource::Explicit => format!("{} (--memory-limit)", bytes(self.memory as f64)),
        }
    }
}

/// The memory this process may use (bytes): the physical memory (`MemTotal` of
/// `/proc/meminfo`, else `sysconf`), or the control group's limit if lower (a batch
/// job's allocation).
pub fn physical_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
                .map(|kb| kb * 1024)
        });
    let physical = meminfo.or_else(|| {
        // SAFETY: sysconf has no preconditions.
        let (pages, size) = unsafe {
            (
                libc::sysconf(libc::_SC_PHYS_PAGES),
                libc::sysconf(libc::_SC_PAGESIZE),
            )
        };
        (pages > 0 && size > 0).then(|| pages as u64 * size as u64)
    })?;
    let cgroup = [
        "/sys/fs/cgroup/memory.max",
        "/sys/fs/cgroup/memory/memory.limit_in_bytes",
    ]
    .iter()
    .filter_map(|p| std::fs::read_to_string(p).ok())
    .filter_map(|t| t.trim().parse::<u64>().ok())
    .min();
    Some(cgroup.map_or(physical, |c| c.min(physical)))
}

/// A size as people write it: `40GiB`, `40 GiB`, `512MiB`, `1.5T`, `2GB`, `1000000`
/// (bytes). `K`/`M`/`G`/`T` alone and with `iB` are powers of 1024; `kB`/`MB`/`GB`/`TB`
/// powers of 1000.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num.parse().map_err(|_| {
        format!("`{text}` is not a size; expected a number with a unit, e.g. 40GiB or 512MiB")
    })?;
    let factor: f64 = match unit.trim() {
        "" | "B" => 1.0,
        "K" | "KiB" | "k" => 1024.0,
        "M" | "MiB" => 1024f64.powi(2),
        "G" | "GiB" => 1024f64.powi(3),
        "T" | "TiB" => 1024f64.powi(4),
        "kB" | "KB" => 1e3,
        "MB" => 1e6,
        "GB" => 1e9,
        "TB" => 1e12,
        other => {
            return Err(format!(
                "unknown unit `{other}` in `{text}`; expected B, KiB, MiB, GiB, TiB (or kB, MB, GB, TB)"
            ))
        }
    };
    let size = value * factor;
    if !(size.is_finite() && size >= 1.0 && size < u64::MAX as f64) {
        return Err(format!("`{text}` is not a usable memory size"));
    }
    Ok(size as u64)
}

/// `bytes` for people: `14.3 GiB`, `512 MiB`, `800 B`; beyond 1024 PiB in powers of
/// ten (`3.2e21 B`), so that an absurd estimate stays one short word.
pub fn bytes(bytes: f64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if v >= 1024.0 {
        format!("{bytes:.1e} B")
    } else if u == 0 {
        format!("{v:.0} B")
    } else if v < 10.0 {
        format!("{v:.2} {}", UNITS[u])
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Reads the grid file at `path`, refusing one larger than [`MAX_GRID_BYTES`]
/// (without reading more than that, so that `/dev/zero` is refused at once). A FIFO
/// is opened without waiting for a writer: one nobody writes to reads as empty.
pub fn read_capped(path: &Path) -> Result<String, String> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| format!("cannot read: {e}"))?;
    // Reads wait again for data (a pipe's writer may be slower than this process).
    // SAFETY: fcntl on a descriptor `file` owns.
    unsafe {
        let flags = libc::fcntl(file.as_raw_fd(), libc::F_GETFL);
        libc::fcntl(file.as_raw_fd(), libc::F_SETFL, flags & !libc::O_NONBLOCK);
    }
    if let Ok(m) = file.metadata() {
        if m.is_dir() {
            return Err("is a directory, not a grid file".into());
        }
        if m.is_file() && m.len() > MAX_GRID_BYTES {
            return Err(too_large(Some(m.len())));
        }
    }
    let mut bytes = Vec::new();
    file.take(MAX_GRID_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > MAX_GRID_BYTES {
        return Err(too_large(None));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "is not a text file (not UTF-8 at byte {}); a grid file is YAML text",
            e.utf8_error().valid_up_to()
        )
    })
}

/// The refusal of a grid file of `len` bytes (`None`: a stream that went on past the cap).
fn too_large(len: Option<u64>) -> String {
    let size = match len {
        Some(len) => format!("is {} ({len} bytes)", bytes(len as f64)),
        None => format!(
            "goes on past {} (a device or stream?)",
            bytes(MAX_GRID_BYTES as f64)
        ),
    };
    format!(
        "{size}: larger than a grid file may be (at most {}); a grid describes its \
         cases with axes, it does not list them",
        bytes(MAX_GRID_BYTES as f64)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_binary_and_decimal_units() {
        assert_eq!(parse_size("40GiB").unwrap(), 40 << 30);
        assert_eq!(parse_size("40 GiB").unwrap(), 40 << 30);
        assert_eq!(parse_size("512M").unwrap(), 512 << 20);
        assert_eq!(parse_size("2GB").unwrap(), 2_000_000_000);
        assert_eq!(parse_size("1.5K").unwrap(), 1536);
        assert_eq!(parse_size("1000").unwrap(), 1000);
        assert!(parse_size("lots").is_err());
        assert!(parse_size("4 parsecs").is_err());
        assert!(parse_size("0").is_err());
    }

    /// A million cases of 20 001 samples, no options.
    fn million_short_cases() -> Shape {
        Shape {
            samples: 20_001,
            window: 10_000,
            spectra: 3,
            float32: false,
            cases: 1_000_000,
            references: 1,
            study_references: 1,
            design_values: 0,
            replicates: 0,
            revolutions: 0,
            sensor_series: 0,
            stored_series: CHANNELS.iter().filter(|c| c.effect.is_none()).count(),
            stored_samples: 20_001,
            order_spectra: 0,
            speed_knots: 0,
        }
    }

    /// Replicates add a second set of series per worker and their values per case.
    #[test]
    fn replicates_count_their_series_and_values() {
        let shape = million_short_cases();
        let plain = MemoryEstimate::of(shape, 2);
        let repl = MemoryEstimate::of(
            Shape {
                replicates: 16,
                ..shape
            },
            2,
        );
        let series = (CHANNELS.len() as f64 + 1.0) * 20_001.0 * 8.0;
        assert_eq!(repl.per_case - plain.per_case, series);
        let n = crate::signal::replicates::replicated_metrics().len() as f64;
        let values = 1e6 * (16.0 * n + 3.0 * n + 2.0) * 8.0;
        assert!((repl.case_table - plain.case_table - values).abs() < 1e-6 * values);
    }

    #[test]
    fn revolutions_count_their_values_in_the_case_table() {
        let shape = million_short_cases();
        let plain = MemoryEstimate::of(shape, 2);
        let revs = MemoryEstimate::of(
            Shape {
                revolutions: 10,
                ..shape
            },
            2,
        );
        // Six per-revolution metrics, ten values each, per case; nothing else grows.
        let values = 1e6 * 10.0 * 6.0 * 8.0;
        assert!((revs.case_table - plain.case_table - values).abs() < 1e-6 * values);
        assert_eq!(revs.per_case, plain.per_case);
    }

    #[test]
    fn a_billion_samples_need_far_more_than_a_terabyte_of_nothing() {
        let shape = Shape {
            samples: 1_000_000_001,
            window: 999_000_000,
            spectra: 3,
            sensor_series: 0,
            stored_series: CHANNELS.len(),
            stored_samples: 1_000_000_001,
            float32: false,
            cases: 1,
            references: 1,
            study_references: 1,
            design_values: 0,
            replicates: 0,
            revolutions: 0,
            order_spectra: 0,
            speed_knots: 0,
        };
        let e = MemoryEstimate::of(shape, 2);
        // 13 float64 series of 1e9 samples per worker and reference, at least.
        assert!(e.total > 3.0 * 104e9, "{}", e.total);
        assert_eq!(e.largest(), Largest::Samples);
        let small = MemoryEstimate::of(
            Shape {
                samples: 2_501,
                window: 2_000,
                spectra: 3,
                sensor_series: 0,
                stored_series: CHANNELS.len(),
                stored_samples: 2_501,
                float32: false,
                cases: 10_000_000,
                references: 1,
                study_references: 1,
                design_values: 0,
                replicates: 0,
                revolutions: 0,
                order_spectra: 0,
                speed_knots: 0,
            },
            2,
        );
        assert_eq!(small.largest(), Largest::CaseTable);
        assert!(small.case_table > 10_000_000.0 * 400.0);
    }

    #[test]
    fn sensor_series_count_in_each_case_and_record_but_not_in_the_references() {
        let shape = |sensor_series| Shape {
            samples: 100_001,
            window: 80_000,
            spectra: 3,
            sensor_series,
            stored_series: CHANNELS.len() + sensor_series,
            stored_samples: 100_001,
            float32: true,
            cases: 100,
            references: 2,
            study_references: 2,
            design_values: 0,
            replicates: 0,
            revolutions: 0,
            order_spectra: 0,
            speed_knots: 0,
        };
        let (without, with) = (
            MemoryEstimate::of(shape(0), 2),
            MemoryEstimate::of(shape(4), 2),
        );
        let n = 100_001.0;
        // Four float64 series and the noise draws in the worker; four float32 series
        // (with the chunk overhead) in the record.
        let record = 4.0 * n * 4.0 * (1.0 + 1.0 / 64.0);
        assert!((with.record - without.record - record).abs() < 1e-6);
        let per_case = 4.0 * n * 8.0 + n * 8.0 + record;
        assert!((with.per_case - without.per_case - per_case).abs() < 1e-6);
        assert_eq!(with.references, without.references);
    }

    /// The housing's two channels, simulated in every case's series either way, are
    /// in the record only when the file stores them.
    #[test]
    fn stored_channels_count_in_the_record_only() {
        let plain = million_short_cases();
        let housing = Shape {
            stored_series: plain.stored_series + 2,
            ..plain
        };
        let (a, b) = (MemoryEstimate::of(plain, 2), MemoryEstimate::of(housing, 2));
        let record = 2.0 * 20_001.0 * 8.0 * (1.0 + 1.0 / 64.0);
        assert!((b.record - a.record - record).abs() < 1e-6);
        assert_eq!(b.references, a.references);
        assert!((b.per_case - a.per_case - record).abs() < 1e-6);
    }

    #[test]
    fn byte_counts_read_as_people_write_them() {
        assert_eq!(bytes(800.0), "800 B");
        assert_eq!(bytes(1536.0), "1.50 KiB");
        assert_eq!(bytes(14.3 * (1u64 << 30) as f64), "14.3 GiB");
        assert_eq!(bytes(3.2e21), "3.2e21 B");
        assert_eq!(bytes(f64::INFINITY), "inf B");
    }
}
