//! The serde mirror of a grid file: what the YAML may contain, with the source
//! location of every value kept for error messages. Unknown keys are refused.
//!
//! A field is named exactly as its key. Where a struct allows fields without a doc
//! comment, the key's unit, default and meaning are in docs/grid-file.md's tables,
//! which `tests/docs.rs` checks against this mirror and the parameter table
//! ([`crate::study::params::PARAMETERS`]); a value is a number in that unit or a
//! string with a unit (docs/grid-file.md, Units).

use indexmap::IndexMap;
use serde::Deserialize;
use serde_saphyr::Spanned;

/// A scalar as written: a number (SI) or a string (a number with a unit, or a name).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Scalar {
    /// A plain number, in the parameter's base unit.
    Num(f64),
    /// A string: `"40 um"`, or a name such as `crank_ground`.
    Text(String),
}

impl std::fmt::Display for Scalar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Scalar::Num(v) => write!(f, "{v}"),
            Scalar::Text(s) => write!(f, "\"{s}\""),
        }
    }
}

/// A value with its place in the file.
pub type S<T> = Spanned<T>;
/// Grid axes or a zip group: parameter name → list of values, in file order.
pub type Axes = IndexMap<String, S<Vec<S<Scalar>>>>;

/// The whole grid file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridFile {
    /// Study name.
    pub name: S<String>,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Simulated time per case (s); required unless the study lists `recordings:`.
    #[serde(default)]
    pub duration: Option<S<Scalar>>,
    /// Output samples per second (Hz); required unless the study lists `recordings:`.
    #[serde(default)]
    pub sample_rate: Option<S<Scalar>>,
    /// Effects simulated: any of clearance, waviness, damping, gravity, defects,
    /// housing.
    #[serde(default)]
    pub effects: Option<S<Vec<S<String>>>>,
    /// Body parameter overrides.
    #[serde(default)]
    pub mechanism: Option<MechanismSection>,
    /// Bearing parameter overrides.
    #[serde(default)]
    pub bearing: Option<BearingSection>,
    /// The housing's parameters (with the `housing` effect only).
    #[serde(default)]
    pub housing: Option<S<HousingSection>>,
    /// Crank speed when not a grid axis.
    #[serde(default)]
    pub rpm: Option<S<Scalar>>,
    /// A varying crank speed, instead of `rpm`.
    #[serde(default)]
    pub speed: Option<S<SpeedSection>>,
    /// Bearing location when not a grid axis.
    #[serde(default)]
    pub location: Option<S<Scalar>>,
    /// Joint kind when not a grid axis: `ball_bearing`, `dry_clearance` or
    /// `lubricated`.
    #[serde(default)]
    pub joint: Option<S<Scalar>>,
    /// The plain journal's parameters (for the plain-joint cases).
    #[serde(default)]
    pub journal: Option<S<JournalSection>>,
    /// Integrator settings.
    #[serde(default)]
    pub solver: Option<SolverSection>,
    /// Time skipped before metrics and spectra (s), or `auto`.
    #[serde(default)]
    pub transient: Option<S<Scalar>>,
    /// Spectrum settings.
    #[serde(default)]
    pub spectra: Option<SpectraSection>,
    /// Envelope analysis and condition indicators (none when absent).
    #[serde(default)]
    pub envelope: Option<S<EnvelopeSection>>,
    /// Transducers applied to stored series (none when absent).
    #[serde(default)]
    pub sensors: Option<S<Vec<S<SensorSection>>>>,
    /// File storage settings.
    #[serde(default)]
    pub output: Option<OutputSection>,
    /// Largest number of cases accepted (default 100 000).
    #[serde(default)]
    pub max_cases: Option<S<u64>>,
    /// Axes expanded as a cartesian product (first axis slowest).
    #[serde(default)]
    pub grid: Axes,
    /// Groups of axes that vary together (equal lengths within a group).
    #[serde(default)]
    pub zip: Vec<S<Axes>>,
    /// Explicit extra cases: parameter → value, over the base.
    #[serde(default)]
    pub cases: Vec<S<IndexMap<String, S<CaseValue>>>>,
    /// A sampled design, repeated at every grid point and explicit case.
    #[serde(default)]
    pub design: Option<S<DesignSection>>,
    /// Run every case several times from perturbed initial states.
    #[serde(default)]
    pub replicates: Option<S<ReplicatesSection>>,
    /// Store each case's predictability horizon and `chaotic` flag (default: on
    /// with two or more replicates).
    #[serde(default)]
    pub chaos_check: Option<S<bool>>,
    /// Measured recordings analysed instead of simulated cases, one case each.
    #[serde(default)]
    pub recordings: Option<S<Vec<S<RecordingSection>>>>,
    /// A recordings study's analysed length (s); default: the shortest recording's.
    #[serde(default)]
    pub window: Option<S<Scalar>>,
    /// The name of a recordings study's measured series (default `vibration`).
    #[serde(default)]
    pub series: Option<S<String>>,
}

/// One entry of `recordings:`: a file, where its samples are, and the case it is.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingSection {
    /// The file (a path relative to the grid file's directory, or absolute).
    pub file: S<String>,
    /// The `.npz` member, HDF5 / netCDF dataset or MAT variable (or struct field path).
    #[serde(default)]
    pub variable: Option<S<String>>,
    /// The WAV channel, 0-based.
    #[serde(default)]
    pub channel_index: Option<S<u64>>,
    /// The CSV column: a header name or a 0-based index.
    #[serde(default)]
    pub column: Option<S<Scalar>>,
    /// Samples per second (Hz).
    pub sample_rate: S<Scalar>,
    /// The shaft speed (rev/min), inner race turning, outer race fixed.
    #[serde(default)]
    pub rpm: Option<S<Scalar>>,
    /// A varying shaft speed, instead of `rpm`.
    #[serde(default)]
    pub speed: Option<S<SpeedSection>>,
    /// The fault label: `none`, `outer`, `inner`, `ball`, or several joined by `+`.
    pub fault: S<String>,
}

/// `replicates:`: how many runs per case and how far apart they start.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplicatesSection {
    /// Runs per case `R` (replicate 0 unperturbed).
    pub count: S<u64>,
    /// Distance of each perturbed start's journal centre from the housing centre (m).
    pub perturbation: S<Scalar>,
    /// Seed of the perturbations' directions (default 0).
    #[serde(default)]
    pub seed: Option<S<u64>>,
}

/// One value of an explicit case: a scalar parameter, or a `speed:` profile.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum CaseValue {
    /// A scalar parameter or `location`.
    Scalar(Scalar),
    /// `speed:`.
    Speed(SpeedSection),
}

/// `speed:`: a crank speed profile (docs/grid-file.md). Which fields a profile takes
/// is checked when the study is built; the whole section carries one place in the
/// file (it may sit inside `cases:`, where serde keeps no inner places).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpeedSection {
    /// `ramp`, `sine` or `table`.
    pub profile: String,
    /// Ramp: the crank speed at `t = 0` (rev/min).
    pub from: Option<Scalar>,
    /// Ramp: the crank speed reached at `over` (rev/min).
    pub to: Option<Scalar>,
    /// Ramp: the time the ramp takes (s).
    pub over: Option<Scalar>,
    /// Sine: the mean crank speed (rev/min).
    pub mean: Option<Scalar>,
    /// Sine: the speed's amplitude about the mean (rev/min).
    pub amplitude: Option<Scalar>,
    /// Sine: the speed's frequency (Hz).
    pub frequency: Option<Scalar>,
    /// Table: the knots' times (s).
    pub time: Option<Vec<Scalar>>,
    /// Table: the crank speed at each knot (rev/min).
    pub rpm: Option<Vec<Scalar>>,
}

/// `design:`: points drawn over parameter ranges (see [`crate::study::design`]).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignSection {
    /// `lhs`, `sobol`, `saltelli` or `random`.
    pub method: S<String>,
    /// Base points `N` (Saltelli: `N (2D + 2)` rows).
    pub samples: S<u64>,
    /// Generator seed (default 0).
    #[serde(default)]
    pub seed: Option<S<u64>>,
    /// Scramble the Sobol points (default `true`; `sobol` and `saltelli` only).
    #[serde(default)]
    pub scramble: Option<S<bool>>,
    /// Parameter → its range, distribution or choices, in design-column order.
    pub parameters: S<IndexMap<String, S<DesignParameter>>>,
}

/// One design parameter: `min` and `max` (with `scale: linear | log`), `mean` and
/// `sd` (normal), or `choices`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct DesignParameter {
    pub min: Option<S<Scalar>>,
    pub max: Option<S<Scalar>>,
    /// `linear` (default) or `log` (log-uniform between `min` and `max`).
    pub scale: Option<S<String>>,
    pub mean: Option<S<Scalar>>,
    pub sd: Option<S<Scalar>>,
    pub choices: Option<S<Vec<S<Scalar>>>>,
}

/// `journal:`: the plain journal (docs/model.md §2.10), each key optional.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct JournalSection {
    pub radius: Option<S<Scalar>>,
    /// Radial clearance: bushing radius minus journal radius.
    pub clearance: Option<S<Scalar>>,
    pub length: Option<S<Scalar>>,
    pub youngs_modulus: Option<S<Scalar>>,
    pub poisson_ratio: Option<S<Scalar>>,
    /// The contact stiffness (default: from the materials and radii).
    pub stiffness: Option<S<Scalar>>,
    pub friction: Option<FrictionSection>,
    pub viscosity: Option<S<Scalar>>,
}

/// `journal.friction:`: the modified Coulomb law (docs/model.md §2.10).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct FrictionSection {
    pub coefficient: Option<S<Scalar>>,
    pub stick_speed: Option<S<Scalar>>,
    pub slip_speed: Option<S<Scalar>>,
}

/// `mechanism:` overrides (each optional).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct MechanismSection {
    pub crank_length: Option<S<Scalar>>,
    pub rod_length: Option<S<Scalar>>,
    pub crank_mass: Option<S<Scalar>>,
    pub crank_inertia: Option<S<Scalar>>,
    pub rod_mass: Option<S<Scalar>>,
    pub rod_inertia: Option<S<Scalar>>,
    pub slider_mass: Option<S<Scalar>>,
    pub slider_inertia: Option<S<Scalar>>,
}

/// `housing:` overrides (each optional; docs/model.md §3.9).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HousingSection {
    /// Mass `m_h` (kg).
    pub m_h: Option<S<Scalar>>,
    /// Support stiffness `k_h` in x and y (N/m).
    pub k_h: Option<S<Scalar>>,
    /// Support damping `c_h` in x and y (N s/m).
    pub c_h: Option<S<Scalar>>,
}

/// `bearing:` overrides (each optional).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct BearingSection {
    pub ball_count: Option<S<Scalar>>,
    pub clearance: Option<S<Scalar>>,
    /// A number/quantity (N/m^1.5) or `harris` (computed from `geometry`).
    pub stiffness: Option<S<Scalar>>,
    pub damping: Option<S<Scalar>>,
    /// `compression_only` (default), `two_sided`, `hunt_crossley_alpha`, or a
    /// restitution-based law: `hunt_crossley`, `lankarani_nikravesh`, `flores`,
    /// `gonthier`.
    pub damping_model: Option<S<String>>,
    /// Coefficient of restitution of a restitution-based `damping_model`.
    pub restitution: Option<S<Scalar>>,
    /// `α` (s/m) of `damping_model: hunt_crossley_alpha`.
    pub alpha: Option<S<Scalar>>,
    pub inner_race_diameter: Option<S<Scalar>>,
    pub outer_race_diameter: Option<S<Scalar>>,
    /// Waviness of both races.
    pub waviness: Option<WavinessSection>,
    pub inner_waviness: Option<WavinessSection>,
    pub outer_waviness: Option<WavinessSection>,
    /// Contact geometry for `stiffness: harris`; its `ball_diameter` also sizes the
    /// balls rolling over defects.
    pub geometry: Option<GeometrySection>,
    /// Localized defects (with the `defects` effect).
    pub defects: Option<S<Vec<DefectSection>>>,
}

/// One defect in a `defects:` list.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DefectSection {
    /// `outer`, `inner` or `ball`.
    pub race: S<String>,
    /// Angle of its centre (rad, or `"90 deg"`); default 0.
    #[serde(default)]
    pub angle: Option<S<Scalar>>,
    /// Width along the surface (m).
    pub width: S<Scalar>,
    /// Depth (m).
    pub depth: S<Scalar>,
    /// `flat` (default) or `rounded`.
    #[serde(default)]
    pub profile: Option<S<String>>,
}

/// One race's waviness: a single harmonic (`number`, `amplitude`, `phase`) or a list.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct WavinessSection {
    pub number: Option<S<Scalar>>,
    pub amplitude: Option<S<Scalar>>,
    pub phase: Option<S<Scalar>>,
    pub offset: Option<S<Scalar>>,
    pub harmonics: Option<S<Vec<HarmonicSection>>>,
}

/// One harmonic in a `harmonics:` list.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct HarmonicSection {
    pub number: S<Scalar>,
    pub amplitude: S<Scalar>,
    #[serde(default)]
    pub phase: Option<S<Scalar>>,
}

/// Ball/groove geometry for Harris's stiffness (defaults: SKF 98205, f = 0.52).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct GeometrySection {
    pub ball_diameter: Option<S<Scalar>>,
    pub pitch_diameter: Option<S<Scalar>>,
    /// Contact angle (rad; default 0): a recordings study's characteristic
    /// frequencies only; a simulated case's planar model refuses a nonzero one.
    pub contact_angle: Option<S<Scalar>>,
    pub inner_conformity: Option<S<Scalar>>,
    pub outer_conformity: Option<S<Scalar>>,
    pub youngs_modulus: Option<S<Scalar>>,
    pub poisson_ratio: Option<S<Scalar>>,
}

/// `solver:` settings.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct SolverSection {
    /// `dop853` (default), `dopri5`, `tsit5` (the adaptive explicit pairs, with
    /// `rtol`, `atol`), `rk4` (with `step`) or `sdirk4` (with `rtol`, `atol`).
    pub method: Option<S<String>>,
    pub rtol: Option<S<Scalar>>,
    pub atol: Option<S<Scalar>>,
    /// RK4 step (s).
    pub step: Option<S<Scalar>>,
    pub max_steps: Option<S<u64>>,
    /// Largest adaptive step (s).
    pub max_step: Option<S<Scalar>>,
    /// Whether the explicit pairs locate contact switches (default `true`).
    pub locate_events: Option<S<bool>>,
    /// Whether the explicit pairs test for stiffness and continue on SDIRK4 (default
    /// `true`).
    pub stiffness_switch: Option<S<bool>>,
}

/// `spectra:` settings.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct SpectraSection {
    /// `hann` (default) or `rectangular`.
    pub window: Option<S<String>>,
    /// Channels to transform (default: slider_acceleration, crank_moment, bearing_force).
    pub channels: Option<S<Vec<S<String>>>>,
    /// Also their order spectra over crank-angle orders (default false).
    pub orders: Option<S<bool>>,
    /// Highest frequency stored of every `[case, frequency]` variable (default: the
    /// Nyquist frequency, every bin).
    pub max_frequency: Option<S<Scalar>>,
}

/// `envelope:` settings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvelopeSection {
    /// Channels analysed (at least one).
    pub channels: S<Vec<S<String>>>,
    /// `[low, high]` frequencies, or `auto` (the fast kurtogram); default `auto`.
    #[serde(default)]
    pub band: Option<S<BandValue>>,
    /// Also the order spectra of the squared envelopes (default false).
    #[serde(default)]
    pub orders: Option<S<bool>>,
}

/// One entry of `sensors:`: a resonant transducer on a stored series.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSection {
    /// Name of the sensor's series (`<name>` noisy, `<name>_clean` noise-free).
    pub name: S<String>,
    /// The stored series it measures (a name of `crate::simulate::CHANNELS`).
    pub channel: S<String>,
    /// Undamped natural frequency (Hz, or a quantity such as `"20 kHz"`).
    pub natural_frequency: S<Scalar>,
    /// Damping ratio (1).
    pub damping_ratio: S<f64>,
    /// White Gaussian measurement noise (none when absent).
    #[serde(default)]
    pub noise: Option<S<NoiseSection>>,
}

/// `sensors[].noise`: white Gaussian noise at a signal-to-noise ratio.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseSection {
    /// Signal-to-noise ratio over the analysed window (dB).
    pub snr_db: S<f64>,
    /// The noise generator's study seed (default 0).
    #[serde(default)]
    pub seed: Option<S<u64>>,
}

/// An `envelope.band` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum BandValue {
    /// `[low, high]`, each a number (Hz) or a quantity (`"2 kHz"`).
    Range(Vec<Scalar>),
    /// A name: `auto`.
    Name(String),
}

/// `output:` settings.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct OutputSection {
    /// `float64` (default) or `float32`.
    pub dtype: Option<S<String>>,
    /// Deflate level 0..=9 (default 1; 0 = uncompressed).
    pub compression: Option<S<u8>>,
    /// The series stored: a list of names, `all` (default) or `none`.
    pub series: Option<S<SeriesValue>>,
    /// Every `decimate`-th sample of the stored series is kept (an integer >= 1,
    /// default 1).
    pub decimate: Option<S<Scalar>>,
}

/// An `output.series` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum SeriesValue {
    /// Series names: simulated channels and sensor series.
    List(Vec<String>),
    /// A name: `all` or `none`.
    Name(String),
}
