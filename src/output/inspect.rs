//! `studyrun inspect`: a summary of a result file, as text for a person or as a
//! [`Summary`] (serialisable: `inspect --json`) for a program.

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;

use crate::output::{shell_word, AttrValue, DataFile, Layout, ParamValues, Status, StudyReader};
use crate::signal::sensor::CLEAN_SUFFIX;

/// What a study file holds, read from its attributes and variables. Field names are
/// the `inspect --json` schema (docs/cli.md); units are in the names (`_s`, `_hz`,
/// `_m`).
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The file summarised.
    pub file: String,
    /// The study's `name`.
    pub study: String,
    /// The study's `description`.
    pub description: String,
    /// The studyrun version that wrote the file.
    pub studyrun_version: String,
    /// The git commit of that studyrun (`unknown` outside a release build).
    pub git_commit: String,
    /// When the file was created (RFC 3339).
    pub created: String,
    /// The grid's axes, slowest first.
    pub grid_axes: Vec<String>,
    /// Simulated duration of each case (s).
    pub duration_s: f64,
    /// Sample rate of the simulation (Hz).
    pub sample_rate_hz: f64,
    /// Start of the analysed window (s).
    pub transient_s: f64,
    /// Frequency bins of the spectra.
    pub frequency_bins: usize,
    /// The stored series: names, samples, rate.
    pub series: Series,
    /// The integrator and its settings, as the grid file words them.
    pub solver: String,
    /// The effects simulated.
    pub effects: Vec<String>,
    /// Case counts by status.
    pub cases: Cases,
    /// `K/N` for a shard file, `None` for a whole study.
    pub shard: Option<String>,
    /// Set when the file belongs to an interrupted run: what it is and how to go on.
    pub interrupted: Option<String>,
    /// The sampled design, if the study has one.
    pub design: Option<Design>,
    /// The envelope analysis, if the study has one.
    pub envelope: Option<Envelope>,
    /// The sensors' series: name and what the sensor is.
    pub sensors: Vec<Sensor>,
    /// The replicates, if the study has them.
    pub replicates: Option<Replicates>,
    /// The order spectra, if the study has them.
    pub orders: Option<Orders>,
    /// Every failed case: id, its axis values and its error.
    pub failed: Vec<Failed>,
}

/// The stored series of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Series {
    /// Variable names, in file order (empty: metrics and spectra only).
    pub names: Vec<String>,
    /// Samples per series.
    pub samples: usize,
    /// Their sample rate (Hz): the simulation's divided by `decimate`.
    pub sample_rate_hz: f64,
    /// One stored sample in `decimate` of the simulation's.
    pub decimate: i64,
}

/// Case counts of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Cases {
    /// Cases in this file.
    pub in_file: usize,
    /// Cases in the whole study (more than `in_file` for a shard).
    pub in_study: i64,
    /// Cases that ran to the end.
    pub ok: usize,
    /// Cases that failed (their messages are in `failed`).
    pub failed: usize,
    /// Cases not yet run (a partial file).
    pub pending: usize,
}

/// The sampled design of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Design {
    /// `lhs`, `sobol`, `saltelli` or `random`.
    pub method: String,
    /// The design's `samples`.
    pub samples: i64,
    /// Its seed.
    pub seed: i64,
    /// Whether Sobol points are scrambled.
    pub scrambled: bool,
    /// Rows of the design (repeated at every grid point).
    pub rows: i64,
    /// The parameters it draws.
    pub parameters: Vec<String>,
}

/// The envelope analysis of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Envelope {
    /// The series analysed.
    pub channels: Vec<String>,
    /// `auto` or `<low> Hz to <high> Hz`.
    pub band: String,
    /// Levels of the fast kurtogram.
    pub kurtogram_depth: i64,
    /// Samples per STFT segment of the spectral kurtosis.
    pub stft_segment: i64,
    /// Samples between STFT segments.
    pub stft_hop: i64,
}

/// A sensor of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Sensor {
    /// Its series' name (the noise-free copy adds `_clean`).
    pub name: String,
    /// What the sensor is: transducer, measured channel, noise.
    pub description: String,
}

/// The replicates of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Replicates {
    /// Replicates per case.
    pub count: usize,
    /// Size of the start perturbation (m).
    pub perturbation_m: f64,
    /// Seed of the perturbations' directions.
    pub seed: i64,
    /// Whether `predictability_horizon` and `chaotic` are stored per case.
    pub chaos_check: bool,
    /// Perturbed replicates of ok cases that failed (`replicate_status` failed).
    pub failed: usize,
}

/// The order spectra of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Orders {
    /// The order spectrum variables.
    pub variables: Vec<String>,
    /// Order bins.
    pub bins: usize,
    /// Whole crank revolutions resampled.
    pub revolutions: i64,
    /// Angle samples over them.
    pub samples: i64,
}

/// A failed case of a [`Summary`].
#[derive(Debug, Clone, Serialize)]
pub struct Failed {
    /// The case id.
    pub case: u64,
    /// Its value of each grid axis.
    pub axes: BTreeMap<String, String>,
    /// Why it failed.
    pub message: String,
}

/// The text summary of the study file at `path`: the study, its grid, status counts
/// and every failed case with its parameters and error.
pub fn inspect(path: &Path) -> Result<String> {
    Ok(Summary::read(path)?.text())
}

impl Summary {
    /// Reads the summary of the study file at `path`.
    pub fn read(path: &Path) -> Result<Summary> {
        let r =
            StudyReader::open(path).with_context(|| format!("cannot open {}", path.display()))?;
        let a = Attributes(&r);
        let l = r.layout();
        let statuses = r.statuses()?;
        let count = |s: Status| statuses.iter().filter(|&&x| x == s).count();
        let grid_axes = a.list("grid_axes");
        let failed_replicates = r.failed_replicates()?;
        let mut failed = Vec::new();
        for row in (0..statuses.len()).filter(|&k| statuses[k] == Status::Failed) {
            failed.push(Failed {
                case: l.case_ids[row],
                axes: axis_values(l, &grid_axes, row),
                message: r.message(row)?.to_string(),
            });
        }
        Ok(Summary {
            file: path.display().to_string(),
            study: a.text("study_name"),
            description: a.text("study_description"),
            studyrun_version: a.text("studyrun_version"),
            git_commit: a.text("git_commit"),
            created: a.text("created"),
            grid_axes,
            duration_s: a.number("duration"),
            sample_rate_hz: a.number("sample_rate"),
            transient_s: a.number("transient"),
            frequency_bins: l.frequencies.len(),
            series: Series {
                names: l.series.iter().map(|s| s.name.clone()).collect(),
                samples: l.times.len(),
                sample_rate_hz: a.number("series_sample_rate"),
                decimate: a.integer("decimate").unwrap_or(1),
            },
            solver: a.text("solver"),
            effects: a.list("effects"),
            cases: Cases {
                in_file: l.case_ids.len(),
                in_study: a.integer("study_cases").unwrap_or(l.case_ids.len() as i64),
                ok: count(Status::Ok),
                failed: count(Status::Failed),
                pending: count(Status::Pending),
            },
            shard: Some(a.text("shard")).filter(|s| !s.is_empty() && s != "?"),
            interrupted: interrupted_run(path),
            design: a.design(),
            envelope: a.envelope(l),
            sensors: sensors(l),
            replicates: (!l.replicates.is_empty()).then(|| Replicates {
                count: l.replicates.len(),
                perturbation_m: a.number("replicate_perturbation"),
                seed: a.integer("replicate_seed").unwrap_or(0),
                chaos_check: l.metrics.iter().any(|m| m.name == "chaotic"),
                failed: failed_replicates,
            }),
            orders: (!l.orders.is_empty()).then(|| Orders {
                variables: l.order_spectra.iter().map(|s| s.name.clone()).collect(),
                bins: l.orders.len(),
                revolutions: a.integer("order_revolutions").unwrap_or(0),
                samples: a.integer("order_samples").unwrap_or(0),
            }),
            failed,
        })
    }

    /// The summary as lines of text, one subject a line.
    pub fn text(&self) -> String {
        let mut out = String::new();
        self.write_text(&mut out).expect("writing to a String");
        out
    }

    fn write_text(&self, out: &mut String) -> std::fmt::Result {
        writeln!(out, "file:     {}", self.file)?;
        writeln!(out, "study:    {} — {}", self.study, self.description)?;
        writeln!(
            out,
            "made by:  studyrun {} (commit {}), {}",
            self.studyrun_version, self.git_commit, self.created
        )?;
        writeln!(out, "grid:     {}", self.grid_axes.join(","))?;
        writeln!(
            out,
            "sampling: {} s at {} Hz; analysed {} s <= t < {} s, {} frequency bins",
            self.duration_s,
            self.sample_rate_hz,
            self.transient_s,
            self.duration_s,
            self.frequency_bins
        )?;
        self.series.write_text(out)?;
        writeln!(out, "solver:   {}", self.solver)?;
        writeln!(out, "effects:  {}", self.effects.join(","))?;
        let c = &self.cases;
        writeln!(
            out,
            "cases:    {} in this file of {} in the study: {} ok, {} failed, {} pending",
            c.in_file, c.in_study, c.ok, c.failed, c.pending
        )?;
        if let Some(shard) = &self.shard {
            writeln!(
                out,
                "shard:    {shard} (merge the shards with `studyrun merge`)"
            )?;
        }
        if let Some(note) = &self.interrupted {
            writeln!(out, "run:      {note}")?;
        }
        self.write_sections(out)?;
        if !self.failed.is_empty() {
            writeln!(out, "failed cases:")?;
        }
        for f in &self.failed {
            let labels: Vec<String> = self
                .grid_axes
                .iter()
                .filter_map(|axis| f.axes.get(axis).map(|v| format!("{axis}={v}")))
                .collect();
            writeln!(
                out,
                "  case {} ({}): {}",
                f.case,
                labels.join(", "),
                f.message
            )?;
        }
        Ok(())
    }

    /// The lines of the optional sections: design, envelope, sensors, replicates, orders.
    fn write_sections(&self, out: &mut String) -> std::fmt::Result {
        if let Some(d) = &self.design {
            writeln!(
                out,
                "design:   {} of {} samples{} ({} rows, seed {}) over {}",
                d.method,
                d.samples,
                if d.scrambled { ", scrambled" } else { "" },
                d.rows,
                d.seed,
                d.parameters.join(", ")
            )?;
        }
        if let Some(e) = &self.envelope {
            writeln!(
                out,
                "envelope: {} (band {}; kurtogram depth {}, STFT segment {} hop {})",
                e.channels.join(", "),
                e.band,
                e.kurtogram_depth,
                e.stft_segment,
                e.stft_hop
            )?;
        }
        for s in &self.sensors {
            writeln!(out, "sensor:   {}: {}", s.name, s.description)?;
        }
        if let Some(r) = &self.replicates {
            writeln!(
                out,
                "replicates: {} per case, perturbation {} m, seed {}{}{}",
                r.count,
                r.perturbation_m,
                r.seed,
                if r.chaos_check {
                    "; predictability_horizon and chaotic per case"
                } else {
                    ""
                },
                if r.failed > 0 {
                    format!(
                        "; {} perturbed replicates failed (replicate_error_message)",
                        r.failed
                    )
                } else {
                    String::new()
                }
            )?;
        }
        if let Some(o) = &self.orders {
            writeln!(
                out,
                "orders:   {} bins 1/{} order apart ({} angle samples over {} whole revolutions): {}",
                o.bins,
                o.revolutions,
                o.samples,
                o.revolutions,
                o.variables.join(", ")
            )?;
        }
        Ok(())
    }
}

impl Series {
    fn write_text(&self, out: &mut String) -> std::fmt::Result {
        if self.names.is_empty() {
            return writeln!(out, "series:   none stored (metrics and spectra only)");
        }
        let every = match self.decimate {
            1 => "every sample of the output".to_string(),
            k => format!("one sample in {k} of the output, no anti-alias filter"),
        };
        writeln!(
            out,
            "series:   {} stored, {} samples each at {} Hz ({every}): {}",
            self.names.len(),
            self.samples,
            self.sample_rate_hz,
            self.names.join(", ")
        )
    }
}

/// The root attributes of a file, read leniently: a summary shows what is there.
struct Attributes<'a>(&'a StudyReader);

impl Attributes<'_> {
    /// A text attribute (a number shown as text), `?` when absent.
    fn text(&self, name: &str) -> String {
        match self.0.attribute(name) {
            Some(AttrValue::Str(s)) => s.clone(),
            Some(AttrValue::F64(x)) => x.to_string(),
            Some(AttrValue::I64(x)) => x.to_string(),
            None => "?".to_string(),
        }
    }

    /// A comma-separated list attribute; empty when absent or empty.
    fn list(&self, name: &str) -> Vec<String> {
        match self.0.attribute(name) {
            Some(AttrValue::Str(s)) => s
                .split(',')
                .filter(|x| !x.is_empty())
                .map(str::to_string)
                .collect(),
            _ => Vec::new(),
        }
    }

    /// A number attribute, NaN when absent or not a number.
    fn number(&self, name: &str) -> f64 {
        match self.0.attribute(name) {
            Some(AttrValue::F64(x)) => *x,
            Some(AttrValue::I64(x)) => *x as f64,
            _ => f64::NAN,
        }
    }

    /// An integer attribute.
    fn integer(&self, name: &str) -> Option<i64> {
        match self.0.attribute(name) {
            Some(AttrValue::I64(x)) => Some(*x),
            _ => None,
        }
    }

    fn design(&self) -> Option<Design> {
        self.0.attribute("design_method")?;
        Some(Design {
            method: self.text("design_method"),
            samples: self.integer("design_samples").unwrap_or(0),
            seed: self.integer("design_seed").unwrap_or(0),
            scrambled: self.integer("design_scrambled") == Some(1),
            rows: self.integer("design_rows").unwrap_or(0),
            parameters: self.list("design_parameters"),
        })
    }

    fn envelope(&self, l: &Layout) -> Option<Envelope> {
        self.0.attribute("envelope_band")?;
        Some(Envelope {
            channels: l
                .spectra
                .iter()
                .filter_map(|s| s.name.strip_suffix("_envelope_spectrum"))
                .map(str::to_string)
                .collect(),
            band: self.text("envelope_band"),
            kurtogram_depth: self.integer("kurtogram_depth").unwrap_or(0),
            stft_segment: self.integer("stft_segment").unwrap_or(0),
            stft_hop: self.integer("stft_hop").unwrap_or(0),
        })
    }
}

/// The sensors whose series the file stores: the series described as a sensor, without
/// their noise-free copies.
fn sensors(l: &Layout) -> Vec<Sensor> {
    l.series
        .iter()
        .filter(|s| s.long_name.starts_with("sensor ") && !s.name.ends_with(CLEAN_SUFFIX))
        .map(|s| Sensor {
            name: s.name.clone(),
            description: s.long_name.clone(),
        })
        .collect()
}

/// The value of each of `axes` in case row `row`, as text.
fn axis_values(l: &Layout, axes: &[String], row: usize) -> BTreeMap<String, String> {
    axes.iter()
        .filter_map(|axis| {
            let p = l.parameters.iter().find(|p| &p.spec.name == axis)?;
            let v = match &p.values {
                ParamValues::F64(v) => format!("{}", v[row]),
                ParamValues::Str(v) => v[row].clone(),
            };
            Some((axis.clone(), v))
        })
        .collect()
}

/// Reads every value of the study file at `path` and checks every checksum
/// ([`StudyReader::verify`]); an error names what is damaged. Returns the line that
/// says so, naming the variables without a checksum if there are any.
pub fn verify(path: &Path) -> Result<String> {
    let r = StudyReader::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let unchecked = r
        .verify()
        .with_context(|| format!("{} is damaged", path.display()))?;
    let n = r.layout().n_cases();
    Ok(if unchecked.is_empty() {
        format!("verified: every value of the {n} cases read, every checksum matches")
    } else {
        format!(
            "verified: every value of the {n} cases read, every checksum matches; these \
             variables carry none (a tool rewrote the file?): {}",
            unchecked.join(", ")
        )
    })
}

/// A note when `path` belongs to an interrupted run: it is a run's partial file (its
/// finished cases are in the journal, not yet marked here), or a result file beside
/// the journal of a run that will replace it.
fn interrupted_run(path: &Path) -> Option<String> {
    let partial = DataFile::output_of(path);
    let output = partial
        .as_ref()
        .map_or(path, |(output, _)| output.as_path());
    let (journal, _) = super::side_paths(output);
    if !journal.is_file() {
        return None;
    }
    Some(if partial.is_some() {
        format!(
            "interrupted: the partial file of {}, whose cases are marked done only when \
             the run finishes; the journal {} records the finished ones, and \
             `studyrun GRID -o {} --resume` continues the run",
            output.display(),
            journal.display(),
            shell_word(&output.to_string_lossy())
        )
    } else {
        format!(
            "the journal {} beside this file holds an interrupted run that replaces it when \
             `--resume` finishes it",
            journal.display()
        )
    })
}
