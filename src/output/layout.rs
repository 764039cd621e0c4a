//! What a study file holds: the [`Layout`] handed to
//! [`StudyWriter::create`](super::StudyWriter::create) and reconstructed by
//! [`StudyReader::layout`](super::StudyReader::layout), and its checks.

use std::collections::HashSet;
use std::time::SystemTime;

pub use crate::signal::{AttrValue, VarSpec};

/// Name of the case dimension and its coordinate variable (case ids, stored as int32).
pub const CASE: &str = "case";
/// Name of the time dimension and its coordinate variable (f64, s from the start of
/// the simulation, with the units [`TIME_UNITS`]).
pub const TIME: &str = "time";
/// Units of the `time` coordinate: seconds, since a nominal reference date that CF
/// requires of a time coordinate (the simulation has no calendar date).
pub const TIME_UNITS: &str = "seconds since 1970-01-01 00:00:00";
/// Whether `units` are seconds since 1970-01-01 00:00:00 UTC (date alone, time with `T`
/// or a space, `Z` or `UTC` or a zero offset), or plain seconds.
pub(super) fn seconds_from_the_epoch(units: &str) -> bool {
    let (unit, date) = match units.split_once(" since ") {
        Some((unit, date)) => (unit.trim(), Some(date.trim())),
        None => (units.trim(), None),
    };
    let seconds = matches!(unit, "s" | "sec" | "secs" | "second" | "seconds");
    let epoch = date.is_none_or(|date| {
        let mut date = date;
        for zone in ["Z", "UTC", "+00:00", "+0000", "+00"] {
            date = date.strip_suffix(zone).unwrap_or(date).trim_end();
        }
        matches!(
            date,
            "1970-01-01" | "1970-01-01 00:00:00" | "1970-01-01T00:00:00" | "1970-01-01 00:00"
        )
    });
    seconds && epoch
}

/// Name of the frequency dimension and its coordinate variable (f64, Hz).
pub const FREQUENCY: &str = "frequency";
/// Name of the reference dimension and its coordinate variable (reference ids, int32).
pub const REFERENCE: &str = "reference";
/// Name of the replicate dimension and its coordinate variable (replicate ids,
/// int32), present only in a file with [`Layout::replicate_metrics`].
pub const REPLICATE: &str = "replicate";
/// Name of the revolution dimension and its coordinate variable (revolution
/// numbers after the transient, int32), present only in a file with
/// [`Layout::revolution_metrics`].
pub const REVOLUTION: &str = "revolution";
/// Name of the order dimension and its coordinate variable (f64, cycles per crank
/// revolution), present only in a file with [`Layout::order_spectra`].
pub const ORDER: &str = "order";
/// Name of the dimension of the spectral kurtosis and its coordinate variable (f64,
/// Hz: the STFT bins), present only in a file with [`Layout::kurtosis`].
pub const SK_FREQUENCY: &str = "sk_frequency";
/// Built-in variable `[case]` i8: the [`Status`] code of each case.
pub const STATUS: &str = "status";
/// Built-in variable `[case]` string: why a case failed (empty otherwise).
pub const ERROR_MESSAGE: &str = "error_message";
/// Built-in variable `[case, replicate]` i8, in a file with replicates: the [`Status`]
/// code of each replicate (replicate 0's is the case's; the perturbed replicates of a
/// failed case were not run and stay pending).
pub const REPLICATE_STATUS: &str = "replicate_status";
/// Built-in variable `[case, replicate]` string, in a file with replicates: why a
/// replicate failed (empty otherwise).
pub const REPLICATE_ERROR_MESSAGE: &str = "replicate_error_message";
/// Built-in variable `[case]` int32: the `reference` row each case is compared with.
pub const REFERENCE_INDEX: &str = "reference_index";

/// Variable attribute naming a caller variable's role (see [`Role`]).
pub(super) const ROLE_ATTR: &str = "studyrun_role";
/// Root attribute marking a study file; its value is [`FORMAT_VERSION`].
pub(super) const FORMAT_ATTR: &str = "studyrun_file_format";
/// Root attribute: the CRC-32 of the names and roles of the variables that carry a
/// `studyrun_role`, so that a variable whose attributes were lost is missed.
pub(super) const VARIABLES_DIGEST_ATTR: &str = "studyrun_variables_crc32";
/// The file format version this module writes and reads.
pub(super) const FORMAT_VERSION: i64 = 2;

/// The names no caller variable may take.
const RESERVED: [&str; 13] = [
    CASE,
    TIME,
    FREQUENCY,
    REFERENCE,
    REPLICATE,
    REVOLUTION,
    ORDER,
    SK_FREQUENCY,
    STATUS,
    ERROR_MESSAGE,
    REPLICATE_STATUS,
    REPLICATE_ERROR_MESSAGE,
    REFERENCE_INDEX,
];

/// Largest id: ids are stored as int32, the widest integer CF-1.8 allows.
pub const MAX_ID: u64 = i32::MAX as u64;

/// Largest chunk HDF5 accepts (bytes): a chunk is one case's series or spectrum.
const MAX_CHUNK_BYTES: usize = u32::MAX as usize;

/// The values of a parameter, one per case (or per reference).
#[derive(Debug, Clone)]
pub enum ParamValues {
    /// Numbers, stored as f64 (in the parameter's units).
    F64(Vec<f64>),
    /// Labels, stored as variable-length UTF-8 strings (no NUL bytes).
    Str(Vec<String>),
}

/// Values are equal when they hold the same bits: a NaN (a parameter a case does
/// not have, e.g. `speed_from` at constant speed) equals the same NaN.
impl PartialEq for ParamValues {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (ParamValues::F64(a), ParamValues::F64(b)) => {
                a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
            }
            (ParamValues::Str(a), ParamValues::Str(b)) => a == b,
            _ => false,
        }
    }
}

impl ParamValues {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Self::F64(v) => v.len(),
            Self::Str(v) => v.len(),
        }
    }

    /// True if there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A parameter variable: its metadata and its values, written when the file is created.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Name, units, long name.
    pub spec: VarSpec,
    /// One value per row of the parameter's dimension.
    pub values: ParamValues,
}

/// How the `[case, *]` and `[reference, time]` arrays are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Storage {
    /// Store series and spectra as float32 (values rounded to nearest) instead of
    /// float64. Metrics, parameters and coordinates are always float64.
    pub float32: bool,
    /// Deflate (gzip) level 0–9 for series and spectra, preceded by the shuffle filter;
    /// 0 stores them without any filter.
    pub deflate_level: u8,
}

impl Default for Storage {
    /// float64, deflate level 1 (most of deflate's gain on floating-point data at a
    /// fraction of the higher levels' cost).
    fn default() -> Self {
        Self {
            float32: false,
            deflate_level: 1,
        }
    }
}

/// State of one case, stored in the `status` variable as i8 with CF `flag_values`
/// `[0, 1, 2]` and `flag_meanings` `"pending ok failed"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(i8)]
pub enum Status {
    /// Not written yet (the fill value).
    #[default]
    Pending = 0,
    /// Ran to the end; its series, spectra and metrics are in the file.
    Ok = 1,
    /// Failed; `error_message` says why.
    Failed = 2,
}

impl Status {
    /// The three states in code order.
    pub const ALL: [Self; 3] = [Self::Pending, Self::Ok, Self::Failed];
    /// The CF `flag_meanings` attribute: the states' names in code order.
    pub const FLAG_MEANINGS: &'static str = "pending ok failed";

    /// The stored code.
    pub fn code(self) -> i8 {
        self as i8
    }

    /// The status with stored code `code`, if any.
    pub fn from_code(code: i8) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.code() == code)
    }
}

/// The role of a caller variable, kept in its `studyrun_role` attribute so that the
/// reader can rebuild the [`Layout`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
    Parameter,
    Metric,
    ReplicateMetric,
    RevolutionMetric,
    OrderSpectrum,
    Series,
    Spectrum,
    SpectralKurtosis,
    ReferenceParameter,
    ReferenceSeries,
}

impl Role {
    const ALL: [Self; 10] = [
        Self::Parameter,
        Self::Metric,
        Self::ReplicateMetric,
        Self::RevolutionMetric,
        Self::OrderSpectrum,
        Self::Series,
        Self::Spectrum,
        Self::SpectralKurtosis,
        Self::ReferenceParameter,
        Self::ReferenceSeries,
    ];

    /// The attribute value.
    pub(super) fn as_str(self) -> &'static str {
        match self {
            Self::Parameter => "parameter",
            Self::Metric => "metric",
            Self::ReplicateMetric => "replicate_metric",
            Self::RevolutionMetric => "revolution_metric",
            Self::OrderSpectrum => "order_spectrum",
            Self::Series => "series",
            Self::Spectrum => "spectrum",
            Self::SpectralKurtosis => "spectral_kurtosis",
            Self::ReferenceParameter => "reference_parameter",
            Self::ReferenceSeries => "reference_series",
        }
    }

    /// The role named by an attribute value.
    pub(super) fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.as_str() == s)
    }
}

/// Everything fixed when a study file is created: coordinates, the variables and their
/// metadata, parameter values, root attributes and storage options.
///
/// Rows of every `[case, ...]` variable follow `case_ids`; rows of every
/// `[reference, ...]` variable follow `reference_ids`. The default is the empty
/// layout: no cases, references, variables or attributes, default storage.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Layout {
    /// Global case ids (any distinct values up to [`MAX_ID`], not necessarily `0..n`);
    /// none for an empty shard.
    pub case_ids: Vec<u64>,
    /// Sample times of every series (s); non-empty if there are series. Empty when
    /// no variable uses it: the file then has no `time` coordinate.
    pub times: Vec<f64>,
    /// Bin frequencies of every spectrum (Hz); non-empty if there are spectra.
    pub frequencies: Vec<f64>,
    /// Ids of the reference (ideal mechanism) runs, distinct, up to [`MAX_ID`]; at
    /// least one.
    pub reference_ids: Vec<u64>,
    /// Per-case time series `[case, time]`.
    pub series: Vec<VarSpec>,
    /// Per-case spectra `[case, frequency]`.
    pub spectra: Vec<VarSpec>,
    /// Per-case scalar results `[case]`, float64.
    pub metrics: Vec<VarSpec>,
    /// Replicate ids (the `replicate` coordinate, distinct, up to [`MAX_ID`]); empty
    /// when the file has no replicate dimension.
    pub replicates: Vec<u64>,
    /// Per-case, per-replicate results `[case, replicate]`, float64; none without
    /// `replicates`.
    pub replicate_metrics: Vec<VarSpec>,
    /// Revolution numbers (the `revolution` coordinate, distinct, up to
    /// [`MAX_ID`]); empty when the file has no revolution dimension.
    pub revolutions: Vec<u64>,
    /// Per-case, per-revolution results `[case, revolution]`, float64; none without
    /// `revolutions`.
    pub revolution_metrics: Vec<VarSpec>,
    /// Bin orders of every order spectrum (the `order` coordinate, cycles per crank
    /// revolution); empty when the file has no order dimension.
    pub orders: Vec<f64>,
    /// Per-case order spectra `[case, order]`, float64, held and written whole like
    /// the per-revolution results; none without `orders`.
    pub order_spectra: Vec<VarSpec>,
    /// Bin frequencies of the spectral kurtosis (the `sk_frequency` coordinate, Hz);
    /// empty when the file has none.
    pub sk_frequencies: Vec<f64>,
    /// Per-case spectral kurtoses `[case, sk_frequency]`, stored like the spectra (a
    /// row per chunk); a record's spectrum rows end with them.
    pub kurtosis: Vec<VarSpec>,
    /// Per-case inputs `[case]`, written at creation.
    pub parameters: Vec<Param>,
    /// Per-reference inputs `[reference]`, written at creation.
    pub reference_parameters: Vec<Param>,
    /// Per-reference time series `[reference, time]`.
    pub reference_series: Vec<VarSpec>,
    /// For each case, the row in `reference_ids` it is compared with.
    pub reference_index: Vec<u64>,
    /// Root attributes in file order (names non-empty, distinct, not starting with `_`,
    /// not `studyrun_file_format`). See [`provenance`] for the usual ones.
    pub attributes: Vec<(String, AttrValue)>,
    /// Element type and compression of series and spectra.
    pub storage: Storage,
}

/// The provenance root attributes: `Conventions` (`CF-1.8`), `studyrun_version`
/// (the crate version), `git_commit` (short hash at build time, `unknown` outside a
/// checkout), `created` (now, RFC 3339, UTC, whole seconds) and `history` (CF §2.6.2:
/// `<created>: <command line>`, see [`command_line`]; stored as netCDF's NC_CHAR, so
/// that NCO puts its own lines on top).
pub fn provenance() -> Vec<(String, AttrValue)> {
    let created = humantime::format_rfc3339_seconds(SystemTime::now()).to_string();
    let history = history_line(&created, &command_line());
    vec![
        ("Conventions".to_owned(), "CF-1.8".into()),
        (
            "studyrun_version".to_owned(),
            env!("CARGO_PKG_VERSION").into(),
        ),
        ("git_commit".to_owned(), env!("STUDYRUN_GIT_COMMIT").into()),
        ("created".to_owned(), created.into()),
        ("history".to_owned(), history.into()),
    ]
}

/// One line of a `history` attribute: `<time>: <command>`.
pub fn history_line(time: &str, command: &str) -> String {
    format!("{time}: {command}")
}

/// This process's command line for `history`: `studyrun <arguments>` when the program
/// is `studyrun`, else `<program> <arguments> (studyrun <version>)`; arguments with
/// spaces or shell characters are single-quoted, line breaks shown as `\n`.
pub fn command_line() -> String {
    let mut args = std::env::args_os().map(|a| a.to_string_lossy().into_owned());
    let program = args
        .next()
        .map(|p| {
            std::path::Path::new(&p)
                .file_name()
                .map_or(p.clone(), |n| n.to_string_lossy().into_owned())
        })
        .unwrap_or_default();
    let words: Vec<String> = args.map(|a| shell_word(&a)).collect();
    let line = std::iter::once(if program == "studyrun" {
        program.clone()
    } else {
        shell_word(&program)
    })
    .chain(words)
    .collect::<Vec<_>>()
    .join(" ");
    if program == "studyrun" {
        line
    } else {
        format!("{line} (studyrun {})", env!("CARGO_PKG_VERSION"))
    }
}

/// `word` as a shell would need it: as it is if plain, else single-quoted; NULs and
/// line breaks (which would break a `history` line) escaped. For command lines that
/// studyrun prints or records, so that they paste back whole.
pub fn shell_word(word: &str) -> String {
    let word = word
        .replace('\0', "\\0")
        .replace('\n', "\\n")
        .replace('\r', "\\r");
    let plain = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_alphanumeric() || "-_./=:,+%@^".contains(c));
    if plain {
        word
    } else {
        format!("'{}'", word.replace('\'', "'\\''"))
    }
}

impl Layout {
    /// Number of cases (rows of the `case` dimension).
    pub fn n_cases(&self) -> usize {
        self.case_ids.len()
    }

    /// Number of references (rows of the `reference` dimension).
    pub fn n_references(&self) -> usize {
        self.reference_ids.len()
    }

    /// The name and role of every variable that carries a `studyrun_role`, sorted by
    /// name (netCDF tools may reorder variables).
    pub(super) fn role_variables(&self) -> Vec<(&str, Role)> {
        let mut all: Vec<(&str, Role)> = Vec::new();
        for (ps, role) in [
            (&self.parameters, Role::Parameter),
            (&self.reference_parameters, Role::ReferenceParameter),
        ] {
            all.extend(ps.iter().map(|p| (p.spec.name.as_str(), role)));
        }
        for (vs, role) in [
            (&self.metrics, Role::Metric),
            (&self.replicate_metrics, Role::ReplicateMetric),
            (&self.revolution_metrics, Role::RevolutionMetric),
            (&self.order_spectra, Role::OrderSpectrum),
            (&self.series, Role::Series),
            (&self.spectra, Role::Spectrum),
            (&self.kurtosis, Role::SpectralKurtosis),
            (&self.reference_series, Role::ReferenceSeries),
        ] {
            all.extend(vs.iter().map(|v| (v.name.as_str(), role)));
        }
        all.sort_unstable_by_key(|&(name, _)| name);
        all
    }

    /// Number of metric values a case record holds: one per [`Layout::metrics`],
    /// then one per replicate for each of [`Layout::replicate_metrics`], then one per
    /// revolution for each of [`Layout::revolution_metrics`], then one per order for
    /// each of [`Layout::order_spectra`].
    pub fn n_metric_values(&self) -> usize {
        self.metrics.len()
            + self.replicate_metrics.len() * self.replicates.len()
            + self.revolution_metrics.len() * self.revolutions.len()
            + self.order_spectra.len() * self.orders.len()
    }

    /// The values of one case row: its series, spectra and metric values.
    pub fn case_values(&self) -> usize {
        let spectra: usize = self.spectrum_rows().map(|(_, n)| n).sum();
        self.series.len() * self.times.len() + spectra + self.n_metric_values()
    }

    /// The root attribute `name`, if the layout has one.
    pub fn attribute(&self, name: &str) -> Option<&AttrValue> {
        self.attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }

    /// The spectrum-like rows of a case record ([`Record::spectra`](super::Record::spectra)),
    /// each with its length: every [`Layout::spectra`] entry over `frequencies`, then
    /// every [`Layout::kurtosis`] entry over `sk_frequencies`.
    pub fn spectrum_rows(&self) -> impl Iterator<Item = (&VarSpec, usize)> {
        let (n_f, n_sk) = (self.frequencies.len(), self.sk_frequencies.len());
        (self.spectra.iter().map(move |s| (s, n_f)))
            .chain(self.kurtosis.iter().map(move |s| (s, n_sk)))
    }

    /// Checks the layout; the error says what is wrong and names the variable.
    pub fn validate(&self) -> Result<(), String> {
        self.validate_as(false)
    }

    /// [`Layout::validate`], or when `unfilled` the layout of a file whose
    /// parameters are written later ([`StudyWriter::create_unfilled`](super::StudyWriter::create_unfilled)):
    /// then every parameter holds no value.
    pub(super) fn validate_as(&self, unfilled: bool) -> Result<(), String> {
        let n_case = self.case_ids.len();
        let n_ref = self.reference_ids.len();
        distinct(CASE, &self.case_ids)?;
        distinct(REFERENCE, &self.reference_ids)?;
        distinct(REPLICATE, &self.replicates)?;
        distinct(REVOLUTION, &self.revolutions)?;
        for (dim, len, specs) in [
            (REPLICATE, self.replicates.len(), &self.replicate_metrics),
            (REVOLUTION, self.revolutions.len(), &self.revolution_metrics),
            (ORDER, self.orders.len(), &self.order_spectra),
        ] {
            if let (0, Some(spec)) = (len, specs.first()) {
                return Err(format!(
                    "`{}` needs the `{dim}` dimension, which is empty",
                    spec.name
                ));
            }
        }
        if self.storage.deflate_level > 9 {
            return Err(format!(
                "deflate level {} is not in 0..=9",
                self.storage.deflate_level
            ));
        }
        let element = if self.storage.float32 { 4 } else { 8 };
        let needs = [
            (
                TIME,
                self.times.len(),
                !self.series.is_empty() || !self.reference_series.is_empty(),
            ),
            (FREQUENCY, self.frequencies.len(), !self.spectra.is_empty()),
            (
                SK_FREQUENCY,
                self.sk_frequencies.len(),
                !self.kurtosis.is_empty(),
            ),
        ];
        for (dim, len, needed) in needs {
            if needed && len == 0 {
                return Err(format!("`{dim}` is empty but variables use it"));
            }
            if len.saturating_mul(element) > MAX_CHUNK_BYTES {
                return Err(format!(
                    "`{dim}` has {len} values: one case's chunk would exceed HDF5's 4 GiB limit"
                ));
            }
        }
        // Without references (measured recordings) the cases refer to none.
        let refer = if n_ref == 0 { 0 } else { n_case };
        if self.reference_index.len() != refer {
            return Err(format!(
                "`{REFERENCE_INDEX}` has {} values for {n_case} cases and {n_ref} references",
                self.reference_index.len()
            ));
        }
        if let Some(bad) = self.reference_index.iter().find(|&&i| i >= n_ref as u64) {
            return Err(format!(
                "`{REFERENCE_INDEX}` holds row {bad}, but there are {n_ref} references"
            ));
        }
        self.check_parameters(unfilled)?;
        self.check_names()?;
        self.check_attributes()
    }

    /// Every parameter has one value per case (reference parameters per reference;
    /// none when `unfilled`), no text one a NUL.
    fn check_parameters(&self, unfilled: bool) -> Result<(), String> {
        let rows = |n: usize| if unfilled { 0 } else { n };
        for (params, dim, len) in [
            (&self.parameters, CASE, rows(self.case_ids.len())),
            (
                &self.reference_parameters,
                REFERENCE,
                rows(self.reference_ids.len()),
            ),
        ] {
            for p in params {
                if p.values.len() != len {
                    return Err(format!(
                        "parameter `{}` has {} values for {len} rows of `{dim}`",
                        p.spec.name,
                        p.values.len()
                    ));
                }
                if let ParamValues::Str(v) = &p.values {
                    if let Some(s) = v.iter().find(|s| s.contains('\0')) {
                        return Err(format!(
                            "parameter `{}`: value {s:?} contains NUL",
                            p.spec.name
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// All caller variable specs, in file order.
    pub(super) fn specs(&self) -> impl Iterator<Item = &VarSpec> {
        self.parameters
            .iter()
            .map(|p| &p.spec)
            .chain(&self.metrics)
            .chain(&self.replicate_metrics)
            .chain(&self.revolution_metrics)
            .chain(&self.order_spectra)
            .chain(&self.series)
            .chain(&self.spectra)
            .chain(&self.kurtosis)
            .chain(self.reference_parameters.iter().map(|p| &p.spec))
            .chain(&self.reference_series)
    }

    /// Every variable name the file holds: the built-in names, then the parameters,
    /// metrics, series, spectra, reference parameters and reference series.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        RESERVED
            .into_iter()
            .chain(self.specs().map(|s| s.name.as_str()))
    }

    fn check_names(&self) -> Result<(), String> {
        let mut seen: HashSet<&str> = RESERVED.into_iter().collect();
        for spec in self.specs() {
            let name = spec.name.as_str();
            if name.is_empty() || name.contains(['/', '\0']) || name.starts_with('_') || name == "."
            {
                return Err(format!(
                    "variable name {name:?} must be non-empty, without `/` or NUL, not starting with `_`"
                ));
            }
            if !seen.insert(name) {
                return Err(format!(
                    "variable name `{name}` is used twice or is a built-in name"
                ));
            }
            for (what, text) in [("units", &spec.units), ("long_name", &spec.long_name)] {
                if text.contains('\0') {
                    return Err(format!("variable `{name}`: {what} contains NUL"));
                }
            }
        }
        Ok(())
    }

    fn check_attributes(&self) -> Result<(), String> {
        let mut seen = HashSet::new();
        for (name, value) in &self.attributes {
            if name.is_empty()
                || name.contains('\0')
                || name.starts_with('_')
                || name == FORMAT_ATTR
                || name == VARIABLES_DIGEST_ATTR
            {
                return Err(format!(
                    "root attribute name {name:?} must be non-empty, without NUL, not starting with `_`, not `{FORMAT_ATTR}` or `{VARIABLES_DIGEST_ATTR}`"
                ));
            }
            if !seen.insert(name.as_str()) {
                return Err(format!("root attribute `{name}` is given twice"));
            }
            if let AttrValue::Str(s) = value {
                if s.contains('\0') {
                    return Err(format!("root attribute `{name}` contains NUL"));
                }
            }
        }
        Ok(())
    }
}

/// Checks that a coordinate's ids are distinct and fit the stored int32.
fn distinct(dim: &str, ids: &[u64]) -> Result<(), String> {
    if let Some(id) = ids.iter().find(|&&id| id > MAX_ID) {
        return Err(format!(
            "`{dim}` id {id} is above {MAX_ID}: ids are stored as int32, the widest integer CF-1.8 allows"
        ));
    }
    let mut seen = HashSet::with_capacity(ids.len());
    match ids.iter().find(|id| !seen.insert(**id)) {
        Some(id) => Err(format!("`{dim}` id {id} appears twice")),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> Layout {
        Layout {
            case_ids: vec![4, 2],
            times: vec![0.0, 0.1],
            frequencies: vec![0.0, 5.0],
            reference_ids: vec![0],
            series: vec![VarSpec::new("x", "m", "position")],
            spectra: vec![VarSpec::new("x_spectrum", "m", "amplitude of x")],
            metrics: vec![VarSpec::new("x_rms", "m", "rms of x")],
            parameters: vec![Param {
                spec: VarSpec::new("rpm", "min-1", "crank speed"),
                values: ParamValues::F64(vec![300.0, 600.0]),
            }],
            reference_index: vec![0, 0],
            attributes: provenance(),
            ..Layout::default()
        }
    }

    #[test]
    fn valid_layout_passes() {
        assert_eq!(small().validate(), Ok(()));
    }

    #[test]
    fn inconsistent_layouts_are_refused_by_name() {
        type Edit = fn(&mut Layout);
        let cases: [(Edit, &str); 11] = [
            (|l| l.case_ids = vec![1, 1], "`case` id 1"),
            (
                |l| l.case_ids = vec![1, 1 << 31],
                "`case` id 2147483648 is above 2147483647",
            ),
            (
                |l| l.reference_ids = vec![u64::MAX],
                "`reference` id 18446744073709551615 is above",
            ),
            (
                |l| l.reference_index = vec![0, 1],
                "`reference_index` holds row 1",
            ),
            (
                |l| l.parameters[0].values = ParamValues::F64(vec![1.0]),
                "`rpm` has 1 values",
            ),
            (|l| l.metrics[0].name = "status".into(), "`status`"),
            (|l| l.series[0].name = "a/b".into(), "\"a/b\""),
            (|l| l.storage.deflate_level = 10, "deflate level 10"),
            (
                |l| l.replicate_metrics = vec![VarSpec::new("x_reps", "m", "x")],
                "`x_reps` needs the `replicate` dimension",
            ),
            (|l| l.times.clear(), "`time` is empty"),
            (
                |l| l.attributes.push(("created".into(), 1.0.into())),
                "`created` is given twice",
            ),
        ];
        for (edit, needle) in cases {
            let mut layout = small();
            edit(&mut layout);
            let err = layout.validate().unwrap_err();
            assert!(err.contains(needle), "{err:?} lacks {needle:?}");
        }
    }

    #[test]
    fn status_codes_round_trip() {
        for s in Status::ALL {
            assert_eq!(Status::from_code(s.code()), Some(s));
        }
        assert_eq!(Status::from_code(3), None);
        assert_eq!(Status::default(), Status::Pending);
    }

    #[test]
    fn provenance_has_rfc3339_time_and_commit() {
        let attrs = provenance();
        let get = |k: &str| attrs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        let Some(AttrValue::Str(created)) = get("created") else {
            panic!("no created attribute")
        };
        assert!(humantime::parse_rfc3339(&created).is_ok(), "{created}");
        assert!(matches!(get("git_commit"), Some(AttrValue::Str(c)) if !c.is_empty()));
        let Some(AttrValue::Str(history)) = get("history") else {
            panic!("no history attribute")
        };
        assert!(
            history.starts_with(&format!("{created}: ")) && history.contains("studyrun"),
            "{history}"
        );
        assert!(!history.contains('\n'), "{history}");
    }

    #[test]
    fn shell_words_are_quoted_when_needed() {
        assert_eq!(shell_word("studies/smoke.yaml"), "studies/smoke.yaml");
        assert_eq!(shell_word("--shard=1/2"), "--shard=1/2");
        assert_eq!(shell_word("my file.h5"), "'my file.h5'");
        assert_eq!(shell_word("it's"), "'it'\\''s'");
        assert_eq!(shell_word(""), "''");
        assert_eq!(shell_word("a\nb"), "'a\\nb'");
    }
}
