//! A case's signal processing, between [`mod@crate::simulate`] and [`crate::output`]:
//! the spectra and the vibration metrics of docs/model.md §6–§7 computed from a
//! case's sampled outputs and the ideal mechanism's, and, when the study asks for
//! it, the envelope analysis and condition indicators of §7.3–§7.7.

pub mod envelope;
pub mod fault_frequencies;
pub mod indicators;
pub mod metrics;
pub mod replicates;
pub mod revolutions;
pub mod sensor;
pub mod spectrum;

use std::ops::Range;

use crate::mechanism::CaseParams;
use crate::output::VarSpec;
use crate::simulate::{CaseOutput, CHANNELS};
use envelope::{EnvelopePlan, EnvelopeSettings};
use fault_frequencies::FaultFrequencies;
use indicators::{band_energy, Indicators, INDICATOR_NAMES};
use metrics::{vibration_metrics, Deviation};
use spectrum::{frequencies, SpectrumError, SpectrumPlan};

/// Channels whose deviation from the ideal mechanism is a metric.
const DEVIATION_CHANNELS: [(&str, &str); 3] = [
    ("slider_acceleration", "m s-2"),
    ("crank_moment", "N m"),
    ("bearing_force", "N"),
];

/// The per-case metric variables, in file order: those of every study, then, for a
/// study with `envelope:` ([`envelope_metric_specs`]), the envelope metrics, then
/// `wall_time` (always last).
pub fn metric_specs(envelope: Option<&EnvelopeSettings>) -> Vec<VarSpec> {
    let mut specs = Vec::new();
    for (ch, units) in DEVIATION_CHANNELS {
        specs.push(VarSpec::new(
            format!("{ch}_rms_deviation"),
            units,
            format!("RMS of {ch} minus the ideal mechanism's, after the transient"),
        ));
        specs.push(VarSpec::new(
            format!("{ch}_peak_deviation"),
            units,
            format!("largest |{ch} minus the ideal mechanism's|, after the transient"),
        ));
        specs.push(VarSpec::new(
            format!("{ch}_reference_rms"),
            units,
            format!("RMS of the ideal mechanism's {ch} over the same window"),
        ));
    }
    specs.extend([
        VarSpec::new(
            "max_bearing_force",
            "N",
            "largest bearing force |F| after the transient",
        ),
        VarSpec::new(
            "min_loaded_balls",
            "1",
            "fewest loaded balls after the transient",
        ),
        VarSpec::new(
            "max_loaded_balls",
            "1",
            "most loaded balls after the transient",
        ),
        VarSpec::new("steps", "1", "accepted integrator steps"),
        VarSpec::new("rejected_steps", "1", "rejected integrator steps"),
        VarSpec::new("rhs_evals", "1", "right-hand-side evaluations"),
        VarSpec::new(
            "contact_events",
            "1",
            "contact switches the integrator located and restarted at",
        ),
        VarSpec::new(
            "stiffness_switch_time",
            "s",
            "time at which the explicit integrator found the case stiff and SDIRK4 took over (NaN: no switch)",
        ),
    ]);
    if let Some(settings) = envelope {
        specs.extend(envelope_metric_specs(settings));
    }
    specs.extend([VarSpec::new(
        "wall_time",
        "s",
        "wall-clock time of the case (integration, sampling, spectra)",
    )]);
    specs
}

/// The units of a channel's `units` raised to the integer power `p` (`m s-2`, 2 →
/// `m2 s-4`); `1` stays `1`.
pub fn units_power(units: &str, p: i32) -> String {
    if units == "1" {
        return units.to_string();
    }
    units
        .split_whitespace()
        .map(|token| {
            let split = token
                .find(|c: char| c == '-' || c.is_ascii_digit())
                .unwrap_or(token.len());
            let (symbol, exponent) = token.split_at(split);
            let e: i32 = if exponent.is_empty() {
                1
            } else {
                exponent
                    .parse()
                    .expect("channel units are symbols with integer powers")
            };
            format!("{symbol}{}", e * p)
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The units of channel `name`.
fn channel_units(name: &str) -> &'static str {
    CHANNELS
        .iter()
        .find(|c| c.name == name)
        .map(|c| c.units)
        .expect("envelope channels are validated")
}

/// The envelope metric suffixes for the characteristic frequencies' bands.
const ENVELOPE_BANDS: [&str; 4] = ["ftf", "bpfo", "bpfi", "2bsf"];

/// The metrics `envelope:` adds (docs/model.md §7.3–§7.7): per channel, the
/// indicators, the band demodulated, its kurtosis and the envelope-spectrum power
/// around FTF, BPFO, BPFI and 2·BSF; then the characteristic frequencies.
pub fn envelope_metric_specs(settings: &EnvelopeSettings) -> Vec<VarSpec> {
    let mut specs = Vec::new();
    for ch in &settings.channels {
        let units = channel_units(ch);
        for (name, dimensional) in INDICATOR_NAMES {
            specs.push(VarSpec::new(
                format!("{ch}_{name}"),
                if dimensional { units } else { "1" },
                format!(
                    "{} of {ch} (mean removed) over the analysed window",
                    name.replace('_', " ")
                ),
            ));
        }
        specs.extend([
            VarSpec::new(
                format!("{ch}_envelope_band_low"),
                "Hz",
                format!("lower edge of the band demodulated for the envelope of {ch}"),
            ),
            VarSpec::new(
                format!("{ch}_envelope_band_high"),
                "Hz",
                format!("upper edge of the band demodulated for the envelope of {ch}"),
            ),
            VarSpec::new(
                format!("{ch}_envelope_band_kurtosis"),
                "1",
                format!(
                    "kurtosis <|z|^4>/<|z|^2>^2 - 2 of the analytic signal of {ch} in that band"
                ),
            ),
        ]);
        for band in ENVELOPE_BANDS {
            specs.push(VarSpec::new(
                format!("{ch}_envelope_energy_{band}"),
                units_power(units, 4),
                format!("energy (line power) of the envelope spectrum of {ch} in the band around {band}"),
            ));
        }
    }
    let long = [
        "cage frequency (fundamental train frequency)",
        "ball pass frequency of the outer race",
        "ball pass frequency of the inner race",
        "ball spin frequency",
    ];
    for (name, long) in FaultFrequencies::NAMES.iter().zip(long) {
        specs.push(VarSpec::new(*name, "Hz", long));
    }
    specs
}

/// The per-case spectrum variables `envelope:` adds, after the study's spectra: per
/// channel its envelope spectrum, then its spectral kurtosis.
pub fn envelope_spectrum_specs(settings: &EnvelopeSettings) -> Vec<VarSpec> {
    let mut specs = Vec::new();
    for ch in &settings.channels {
        specs.extend([
            VarSpec::new(
                format!("{ch}_envelope_spectrum"),
                units_power(channel_units(ch), 2),
                format!("one-sided amplitude spectrum of the squared envelope of {ch}"),
            ),
            VarSpec::new(
                format!("{ch}_spectral_kurtosis"),
                "1",
                format!("spectral kurtosis of {ch} over the short-time Fourier transform"),
            ),
        ]);
    }
    specs
}

/// The envelope analysis of a study: its settings and the plan a worker reuses.
#[derive(Debug)]
pub struct EnvelopeAnalysis {
    settings: EnvelopeSettings,
    plan: EnvelopePlan,
    /// Bin frequencies of the analysed window (Hz).
    freqs: Vec<f64>,
}

impl EnvelopeAnalysis {
    /// Plans `settings` for windows of `n ≥ 2` samples at `sample_rate` (Hz).
    pub fn new(
        settings: EnvelopeSettings,
        n: usize,
        sample_rate: f64,
    ) -> Result<Self, SpectrumError> {
        Ok(Self {
            plan: EnvelopePlan::new(n, sample_rate)?,
            freqs: frequencies(n, sample_rate),
            settings,
        })
    }

    /// Appends the envelope spectra and spectral kurtoses of `out`'s channels over
    /// `window` to `spectra` and their metrics ([`envelope_metric_specs`] order) to
    /// `metrics`.
    fn run(
        &mut self,
        params: &CaseParams,
        out: &CaseOutput,
        window: Range<usize>,
        spectra: &mut Vec<Vec<f64>>,
        metrics: &mut Vec<f64>,
    ) -> Result<(), SpectrumError> {
        let faults = FaultFrequencies::of(params);
        let lines = [faults.ftf, faults.bpfo, faults.bpfi, 2.0 * faults.bsf];
        for ch in &self.settings.channels {
            let series = &out.channel(ch).expect("envelope channels are validated")[window.clone()];
            let env = self.plan.analyse(series, self.settings.band)?;
            metrics.extend(Indicators::of(series).values());
            metrics.extend([env.band.low, env.band.high, env.band_kurtosis]);
            metrics.extend(lines.map(|f| band_energy(&env.spectrum, &self.freqs, f)));
            spectra.push(env.spectrum);
            spectra.push(env.spectral_kurtosis);
        }
        metrics.extend(faults.values());
        Ok(())
    }
}

/// What the signal processing derives from one case.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseAnalysis {
    /// One amplitude spectrum per requested channel, in request order.
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`metric_specs`] entry but the last (`wall_time`, which the
    /// caller measures around the whole case).
    pub metrics: Vec<f64>,
}

/// The spectra of `spectrum_channels` and the metrics of `out` (the case `params`)
/// against `reference` (the ideal mechanism at the same speed and sample times), over
/// the analysed `window` of samples; with `envelope`, also its spectra (after the
/// others) and metrics (before `wall_time`).
pub fn analyse(
    params: &CaseParams,
    out: &CaseOutput,
    reference: &CaseOutput,
    window: Range<usize>,
    spectrum_channels: &[&str],
    plan: &mut SpectrumPlan,
    envelope: Option<&mut EnvelopeAnalysis>,
) -> Result<CaseAnalysis, SpectrumError> {
    let mut spectra = Vec::with_capacity(spectrum_channels.len());
    for ch in spectrum_channels {
        let series = out.channel(ch).expect("spectrum channels are validated");
        let mut amp = vec![0.0; plan.bins()];
        plan.amplitude(&series[window.clone()], &mut amp)?;
        spectra.push(amp);
    }
    let m = vibration_metrics(out, reference, window.clone());
    let analysed = |name: &str| &out.channel(name).expect("channel exists")[window.clone()];
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let mut metrics = Vec::new();
    for d in [m.slider_acceleration, m.crank_moment, m.bearing_force] {
        let Deviation {
            rms,
            peak,
            reference_rms,
        } = d;
        metrics.extend([rms, peak, reference_rms]);
    }
    let loaded = analysed("loaded_balls");
    metrics.extend([
        max(analysed("bearing_force")),
        min(loaded),
        max(loaded),
        out.stats.steps as f64,
        out.stats.rejected as f64,
        out.stats.rhs_evals as f64,
        out.stats.events as f64,
        out.stats.switched_at.unwrap_or(f64::NAN),
    ]);
    if let Some(envelope) = envelope {
        envelope.run(params, out, window, &mut spectra, &mut metrics)?;
    }
    Ok(CaseAnalysis { spectra, metrics })
}
