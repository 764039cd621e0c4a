//! Studies: a grid file parsed, validated and expanded into cases before anything runs.
//!
//! Two stages (docs/model.md defaults fill everything a file leaves out):
//! 1. [`config`]: the serde mirror of the YAML (unknown keys refused), every value
//!    with its line and column;
//! 2. [`Study::from_yaml`]: units resolved ([`units`]), effects applied, axes
//!    expanded (cartesian product of `grid:` in file order, first axis slowest, then
//!    the `zip:` groups, then the explicit `cases:`), every case validated.
//!
//! Errors name the file, line, column, field and reason.

pub mod config;
pub mod design;
mod expand;
pub mod layout;
pub mod memory;
pub mod params;
mod tree;
pub mod units;
mod yaml;

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::mechanism::CaseParams;
use crate::recordings::read::Selector;
use crate::signal::channel::AnalysisChannel;
use crate::signal::envelope::EnvelopeSettings;
use crate::signal::order::OrderSettings;
use crate::signal::sensor::Sensor;
use crate::simulate::{Sampling, CHANNELS};
use crate::solve::SolverSettings;

pub use expand::Effects;
pub use layout::{
    stored_reference_channels, study_layout, study_metric_specs, StudyFingerprint,
    MODEL_CONVENTIONS, REFERENCE_CHANNELS,
};
pub use memory::{Limits, MemoryEstimate};

/// Default largest number of cases a grid may expand to (`max_cases:` overrides).
pub const DEFAULT_MAX_CASES: u64 = 100_000;

/// A grid file problem: where it is and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyError {
    /// The grid file.
    pub path: PathBuf,
    /// 1-based line and column of the offending value, when known.
    pub location: Option<(u64, u64)>,
    /// Dotted name of the field (`grid.ball_count[1]`), or empty for syntax errors.
    pub field: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl fmt::Display for StudyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some((line, col)) = self.location {
            write!(f, ":{line}:{col}")?;
        }
        if self.field.is_empty() {
            write!(f, ": {}", self.message)
        } else {
            write!(f, ": `{}`: {}", self.field, self.message)
        }
    }
}

impl std::error::Error for StudyError {}

/// One case of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Position in the expanded study (0-based, deterministic).
    pub id: u64,
    /// Everything that defines the simulation.
    pub params: CaseParams,
    /// Id of the ideal mechanism it is compared with ([`Reference::id`], found with
    /// [`Study::reference`]).
    pub reference: usize,
}

/// An ideal mechanism cases compare with: a case's bodies, speed and gravity, without
/// its bearing.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Its id in the whole study: the references are numbered in the order of the
    /// first case that uses each, whatever part of the study a [`Study`] holds.
    pub id: usize,
    /// The ideal mechanism.
    pub params: CaseParams,
}

/// What a study is as a whole, whatever part of its cases a [`Study`] holds: the
/// figures a shard's file records of the whole study, and the facts of every case
/// that decide which variables the file has (the same in every shard, so that
/// shards merge).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WholeStudy {
    /// Cases of the study.
    pub cases: u64,
    /// Distinct ideal references of the study.
    pub references: u64,
    /// Whether some case has a plain journal (`joint: dry_clearance` or
    /// `lubricated`) at a location.
    pub plain_joints: bool,
    /// The names of the speed profiles some case runs ([`crate::mechanism::SpeedProfile::name`]), in
    /// the order of their first case.
    pub speed_profiles: Vec<&'static str>,
}

impl WholeStudy {
    /// The figures of a study of `cases`, all of them held, without references.
    fn of(cases: &[Case]) -> Self {
        let mut whole = Self::default();
        for c in cases {
            whole.add(&c.params);
        }
        whole
    }

    /// Counts one more case of the study, of parameters `p`.
    fn add(&mut self, p: &CaseParams) {
        self.cases += 1;
        self.plain_joints |= p.joint.is_plain() && p.location != crate::mechanism::Location::Ideal;
        if let Some(name) = p.speed.as_ref().map(|s| s.name()) {
            if !self.speed_profiles.contains(&name) {
                self.speed_profiles.push(name);
            }
        }
    }
}

/// A validated, expanded study.
#[derive(Debug, Clone)]
pub struct Study {
    /// Study name.
    pub name: String,
    /// Free-text description.
    pub description: String,
    /// The grid file's text, verbatim.
    pub source: String,
    /// Where it was read from.
    pub path: PathBuf,
    /// Output sampling.
    pub sampling: Sampling,
    /// Integrator settings.
    pub solver: SolverSettings,
    /// Which effects are simulated.
    pub effects: Effects,
    /// Start of the window analysed by metrics and spectra (s); the window is
    /// `transient ≤ t < duration` ([`Study::analysis_window`]).
    pub transient: f64,
    /// Spectrum window name: `hann` or `rectangular`.
    pub window: String,
    /// Channels transformed into spectra (simulated channels or sensor series).
    pub spectrum_channels: Vec<AnalysisChannel>,
    /// Highest frequency the file stores of every `[case, frequency]` variable (Hz,
    /// `spectra.max_frequency`); none: every bin up to the Nyquist frequency. The
    /// analysis uses every bin either way ([`Study::stored_bins`]).
    pub max_frequency: Option<f64>,
    /// The envelope analysis and condition indicators (`envelope:`); none when the
    /// grid has no `envelope:`, and then nothing of it is computed or stored.
    pub envelope: Option<EnvelopeSettings>,
    /// The order analysis (`spectra: {orders: true}` or `envelope: {orders: true}`,
    /// docs/model.md §7.9); none when neither asks, and then nothing of it is
    /// computed or stored.
    pub orders: Option<OrderSettings>,
    /// The transducers applied to stored series (`sensors:`, docs/model.md §7.8), in
    /// file order; empty when the grid has none, and then nothing of them is
    /// computed or stored.
    pub sensors: Vec<Sensor>,
    /// Store series and spectra as float32.
    pub float32: bool,
    /// Deflate level (0 = none).
    pub compression: u8,
    /// Which series the file stores and at what rate (`output.series`,
    /// `output.decimate`).
    pub output: SeriesOutput,
    /// Names of the parameters the grid varies, in expansion order.
    pub axes: Vec<String>,
    /// The cases it holds, in id order: every case of the study, or those of
    /// [`Study::part`].
    pub cases: Vec<Case>,
    /// The distinct ideal mechanisms (one per speed and body set) the held cases
    /// compare with, in id order.
    pub references: Vec<Reference>,
    /// The shard whose cases it holds; none: the whole study.
    pub part: Option<Shard>,
    /// The whole study's case and reference counts and the facts of all its cases.
    pub whole: WholeStudy,
    /// The sampled design, when the grid file has one.
    pub design: Option<DesignInfo>,
    /// Replicates per case, when the grid file asks for them.
    pub replicates: Option<Replicates>,
    /// Whether each case's predictability horizon is computed from its replicates.
    pub chaos_check: bool,
    /// The most whole crank revolutions any case has in the analysed window: the
    /// length of the file's `revolution` dimension (docs/model.md §6.1).
    pub revolutions: usize,
    /// The measured recordings a `recordings:` study analyses, one per case; none
    /// for a study of simulated cases.
    pub recordings: Option<Recordings>,
}

/// A `recordings:` study's measured series (docs/grid-file.md, Recordings): what it
/// is called and where each case's samples are.
#[derive(Debug, Clone, PartialEq)]
pub struct Recordings {
    /// The series every recording becomes (`vibration`, or the grid's `series:`).
    pub series: AnalysisChannel,
    /// One per case, in case order.
    pub list: Vec<Recording>,
}

/// One measured recording: one case of a `recordings:` study.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The file, resolved against the grid file's directory.
    pub file: PathBuf,
    /// The file as the grid file writes it (what the study file records).
    pub written: String,
    /// Where in the file the samples are.
    pub selector: Selector,
    /// How many samples the file holds (the case analyses the study's window of them).
    pub samples: usize,
    /// The fault label (`none`, `outer`, `inner`, `ball`, or several joined by `+`).
    pub fault: String,
}

/// What a study file stores of each case's series (`output.series` and
/// `output.decimate`, docs/model.md §5.2). Spectra, metrics, envelope analysis and
/// sensors are computed from the full-rate series whatever is stored.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SeriesOutput {
    /// The names of the series stored (simulated channels and sensor series), or
    /// `None` for every series the study simulates (`all`); empty for `none`.
    pub names: Option<Vec<String>>,
    /// Every `decimate`-th sample of the output is stored, samples `0, k, 2k, …`
    /// (≥ 1; 1 stores every sample).
    pub decimate: usize,
}

impl Default for SeriesOutput {
    /// Every series, every sample.
    fn default() -> Self {
        Self {
            names: None,
            decimate: 1,
        }
    }
}

impl SeriesOutput {
    /// Whether the series `name` is stored (the study simulating it).
    pub fn stores(&self, name: &str) -> bool {
        self.names
            .as_ref()
            .is_none_or(|names| names.iter().any(|n| n == name))
    }
}

/// A study's `replicates:`: every case runs `count` times, replicate `k ≥ 1` from
/// the journal centre displaced by `perturbation` in a direction drawn from
/// `seed`, the case id and `k` (docs/model.md §9.5); replicate 0 is the case itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Replicates {
    /// Runs per case, replicate 0 included (≥ 1).
    pub count: usize,
    /// Size of the initial eccentricity of replicates `k ≥ 1` (m).
    pub perturbation: f64,
    /// Seed of the directions.
    pub seed: u64,
}

impl Replicates {
    /// The initial journal-centre eccentricity of replicate `k` of case `id` (m):
    /// zero for `k = 0`, else `perturbation (cos θ, sin θ)` with `θ = 2π u` and `u`
    /// the first [`design::SplitMix64`] draw seeded with
    /// `seed ⊕ (id · 2^32 + k) · φ64` (`φ64` = 0x9E3779B97F4A7C15).
    pub fn eccentricity(&self, id: u64, k: usize) -> [f64; 2] {
        if k == 0 {
            return [0.0; 2];
        }
        let key = (id << 32).wrapping_add(k as u64);
        let mut rng = design::SplitMix64::new(self.seed ^ key.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let (s, c) = (std::f64::consts::TAU * rng.next_f64()).sin_cos();
        [self.perturbation * c, self.perturbation * s]
    }
}

/// A study's sampled design (`design:`), as the study file records it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DesignInfo {
    /// How the points were drawn.
    pub method: design::Method,
    /// Base points `N`.
    pub samples: u64,
    /// The generator's seed.
    pub seed: u64,
    /// Whether the Sobol points were scrambled.
    pub scramble: bool,
    /// The design's parameters, in column order.
    pub parameters: Vec<String>,
    /// Rows per grid point and explicit case (`N`, or `N (2D + 2)` for Saltelli).
    pub rows: u64,
}

impl Study {
    /// The design row of case `id`: the design repeats at every grid point and
    /// explicit case, its rows fastest. `None` without a design.
    pub fn design_row(&self, id: u64) -> Option<u64> {
        self.design.as_ref().map(|d| id % d.rows)
    }

    /// The parameters that vary between cases: the grid's axes, then the design's.
    pub fn varied(&self) -> Vec<&str> {
        let design = self.design.iter().flat_map(|d| &d.parameters);
        self.axes.iter().chain(design).map(String::as_str).collect()
    }

    /// The parameters the file records for every case: those of the study's effects
    /// ([`Effects::recorded_parameters`]), the `speed_*` fields of a profile only when
    /// some case runs that profile.
    pub fn recorded_parameters(&self) -> impl Iterator<Item = &'static params::ParamDef> + '_ {
        let runs = |profile: &str| self.whole.speed_profiles.contains(&profile);
        let (ramp, sine) = (runs("ramp"), runs("sine"));
        let plain = self.has_plain_joints();
        self.effects.recorded_parameters().filter(move |p| {
            match params::speed_profile_field(p.name) {
                Some("ramp") => ramp,
                Some("sine") => sine,
                _ => plain || !params::is_journal_parameter(p),
            }
        })
    }

    /// Whether any case has a plain journal (`joint: dry_clearance` or `lubricated`)
    /// at a location: then the file records the `journal_*` parameters and the
    /// `joint` label.
    pub fn has_plain_joints(&self) -> bool {
        self.whole.plain_joints
    }

    /// The ideal mechanism of reference `id` ([`Reference::id`]).
    ///
    /// # Panics
    /// When the study does not hold it: every held case's reference is held.
    pub fn reference(&self, id: usize) -> &CaseParams {
        let at = self
            .references
            .binary_search_by_key(&id, |r| r.id)
            .unwrap_or_else(|_| panic!("reference {id} is not held"));
        &self.references[at].params
    }
}

impl Study {
    /// The indices into [`CHANNELS`] of the simulated channels the file stores, in
    /// [`CHANNELS`] order: every channel whose `effect` is `None` or on in the study,
    /// then those `output.series` names.
    pub fn stored_channels(&self) -> Vec<usize> {
        self.simulated_channels()
            .into_iter()
            .filter(|&k| self.output.stores(CHANNELS[k].name))
            .collect()
    }

    /// The indices into [`CHANNELS`] of the channels the study simulates: those whose
    /// `effect` is `None` or on in the study; none in a study of recordings.
    pub fn simulated_channels(&self) -> Vec<usize> {
        match self.recordings {
            Some(_) => Vec::new(),
            None => self.effects.channels(),
        }
    }

    /// Whether the file stores a recordings study's measured series.
    pub fn stores_recording(&self) -> bool {
        self.recordings
            .as_ref()
            .is_some_and(|r| self.output.stores(&r.series.name))
    }

    /// The sensor series the file stores, as indices into the list of every
    /// sensor's noisy then noise-free series (`2 s` and `2 s + 1` for sensor `s`).
    pub fn stored_sensor_series(&self) -> Vec<usize> {
        self.sensors
            .iter()
            .flat_map(|s| s.specs())
            .enumerate()
            .filter(|(_, spec)| self.output.stores(&spec.name))
            .map(|(k, _)| k)
            .collect()
    }

    /// Number of series per case the file stores: channels, sensor series and a
    /// recording's series.
    pub fn stored_series_count(&self) -> usize {
        self.stored_channels().len()
            + self.stored_sensor_series().len()
            + usize::from(self.stores_recording())
    }

    /// The sample indices the stored series keep: `0, k, 2k, …` below the
    /// sampling's length (`k` = `output.decimate`).
    pub fn stored_samples(&self) -> std::iter::StepBy<Range<usize>> {
        (0..self.sampling.len()).step_by(self.output.decimate)
    }

    /// The stored series' sample times (s): the output's times at
    /// [`Study::stored_samples`], bit for bit; empty when no series is stored.
    pub fn stored_times(&self) -> Vec<f64> {
        if self.stored_series_count() == 0 {
            return Vec::new();
        }
        let times = self.sampling.times();
        self.stored_samples().map(|k| times[k]).collect()
    }

    /// A full-rate series reduced to its stored samples ([`Study::stored_samples`]),
    /// in place; returned as it is when every sample is stored.
    pub fn keep_stored_samples(&self, mut series: Vec<f64>) -> Vec<f64> {
        if self.output.decimate == 1 {
            return series;
        }
        let mut kept = 0;
        for k in self.stored_samples() {
            series[kept] = series[k];
            kept += 1;
        }
        series.truncate(kept);
        series.shrink_to_fit();
        series
    }

    /// The stored series' sample rate (Hz): `sample_rate / decimate`.
    pub fn stored_sample_rate(&self) -> f64 {
        self.sampling.sample_rate / self.output.decimate as f64
    }
}

impl Study {
    /// Reads and validates the grid file at `path` under the default [`Limits`] (half
    /// the memory, all cores).
    pub fn load(path: &Path) -> Result<Self, StudyError> {
        Self::load_with(path, &Limits::default())
    }

    /// Reads and validates the grid file at `path`, refusing a file larger than
    /// [`memory::MAX_GRID_BYTES`] before parsing it and a study whose run needs more
    /// memory than `limits` allow before expanding it.
    pub fn load_with(path: &Path, limits: &Limits) -> Result<Self, StudyError> {
        Self::load_part(path, limits, None)
    }

    /// [`Study::load_with`], holding only the cases of `part` (every case without):
    /// the whole study is expanded and checked, a case at a time, and whatever is a
    /// property of the whole study (case and reference ids, the file's dimensions
    /// and attributes) is the same as the whole study's, so that the shard's run is
    /// bit for bit the whole run's cases of that shard. The memory check counts the
    /// shard's cases.
    pub fn load_part(
        path: &Path,
        limits: &Limits,
        part: Option<Shard>,
    ) -> Result<Self, StudyError> {
        let text = memory::read_capped(path).map_err(|message| StudyError {
            path: path.to_path_buf(),
            location: None,
            field: String::new(),
            message,
        })?;
        Self::from_yaml_part(&text, path, limits, part)
    }

    /// Parses and validates grid-file `text` (`path` is used in messages only) under
    /// the default [`Limits`].
    pub fn from_yaml(text: &str, path: &Path) -> Result<Self, StudyError> {
        Self::from_yaml_with(text, path, &Limits::default())
    }

    /// Parses and validates grid-file `text` under `limits`.
    pub fn from_yaml_with(text: &str, path: &Path, limits: &Limits) -> Result<Self, StudyError> {
        Self::from_yaml_part(text, path, limits, None)
    }

    /// [`Study::from_yaml_with`], holding only the cases of `part` ([`Study::load_part`]).
    pub fn from_yaml_part(
        text: &str,
        path: &Path,
        limits: &Limits,
        part: Option<Shard>,
    ) -> Result<Self, StudyError> {
        expand::build(text, path, limits, part)
    }

    /// What a run of this study on `jobs` workers needs in memory.
    pub fn memory_estimate(&self, jobs: usize) -> MemoryEstimate {
        MemoryEstimate::of(
            memory::Shape {
                samples: self.sampling.len() as u64,
                window: self.analysis_window().len() as u64,
                spectra: self.stored_spectra_count(),
                sensor_series: 2 * self.sensors.len(),
                stored_series: self.stored_series_count(),
                stored_samples: self.stored_times().len() as u64,
                order_spectra: self.order_spectrum_count(),
                float32: self.float32,
                cases: self.cases.len() as u64,
                references: self.references.len() as u64,
                study_references: self.whole.references,
                design_values: self
                    .design
                    .as_ref()
                    .map_or(0, |d| d.rows * d.parameters.len() as u64),
                replicates: self.replicates.map_or(0, |r| r.count as u64),
                revolutions: self.revolutions as u64,
                speed_knots: self
                    .cases
                    .iter()
                    .map(|c| match &c.params.speed {
                        Some(crate::mechanism::SpeedProfile::Table { time, .. }) => time.len(),
                        _ => 0,
                    })
                    .max()
                    .unwrap_or(0) as u64,
            },
            jobs,
        )
    }

    /// Indices of the samples the metrics and spectra analyse, `transient ≤ t <
    /// duration` ([`Sampling::analysis_window`]).
    pub fn analysis_window(&self) -> Range<usize> {
        self.sampling.analysis_window(self.transient)
    }

    /// Frequency bins the file stores of every `[case, frequency]` variable: those of
    /// the analysed window's spectrum (`window / 2 + 1`) up to
    /// [`Study::max_frequency`].
    pub fn stored_bins(&self) -> usize {
        let n = self.analysis_window().len();
        let all = if n == 0 { 0 } else { n / 2 + 1 };
        match self.max_frequency {
            // Bin k is at k·sample_rate/n; the tolerance keeps a bin the given
            // frequency names exactly ("2 kHz" at 2000.0000000001 Hz after rounding).
            Some(f) => {
                let k = (f * n as f64 / self.sampling.sample_rate * (1.0 + 1e-12)).floor();
                all.min(k as usize + 1)
            }
            None => all,
        }
    }

    /// Spectra per case the file stores over `frequency`: the spectrum channels', and
    /// an envelope spectrum per envelope channel (each also has a spectral kurtosis,
    /// over `sk_frequency`).
    pub fn stored_spectra_count(&self) -> usize {
        self.spectrum_channels.len() + self.envelope.as_ref().map_or(0, |e| e.channels.len())
    }

    /// Order spectra per case ([`crate::signal::order_spectrum_specs`]).
    pub fn order_spectrum_count(&self) -> usize {
        self.orders.map_or(0, |o| {
            usize::from(o.spectra) * self.spectrum_channels.len()
                + usize::from(o.envelope) * self.envelope.as_ref().map_or(0, |e| e.channels.len())
        })
    }

    /// The rows of [`Study::cases`] of shard `k` of `n` (1-based `k`): cases whose id
    /// ≡ k − 1 (mod n), so shards are balanced and their union is the whole study.
    /// Of a study holding only that shard ([`Study::part`]), every row.
    pub fn shard(&self, k: u64, n: u64) -> Vec<usize> {
        (0..self.cases.len())
            .filter(|&i| self.cases[i].id % n == k - 1)
            .collect()
    }
}

/// A part of a study: shard `k` of `n` (1-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 1..=n.
    pub k: u64,
    /// Number of shards.
    pub n: u64,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let err = || format!("`{s}` is not a shard: expected K/N with 1 <= K <= N, e.g. 3/8");
        let (k, n) = s.split_once('/').ok_or_else(err)?;
        let (k, n): (u64, u64) = (
            k.trim().parse().map_err(|_| err())?,
            n.trim().parse().map_err(|_| err())?,
        );
        if k == 0 || n == 0 || k > n {
            return Err(err());
        }
        Ok(Self { k, n })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}
